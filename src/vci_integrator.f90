!> The driver: state, time loop, statistics, error reporting and observers around the stepper.
!>
!> Usage: extend vci_model_t; `call integ%create(model, h, stat)`; initialise from a pair or from
!> (q0, p0); `call integ%integrate(nsteps, +1 or -1, stat, observer)`. On any failure the state
!> stays at the last accepted step, `stat` says what went wrong and `integ%message` says where
!> (step, time) and why. Nothing here stops or prints.
module vci_integrator
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_quiet_nan
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_model, only: vci_model_t
  use vci_limits, only: vci_size_problem
  use vci_stepper, only: vci_stepper_t, vci_settings_t
  use vci_step_system, only: VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN
  use vci_observer, only: vci_observer_t, vci_run_info_t
  implicit none
  private
  public :: VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN

  !> Counters over the integrator's life.
  type, public :: vci_stats_t
    integer(i8) :: steps = 0, impacts = 0, newton_solves = 0, newton_iterations = 0, fallbacks = 0
  end type vci_stats_t

  !> Everything needed to continue a run bit for bit: the state plus the solver's memory
  !> (velocity used for initial guesses, energy of the arriving sub-step).
  type, public :: vci_checkpoint_t
    real(dp) :: t0 = 0.0_dp, h = 0.0_dp, energy = 0.0_dp, e_arrive = 0.0_dp
    integer(i8) :: k = 0_i8
    integer :: e_dir = 0
    real(dp), allocatable :: q(:), p(:), lambda(:), vel(:)
  end type vci_checkpoint_t

  type, public :: vci_integrator_t
    class(vci_model_t), pointer :: model => null()
    type(vci_stepper_t) :: stepper
    type(vci_settings_t) :: settings
    real(dp) :: h = 0.0_dp
    real(dp) :: t = 0.0_dp                     !< time of the current state
    integer(i8) :: k = 0_i8                    !< index of the current state (t = t0 + k h)
    real(dp) :: t0 = 0.0_dp                    !< time of index 0, so t = t0 + k h without drift
    real(dp), allocatable :: q(:), p(:), lambda(:)
    real(dp) :: energy = 0.0_dp                !< E_d of the last step (of its last sub-step)
    integer :: status = VCI_OK                 !< status of the last call
    character(len=VCI_MSG_LEN) :: message = '' !< what went wrong in the last call, naming step and time
    type(vci_stats_t) :: stats
    logical :: created = .false., initialized = .false.
    real(dp), allocatable, private :: vel(:), qn(:), pn(:), lambdan(:)
    real(dp), private :: e_arrive = 0.0_dp
    integer, private :: e_dir = 0              !< direction in which e_arrive is known (0: unknown)
  contains
    procedure :: create
    procedure :: set_tolerances
    procedure :: set_impact_energy
    procedure :: set_max_impacts
    procedure :: init_from_pair
    procedure :: init_from_momentum
    procedure :: step
    procedure :: integrate
    procedure :: run_info
    procedure :: checkpoint
    procedure :: restore
  end type vci_integrator_t

contains

  !> Bind a model and a step length. The model must outlive the integrator.
  subroutine create(self, model, h, stat)
    class(vci_integrator_t), intent(inout) :: self
    class(vci_model_t), target, intent(inout) :: model
    real(dp), intent(in) :: h
    integer, intent(out) :: stat
    character(len=80) :: why
    self%created = .false.; self%initialized = .false.
    self%stats = vci_stats_t()
    why = vci_size_problem(model%n, model%m, model%n_gaps)
    if (why /= '') then
      write (self%message, '(a,3(i0,a))') 'create: model sizes invalid (n = ', model%n, ', m = ', model%m, &
        ', n_gaps = ', model%n_gaps, '; '//trim(why)//')'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (.not. (ieee_is_finite(h) .and. h > 0.0_dp)) then
      write (self%message, '(a,es12.4,a)') 'create: step length h = ', h, ' must be positive and finite'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    self%model => model
    self%h = h
    if (allocated(self%q)) deallocate (self%q, self%p, self%lambda, self%vel, self%qn, self%pn, self%lambdan)
    allocate (self%q(model%n), self%p(model%n), self%lambda(model%m), self%vel(model%n), &
              self%qn(model%n), self%pn(model%n), self%lambdan(model%m), stat=stat)
    if (stat == 0) call self%stepper%setup(model, self%settings, stat)
    if (stat /= 0) then
      write (self%message, '(a,3(i0,a))') 'create: cannot allocate the workspace for n = ', model%n, ', m = ', &
        model%m, ', n_gaps = ', model%n_gaps, ' (out of memory)'
      call finish(self, VCI_ERR_MEMORY, stat); return
    end if
    self%lambda = 0.0_dp; self%q = 0.0_dp; self%p = 0.0_dp; self%vel = 0.0_dp
    self%created = .true.
    self%message = ''
    call finish(self, VCI_OK, stat)
  end subroutine create

  !> Newton tolerances: |r_i| <= atol + rtol * (size of row i's terms); iteration cap.
  subroutine set_tolerances(self, atol, rtol, max_iterations, stat)
    class(vci_integrator_t), intent(inout) :: self
    real(dp), intent(in) :: atol, rtol
    integer, intent(in) :: max_iterations
    integer, intent(out) :: stat
    ! rtol >= 1 accepts any iterate whose residual is smaller than its terms: even the initial guess
    if (.not. (ieee_is_finite(atol) .and. atol >= 0.0_dp .and. ieee_is_finite(rtol) .and. rtol >= 0.0_dp &
               .and. rtol < 1.0_dp .and. atol + rtol > 0.0_dp .and. max_iterations >= 1)) then
      write (self%message, '(a,es10.3,a,es10.3,a,i0,a)') 'set_tolerances: atol = ', atol, ', rtol = ', rtol, &
        ', max_iterations = ', max_iterations, ' (need atol >= 0, 0 <= rtol < 1, not both 0, max_iterations >= 1)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    self%settings%atol = atol; self%settings%rtol = rtol; self%settings%max_iterations = max_iterations
    self%stepper%settings = self%settings
    call finish(self, VCI_OK, stat)
  end subroutine set_tolerances

  !> Impact energy condition: VCI_IMPACT_DISCRETE (the paper's E_d(alpha h) = E_d((1-alpha) h), default)
  !> or VCI_IMPACT_HAMILTONIAN (H(q~, p+) = H(q~, p-); the model must supply `energy`).
  subroutine set_impact_energy(self, mode, stat)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: mode
    integer, intent(out) :: stat
    real(dp) :: e
    integer :: s
    if (mode /= VCI_IMPACT_DISCRETE .and. mode /= VCI_IMPACT_HAMILTONIAN) then
      write (self%message, '(a,i0,a)') 'set_impact_energy: unknown mode ', mode, &
        ' (0 = discrete, 1 = hamiltonian)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (mode == VCI_IMPACT_HAMILTONIAN) then
      if (.not. self%created) then
        self%message = 'set_impact_energy: create the integrator first'
        call finish(self, VCI_ERR_STATE, stat); return
      end if
      ! probe: the default energy answers VCI_NOT_PROVIDED whatever its arguments (q, p are zero
      ! before initialisation)
      s = 0
      call self%model%energy(self%q, self%p, e, s)
      if (s == VCI_NOT_PROVIDED) then
        self%message = 'set_impact_energy: the hamiltonian condition needs the model''s energy(q, p), '// &
                       'which this model does not supply'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
    end if
    self%settings%impact_energy = mode
    self%stepper%settings = self%settings
    call finish(self, VCI_OK, stat)
  end subroutine set_impact_energy

  !> Bound on impacts resolved inside one step (default 16).
  subroutine set_max_impacts(self, max_impacts, stat)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: max_impacts
    integer, intent(out) :: stat
    if (max_impacts < 1) then
      write (self%message, '(a,i0,a)') 'set_max_impacts: ', max_impacts, ' (need >= 1)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    self%settings%max_impacts_per_step = max_impacts   ! records grow on demand up to it
    self%stepper%settings = self%settings
    call finish(self, VCI_OK, stat)
  end subroutine set_max_impacts

  !> Start from q0 at t0 and q1 at t0 + h (the paper's initial pair). The current state becomes
  !> (t0 + h, q1, p1) with p1 = D2 L_d(q0, q1, h); the step index is 1.
  subroutine init_from_pair(self, t0, q0, q1, stat)
    class(vci_integrator_t), intent(inout) :: self
    real(dp), intent(in) :: t0, q0(:), q1(:)
    integer, intent(out) :: stat
    call check_init(self, 'init_from_pair', t0, q0, q1, stat, q1)
    if (stat /= VCI_OK) return
    if (.not. ieee_is_finite(t0 + self%h)) then
      self%initialized = .false.
      write (self%message, '(a,es12.4,a,es12.4,a)') 'init_from_pair: t0 + h = ', t0, ' + ', self%h, ' overflows'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    self%stepper%sys%dir = 1
    call self%stepper%sys%momentum_out(q0, q1, self%h, self%p, stat)
    if (stat == VCI_OK) call self%stepper%sys%energy_of(q0, q1, self%h, self%energy, stat)
    if (stat /= VCI_OK) then
      self%message = 'init_from_pair: callback '//trim(self%stepper%sys%failed_callback)// &
                     ' failed or returned NaN/Inf at the initial pair'
      call finish(self, failure_of(stat), stat); return
    end if
    self%t0 = t0; self%k = 1_i8; self%t = t0 + self%h
    self%q = q1
    self%lambda = 0.0_dp
    self%vel = (q1 - q0) / self%h
    self%e_arrive = self%energy; self%e_dir = 1
    self%initialized = .true.
    call finish(self, VCI_OK, stat)
  end subroutine init_from_pair

  !> Start from (q0, p0) at t0; step index 0.
  subroutine init_from_momentum(self, t0, q0, p0, stat)
    class(vci_integrator_t), intent(inout) :: self
    real(dp), intent(in) :: t0, q0(:), p0(:)
    integer, intent(out) :: stat
    call check_init(self, 'init_from_momentum', t0, q0, p0, stat)
    if (stat /= VCI_OK) return
    self%t0 = t0; self%t = t0; self%k = 0_i8
    self%q = q0; self%p = p0
    self%lambda = 0.0_dp
    self%vel = 0.0_dp
    self%energy = ieee_value(1.0_dp, ieee_quiet_nan)
    self%e_dir = 0
    self%initialized = .true.
    call finish(self, VCI_OK, stat)
  end subroutine init_from_momentum

  !> Validate initial data and probe which optional model procedures exist.
  subroutine check_init(self, who, t0, q0, v0, stat, q1)
    class(vci_integrator_t), intent(inout) :: self
    character(len=*), intent(in) :: who
    real(dp), intent(in) :: t0, q0(:), v0(:)
    integer, intent(out) :: stat
    real(dp), intent(in), optional :: q1(:)   !< second configuration of a pair: must be admissible too
    integer :: n, s, j
    real(dp), allocatable :: g(:), omega(:, :), hess(:, :), w(:), dg(:, :), w2(:)
    self%initialized = .false.
    if (.not. self%created) then
      self%message = who//': create the integrator first'
      call finish(self, VCI_ERR_STATE, stat); return
    end if
    n = self%model%n
    if (size(q0) /= n .or. size(v0) /= n) then
      write (self%message, '(a,3(i0,a))') who//': arrays of size ', size(q0), ' and ', size(v0), &
        ' given, model has n = ', n, ''
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (.not. (ieee_is_finite(t0) .and. all(ieee_is_finite(q0)) .and. all(ieee_is_finite(v0)))) then
      self%message = who//': initial data contain NaN or Inf'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    ! optional procedures: the defaults answer VCI_NOT_PROVIDED
    allocate (hess(n, n), omega(n, max(1, self%model%m)), g(self%model%n_gaps), w(self%model%m), &
              dg(n, self%model%n_gaps), w2(self%model%n_gaps), stat=s)
    if (s /= 0) then
      self%message = who//': cannot allocate the probes of the model (out of memory)'
      call finish(self, VCI_ERR_MEMORY, stat); return
    end if
    s = 0
    call self%model%mixed_hessian(q0, v0, self%h, hess, s)
    self%stepper%sys%has_hessian = (s /= VCI_NOT_PROVIDED)
    if (self%model%m > 0) then
      s = 0
      call self%model%constraint_forms(q0, omega(:, 1:self%model%m), s)
      if (s == VCI_NOT_PROVIDED) then
        write (self%message, '(a,i0,a)') who//': the model has m = ', self%model%m, &
          ' constraints but does not supply constraint_forms'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
      if (s /= 0) then
        write (self%message, '(a,i0,a)') who//': callback constraint_forms failed at the initial '// &
          'configuration (stat = ', s, ')'
        call finish(self, VCI_ERR_CALLBACK, stat); return
      end if
      s = 0
      call self%model%discrete_constraint(q0, q0, self%h, w, s)
      if (s == VCI_NOT_PROVIDED) then
        write (self%message, '(a,i0,a)') who//': the model has m = ', self%model%m, &
          ' constraints but does not supply discrete_constraint'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
    end if
    if (self%model%n_gaps > 0) then
      s = 0
      call self%model%gaps(q0, g, s)
      if (s == VCI_NOT_PROVIDED) then
        write (self%message, '(a,i0,a)') who//': the model has n_gaps = ', self%model%n_gaps, &
          ' walls but does not supply gaps'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
      if (s /= 0 .or. .not. all(ieee_is_finite(g))) then
        self%message = who//': callback gaps failed or returned NaN/Inf at the initial configuration'
        call finish(self, VCI_ERR_CALLBACK, stat); return
      end if
      if (present(q1)) then
        s = 0
        call self%model%gaps(q1, w2, s)
        if (s /= 0 .or. .not. all(ieee_is_finite(w2))) then
          self%message = who//': callback gaps failed or returned NaN/Inf at the second configuration'
          call finish(self, VCI_ERR_CALLBACK, stat); return
        end if
        g = min(g, w2)
      end if
      do j = 1, self%model%n_gaps
        if (g(j) < 0.0_dp) then
          write (self%message, '(a,i0,a,es12.4,a)') who//': initial configuration outside the admissible set (g_', &
            j, ' = ', g(j), ' < 0)'
          call finish(self, VCI_ERR_INADMISSIBLE, stat); return
        end if
      end do
      s = 0
      call self%model%gap_gradients(q0, dg, s)
      self%stepper%sys%has_gap_gradients = (s /= VCI_NOT_PROVIDED)
    end if
    stat = VCI_OK
  end subroutine check_init

  !> One step in direction +1 (forward, (+) scheme) or -1 (backward, (-) scheme). Impacts of the
  !> step are in self%stepper%impacts(1:self%stepper%n_impacts) afterwards.
  subroutine step(self, direction, stat, observer)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: direction
    integer, intent(out) :: stat
    class(vci_observer_t), intent(inout), optional :: observer
    integer :: i, ostat
    character(len=16) :: dname
    if (.not. self%initialized) then
      self%message = 'step: initialise the integrator first (init_from_pair or init_from_momentum)'
      call finish(self, VCI_ERR_STATE, stat); return
    end if
    if (direction /= 1 .and. direction /= -1) then
      write (self%message, '(a,i0,a)') 'step: direction ', direction, ' (need +1 or -1)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (.not. ieee_is_finite(self%t0 + real(self%k + direction, dp) * self%h)) then
      write (self%message, '(a,i0,a,es14.7,a,es10.3,a)') 'step from index ', self%k, ' (t = ', self%t, &
        '): the time of the next state overflows (h = ', self%h, ')'
      call finish(self, VCI_ERR_NONFINITE, stat); return
    end if
    if (self%e_dir /= direction) self%e_arrive = ieee_value(1.0_dp, ieee_quiet_nan)
    call self%stepper%advance(direction, self%h, self%t, self%q, self%p, self%lambda, self%vel, &
                              self%e_arrive, self%qn, self%pn, self%lambdan, self%energy, stat)
    self%stats%newton_solves = self%stepper%stats%newton_solves
    self%stats%newton_iterations = self%stepper%stats%newton_iterations
    self%stats%fallbacks = self%stepper%stats%fallbacks
    if (stat /= VCI_OK) then
      dname = 'forward'
      if (direction < 0) dname = 'backward'
      write (self%message, '(a,i0,a,es14.7,a)') 'step from index ', self%k, ' (t = ', self%t, ', '// &
        trim(dname)//'): '//trim(self%stepper%cause)
      self%e_dir = 0
      call finish(self, failure_of(stat), stat); return
    end if
    self%e_dir = direction
    do i = 1, self%stepper%n_impacts
      self%stepper%impacts(i)%step = self%k
    end do
    self%q = self%qn; self%p = self%pn
    if (self%model%m > 0) self%lambda = self%lambdan
    self%k = self%k + direction
    self%t = self%t0 + real(self%k, dp) * self%h
    self%stats%steps = self%stats%steps + 1
    self%stats%impacts = self%stats%impacts + self%stepper%n_impacts
    stat = VCI_OK
    if (present(observer)) then
      ostat = 0
      do i = 1, self%stepper%n_impacts
        call observer%on_impact(self%stepper%impacts(i), ostat)
      end do
      if (ostat == 0) call observer%on_step(self%k, self%t, self%q, self%p, self%lambda, self%energy, ostat)
      if (ostat /= 0) then
        write (self%message, '(a,i0,a,es14.7,a)') 'observer failed after step to index ', self%k, &
          ' (t = ', self%t, ')'
        call finish(self, VCI_ERR_IO, stat); return
      end if
    end if
    call finish(self, VCI_OK, stat)
  end subroutine step

  !> nsteps steps in one direction, reported to the observer (on_start, on_impact, on_step,
  !> on_finish). Stops at the first failure; the state is then the last accepted step.
  subroutine integrate(self, nsteps, direction, stat, observer)
    class(vci_integrator_t), intent(inout) :: self
    integer(i8), intent(in) :: nsteps
    integer, intent(in) :: direction
    integer, intent(out) :: stat
    class(vci_observer_t), intent(inout), optional :: observer
    integer(i8) :: i
    integer :: ostat
    if (nsteps < 0) then
      write (self%message, '(a,i0,a)') 'integrate: nsteps = ', nsteps, ' (need >= 0)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (.not. self%initialized) then
      self%message = 'integrate: initialise the integrator first (init_from_pair or init_from_momentum)'
      call finish(self, VCI_ERR_STATE, stat); return
    end if
    if (direction /= 1 .and. direction /= -1) then
      write (self%message, '(a,i0,a)') 'integrate: direction ', direction, ' (need +1 or -1)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (present(observer)) then
      ostat = 0
      call observer%on_start(self%run_info(direction), self%q, self%p, ostat)
      if (ostat /= 0) then
        self%message = 'integrate: observer failed at the start of the run'
        call finish(self, VCI_ERR_IO, stat); return
      end if
    end if
    stat = VCI_OK
    do i = 1, nsteps
      call self%step(direction, stat, observer)
      if (stat /= VCI_OK) exit
    end do
    if (present(observer)) then
      ostat = 0
      call observer%on_finish(stat, trim(self%message), ostat)
      if (ostat /= 0 .and. stat == VCI_OK) then
        self%message = 'integrate: observer failed at the end of the run'
        call finish(self, VCI_ERR_IO, stat); return
      end if
    end if
    self%status = stat
    if (stat == VCI_OK) self%message = ''   ! also after 0 steps: no message of an earlier call
  end subroutine integrate

  !> The current state and solver memory, for restarts that continue bit for bit.
  function checkpoint(self) result(cp)
    class(vci_integrator_t), intent(in) :: self
    type(vci_checkpoint_t) :: cp
    cp%t0 = self%t0; cp%h = self%h; cp%energy = self%energy; cp%e_arrive = self%e_arrive
    cp%k = self%k; cp%e_dir = self%e_dir
    cp%q = self%q; cp%p = self%p; cp%lambda = self%lambda; cp%vel = self%vel
  end function checkpoint

  !> Continue from a checkpoint taken with the same model and step length.
  subroutine restore(self, cp, stat)
    class(vci_integrator_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: cp
    integer, intent(out) :: stat
    if (.not. self%created) then
      self%message = 'restore: create the integrator first'
      call finish(self, VCI_ERR_STATE, stat); return
    end if
    if (.not. allocated(cp%q)) then
      self%message = 'restore: empty checkpoint'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (size(cp%q) /= self%model%n .or. size(cp%lambda) /= self%model%m .or. cp%h /= self%h) then
      self%message = 'restore: checkpoint does not match this model or step length'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    call check_init(self, 'restore', cp%t0, cp%q, cp%p, stat)
    if (stat /= VCI_OK) return
    self%t0 = cp%t0; self%energy = cp%energy; self%e_arrive = cp%e_arrive
    self%k = cp%k; self%e_dir = cp%e_dir
    self%q = cp%q; self%p = cp%p; self%lambda = cp%lambda; self%vel = cp%vel
    self%t = self%t0 + real(self%k, dp) * self%h
    self%initialized = .true.
    call finish(self, VCI_OK, stat)
  end subroutine restore

  !> What observers are told at the start of a run.
  function run_info(self, direction) result(info)
    class(vci_integrator_t), intent(in) :: self
    integer, intent(in) :: direction
    type(vci_run_info_t) :: info
    info%n = self%model%n; info%m = self%model%m; info%n_gaps = self%model%n_gaps
    info%direction = direction; info%h = self%h; info%t0 = self%t; info%step0 = self%k
    info%impact_energy = self%settings%impact_energy
  end function run_info

  pure integer function failure_of(stat)
    integer, intent(in) :: stat
    failure_of = stat
  end function failure_of

  subroutine finish(self, status, stat)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: status
    integer, intent(out) :: stat
    self%status = status
    if (status == VCI_OK) self%message = ''
    stat = status
  end subroutine finish
end module vci_integrator
