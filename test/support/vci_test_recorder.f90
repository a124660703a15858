!> An observer that keeps a run in memory, for tests: every state and every impact.
module vci_test_recorder
  use vci
  implicit none
  private

  type, extends(vci_observer_t), public :: recorder_t
    integer :: nsteps = 0, nimpacts = 0
    real(dp), allocatable :: t(:), q(:, :), p(:, :), lambda(:, :), energy(:)
    type(vci_impact_t), allocatable :: impacts(:)
    integer :: finish_status = -1
    character(len=:), allocatable :: finish_message
  contains
    procedure :: on_start => r_start
    procedure :: on_step => r_step
    procedure :: on_impact => r_impact
    procedure :: on_finish => r_finish
  end type recorder_t

contains

  subroutine r_start(self, info, q, p, stat)
    class(recorder_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
    self%nsteps = 0; self%nimpacts = 0
    if (allocated(self%t)) deallocate (self%t, self%q, self%p, self%lambda, self%energy)
    allocate (self%t(0:1023), self%q(info%n, 0:1023), self%p(info%n, 0:1023), self%lambda(info%m, 0:1023), &
              self%energy(0:1023))
    if (allocated(self%impacts)) deallocate (self%impacts)
    allocate (self%impacts(0))
    self%t(0) = info%t0; self%q(:, 0) = q; self%p(:, 0) = p
    self%lambda(:, 0) = 0.0_dp; self%energy(0) = 0.0_dp
  end subroutine r_start

  subroutine r_step(self, step, t, q, p, lambda, energy, stat)
    class(recorder_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    integer :: k
    k = self%nsteps + 1
    if (k > ubound(self%t, 1)) call grow(self)
    self%t(k) = t; self%q(:, k) = q; self%p(:, k) = p; self%lambda(:, k) = lambda; self%energy(k) = energy
    self%nsteps = k
  end subroutine r_step

  subroutine grow(self)
    type(recorder_t), intent(inout) :: self
    real(dp), allocatable :: t(:), q(:, :), p(:, :), l(:, :), e(:)
    integer :: nmax
    nmax = 2 * (ubound(self%t, 1) + 1) - 1
    allocate (t(0:nmax), q(size(self%q, 1), 0:nmax), p(size(self%p, 1), 0:nmax), l(size(self%lambda, 1), 0:nmax), &
              e(0:nmax))
    t(0:self%nsteps) = self%t(0:self%nsteps); q(:, 0:self%nsteps) = self%q(:, 0:self%nsteps)
    p(:, 0:self%nsteps) = self%p(:, 0:self%nsteps); l(:, 0:self%nsteps) = self%lambda(:, 0:self%nsteps)
    e(0:self%nsteps) = self%energy(0:self%nsteps)
    call move_alloc(t, self%t); call move_alloc(q, self%q); call move_alloc(p, self%p)
    call move_alloc(l, self%lambda); call move_alloc(e, self%energy)
  end subroutine grow

  subroutine r_impact(self, impact, stat)
    class(recorder_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    self%impacts = [self%impacts, impact]
    self%nimpacts = self%nimpacts + 1
  end subroutine r_impact

  subroutine r_finish(self, status, message, stat)
    class(recorder_t), intent(inout) :: self
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    integer, intent(inout) :: stat
    self%finish_status = status
    self%finish_message = message
  end subroutine r_finish
end module vci_test_recorder
