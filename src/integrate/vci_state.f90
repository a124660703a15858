!> What a run carries from one step to the next, in one object the driver owns and hands the
!> stepper whole: the state (t = t0 + k h, q, p, lambda, the last step's E_d) and the history the
!> next step needs (the predictor's velocities and multipliers, the energy of the sub-step that
!> arrived at q). A checkpoint is this object written out (to_checkpoint / from_checkpoint).
!> Also the buffer a step leaves its impacts in.
module vci_state
  use vci_kinds, only: dp, i8
  use vci_status, only: VCI_OK, VCI_ERR_MEMORY
  use vci_checkpoint, only: vci_checkpoint_t, copy_vector
  use vci_observer, only: vci_impact_t
  implicit none
  private

  type, public :: vci_state_t
    real(dp) :: h = 0.0_dp                      !< step length
    real(dp) :: t0 = 0.0_dp                     !< time of index 0: t = t0 + k h without drift
    integer(i8) :: k = 0_i8                     !< index of the state
    real(dp), allocatable :: q(:), p(:), lambda(:)
    real(dp) :: step_energy = 0.0_dp            !< E_d of the last step (of its last sub-step)
    !> forward-time velocity of the last sub-step: Newton's first guess
    real(dp), allocatable :: velocity(:)
    !> the predictor's history (vci_predictor): the velocity and multipliers of the steps before
    !> the last, from |predictor_depth| consecutive regular steps in direction sign(predictor_depth)
    real(dp), allocatable :: velocity_before(:), lambda_before(:), lambda_before2(:)
    integer :: predictor_depth = 0
    real(dp) :: arriving_energy = 0.0_dp        !< E_d of the sub-step that arrived at q
    integer :: arriving_direction = 0           !< direction in which arriving_energy is known (0: unknown)
  contains
    procedure :: reserve => reserve_state
    procedure :: time => state_time
    procedure :: forget_history
    procedure :: to_checkpoint
    procedure :: from_checkpoint
  end type vci_state_t

  !> The impacts of the last step: records(1:count). The records grow on demand.
  type, public :: vci_impact_buffer_t
    type(vci_impact_t), allocatable :: records(:)
    integer :: count = 0
  contains
    procedure :: reserve => reserve_impacts
  end type vci_impact_buffer_t

contains

  !> Arrays for n coordinates and m multipliers, zeroed, no history. stat = VCI_ERR_MEMORY when
  !> an allocation fails.
  subroutine reserve_state(self, n, m, stat)
    class(vci_state_t), intent(inout) :: self
    integer, intent(in) :: n, m
    integer, intent(out) :: stat
    ! array by array: after an allocate that failed part-way some are allocated and some not
    if (allocated(self%q)) deallocate (self%q)
    if (allocated(self%p)) deallocate (self%p)
    if (allocated(self%lambda)) deallocate (self%lambda)
    if (allocated(self%velocity)) deallocate (self%velocity)
    if (allocated(self%velocity_before)) deallocate (self%velocity_before)
    if (allocated(self%lambda_before)) deallocate (self%lambda_before)
    if (allocated(self%lambda_before2)) deallocate (self%lambda_before2)
    allocate (self%q(n), self%p(n), self%lambda(m), self%velocity(n), self%velocity_before(n), &
              self%lambda_before(m), self%lambda_before2(m), stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    self%lambda = 0.0_dp; self%q = 0.0_dp; self%p = 0.0_dp; self%velocity = 0.0_dp
    call self%forget_history()
    stat = VCI_OK
  end subroutine reserve_state

  pure real(dp) function state_time(self)
    class(vci_state_t), intent(in) :: self
    state_time = self%t0 + real(self%k, dp) * self%h
  end function state_time

  !> No predictor history: the next step starts from q + h velocity and the last multipliers.
  subroutine forget_history(self)
    class(vci_state_t), intent(inout) :: self
    self%velocity_before = 0.0_dp; self%lambda_before = 0.0_dp; self%lambda_before2 = 0.0_dp
    self%predictor_depth = 0
  end subroutine forget_history

  !> The state and its history as a checkpoint (position_lo is the scheme's and left to the caller).
  !> stat = VCI_ERR_MEMORY when a copy cannot be allocated (cp is then empty; the state unchanged).
  subroutine to_checkpoint(self, cp, stat)
    class(vci_state_t), intent(in) :: self
    type(vci_checkpoint_t), intent(out) :: cp
    integer, intent(out) :: stat
    ! array by array with stat=: a copy of n or m values is not tiny (issue 24, no runtime stop)
    stat = 0
    call copy_vector(self%q, cp%q, stat); call copy_vector(self%p, cp%p, stat)
    call copy_vector(self%lambda, cp%lambda, stat); call copy_vector(self%velocity, cp%velocity, stat)
    call copy_vector(self%velocity_before, cp%velocity_before, stat)
    call copy_vector(self%lambda_before, cp%lambda_before, stat)
    call copy_vector(self%lambda_before2, cp%lambda_before2, stat)
    if (stat /= 0) then
      call cp%release(); stat = VCI_ERR_MEMORY; return
    end if
    cp%t0 = self%t0; cp%h = self%h; cp%step = self%k
    cp%predictor_depth = self%predictor_depth
    cp%step_energy = self%step_energy
    cp%arriving_energy = self%arriving_energy; cp%arriving_direction = self%arriving_direction
    stat = VCI_OK
  end subroutine to_checkpoint

  !> Take the state and history of a checkpoint whose sizes the caller has checked (q, p, lambda,
  !> velocity); a history of other sizes, or none, is forgotten.
  subroutine from_checkpoint(self, cp)
    class(vci_state_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: cp
    self%t0 = cp%t0; self%k = cp%step
    self%q = cp%q; self%p = cp%p; self%lambda = cp%lambda; self%velocity = cp%velocity
    call self%forget_history()
    if (allocated(cp%velocity_before) .and. allocated(cp%lambda_before) .and. allocated(cp%lambda_before2)) then
      if (size(cp%velocity_before) == size(self%q) .and. size(cp%lambda_before) == size(self%lambda) .and. &
          size(cp%lambda_before2) == size(self%lambda)) then
        self%velocity_before = cp%velocity_before
        self%lambda_before = cp%lambda_before; self%lambda_before2 = cp%lambda_before2
        self%predictor_depth = cp%predictor_depth
      end if
    end if
    self%step_energy = cp%step_energy
    self%arriving_energy = cp%arriving_energy; self%arriving_direction = cp%arriving_direction
  end subroutine from_checkpoint

  !> Room for at least `count` impact records of n coordinates, keeping those already recorded.
  !> stat = VCI_ERR_MEMORY when an allocation fails (the records are then unchanged).
  subroutine reserve_impacts(self, count, n, stat)
    class(vci_impact_buffer_t), intent(inout) :: self
    integer, intent(in) :: count, n
    integer, intent(out) :: stat
    type(vci_impact_t), allocatable :: grown(:)
    integer :: i, k
    stat = VCI_OK
    k = 0
    if (allocated(self%records)) k = size(self%records)
    if (k >= max(1, count)) return
    allocate (grown(max(1, count)), stat=stat)
    do i = k + 1, size(grown)
      if (stat /= 0) exit
      allocate (grown(i)%q(n), grown(i)%p_before(n), grown(i)%p_after(n), grown(i)%grad_g(n), stat=stat)
    end do
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    do i = 1, k
      call move_alloc(self%records(i)%q, grown(i)%q)
      call move_alloc(self%records(i)%p_before, grown(i)%p_before)
      call move_alloc(self%records(i)%p_after, grown(i)%p_after)
      call move_alloc(self%records(i)%grad_g, grown(i)%grad_g)
      grown(i)%t = self%records(i)%t; grown(i)%step = self%records(i)%step; grown(i)%alpha = self%records(i)%alpha
      grown(i)%gap = self%records(i)%gap; grown(i)%impulse = self%records(i)%impulse
      grown(i)%condition = self%records(i)%condition
      grown(i)%energy_before = self%records(i)%energy_before; grown(i)%energy_after = self%records(i)%energy_after
      grown(i)%leave_rate = self%records(i)%leave_rate
      grown(i)%stage1_residual = self%records(i)%stage1_residual
      grown(i)%stage2_residual = self%records(i)%stage2_residual
    end do
    call move_alloc(grown, self%records)
  end subroutine reserve_impacts
end module vci_state
