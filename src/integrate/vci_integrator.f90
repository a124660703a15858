!> The driver: state, time grid, statistics, error reporting and observers around the stepper
!> (docs/DESIGN.md §4). Its state is private and read through procedures.
!>
!> Usage: extend vci_model_t (a discrete L_d) or vci_lagrangian_t (a continuous L; then optionally
!> `call integ%set_scheme(VCI_SCHEME_LOBATTO, s, stat)`); `call integ%create(model, h, stat)`;
!> initialise from a pair or from (q0, p0); `call integ%integrate(nsteps, +1 or -1, stat, observer)`.
!> Read the state with `time()`, `configuration()`, `momentum()`, `multipliers()`, `energy()`,
!> the impacts of the last step with `impact_count()` and `impact(i)`, the counters with
!> `statistics()`. On any failure the state stays at the last accepted step, `stat` says what went
!> wrong and `message()` says where (step, time) and why. Nothing here stops or prints.
module vci_integrator
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite, ieee_value, ieee_quiet_nan
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_message, only: vci_set_message, vci_int_text, vci_real_text
  use vci_model_base, only: vci_model_base_t
  use vci_model, only: vci_model_t
  use vci_lagrangian, only: vci_lagrangian_t, lagrangian_check_band
  use vci_sparse_hessian_check, only: lagrangian_check_sparse
  use vci_limits, only: vci_size_problem
  use vci_sparse, only: sparse_available
  use vci_settings, only: vci_settings_t, vci_solver_stats_t, vci_default_max_impacts
  use vci_state, only: vci_state_t, vci_impact_buffer_t
  use vci_stepper, only: vci_stepper_t
  use vci_scheme, only: vci_scheme_t, VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN, VCI_IMPACT_BLENDED, VCI_SCHEME_DISCRETE, &
                        VCI_SCHEME_LEFT, VCI_SCHEME_MIDPOINT, VCI_SCHEME_LOBATTO, VCI_SCHEME_COMPOSITION
  use vci_separable, only: vci_separable_t
  use vci_composition, only: VCI_COMPOSITION_ORDERS
  use vci_explicit_step, only: vci_explicit_t
  use vci_scheme_discrete, only: vci_scheme_discrete_t
  use vci_scheme_lobatto, only: vci_scheme_lobatto_t
  use vci_retraction, only: vci_retraction_model_t, RETRACTION_LEFT, RETRACTION_MIDPOINT
  use vci_lobatto_rule, only: VCI_LOBATTO_MAX_STAGES
  use vci_checkpoint, only: vci_checkpoint_t
  use vci_observer, only: vci_observer_t, vci_run_info_t, vci_impact_t
  use vci_progress, only: vci_progress_t, vci_progress_info_t
  implicit none
  private
  public :: VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN, VCI_IMPACT_BLENDED
  public :: VCI_SCHEME_DISCRETE, VCI_SCHEME_LEFT, VCI_SCHEME_MIDPOINT, VCI_SCHEME_LOBATTO, VCI_LOBATTO_MAX_STAGES
  public :: VCI_SCHEME_COMPOSITION, VCI_COMPOSITION_ORDERS
  public :: vci_scheme_name, vci_settings_t

  !> Counters over the integrator's life.
  type, public :: vci_stats_t
    integer(i8) :: steps = 0              !< steps taken
    integer(i8) :: impacts = 0            !< impacts resolved
    integer(i8) :: newton_solves = 0      !< Newton solves
    integer(i8) :: newton_iterations = 0  !< their iterations
    integer(i8) :: fallbacks = 0          !< least-squares fallbacks (singular Newton matrices)
    integer(i8) :: factorisations = 0   !< LU factorisations of Newton matrices
    integer(i8) :: fused_solves = 0     !< regular sub-steps solved by the scheme's fused routine
    !> impacts where no impulse matches the discrete energy (a graze): H(q, p) kept instead
    integer(i8) :: energy_fallbacks = 0
    !> impacts of a step with several whose energy condition could not be held on the sub-step that
    !> leaves them up to the next wall (the search found no such impulse); a reversed run poses
    !> another condition there and need not return (docs/BACKWARD.md, "Impacts that cannot be tied");
    !> and steps taken free whose poke screen from the end (a reversed run's) finds a poke that the
    !> one from the start did not (docs/DESIGN.md, "A poke seen from the end only"); and impacts
    !> whose energy condition has a second root of the other kind, meeting a wall within the rest
    !> or leaving it free (two solutions: docs/BACKWARD.md, "Two solutions of a step with a soft impact")
    integer(i8) :: irreversible_impacts = 0
    !> steps that failed and were then taken as 2, 4, ... equal sub-steps (the safety net,
    !> set_step_splits; docs/DESIGN.md §2), and the most sub-steps one of them needed
    integer(i8) :: split_steps = 0
    integer(i8) :: largest_split = 0   !< the most equal sub-steps one split step needed (0: none)
    !> impact-stage Newton directions solved by bordering the sub-step's block (set_bordered_impacts)
    integer(i8) :: bordered_directions = 0
  end type vci_stats_t

  !> The driver: create it for a model and a step length, choose settings, initialise, then step or
  !> integrate; its state is read through the procedures below (module doc).
  type, public :: vci_integrator_t
    private
    class(vci_model_base_t), pointer :: model => null()   !< the user's model (discrete or continuous)
    class(vci_model_t), pointer :: discrete => null()       !< the user's L_d, or
    class(vci_lagrangian_t), pointer :: lag => null()       !< the user's L
    !> owned: the left/midpoint L_d of lag. Allocatable, not a pointer, so that it is freed with the
    !> integrator (the scheme points into it: do not copy a created integrator by assignment).
    type(vci_retraction_model_t), allocatable :: retraction
    logical :: lag_hessians = .false.  !< lag supplies its Hessians
    logical :: lag_energy = .false.    !< lag supplies its energy H(q, p)
    integer :: scheme_id = VCI_SCHEME_DISCRETE  !< VCI_SCHEME_*; set_scheme chooses it for a continuous model
    integer :: start_kind = 0   !< how the run started: 0 not known, 1 pair, 2 momentum, 3 a checkpoint (provenance)
    integer :: n_stages = 0                     !< s of the lobatto scheme
    !> the run's split steps before this integrator took it over (a restored checkpoint's):
    !> checkpoints carry the run's counts (issue 24)
    integer(i8) :: run_splits_before = 0_i8
    integer(i8) :: run_largest_before = 0_i8   !< the run's largest split before this integrator took it over
    integer(i8) :: splits_at_start = 0_i8      !< this integrator's split_steps when the run started or was restored
    type(vci_stepper_t) :: stepper              !< holds the scheme and the one settings object
    logical :: created = .false.      !< create has succeeded
    !> the stepper holds the midpoint retraction's scheme for lag, built by the last build_scheme
    !> (a composition set right after create reuses it instead of building it a second time)
    logical :: midpoint_built = .false.
    logical :: initialized = .false.  !< there is a state to step from
    !> why the last set_scheme failed (blank: the scheme is usable); until a set_scheme succeeds
    !> the stepper has no complete workspace, and initialisation refuses with VCI_ERR_STATE
    character(len=VCI_MSG_LEN) :: scheme_failure = ''
    !> the state and the history the next step needs (t = t0 + k h, q, p, lambda, E_d, the
    !> predictor's and the energy condition's memory): handed to the stepper whole
    type(vci_state_t) :: state
    type(vci_impact_buffer_t) :: impacts        !< impacts of the last step, records(1:count)
    ! outcome
    integer :: last_status = VCI_OK             !< status of the last call
    character(len=VCI_MSG_LEN) :: last_message = ''  !< what went wrong in the last call, naming step and time
    integer(i8) :: steps_taken = 0_i8    !< steps over the integrator's life
    integer(i8) :: impacts_found = 0_i8  !< impacts over the integrator's life
  contains
    procedure, private :: create_discrete, create_continuous
    !> Bind a discrete model (L_d) and a step length.
    generic :: create => create_discrete, create_continuous
    !> Choose the scheme of a continuous model (VCI_SCHEME_LEFT, _MIDPOINT, _LOBATTO with s stages); resets the state.
    procedure :: set_scheme
    !> Newton tolerances: |r_i| <= atol + rtol * (size of row i's terms); iteration cap.
    procedure :: set_tolerances
    !> Impact energy condition: VCI_IMPACT_DISCRETE (the paper's, default) or VCI_IMPACT_HAMILTONIAN.
    procedure :: set_impact_energy
    !> Bound on impacts resolved inside one step (default max(16, 4 n_gaps): vci_default_max_impacts).
    procedure :: set_max_impacts
    !> Sample sub-steps inside for walls poked within one (on by default; docs/BACKWARD.md).
    procedure :: set_poke_samples
    !> The safety net: retry a failed step as up to max_splits equal sub-steps (1: off).
    procedure :: set_step_splits
    !> Solve impact stages by bordering the sub-step's block (default) or as whole matrices.
    procedure :: set_bordered_impacts
    !> Start from q0 at t0 and q1 at t0 + h (the paper's initial pair).
    procedure :: init_from_pair
    !> Start from (q0, p0) at t0; step index 0.
    procedure :: init_from_momentum
    !> One step in direction +1 (forward, (+) scheme) or -1 (backward, (-) scheme).
    procedure :: step
    !> nsteps steps in one direction, reported to the observer (on_start, on_impact, on_step, on_finish).
    procedure :: integrate
    !> What observers are told at the start of a run.
    procedure :: run_info
    !> The current state and solver memory, for restarts that continue bit for bit.
    procedure :: checkpoint
    !> A checkpoint taken now handed to an observer's on_checkpoint (no copy of it made; its
    !> status VCI_ERR_MEMORY, and why, when it cannot be taken).
    procedure :: checkpoint_to => hand_checkpoint
    !> Continue from a checkpoint taken with the same model and step length.
    procedure :: restore
    ! reading the state and the outcome
    !> Time of the current state, t0 + k h.
    procedure :: time => current_time
    !> Index k of the current state.
    procedure :: step_index
    !> The step length h.
    procedure :: step_length
    !> q of the current state (size n).
    procedure :: configuration
    !> p of the current state (size n).
    procedure :: momentum
    !> The multipliers lambda of the last step (size m).
    procedure :: multipliers
    !> E_d of the last step (of its last sub-step when it had impacts); NaN before the first step from (q, p).
    procedure :: energy
    !> Number of impacts of the last step.
    procedure :: impact_count
    !> Impact i (1 .. impact_count()) of the last step (assign the result: `imp = integ%impact(i)`).
    procedure :: impact
    !> Counters over the integrator's life (since create).
    procedure :: statistics
    !> Linear-algebra paths of Newton (docs/DESIGN.md §6): in-line LU, factor reuse, the fused regular solve.
    procedure :: set_solver_paths
    !> Status of the last call (VCI_OK or a VCI_ERR_*).
    procedure :: status
    !> What went wrong in the last call, naming the step, the time and the cause ('' after success).
    procedure :: message
    !> message() with trailing blanks, as a fixed-length result (for the boundary layers, thread-safe).
    procedure :: message_text
    !> The settings in force (tolerances, impact bound, impact condition).
    procedure :: settings
    !> The scheme (VCI_SCHEME_*) and its number of stages.
    procedure :: scheme
    !> The lobatto scheme's number of stages s (1 for the others).
    procedure :: stages
    !> Has the integrator a state to step from (after init_from_pair, init_from_momentum or restore)?
    procedure :: is_initialized
    !> Sizes of the bound model: n (configuration) and m (constraints); 0 before create.
    procedure :: n_coordinates
    !> m, the number of constraints of the bound model.
    procedure :: n_constraints
    ! for the boundary layers (C ABI, legacy entry), which detect failures of their own
    !> Record a failure that a boundary layer detected on a call into this integrator (status and message).
    procedure :: report_failure
    !> The state is no longer valid (an initialisation that failed before reaching this integrator).
    procedure :: forget_state
  end type vci_integrator_t

contains

  !> Bind a discrete model (L_d) and a step length. The model must outlive the integrator.
  subroutine create_discrete(self, model, h, stat)
    class(vci_integrator_t), intent(inout) :: self
    class(vci_model_t), target, intent(inout) :: model
    real(dp), intent(in) :: h
    integer, intent(out) :: stat
    call bind_sizes(self, model, h, stat)
    if (stat /= VCI_OK) return
    self%discrete => model
    self%lag => null()
    self%scheme_id = VCI_SCHEME_DISCRETE; self%n_stages = 0
    call build_scheme(self, 'create', stat)
  end subroutine create_discrete

  !> Bind a continuous model (L) and a step length; the scheme is `midpoint` until set_scheme
  !> chooses another. The model must outlive the integrator.
  subroutine create_continuous(self, model, h, stat)
    class(vci_integrator_t), intent(inout) :: self
    class(vci_lagrangian_t), target, intent(inout) :: model
    real(dp), intent(in) :: h
    integer, intent(out) :: stat
    real(dp), allocatable :: q(:), v(:), hq(:, :), hv(:, :), hw(:, :)
    real(dp) :: e
    integer :: s, ierr
    character(len=12) :: missing
    call bind_sizes(self, model, h, stat)
    if (stat /= VCI_OK) return
    self%created = .false.
    self%discrete => null()
    self%lag => model
    ! which procedures the model supplies (the values at these probe points are discarded)
    allocate (q(model%n), v(model%n), stat=ierr)
    if (ierr == 0 .and. .not. (supplies_band_hessians(model) .or. supplies_sparse_hessians(model))) &
      allocate (hq(model%n, model%n), hv(model%n, model%n), hw(model%n, model%n), stat=ierr)
    if (ierr == 0 .and. .not. allocated(hq)) allocate (hq(model%n, 1), stat=ierr)
    if (ierr /= 0) then
      self%last_message = 'create: cannot allocate the probes of the model (out of memory)'
      call finish(self, VCI_ERR_MEMORY, stat); return
    end if
    q = 0.0_dp; v = 0.0_dp
    missing = ''
    call model%clear_not_provided(); s = 0; call model%lagrangian(q, v, e, s)
    if (model%answered_not_provided()) missing = 'lagrangian'
    call model%clear_not_provided(); s = 0; call model%dl_dq(q, v, hq(:, 1), s)
    if (model%answered_not_provided()) missing = 'dl_dq'
    call model%clear_not_provided(); s = 0; call model%dl_dv(q, v, hq(:, 1), s)
    if (model%answered_not_provided()) missing = 'dl_dv'
    if (missing /= '') then
      self%last_message = 'create: the continuous model does not supply '//trim(missing)// &
                     ' (L, dL/dq and dL/dqdot are required)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    self%lag_hessians = .false.
    if (.not. (supplies_band_hessians(model) .or. supplies_sparse_hessians(model))) then
      ! (else no n x n probe: the band's or the pattern's schemes use those callbacks)
      call model%clear_not_provided(); s = 0; call model%hessians(q, v, hq, hv, hw, s)
      self%lag_hessians = .not. model%answered_not_provided()
    end if
    call model%clear_not_provided(); s = 0; call model%energy(q, v, e, s)
    self%lag_energy = .not. model%answered_not_provided()
    self%scheme_id = VCI_SCHEME_MIDPOINT; self%n_stages = 1
    call build_scheme(self, 'create', stat)
  end subroutine create_continuous

  !> A continuous model with a declared bandwidth (and no debug check) that supplies hessians_band:
  !> the `left` and `midpoint` schemes use it alone, and the Lobatto scheme differences its
  !> Hessians, so its dense hessians are never probed (that probe alone is 3 n^2 numbers).
  logical function supplies_band_hessians(model) result(yes)
    class(vci_lagrangian_t), intent(inout) :: model
    real(dp), allocatable :: z(:), b1(:, :), b2(:, :), b3(:, :)
    integer :: s, bw
    yes = .false.
    bw = model%hessian_bandwidth
    if (bw < 0 .or. model%check_bandwidth) return
    allocate (z(model%n), b1(2 * bw + 1, model%n), b2(2 * bw + 1, model%n), b3(2 * bw + 1, model%n), stat=s)
    if (s /= 0) return
    z = 0.0_dp
    call model%clear_not_provided(); s = 0
    call model%hessians_band(z, z, bw, b1, b2, b3, s)
    yes = .not. model%answered_not_provided()
    call model%clear_not_provided()
  end function supplies_band_hessians

  !> A continuous model with a declared sparse pattern (and no debug check) that supplies
  !> hessians_sparse: as supplies_band_hessians, its dense hessians are never probed.
  logical function supplies_sparse_hessians(model) result(yes)
    class(vci_lagrangian_t), intent(inout) :: model
    real(dp), allocatable :: z(:), b1(:), b2(:), b3(:)
    integer :: s, nu
    yes = .false.
    if (model%hessian_bandwidth >= 0 .or. model%hessian_pattern%n /= model%n .or. model%check_pattern) return
    nu = size(model%hessian_pattern%upos)
    allocate (z(model%n), b1(nu), b2(nu), b3(nu), stat=s)
    if (s /= 0) return
    z = 0.0_dp
    call model%clear_not_provided(); s = 0
    call model%hessians_sparse(z, z, b1, b2, b3, s)
    yes = .not. model%answered_not_provided()
    call model%clear_not_provided()
  end function supplies_sparse_hessians

  !> Checks and state common to both kinds of model.
  subroutine bind_sizes(self, model, h, stat)
    class(vci_integrator_t), intent(inout) :: self
    class(vci_model_base_t), target, intent(inout) :: model
    real(dp), intent(in) :: h
    integer, intent(out) :: stat
    character(len=80) :: why
    type(vci_settings_t) :: settings
    self%created = .false.; self%initialized = .false.
    self%steps_taken = 0_i8; self%impacts_found = 0_i8; self%impacts%count = 0
    ! sizes checked before anything is allocated (vci_limits)
    why = vci_size_problem(model%n, model%m, model%n_gaps)
    if (why /= '') then
      write (self%last_message, '(a,3(i0,a))') 'create: model sizes invalid (n = ', model%n, ', m = ', model%m, &
        ', n_gaps = ', model%n_gaps, '; '//trim(why)//')'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (.not. (ieee_is_finite(h) .and. h > 0.0_dp)) then
      write (self%last_message, '(a,es12.4,a)') 'create: step length h = ', h, ' must be positive and finite'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    self%model => model
    self%state%h = h
    ! the impacts-per-step bound scales with the walls, unless the caller chose it
    settings = self%stepper%current_settings()
    if (.not. settings%max_impacts_chosen) then
      settings%max_impacts_per_step = vci_default_max_impacts(model%n_gaps)
      call self%stepper%configure(settings)
    end if
    call self%state%reserve(model%n, model%m, stat)
    if (stat /= VCI_OK) then
      call out_of_memory(self, 'create', model, stat); return
    end if
  end subroutine bind_sizes

  !> Build the scheme object for the current model and scheme choice and hand it to the stepper.
  subroutine build_scheme(self, who, stat)
    class(vci_integrator_t), target, intent(inout) :: self
    character(len=*), intent(in) :: who     !< the caller's name, for the message
    integer, intent(out) :: stat
    class(vci_scheme_t), allocatable :: sch
    integer :: rule
    type(vci_settings_t) :: settings
    stat = VCI_OK
    if (.not. pattern_usable(self, who, stat)) return
    ! A composition steps explicitly; its stepper's scheme (for the stepper's other queries) is
    ! the midpoint retraction's, which create built already: only the composition is attached
    ! (half of the set-up's instructions were this second build, docs/DESIGN.md §9).
    if (self%scheme_id == VCI_SCHEME_COMPOSITION .and. &
        self%midpoint_built .and. self%created .and. &
        self%scheme_failure == '') then
      call attach_composition(self, stat)
      if (stat /= VCI_OK) then
        self%midpoint_built = .false.
        call out_of_memory(self, who, self%model, stat)
        call scheme_failed(self, VCI_ERR_MEMORY, stat); return
      end if
      self%initialized = .false.
      self%last_message = ''
      call finish(self, VCI_OK, stat); return
    end if
    self%midpoint_built = .false.
    select case (self%scheme_id)
    case (VCI_SCHEME_DISCRETE)
      allocate (vci_scheme_discrete_t :: sch, stat=stat)
      if (stat == 0) then
        select type (sch)
        type is (vci_scheme_discrete_t)
          call sch%setup(self%discrete, stat)
        end select
      end if
      if (stat /= 0) stat = VCI_ERR_MEMORY
    case (VCI_SCHEME_LEFT, VCI_SCHEME_MIDPOINT, VCI_SCHEME_COMPOSITION)
      ! (the composition steps explicitly; its midpoint scheme serves the stepper's other queries)
      rule = merge(RETRACTION_LEFT, RETRACTION_MIDPOINT, self%scheme_id == VCI_SCHEME_LEFT)
      if (.not. allocated(self%retraction)) allocate (self%retraction, stat=stat)
      if (stat == 0) call self%retraction%bind(self%lag, rule, self%lag_hessians, self%lag_energy, stat)
      if (stat == 0) allocate (vci_scheme_discrete_t :: sch, stat=stat)
      if (stat == 0) then
        select type (sch)
        type is (vci_scheme_discrete_t)
          call sch%setup(self%retraction, stat)
          ! (the model's banded Hessians serve the mixed Hessian too: vci_retraction's band_hessians)
          call sch%use_derivatives(mixed_hessian=self%lag_hessians .or. self%retraction%band_hessians .or. &
                                   self%retraction%sparse_hessians)
        end select
      end if
      if (stat /= 0) stat = VCI_ERR_MEMORY
    case (VCI_SCHEME_LOBATTO)
      allocate (vci_scheme_lobatto_t :: sch, stat=stat)
      if (stat == 0) then
        select type (sch)
        type is (vci_scheme_lobatto_t)
          call sch%setup(self%lag, self%n_stages, self%lag_hessians, self%lag_energy, stat)
        end select
      else
        stat = VCI_ERR_MEMORY
      end if
      if (stat /= VCI_OK .and. stat /= VCI_ERR_MEMORY) then
        write (self%last_message, '(a,i0,a)') who//': could not set up the lobatto scheme with s = ', self%n_stages, ''
        call scheme_failed(self, VCI_ERR_ARGUMENT, stat); return
      end if
    end select
    if (stat == VCI_OK) call self%stepper%setup(sch, stat)
    if (stat == VCI_OK .and. self%scheme_id == VCI_SCHEME_COMPOSITION) call attach_composition(self, stat)
    ! records for the impacts of one step, grown on demand up to the bound (which may be huge)
    settings = self%stepper%current_settings()
    self%impacts%count = 0
    if (stat == VCI_OK) call self%impacts%reserve(min(settings%max_impacts_per_step, 16), self%model%n, stat)
    if (stat /= VCI_OK) then
      call out_of_memory(self, who, self%model, stat)
      call scheme_failed(self, VCI_ERR_MEMORY, stat); return
    end if
    self%created = .true.
    self%midpoint_built = self%scheme_id == VCI_SCHEME_MIDPOINT .or. self%scheme_id == VCI_SCHEME_COMPOSITION
    self%initialized = .false.
    self%scheme_failure = ''
    self%last_message = ''
    call finish(self, VCI_OK, stat)
  end subroutine build_scheme

  !> The explicit composition of order n_stages on the separable model, handed to the stepper
  !> (set_scheme checked the model's kind, its mass matrix and m = 0).
  subroutine attach_composition(self, stat)
    class(vci_integrator_t), target, intent(inout) :: self
    integer, intent(out) :: stat
    type(vci_explicit_t), allocatable :: ex
    allocate (ex, stat=stat)
    if (stat /= 0) then
      stat = VCI_ERR_MEMORY; return
    end if
    select type (lag => self%lag)
    class is (vci_separable_t)
      call ex%setup(lag, self%n_stages, stat)
    class default
      stat = VCI_ERR_ARGUMENT
    end select
    if (stat == VCI_OK) call self%stepper%use_explicit(ex)
  end subroutine attach_composition

  !> The scheme could not be built (its message is set): the integrator keeps its model but cannot
  !> A declared sparse Hessian pattern (issue 28) needs the sparse solver and must fit the model;
  !> else VCI_ERR_ARGUMENT with a message saying why (false: stat is set, the scheme not built).
  logical function pattern_usable(self, who, stat) result(ok)
    class(vci_integrator_t), intent(inout) :: self
    character(len=*), intent(in) :: who
    integer, intent(out) :: stat
    ok = .true.; stat = VCI_OK
    if (.not. associated(self%model)) return
    if (self%model%hessian_pattern%n == 0 .and. self%model%pattern_status == 0) return
    ok = .false.
    if (.not. sparse_available()) then
      self%last_message = who//': the model declares a sparse Hessian pattern but vci was built without '// &
        'the sparse solver (CMake option VCI_SPARSE=ON, SuiteSparse KLU: Debian libsuitesparse-dev)'
    else if (self%model%pattern_status /= 0) then
      self%last_message = who//': the declared Hessian pattern is invalid: '//trim(self%model%pattern_message)
    else if (self%model%hessian_pattern%n /= self%model%n) then
      write (self%last_message, '(a,i0,a,i0,a)') who//': the declared Hessian pattern has ', &
        self%model%hessian_pattern%n, ' columns, the model n = ', self%model%n, ''
    else if (self%model%hessian_bandwidth >= 0) then
      self%last_message = who//': the model declares both a Hessian bandwidth and a sparse pattern; declare one'
    else
      ok = .true.; return
    end if
    call scheme_failed(self, VCI_ERR_ARGUMENT, stat)
  end function pattern_usable

  !> be initialised or stepped until a set_scheme succeeds (the stepper may hold part of a workspace).
  subroutine scheme_failed(self, status, stat)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: status
    integer, intent(out) :: stat
    self%initialized = .false.
    self%scheme_failure = self%last_message
    call finish(self, status, stat)
  end subroutine scheme_failed

  !> Choose the scheme that discretises a continuous model: VCI_SCHEME_LEFT (the paper's retraction,
  !> order 1), VCI_SCHEME_MIDPOINT (order 2, the default) or VCI_SCHEME_LOBATTO with `stages` = s in
  !> 1..VCI_LOBATTO_MAX_STAGES (order 2s, with or without constraints). `stages` is ignored except for
  !> lobatto. Call after create and before initialising: once initialised, VCI_ERR_STATE (the state stays).
  subroutine set_scheme(self, scheme, stages, stat)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: scheme, stages
    integer, intent(out) :: stat
    if (self%initialized) then   ! was a silent reset of the state: refused, the run stays as it was
      self%last_message = 'set_scheme: the integrator is already initialised; choose the scheme after '// &
        'create and before init_from_pair/init_from_momentum (or create a new integrator)'
      call finish(self, VCI_ERR_STATE, stat); return
    end if
    if (.not. self%created) then
      self%last_message = 'set_scheme: create the integrator first'
      call finish(self, VCI_ERR_STATE, stat); return
    end if
    if (.not. associated(self%lag)) then
      self%last_message = 'set_scheme: the model is a discrete Lagrangian (vci_model_t); schemes discretise '// &
                     'a continuous one (vci_lagrangian_t)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    select case (scheme)
    case (VCI_SCHEME_LEFT, VCI_SCHEME_MIDPOINT)
    case (VCI_SCHEME_LOBATTO)
      if (stages < 1 .or. stages > VCI_LOBATTO_MAX_STAGES) then
        write (self%last_message, '(a,i0,a,i0,a)') 'set_scheme: lobatto with s = ', stages, ' stages (need 1 <= s <= ', &
          VCI_LOBATTO_MAX_STAGES, ')'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
    case (VCI_SCHEME_COMPOSITION)
      if (.not. any(VCI_COMPOSITION_ORDERS == stages)) then
        write (self%last_message, '(a,i0,a)') 'set_scheme: composition of order ', stages, ' (need 2, 4, 6, 8 or 10)'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
      select type (lag => self%lag)
      class is (vci_separable_t)
        if (.not. lag%has_mass()) then
          self%last_message = 'set_scheme: the separable model has no mass matrix (set_mass_diagonal or set_mass_matrix)'
          call finish(self, VCI_ERR_ARGUMENT, stat); return
        end if
      class default
        self%last_message = 'set_scheme: composition needs a separable model (vci_separable_t: L = 1/2 qdot^T M qdot - V(q))'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end select
      if (self%model%m > 0) then
        write (self%last_message, '(a,i0,a)') 'set_scheme: composition does not support nonholonomic constraints (m = ', &
          self%model%m, '); use lobatto (order 2s with constraints) or midpoint'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
    case default
      write (self%last_message, '(a,i0,a)') 'set_scheme: unknown scheme ', scheme, &
        ' (1 = left, 2 = midpoint, 3 = lobatto, 4 = composition)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end select
    self%scheme_id = scheme
    self%n_stages = merge(stages, 1, scheme == VCI_SCHEME_LOBATTO .or. scheme == VCI_SCHEME_COMPOSITION)
    call build_scheme(self, 'set_scheme', stat)
  end subroutine set_scheme

  !> A short name of a scheme identifier ('left', 'midpoint', 'lobatto', 'discrete'), blank-padded
  !> (trim it). Fixed length, not deferred: gfortran 12 keeps a deferred-length result's length in
  !> a static per call site, which races across threads.
  pure function vci_scheme_name(scheme) result(name)
    integer, intent(in) :: scheme
    character(len=11) :: name
    select case (scheme)
    case (VCI_SCHEME_DISCRETE); name = 'discrete'
    case (VCI_SCHEME_LEFT); name = 'left'
    case (VCI_SCHEME_MIDPOINT); name = 'midpoint'
    case (VCI_SCHEME_LOBATTO); name = 'lobatto'
    case (VCI_SCHEME_COMPOSITION); name = 'composition'
    case default; name = 'unknown'
    end select
  end function vci_scheme_name

  !> Newton tolerances: |r_i| <= atol + rtol * (size of row i's terms); iteration cap.
  subroutine set_tolerances(self, atol, rtol, max_iterations, stat)
    class(vci_integrator_t), intent(inout) :: self
    real(dp), intent(in) :: atol, rtol
    integer, intent(in) :: max_iterations
    integer, intent(out) :: stat
    type(vci_settings_t) :: settings
    ! rtol >= 1 accepts any iterate whose residual is smaller than its terms: even the initial guess
    if (.not. (ieee_is_finite(atol) .and. atol >= 0.0_dp .and. ieee_is_finite(rtol) .and. rtol >= 0.0_dp &
               .and. rtol < 1.0_dp .and. atol + rtol > 0.0_dp .and. max_iterations >= 1)) then
      write (self%last_message, '(a,es10.3,a,es10.3,a,i0,a)') 'set_tolerances: atol = ', atol, ', rtol = ', rtol, &
        ', max_iterations = ', max_iterations, ' (need atol >= 0, 0 <= rtol < 1, not both 0, max_iterations >= 1)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    settings = self%stepper%current_settings()
    settings%atol = atol; settings%rtol = rtol; settings%max_iterations = max_iterations
    call self%stepper%configure(settings)
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
    type(vci_settings_t) :: settings
    if (mode /= VCI_IMPACT_DISCRETE .and. mode /= VCI_IMPACT_HAMILTONIAN) then
      write (self%last_message, '(a,i0,a)') 'set_impact_energy: unknown mode ', mode, &
        ' (0 = discrete, 1 = hamiltonian)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (mode == VCI_IMPACT_HAMILTONIAN) then
      if (.not. self%created) then
        self%last_message = 'set_impact_energy: create the integrator first'
        call finish(self, VCI_ERR_STATE, stat); return
      end if
      ! a continuous model always has H: the Legendre inversion of dL/dqdot when it supplies none
      ! (the probe's values are discarded; q, p are zero before initialisation)
      if (.not. associated(self%lag)) then
        call self%model%clear_not_provided(); s = 0
        call self%model%energy(self%state%q, self%state%p, e, s)
      end if
      if (.not. associated(self%lag) .and. self%model%answered_not_provided()) then
        self%last_message = 'set_impact_energy: the hamiltonian condition needs the model''s energy(q, p), '// &
                       'which this model does not supply'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
    end if
    settings = self%stepper%current_settings()
    settings%impact_energy = mode
    settings%impact_energy_chosen = .true.
    call self%stepper%configure(settings)
    call finish(self, VCI_OK, stat)
  end subroutine set_impact_energy

  !> Bound on impacts resolved inside one step (default max(16, 4 n_gaps): vci_default_max_impacts).
  subroutine set_max_impacts(self, max_impacts, stat)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: max_impacts
    integer, intent(out) :: stat
    type(vci_settings_t) :: settings
    if (max_impacts < 1) then
      write (self%last_message, '(a,i0,a)') 'set_max_impacts: ', max_impacts, ' (need >= 1)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    settings = self%stepper%current_settings()
    settings%max_impacts_per_step = max_impacts
    settings%max_impacts_chosen = .true.
    call self%stepper%configure(settings)   ! the impact records grow on demand up to it
    call finish(self, VCI_OK, stat)
  end subroutine set_max_impacts

  !> Look for a wall that the motion crosses and leaves again within one sub-step (docs/BACKWARD.md,
  !> "A wall poked within one sub-step"): with it on, N steps back return through such grazes too
  !> (m = 0), and a touch between grid points is an impact (docs/STABILITY.md). Used only where two
  !> half sub-steps compose to the whole one (a stiff motion the step does not resolve keeps the
  !> grid-point test). On by default; off tests the gaps at the sub-steps' ends only (the cost:
  !> docs/bench/poke.md).
  subroutine set_poke_samples(self, on, stat)
    class(vci_integrator_t), intent(inout) :: self
    logical, intent(in) :: on
    integer, intent(out) :: stat
    type(vci_settings_t) :: settings
    settings = self%stepper%current_settings()
    settings%poke_samples = on
    call self%stepper%configure(settings)
    call finish(self, VCI_OK, stat)
  end subroutine set_poke_samples

  !> The safety net (docs/DESIGN.md §2, "Steps that cannot be solved"): a step whose Newton solve or
  !> impact stages fail, or that exceeds the impacts-per-step bound, is retried as 2, 4, ... equal
  !> sub-steps of the same scheme up to max_splits of them (default 16; a power of two is reached
  !> at most); max_splits = 1 turns it off, and such a step fails with its own status. Counted in
  !> statistics() (split_steps, largest_split).
  subroutine set_step_splits(self, max_splits, stat)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: max_splits
    integer, intent(out) :: stat
    type(vci_settings_t) :: settings
    if (max_splits < 1 .or. max_splits > 1024) then
      write (self%last_message, '(a,i0,a)') 'set_step_splits: ', max_splits, ' (need 1 (off) to 1024)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    settings = self%stepper%current_settings()
    settings%max_step_splits = max_splits
    call self%stepper%configure(settings)
    call finish(self, VCI_OK, stat)
  end subroutine set_step_splits

  !> Impact stages 1 and 2 by bordering (on, the default: the sub-step's block factorised and the
  !> alpha/mu row and column eliminated by their Schur complement, docs/DESIGN.md "Impact systems by
  !> bordering") or with the whole stage matrix factorised (off: the comparison path). min_unknowns:
  !> border stage systems of at least this many unknowns (default 16; smaller ones cost less whole).
  subroutine set_bordered_impacts(self, on, min_unknowns)
    class(vci_integrator_t), intent(inout) :: self
    logical, intent(in) :: on
    integer, intent(in), optional :: min_unknowns
    type(vci_settings_t) :: settings
    settings = self%stepper%current_settings()
    settings%bordered_impacts = on
    if (present(min_unknowns)) settings%border_min = max(2, min_unknowns)
    call self%stepper%configure(settings)
  end subroutine set_bordered_impacts

  !> Start from q0 at t0 and q1 at t0 + h (the paper's initial pair). The current state becomes
  !> (t0 + h, q1, p1) with p1 = D2 L_d(q0, q1, h); the step index is 1.
  subroutine init_from_pair(self, t0, q0, q1, stat)
    class(vci_integrator_t), intent(inout) :: self
    real(dp), intent(in) :: t0, q0(:), q1(:)
    integer, intent(out) :: stat
    call check_init(self, 'init_from_pair', t0, q0, q1, stat, q1)
    if (stat /= VCI_OK) return
    if (.not. ieee_is_finite(t0 + self%state%h)) then
      self%initialized = .false.
      write (self%last_message, '(a,es12.4,a,es12.4,a)') 'init_from_pair: t0 + h = ', t0, ' + ', self%state%h, ' overflows'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (self%scheme_id == VCI_SCHEME_COMPOSITION) then
      ! (the pair's momentum is D2 of the composed L_d, which has no closed form)
      self%last_message = 'init_from_pair: the composition scheme starts from (q0, p0): use init_from_momentum'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    call self%stepper%forget_factors()   ! a new run solves as a fresh integrator would
    call start_run_counts(self, 0_i8, 0_i8)
    call self%stepper%pair_momentum(q0, q1, self%state%h, self%state%p, self%state%step_energy, stat)
    if (stat /= VCI_OK) then
      self%last_message = 'init_from_pair: '//trim(self%stepper%failure_cause())
      call keep_failure(self, stat); return
    end if
    self%state%t0 = t0; self%state%k = 1_i8
    self%state%q = q1
    self%state%lambda = 0.0_dp
    self%state%velocity = (q1 - q0) / self%state%h
    call self%state%forget_history()
    self%state%arriving_energy = self%state%step_energy; self%state%arriving_direction = 1
    self%initialized = .true.; self%start_kind = 1
    call finish(self, VCI_OK, stat)
  end subroutine init_from_pair

  !> Start from (q0, p0) at t0; step index 0.
  subroutine init_from_momentum(self, t0, q0, p0, stat)
    class(vci_integrator_t), intent(inout) :: self
    real(dp), intent(in) :: t0, q0(:), p0(:)
    integer, intent(out) :: stat
    call check_init(self, 'init_from_momentum', t0, q0, p0, stat)
    if (stat /= VCI_OK) return
    self%state%t0 = t0; self%state%k = 0_i8
    self%state%q = q0; self%state%p = p0
    self%state%lambda = 0.0_dp
    self%state%velocity = 0.0_dp
    call self%state%forget_history()
    self%state%step_energy = ieee_value(1.0_dp, ieee_quiet_nan)
    self%state%arriving_direction = 0
    call self%stepper%forget_factors()
    call self%stepper%momentum_velocity(self%state)   ! the first step's start (issue 27)
    call start_run_counts(self, 0_i8, 0_i8)
    self%initialized = .true.; self%start_kind = 2
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
    real(dp), allocatable :: g(:), omega(:, :), hess(:, :), w(:), dg(:, :), w2(:), cjo(:, :), dg1(:), fd(:, :)
    real(dp) :: fe
    self%initialized = .false.
    if (.not. self%created) then
      self%last_message = who//': create the integrator first'
      call finish(self, VCI_ERR_STATE, stat); return
    end if
    if (self%scheme_failure /= '') then
      self%last_message = who//': no usable scheme, set_scheme must succeed first (the last one failed: '// &
                          trim(self%scheme_failure)//')'
      call finish(self, VCI_ERR_STATE, stat); return
    end if
    n = self%model%n
    if (size(q0) /= n .or. size(v0) /= n) then
      write (self%last_message, '(a,3(i0,a))') who//': arrays of size ', size(q0), ' and ', size(v0), &
        ' given, model has n = ', n, ''
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (.not. (ieee_is_finite(t0) .and. all(ieee_is_finite(q0)) .and. all(ieee_is_finite(v0)))) then
      self%last_message = who//': initial data contain NaN or Inf'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    ! optional procedures: each is probed once (vci_model_base: not_provided)
    allocate (hess(n, merge(n, 1, associated(self%discrete))), omega(n, max(1, self%model%m)), &
              g(self%model%n_gaps), w(self%model%m), &
              cjo(self%model%m, n), dg1(n), fd(n, 2), w2(self%model%n_gaps), stat=s)
    if (s /= 0) then
      self%last_message = who//': cannot allocate the probes of the model (out of memory)'
      call finish(self, VCI_ERR_MEMORY, stat); return
    end if
    if (associated(self%discrete)) then
      call self%model%clear_not_provided(); s = 0
      call self%discrete%mixed_hessian(q0, v0, self%state%h, hess, s)
      call self%stepper%use_model_derivatives(mixed_hessian=.not. self%model%answered_not_provided())
      call self%model%clear_not_provided(); s = 0
      call self%discrete%ld_fused(q0, v0, self%state%h, fd(:, 1), fd(:, 2), fe, hess, s)
      call self%stepper%use_model_derivatives(fused=.not. self%model%answered_not_provided())
    end if
    if (associated(self%lag) .and. self%model%check_bandwidth) then
      ! the debug check of a declared band: hessians_band against the dense blocks (vci_lagrangian)
      call lagrangian_check_band(self%lag, q0, v0, self%last_message, s)
      if (s /= VCI_OK) then
        self%last_message = who//': '//trim(self%last_message)
        call finish(self, s, stat); return
      end if
    end if
    if (associated(self%lag)) then
      ! a model's hessians_sparse against differences of its gradients, once (vci_sparse_hessian_check)
      call lagrangian_check_sparse(self%lag, q0, v0, self%last_message, s)
      if (s /= VCI_OK) then
        self%last_message = who//': '//trim(self%last_message)
        call finish(self, s, stat); return
      end if
    end if
    if (self%model%m > 0) then
      call self%model%clear_not_provided(); s = 0
      call self%model%constraint_forms(q0, omega(:, 1:self%model%m), s)
      if (self%model%answered_not_provided()) then
        write (self%last_message, '(a,i0,a)') who//': the model has m = ', self%model%m, &
          ' constraints but does not supply constraint_forms'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
      if (s /= 0) then
        write (self%last_message, '(a,i0,a)') who//': callback constraint_forms failed at the initial '// &
          'configuration (stat = ', s, ')'
        call finish(self, VCI_ERR_CALLBACK, stat); return
      end if
      call self%model%clear_not_provided(); s = 0
      if (associated(self%discrete)) call self%discrete%discrete_constraint(q0, q0, self%state%h, w, s)
      if (self%model%answered_not_provided()) then
        write (self%last_message, '(a,i0,a)') who//': the model has m = ', self%model%m, &
          ' constraints but does not supply discrete_constraint'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
      if (associated(self%discrete)) then
        call self%model%clear_not_provided(); s = 0
        call self%discrete%discrete_constraint_jacobian(q0, v0, self%state%h, cjo, s)
        call self%stepper%use_model_derivatives(constraint_jacobian=.not. self%model%answered_not_provided())
      end if
    end if
    if (self%model%n_gaps > 0) then
      call self%model%clear_not_provided(); s = 0
      call self%model%gaps(q0, g, s)
      if (self%model%answered_not_provided()) then
        write (self%last_message, '(a,i0,a)') who//': the model has n_gaps = ', self%model%n_gaps, &
          ' walls but does not supply gaps'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
      if (s /= 0 .or. .not. all(ieee_is_finite(g))) then
        self%last_message = who//': callback gaps failed or returned NaN/Inf at the initial configuration'
        call finish(self, VCI_ERR_CALLBACK, stat); return
      end if
      if (present(q1)) then
        s = 0
        call self%model%gaps(q1, w2, s)
        if (s /= 0 .or. .not. all(ieee_is_finite(w2))) then
          self%last_message = who//': callback gaps failed or returned NaN/Inf at the second configuration'
          call finish(self, VCI_ERR_CALLBACK, stat); return
        end if
        g = min(g, w2)
      end if
      do j = 1, self%model%n_gaps
        if (g(j) < 0.0_dp) then
          write (self%last_message, '(a,i0,a,es12.4,a)') who//': initial configuration outside the admissible set (g_', &
            j, ' = ', g(j), ' < 0)'
          call finish(self, VCI_ERR_INADMISSIBLE, stat); return
        end if
      end do
      ! one wall's gradient first: a model that has it need not fill every wall's (O(n n_gaps))
      call self%model%clear_not_provided(); s = 0
      call self%model%gap_gradient(q0, 1, dg1, s)
      if (self%model%answered_not_provided()) then
        ! (every wall's gradients, n x n_gaps, only for a model without the one-wall gradient)
        allocate (dg(n, self%model%n_gaps), stat=s)
        if (s /= 0) then
          self%last_message = who//': cannot allocate the probe of gap_gradients (out of memory)'
          call finish(self, VCI_ERR_MEMORY, stat); return
        end if
        call self%model%clear_not_provided(); s = 0
        call self%model%gap_gradients(q0, dg, s)
        call self%stepper%use_model_derivatives(gap_gradients=.not. self%model%answered_not_provided(), &
                                                gap_gradient=.false.)
      else
        call self%stepper%use_model_derivatives(gap_gradients=.false., gap_gradient=.true.)
      end if
      ! H(q, p) for the impacts where the discrete energy condition has no solution (a continuous
      ! model always has it); the probe's value is discarded
      if (associated(self%lag)) then
        call self%stepper%use_model_derivatives(energy=.true.)
      else
        call self%model%clear_not_provided(); s = 0
        hess(:, 1) = 0.0_dp
        call self%model%energy(q0, hess(:, 1), w2(1), s)
        call self%stepper%use_model_derivatives(energy=.not. self%model%answered_not_provided())
      end if
    end if
    stat = VCI_OK
  end subroutine check_init

  !> One step in direction +1 (forward, (+) scheme) or -1 (backward, (-) scheme). The impacts of
  !> the step are `impact(1)` .. `impact(impact_count())` afterwards.
  subroutine step(self, direction, stat, observer)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: direction
    integer, intent(out) :: stat
    class(vci_observer_t), intent(inout), optional :: observer
    integer :: i, ostat
    real(dp) :: t
    character(len=16) :: dname
    character(len=160) :: cause   !< why a checkpoint the observer wanted could not be taken
    if (.not. self%initialized) then
      self%last_message = 'step: initialise the integrator first (init_from_pair or init_from_momentum)'
      call finish(self, VCI_ERR_STATE, stat); return
    end if
    if (direction /= 1 .and. direction /= -1) then
      write (self%last_message, '(a,i0,a)') 'step: direction ', direction, ' (need +1 or -1)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    t = self%time()
    if (.not. ieee_is_finite(self%state%t0 + real(self%state%k + direction, dp) * self%state%h)) then
      write (self%last_message, '(a,i0,a,es14.7,a,es10.3,a)') 'step from index ', self%state%k, ' (t = ', t, &
        '): the time of the next state overflows (h = ', self%state%h, ')'
      call finish(self, VCI_ERR_NONFINITE, stat); return
    end if
    call self%stepper%advance(self%state, direction, self%impacts, stat)
    if (stat /= VCI_OK) then
      dname = 'forward'
      if (direction < 0) dname = 'backward'
      call vci_set_message(self%last_message, 'step from index '//trim(vci_int_text(self%state%k))//' (t = '// &
        trim(vci_real_text(t, '(es14.7)'))//', '//trim(dname)//'): '//trim(self%stepper%failure_cause()))
      call keep_failure(self, stat); return
    end if
    t = self%time()
    self%steps_taken = self%steps_taken + 1
    self%impacts_found = self%impacts_found + self%impacts%count
    stat = VCI_OK
    if (present(observer)) then
      ostat = 0
      if (self%stepper%last_step_parts() > 1) &
        call observer%on_split(self%state%k - direction, self%stepper%last_step_parts(), ostat)
      do i = 1, self%impacts%count
        call observer%on_impact(self%impacts%records(i), ostat)
      end do
      cause = ''
      if (ostat == 0 .and. observer%wants_checkpoint()) call hand_checkpoint(self, observer, ostat, cause)
      if (ostat == 0) call observer%on_step(self%state%k, t, self%state%q, self%state%p, self%state%lambda, &
                                            self%state%step_energy, ostat)
      if (ostat /= 0) then
        write (self%last_message, '(a,i0,a,es14.7,a)') 'observer failed after step to index ', self%state%k, &
          ' (t = ', t, ')'
        call append_failure_cause(self, observer, cause)
        call finish(self, observer_failure_status(ostat), stat); return
      end if
    end if
    call finish(self, VCI_OK, stat)
  end subroutine step

  !> nsteps steps in one direction, reported to the observer (on_start, on_impact, on_step,
  !> on_finish). Stops at the first failure; the state is then the last accepted step.
  subroutine integrate(self, nsteps, direction, stat, observer, progress)
    class(vci_integrator_t), intent(inout) :: self
    integer(i8), intent(in) :: nsteps
    integer, intent(in) :: direction
    integer, intent(out) :: stat
    class(vci_observer_t), intent(inout), optional :: observer
    !> progress%report(info, stop_requested) at most once per progress%interval seconds and after the last
    !> step; stop_requested = .true. ends the run after the current step with VCI_STOPPED (vci_progress)
    class(vci_progress_t), intent(inout), optional :: progress
    integer(i8) :: i, first
    integer :: ostat
    character(len=160) :: cause   !< why a checkpoint the observer wanted could not be taken
    if (nsteps < 0) then
      write (self%last_message, '(a,i0,a)') 'integrate: nsteps = ', nsteps, ' (need >= 0)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (.not. self%initialized) then
      self%last_message = 'integrate: initialise the integrator first (init_from_pair or init_from_momentum)'
      call finish(self, VCI_ERR_STATE, stat); return
    end if
    if (direction /= 1 .and. direction /= -1) then
      write (self%last_message, '(a,i0,a)') 'integrate: direction ', direction, ' (need +1 or -1)'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (present(progress)) then
      if (.not. (progress%interval >= 0.0_dp .and. progress%interval <= 1.0e9_dp)) then
        self%last_message = 'integrate: progress%interval must be a number of seconds in [0, 1e9]'
        call finish(self, VCI_ERR_ARGUMENT, stat); return
      end if
    end if
    if (present(observer)) then
      ostat = 0
      cause = ''
      if (observer%wants_checkpoint()) call hand_checkpoint(self, observer, ostat, cause)
      if (ostat == 0) call observer%on_start(self%run_info(direction), self%state%q, self%state%p, ostat)
      if (ostat /= 0) then
        self%last_message = 'integrate: observer failed at the start of the run'
        call append_failure_cause(self, observer, cause)
        call finish(self, observer_failure_status(ostat), stat); return
      end if
    end if
    stat = VCI_OK
    if (present(progress)) then
      call steps_with_progress(self, nsteps, direction, stat, progress, observer)
    else
      first = 1
      if (.not. present(observer)) call run_explicit_steps(self, nsteps, direction, first)
      do i = first, nsteps
        call self%step(direction, stat, observer)
        if (stat /= VCI_OK) exit
      end do
    end if
    if (present(observer)) then
      ostat = 0
      ! the state is the last accepted step's: an output that flushes at the end stores it
      cause = ''
      if (observer%keeps_checkpoints()) call hand_checkpoint(self, observer, ostat, cause)
      if (ostat == VCI_ERR_MEMORY .and. stat == VCI_OK) then
        ! the end's flush then stores no checkpoint of the last row: a run that was fine says so
        self%last_message = 'integrate: no checkpoint of the run''s last state'
        call append_failure_cause(self, observer, cause)
        stat = VCI_ERR_MEMORY; self%last_status = stat
      end if
      ostat = 0
      call observer%on_finish(stat, trim(self%last_message), ostat)
      if (ostat /= 0 .and. stat == VCI_OK) then
        self%last_message = 'integrate: observer failed at the end of the run'
        call append_observer_cause(self, observer)
        call finish(self, VCI_ERR_IO, stat); return
      end if
    end if
    self%last_status = stat
    if (stat == VCI_OK) self%last_message = ''   ! also after 0 steps: no message of an earlier call
  end subroutine integrate

  !> integrate without an observer on an explicit composition: the steps before the last run in
  !> one call (vci_stepper's explicit_steps: the same bits, no per-step H), when none of their
  !> times overflows; next = the index of the first step left to the general loop (the last one,
  !> which sets H and the velocity, or the one that failed in the run, retaken there to report it).
  subroutine run_explicit_steps(self, nsteps, direction, next)
    class(vci_integrator_t), intent(inout) :: self
    integer(i8), intent(in) :: nsteps
    integer, intent(in) :: direction
    integer(i8), intent(out) :: next
    integer(i8) :: done, found
    next = 1
    if (nsteps < 2) return
    if (.not. ieee_is_finite(self%state%t0 + real(self%state%k + direction * nsteps, dp) * self%state%h)) return
    call self%stepper%explicit_steps(self%state, nsteps - 1, direction, self%impacts, done, found)
    self%steps_taken = self%steps_taken + done
    self%impacts_found = self%impacts_found + found
    next = done + 1
  end subroutine run_explicit_steps

  !> integrate's loop with progress reports (the clock is read each step: ~20 ns against a step's
  !> microseconds).
  subroutine steps_with_progress(self, nsteps, direction, stat, progress, observer)
    class(vci_integrator_t), intent(inout) :: self
    integer(i8), intent(in) :: nsteps
    integer, intent(in) :: direction
    integer, intent(out) :: stat
    class(vci_progress_t), intent(inout) :: progress
    class(vci_observer_t), intent(inout), optional :: observer
    integer(i8) :: i, c0, c, rate, next
    type(vci_progress_info_t) :: info
    logical :: stop_requested
    call system_clock(c0, rate)
    next = c0 + int(progress%interval * real(rate, dp), i8)
    stat = VCI_OK
    do i = 1, nsteps
      call self%step(direction, stat, observer)
      if (stat /= VCI_OK) exit
      call system_clock(c)
      if (c < next .and. i < nsteps) cycle
      info%steps_done = i; info%steps_total = nsteps; info%t = self%state%time()
      info%impacts = self%impacts_found
      info%elapsed = real(c - c0, dp) / real(rate, dp)
      info%steps_per_second = 0.0_dp; info%eta = -1.0_dp
      if (info%elapsed > 0.0_dp) then
        info%steps_per_second = real(i, dp) / info%elapsed
        info%eta = real(nsteps - i, dp) / info%steps_per_second
      end if
      stop_requested = .false.
      call progress%report(info, stop_requested)
      next = c + int(progress%interval * real(rate, dp), i8)
      if (stop_requested .and. i < nsteps) then
        write (self%last_message, '(a,i0,a,i0,a,es15.8,a)') 'integrate: stopped by the progress report after ', i, &
          ' of ', nsteps, ' steps (t = ', self%state%time(), ')'
        stat = VCI_STOPPED
        self%last_status = stat
        exit
      end if
    end do
  end subroutine steps_with_progress

  !> An observer stopped the run: its own reason (the file, the OS's cause) after the message.
  subroutine append_observer_cause(self, observer)
    class(vci_integrator_t), intent(inout) :: self
    class(vci_observer_t), intent(in) :: observer
    character(len=len(self%last_message)) :: cause
    call observer%failure_cause(cause)
    if (len_trim(cause) > 0) self%last_message = trim(self%last_message)//': '//trim(cause)
  end subroutine append_observer_cause

  !> The current state and solver memory, for restarts that continue bit for bit. stat (optional):
  !> VCI_OK, or VCI_ERR_MEMORY when the copies could not be allocated; the checkpoint is then empty
  !> (restore refuses it), message names what was missing, and the integrator is unchanged.
  function checkpoint(self, stat, message) result(cp)
    class(vci_integrator_t), intent(in) :: self
    integer, intent(out), optional :: stat
    character(len=*), intent(out), optional :: message
    type(vci_checkpoint_t) :: cp
    integer :: s
    character(len=160) :: cause
    call take_checkpoint(self, cp, s, cause)
    if (present(stat)) stat = s
    if (present(message)) message = cause
  end function checkpoint

  !> checkpoint() with its status: on VCI_ERR_MEMORY cp is empty and cause says which copy failed.
  subroutine take_checkpoint(self, cp, stat, cause)
    class(vci_integrator_t), intent(in) :: self
    type(vci_checkpoint_t), intent(inout) :: cp
    integer, intent(out) :: stat
    character(len=*), intent(out) :: cause
    type(vci_solver_stats_t) :: solver
    character(len=40) :: what
    cause = ''
    call self%state%to_checkpoint(cp, stat)
    if (stat /= VCI_OK) then
      call vci_set_message(cause, 'checkpoint at index '//trim(vci_int_text(self%state%k))// &
        ': no memory for a copy of the state ('//trim(vci_int_text(self%model%n))//' coordinates)')
      return
    end if
    allocate (cp%position_lo(size(self%state%q)), stat=stat)
    if (stat /= 0) then
      call cp%release(); stat = VCI_ERR_MEMORY
      call vci_set_message(cause, 'checkpoint at index '//trim(vci_int_text(self%state%k))// &
        ': no memory for the position carry ('//trim(vci_int_text(self%model%n))//' values)')
      return
    end if
    call self%stepper%position_carry(self%state%q, cp%position_lo)
    ! without them a restart would be correct but not bit for bit: then no checkpoint at all
    call self%stepper%factors_to_checkpoint(cp, stat, what)
    if (stat /= VCI_OK) then
      call cp%release()
      call vci_set_message(cause, 'checkpoint at index '//trim(vci_int_text(self%state%k))// &
        ': no memory for a copy of '//trim(what)//' (a restart without it is not bit for bit)')
      return
    end if
    solver = self%stepper%solver_stats()
    cp%split_steps = self%run_splits_before + (solver%split_steps - self%splits_at_start)
    cp%largest_split = self%run_largest_before
    ! (the integrator's largest split is over its life: it is the run's when this run split at all)
    if (solver%split_steps > self%splits_at_start) cp%largest_split = max(cp%largest_split, solver%largest_split)
    stat = VCI_OK
  end subroutine take_checkpoint

  !> The observer's on_checkpoint with a checkpoint taken now; ostat = VCI_ERR_MEMORY and cause
  !> naming the copy when it cannot be taken (the state stays as it is).
  subroutine hand_checkpoint(self, observer, ostat, cause)
    class(vci_integrator_t), intent(inout) :: self
    class(vci_observer_t), intent(inout) :: observer
    integer, intent(inout) :: ostat
    character(len=*), intent(out), optional :: cause   !< why no checkpoint could be taken ('' when one was)
    type(vci_checkpoint_t) :: cp
    integer :: s
    character(len=160) :: why
    call take_checkpoint(self, cp, s, why)
    if (present(cause)) cause = why
    if (s /= VCI_OK) then
      ostat = s; return
    end if
    call observer%on_checkpoint(cp, ostat)
  end subroutine hand_checkpoint

  !> After the message of a run an observer stopped: why the checkpoint could not be taken
  !> (cause, when not blank), else the observer's own reason.
  subroutine append_failure_cause(self, observer, cause)
    class(vci_integrator_t), intent(inout) :: self
    class(vci_observer_t), intent(in) :: observer
    character(len=*), intent(in) :: cause
    if (len_trim(cause) > 0) then
      self%last_message = trim(self%last_message)//': '//trim(cause)
    else
      call append_observer_cause(self, observer)
    end if
  end subroutine append_failure_cause

  !> The status of a run an observer stopped: no memory (a checkpoint that could not be taken or
  !> kept) stays VCI_ERR_MEMORY, anything else is the output's VCI_ERR_IO.
  pure integer function observer_failure_status(ostat)
    integer, intent(in) :: ostat
    observer_failure_status = VCI_ERR_IO
    if (ostat == VCI_ERR_MEMORY) observer_failure_status = VCI_ERR_MEMORY
  end function observer_failure_status

  !> A run starts: its safety-net counts so far (a checkpoint's, or none) and this integrator's now.
  subroutine start_run_counts(self, splits, largest)
    class(vci_integrator_t), intent(inout) :: self
    integer(i8), intent(in) :: splits, largest
    type(vci_solver_stats_t) :: solver
    solver = self%stepper%solver_stats()
    self%run_splits_before = splits; self%run_largest_before = largest
    self%splits_at_start = solver%split_steps
  end subroutine start_run_counts

  !> Continue from a checkpoint taken with the same model and step length.
  subroutine restore(self, cp, stat)
    class(vci_integrator_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: cp
    integer, intent(out) :: stat
    if (.not. self%created) then
      self%last_message = 'restore: create the integrator first'
      call finish(self, VCI_ERR_STATE, stat); return
    end if
    if (.not. (allocated(cp%q) .and. allocated(cp%p) .and. allocated(cp%lambda) .and. allocated(cp%velocity))) then
      self%last_message = 'restore: empty checkpoint'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    if (size(cp%q) /= self%model%n .or. size(cp%lambda) /= self%model%m .or. cp%h /= self%state%h) then
      self%last_message = 'restore: checkpoint does not match this model or step length'
      call finish(self, VCI_ERR_ARGUMENT, stat); return
    end if
    call check_init(self, 'restore', cp%t0, cp%q, cp%p, stat)
    if (stat /= VCI_OK) return
    call self%state%from_checkpoint(cp)
    if (allocated(cp%position_lo)) then
      if (size(cp%position_lo) == self%model%n) call self%stepper%restore_position_carry(self%state%q, cp%position_lo)
    end if
    call self%stepper%factors_from_checkpoint(cp)
    call start_run_counts(self, max(0_i8, cp%split_steps), max(0_i8, cp%largest_split))
    self%initialized = .true.; self%start_kind = 3
    call finish(self, VCI_OK, stat)
  end subroutine restore

  !> What observers are told at the start of a run.
  function run_info(self, direction) result(info)
    class(vci_integrator_t), intent(in) :: self
    integer, intent(in) :: direction
    type(vci_run_info_t) :: info
    type(vci_settings_t) :: settings
    settings = self%stepper%current_settings()
    info%n = self%model%n; info%m = self%model%m; info%n_gaps = self%model%n_gaps
    info%direction = direction; info%h = self%state%h; info%t0 = self%time(); info%step0 = self%state%k
    info%impact_energy = settings%impact_energy
    ! the compositions keep the hamiltonian condition unless it was chosen (vci_stepper's explicit_condition)
    if (self%scheme_id == VCI_SCHEME_COMPOSITION .and. .not. settings%impact_energy_chosen) &
      info%impact_energy = VCI_IMPACT_HAMILTONIAN
    info%scheme = self%scheme_id; info%stages = self%n_stages
    info%rtol = settings%rtol; info%atol = settings%atol; info%max_impacts = settings%max_impacts_per_step
    info%start = self%start_kind
  end function run_info

  !> An allocation for the model's sizes failed: VCI_ERR_MEMORY naming the sizes.
  subroutine out_of_memory(self, who, model, stat)
    class(vci_integrator_t), intent(inout) :: self
    character(len=*), intent(in) :: who
    class(vci_model_base_t), intent(in) :: model
    integer, intent(out) :: stat
    character(len=40) :: scheme
    scheme = ''
    if (self%scheme_id == VCI_SCHEME_LOBATTO) write (scheme, '(a,i0)') ', scheme lobatto with s = ', self%n_stages
    write (self%last_message, '(a,3(i0,a))') who//': cannot allocate the workspace for n = ', model%n, ', m = ', &
      model%m, ', n_gaps = ', model%n_gaps, trim(scheme)//' (out of memory)'
    call finish(self, VCI_ERR_MEMORY, stat)
  end subroutine out_of_memory

  !> A failure detected by a boundary layer on a call into this integrator (a NULL array, a
  !> callback's return code): it becomes the status and message read back by status()/message().
  subroutine report_failure(self, status, message)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    self%last_status = status
    self%last_message = message
  end subroutine report_failure

  !> The state is no longer valid (an initialisation that failed before reaching this integrator).
  subroutine forget_state(self)
    class(vci_integrator_t), intent(inout) :: self
    self%initialized = .false.
  end subroutine forget_state

  ! ---------------------------------------------------------------------------------------------
  ! Reading the state and the outcome

  !> Sizes of the bound model: n (configuration) and m (constraints); 0 before create.
  pure integer function n_coordinates(self)
    class(vci_integrator_t), intent(in) :: self
    n_coordinates = 0
    if (associated(self%model)) n_coordinates = self%model%n
  end function n_coordinates

  pure integer function n_constraints(self)
    class(vci_integrator_t), intent(in) :: self
    n_constraints = 0
    if (associated(self%model)) n_constraints = self%model%m
  end function n_constraints

  !> Time of the current state, t0 + k h.
  pure real(dp) function current_time(self)
    class(vci_integrator_t), intent(in) :: self
    current_time = self%state%t0 + real(self%state%k, dp) * self%state%h
  end function current_time

  !> Index k of the current state.
  pure integer(i8) function step_index(self)
    class(vci_integrator_t), intent(in) :: self
    step_index = self%state%k
  end function step_index

  pure real(dp) function step_length(self)
    class(vci_integrator_t), intent(in) :: self
    step_length = self%state%h
  end function step_length

  !> q of the current state (size n).
  pure function configuration(self) result(q)
    class(vci_integrator_t), intent(in) :: self
    real(dp), allocatable :: q(:)
    q = self%state%q
  end function configuration

  !> p of the current state (size n).
  pure function momentum(self) result(p)
    class(vci_integrator_t), intent(in) :: self
    real(dp), allocatable :: p(:)
    p = self%state%p
  end function momentum

  !> The multipliers lambda of the last step (size m).
  pure function multipliers(self) result(lambda)
    class(vci_integrator_t), intent(in) :: self
    real(dp), allocatable :: lambda(:)
    lambda = self%state%lambda
  end function multipliers

  !> E_d of the last step (of its last sub-step when it had impacts); NaN before the first step
  !> from (q, p).
  pure real(dp) function energy(self)
    class(vci_integrator_t), intent(in) :: self
    energy = self%state%step_energy
  end function energy

  !> Number of impacts of the last step.
  pure integer function impact_count(self)
    class(vci_integrator_t), intent(in) :: self
    impact_count = self%impacts%count
  end function impact_count

  !> Impact i (1 .. impact_count()) of the last step. Assign the result (`imp = integ%impact(i)`):
  !> `associate (imp => integ%impact(i))` crashed in free() with gfortran 12 (test/stability, seen once).
  function impact(self, i) result(imp)
    class(vci_integrator_t), intent(in) :: self
    integer, intent(in) :: i
    type(vci_impact_t) :: imp
    if (i >= 1 .and. i <= self%impacts%count) imp = self%impacts%records(i)
  end function impact

  !> Counters over the integrator's life (since create).
  pure function statistics(self) result(stats)
    class(vci_integrator_t), intent(in) :: self
    type(vci_stats_t) :: stats
    type(vci_solver_stats_t) :: solver
    solver = self%stepper%solver_stats()
    stats%steps = self%steps_taken; stats%impacts = self%impacts_found
    stats%newton_solves = solver%newton_solves; stats%newton_iterations = solver%newton_iterations
    stats%factorisations = self%stepper%factorisations()
    stats%bordered_directions = self%stepper%bordered_directions()
    stats%fallbacks = solver%fallbacks
    stats%fused_solves = solver%fused_solves
    stats%energy_fallbacks = solver%energy_fallbacks
    stats%irreversible_impacts = solver%irreversible_impacts
    stats%split_steps = solver%split_steps
    stats%largest_split = solver%largest_split
  end function statistics

  !> Linear-algebra paths of Newton (docs/DESIGN.md §6): the in-line LU for systems of at most
  !> small_lu_max unknowns (0: LAPACK always), factor reuse for systems of at least reuse_min
  !> unknowns (huge: full Newton always), and `fused` (default on): the regular sub-step of a small
  !> system with analytic derivatives solved by the scheme's fused routine (vci_scheme_discrete_fused).
  !> `rates_first` (default on): stage 2 under the hamiltonian condition without constraints takes
  !> the impulse from the rates along the impulse line where they decide, without solving the free
  !> motion first (off: the free motion always, as before issue 28's cut).
  !> For tests and benchmarks that compare the paths.
  subroutine set_solver_paths(self, small_lu_max, reuse_min, fused, rates_first)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: small_lu_max, reuse_min
    logical, intent(in), optional :: fused, rates_first
    call self%stepper%set_solver_paths(small_lu_max, reuse_min, fused, rates_first)
  end subroutine set_solver_paths

  !> Status of the last call (VCI_OK or a VCI_ERR_*).
  pure integer function status(self)
    class(vci_integrator_t), intent(in) :: self
    status = self%last_status
  end function status

  !> What went wrong in the last call, naming the step, the time and the cause ('' after success).
  !> (A result of specification-expression length, not a deferred-length one: gfortran 12 keeps the
  !> length of a deferred-length result in a static variable per call site, which races when
  !> integrators on different threads ask for their messages.)
  pure function message(self) result(msg)
    class(vci_integrator_t), intent(in) :: self
    character(len=len_trim(self%last_message)) :: msg
    msg = self%last_message
  end function message

  !> message() with trailing blanks, for the boundary layers called from several threads (a
  !> fixed-length result: gfortran's deferred-length function results are not thread-safe).
  pure function message_text(self) result(msg)
    class(vci_integrator_t), intent(in) :: self
    character(len=VCI_MSG_LEN) :: msg
    msg = self%last_message
  end function message_text

  !> The settings in force (tolerances, impact bound, impact condition).
  pure function settings(self) result(s)
    class(vci_integrator_t), intent(in) :: self
    type(vci_settings_t) :: s
    s = self%stepper%current_settings()
  end function settings

  !> The scheme (VCI_SCHEME_*) and its number of stages.
  pure integer function scheme(self)
    class(vci_integrator_t), intent(in) :: self
    scheme = self%scheme_id
  end function scheme

  pure integer function stages(self)
    class(vci_integrator_t), intent(in) :: self
    stages = self%n_stages
  end function stages

  !> Has the integrator a state to step from (after init_from_pair, init_from_momentum or restore)?
  pure logical function is_initialized(self)
    class(vci_integrator_t), intent(in) :: self
    is_initialized = self%initialized
  end function is_initialized

  !> A failure reported by a lower layer: keep its status.
  subroutine keep_failure(self, stat)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: stat
    self%last_status = stat
  end subroutine keep_failure

  subroutine finish(self, status, stat)
    class(vci_integrator_t), intent(inout) :: self
    integer, intent(in) :: status
    integer, intent(out) :: stat
    self%last_status = status
    ! (messages start with a word: a blank first character means blank, and blanking the whole
    ! buffer on every step would cost more than the step's bookkeeping)
    if (status == VCI_OK .and. self%last_message(1:1) /= ' ') self%last_message = ''
    stat = status
  end subroutine finish
end module vci_integrator
