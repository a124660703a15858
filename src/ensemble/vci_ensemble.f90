!> Ensembles: many independent trajectories of one kind of system (a cloud of starts and/or
!> parameters), run by OpenMP threads within a process. The distributed driver that writes one
!> HDF5 file (vci_ensemble_mpi) runs its members through `vci_ensemble_run_member` below.
!>
!> A member is built by a factory (`vci_model_factory_t%build`, or `vci_prototype_factory_t`,
!> which copies a prototype), so members never share mutable model state; each member gets its own
!> integrator. Continuous models (a `vci_lagrangian_t`, discretised by `config%scheme` with
!> `config%stages`) come from `vci_lagrangian_prototype_factory_t`, or from any factory that
!> overrides `build_model`, the procedure the run calls (its default wraps `build`). What a member yields depends only on its own inputs (start, parameters, the shared
!> configuration), never on which thread or rank ran it: results are bitwise reproducible.
!>
!> Per member: status and message, final (t, q, p), accepted steps, total impact count, the first
!> `impact_cap` impact times and walls, energy at start and end (H(q, p) when the model supplies
!> `energy`, else the discrete energy E_d of the first and last steps), Newton iterations, and,
!> with `stride > 0`, the states every `stride` steps. A member that fails is recorded with its
!> status and message and does not stop the others. Layout of the file: docs/ENSEMBLES.md.
module vci_ensemble
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_finite
  !$ use omp_lib, only: omp_get_max_threads, omp_get_thread_num
  use vci_kinds, only: dp, i8
  use vci_status
  use vci_model, only: vci_model_t
  use vci_model_base, only: vci_model_base_t
  use vci_lagrangian, only: vci_lagrangian_t
  use vci_observer, only: vci_observer_t, vci_run_info_t, vci_impact_t
  use vci_integrator, only: vci_integrator_t, vci_stats_t
  implicit none
  private

  !> How the table's second array is read: the second configuration of the paper's initial pair
  !> (q0 at t0, q1 at t0 + h) or the momentum p0 at t0.
  integer, parameter, public :: VCI_START_PAIR = 0      !< v0 is q1, at t0 + h (the paper's initial pair)
  integer, parameter, public :: VCI_START_MOMENTUM = 1  !< v0 is p0, at t0
  !> Status of a member that has not (yet) been run: the fill value of the file's status.
  integer, parameter, public :: VCI_MEMBER_NOT_RUN = -1
  !> Which energy a member's energy_start/energy_end are.
  integer, parameter, public :: VCI_ENERGY_DISCRETE = 0     !< E_d of the first and last steps
  integer, parameter, public :: VCI_ENERGY_HAMILTONIAN = 1  !< H(q, p) (the model has energy)

  !> Builds the model of one member. `build` must allocate a new, independent model (no pointer to
  !> mutable state shared with other members): it is called concurrently from several threads, so
  !> it may only read `self`. `params` is the member's column of the table's parameters (size 0
  !> without parameters). Set `stat` nonzero (or leave `model` unallocated) to report a failure.
  type, abstract, public :: vci_model_factory_t
  contains
    !> Allocate the model of member `member` from its parameters `params` (interface factory_build).
    procedure(factory_build), deferred :: build
    !> The model of a member as the run takes it, discrete or continuous: by default `build`'s
    !> discrete model; a factory of continuous models overrides this (and refuses `build`).
    procedure :: build_model => factory_build_model
  end type vci_model_factory_t

  abstract interface
    !> Allocate in `model` a new model for member `member` with parameters `params`; stat /= 0 on failure.
    subroutine factory_build(self, member, params, model, stat)
      import :: vci_model_factory_t, vci_model_t, dp
      class(vci_model_factory_t), intent(in) :: self
      integer, intent(in) :: member
      real(dp), intent(in) :: params(:)
      class(vci_model_t), allocatable, intent(out) :: model
      integer, intent(inout) :: stat
    end subroutine factory_build
  end interface

  !> The simplest factory: every member is a deep copy of `prototype` (parameters are ignored; to
  !> vary parameters, extend vci_model_factory_t). The copy is `allocate(source=)`, so the prototype
  !> must not hold pointers to mutable state.
  type, extends(vci_model_factory_t), public :: vci_prototype_factory_t
    class(vci_model_t), allocatable :: prototype  !< the model every member gets a deep copy of
  contains
    !> A deep copy of the prototype (`allocate(source=)`), whatever the member's parameters.
    procedure :: build => prototype_build
  end type vci_prototype_factory_t

  !> Every member is a deep copy of a continuous model `prototype` (a vci_lagrangian_t: the
  !> ensemble's config%scheme and config%stages discretise it). To vary parameters, extend
  !> vci_model_factory_t and override build_model instead.
  type, extends(vci_model_factory_t), public :: vci_lagrangian_prototype_factory_t
    class(vci_lagrangian_t), allocatable :: prototype  !< the model every member gets a deep copy of
  contains
    !> Refused (stat = VCI_ERR_ARGUMENT): the prototype is not a discrete vci_model_t.
    procedure :: build => lagrangian_prototype_refuse
    !> A deep copy of the prototype (`allocate(source=)`), whatever the member's parameters.
    procedure :: build_model => lagrangian_prototype_build
  end type vci_lagrangian_prototype_factory_t

  !> What every member shares. Settings left negative (or 0 for counts) keep the integrator's defaults.
  type, public :: vci_ensemble_config_t
    real(dp) :: h = 0.0_dp                 !< step length
    integer(i8) :: nsteps = 0_i8           !< steps per member
    integer :: direction = 1               !< +1 forward, -1 backward
    integer :: start_kind = VCI_START_PAIR  !< VCI_START_PAIR or VCI_START_MOMENTUM: what the table's v0 is
    real(dp) :: atol = -1.0_dp             !< Newton's absolute tolerance (set_tolerances) when >= 0
    real(dp) :: rtol = -1.0_dp             !< Newton's relative tolerance (set_tolerances) when >= 0
    integer :: max_iterations = 0               !< Newton iteration cap when > 0
    integer :: impact_energy = -1          !< VCI_IMPACT_DISCRETE or VCI_IMPACT_HAMILTONIAN when >= 0
    integer :: max_impacts_per_step = 0    !< set_max_impacts when > 0
    !> VCI_SCHEME_LEFT, _MIDPOINT, _LOBATTO or _COMPOSITION for continuous models when >= 0 (the
    !> integrator's default, midpoint, when negative); a discrete model takes none
    integer :: scheme = -1
    integer :: stages = 0                  !< the scheme's stages s (lobatto) or order (composition)
    integer :: impact_cap = 64             !< impact times kept per member (the count is always total)
    integer(i8) :: stride = 0_i8           !< keep the state every `stride` steps (0: no trajectories)
    integer :: threads = 0                 !< OpenMP threads (0: OpenMP's default, OMP_NUM_THREADS)
    integer :: chunk = 0                   !< members a process takes at a time (file driver; 0: automatic)
    character(len=128) :: name = ''        !< the ensemble's name (a file attribute)
  end type vci_ensemble_config_t

  !> The members' starts and parameters, one column per member (N = size(t0)). Every column of
  !> q0/v0 has the model's n entries; v0 is q1 (VCI_START_PAIR) or p0 (VCI_START_MOMENTUM).
  type, public :: vci_ensemble_table_t
    real(dp), allocatable :: t0(:)          !< (N)
    real(dp), allocatable :: q0(:, :)       !< (n, N)
    real(dp), allocatable :: v0(:, :)       !< (n, N)
    real(dp), allocatable :: params(:, :)   !< (n_params, N); unallocated: no parameters
  end type vci_ensemble_table_t

  !> Results of members first .. first + count - 1, one column (last index) per member.
  !> Values that do not exist are NaN (times, states, energies) or 0 (walls).
  type, public :: vci_ensemble_results_t
    integer :: first = 1                    !< global index of the first member held
    integer :: count = 0                    !< members held
    integer :: n = 0                        !< configuration size
    integer :: impact_cap = 0               !< impact times kept per member
    integer :: samples = 0                  !< states kept per member (trajectories)
    integer, allocatable :: status(:)                       !< VCI_OK, VCI_ERR_*, or VCI_MEMBER_NOT_RUN
    character(len=VCI_MSG_LEN), allocatable :: message(:)   !< why a member failed ('' when it did not)
    real(dp), allocatable :: t(:)                           !< time of the last accepted state
    real(dp), allocatable :: q(:, :)                        !< (n, count) configuration of the last accepted state
    real(dp), allocatable :: p(:, :)                        !< (n, count) momentum of the last accepted state
    integer(i8), allocatable :: steps(:)                    !< steps taken
    integer(i8), allocatable :: impacts(:)                  !< impacts found (all of them, beyond impact_cap)
    integer(i8), allocatable :: newton_iterations(:)        !< Newton iterations
    real(dp), allocatable :: impact_t(:, :)                 !< (impact_cap, count)
    integer, allocatable :: impact_gap(:, :)                !< (impact_cap, count)
    integer, allocatable :: energy_kind(:)                  !< VCI_ENERGY_DISCRETE or VCI_ENERGY_HAMILTONIAN
    real(dp), allocatable :: energy_start(:)                !< the energy (energy_kind) at the start
    real(dp), allocatable :: energy_end(:)                  !< the energy at the end
    real(dp), allocatable :: energy_change(:)               !< energy_end - energy_start
    integer, allocatable :: traj_count(:)                   !< samples kept (<= samples)
    real(dp), allocatable :: traj_t(:, :)                   !< (samples, count)
    real(dp), allocatable :: traj_q(:, :, :)                !< (n, samples, count) configurations kept
    real(dp), allocatable :: traj_p(:, :, :)                !< (n, samples, count) momenta kept
    integer, allocatable :: thread(:)                       !< OpenMP thread that ran the member (not reproducible)
    real(dp), allocatable :: seconds(:)                     !< wall time of the member (not reproducible)
  end type vci_ensemble_results_t

  !> Collects what a member yields while it runs (the integrator's observer interface).
  type, extends(vci_observer_t) :: member_observer_t
    integer :: cap = 0, samples = 0, kept = 0, n_samples = 0
    integer(i8) :: stride = 0_i8, steps = 0_i8, impacts = 0_i8
    real(dp) :: t = 0.0_dp, e_first = 0.0_dp, e_last = 0.0_dp
    logical :: started = .false.
    real(dp), allocatable :: q(:), p(:), q_start(:), p_start(:)
    real(dp), allocatable :: imp_t(:), tr_t(:), tr_q(:, :), tr_p(:, :)
    integer, allocatable :: imp_gap(:)
    integer :: status = VCI_OK
    character(len=VCI_MSG_LEN) :: message = ''
  contains
    procedure :: on_start => m_start
    procedure :: on_step => m_step
    procedure :: on_impact => m_impact
    procedure :: on_finish => m_finish
  end type member_observer_t

  public :: vci_ensemble_run, vci_ensemble_run_member, vci_ensemble_check
  public :: vci_ensemble_results_alloc, vci_ensemble_samples, vci_ensemble_size

contains

  !> Run every member of `table` with OpenMP threads (config%threads) and keep the results in memory.
  !> `stat` is VCI_OK when the ensemble ran, whatever its members did (see results%status), or
  !> VCI_ERR_ARGUMENT with `message` when the inputs are unusable, VCI_ERR_MEMORY when the results
  !> cannot be allocated.
  subroutine vci_ensemble_run(factory, config, table, results, stat, message)
    class(vci_model_factory_t), intent(in) :: factory
    type(vci_ensemble_config_t), intent(in) :: config
    type(vci_ensemble_table_t), intent(in) :: table
    type(vci_ensemble_results_t), intent(out) :: results
    integer, intent(out) :: stat
    character(len=*), intent(out), optional :: message
    character(len=VCI_MSG_LEN) :: msg
    integer :: i, n_members, nt
    call vci_ensemble_check(config, table, stat, msg)
    if (stat == VCI_OK) then
      n_members = vci_ensemble_size(table)
      call vci_ensemble_results_alloc(results, config, size(table%q0, 1), 1, n_members, stat, msg)
    end if
    if (stat /= VCI_OK) then
      if (present(message)) message = msg
      return
    end if
    nt = max(1, config%threads)
    !$ if (config%threads <= 0) nt = omp_get_max_threads()
    if (nt == 1) then
      ! one thread: no OpenMP team (the runtime ends the program when it cannot allocate one)
      do i = 1, n_members
        call vci_ensemble_run_member(factory, config, table, i, results)
      end do
    else
      ! Each iteration writes only column i of `results`; dynamic scheduling because impact-rich
      ! members cost more.
      !$omp parallel do num_threads(nt) schedule(dynamic, 1) default(none) &
      !$omp   shared(factory, config, table, results, n_members) private(i)
      do i = 1, n_members
        call vci_ensemble_run_member(factory, config, table, i, results)
      end do
      !$omp end parallel do
    end if
    if (present(message)) message = ''
  end subroutine vci_ensemble_run

  !> Number of members of a table (0 when it has no t0).
  pure integer function vci_ensemble_size(table)
    type(vci_ensemble_table_t), intent(in) :: table
    vci_ensemble_size = 0
    if (allocated(table%t0)) vci_ensemble_size = size(table%t0)
  end function vci_ensemble_size

  !> Trajectory samples per member: the start and every `stride` steps after it.
  pure integer function vci_ensemble_samples(config)
    type(vci_ensemble_config_t), intent(in) :: config
    vci_ensemble_samples = 0
    if (config%stride > 0) vci_ensemble_samples = int(config%nsteps / config%stride) + 1
  end function vci_ensemble_samples

  !> Validate a configuration and a table: VCI_OK, or VCI_ERR_ARGUMENT and a message saying what is wrong.
  subroutine vci_ensemble_check(config, table, stat, message)
    type(vci_ensemble_config_t), intent(in) :: config
    type(vci_ensemble_table_t), intent(in) :: table
    integer, intent(out) :: stat
    character(len=*), intent(out) :: message
    integer :: n_members
    stat = VCI_ERR_ARGUMENT
    message = ''
    if (.not. (ieee_is_finite(config%h) .and. config%h > 0.0_dp)) then
      write (message, '(a,es12.4,a)') 'ensemble: step length h = ', config%h, ' must be positive and finite'
    else if (config%nsteps < 0) then
      write (message, '(a,i0,a)') 'ensemble: nsteps = ', config%nsteps, ' (need >= 0)'
    else if (config%direction /= 1 .and. config%direction /= -1) then
      write (message, '(a,i0,a)') 'ensemble: direction ', config%direction, ' (need +1 or -1)'
    else if (config%start_kind /= VCI_START_PAIR .and. config%start_kind /= VCI_START_MOMENTUM) then
      write (message, '(a,i0,a)') 'ensemble: start_kind ', config%start_kind, ' (need VCI_START_PAIR or VCI_START_MOMENTUM)'
    else if (config%impact_cap < 0 .or. config%stride < 0 .or. config%threads < 0 .or. config%chunk < 0) then
      message = 'ensemble: impact_cap, stride, threads and chunk must be >= 0'
    else if (config%stride > 0 .and. config%nsteps / max(config%stride, 1_i8) >= int(huge(1), i8)) then
      message = 'ensemble: too many trajectory samples per member (nsteps / stride)'
    else if (.not. (allocated(table%t0) .and. allocated(table%q0) .and. allocated(table%v0))) then
      message = 'ensemble: the table needs t0, q0 and v0'
    else
      n_members = size(table%t0)
      if (n_members < 1) then
        message = 'ensemble: the table has no members'
      else if (size(table%q0, 1) < 1 .or. size(table%q0, 2) /= n_members .or. &
               any(shape(table%v0) /= shape(table%q0))) then
        write (message, '(a,i0,a,2(i0,a),2(i0,a))') 'ensemble: table shapes disagree (t0: ', n_members, &
          ', q0: ', size(table%q0, 1), ' x ', size(table%q0, 2), ', v0: ', size(table%v0, 1), ' x ', &
          size(table%v0, 2), '; need q0 and v0 of n x N with n >= 1)'
      else if (allocated(table%params)) then
        if (size(table%params, 2) /= n_members) then
          write (message, '(a,i0,a,i0,a)') 'ensemble: params has ', size(table%params, 2), &
            ' columns for ', n_members, ' members'
        else
          stat = VCI_OK
        end if
      else
        stat = VCI_OK
      end if
    end if
  end subroutine vci_ensemble_check

  !> Allocate results for members first .. first + count - 1 of dimension n, all "not run".
  subroutine vci_ensemble_results_alloc(results, config, n, first, count, stat, message)
    type(vci_ensemble_results_t), intent(out) :: results
    type(vci_ensemble_config_t), intent(in) :: config
    integer, intent(in) :: n, first, count
    integer, intent(out) :: stat
    character(len=*), intent(out) :: message
    integer :: s(9), ns, cap
    real(dp) :: nan
    nan = ieee_value(1.0_dp, ieee_quiet_nan)
    ns = vci_ensemble_samples(config)
    cap = config%impact_cap
    results%first = first; results%count = count; results%n = n
    results%impact_cap = cap; results%samples = ns
    s = 0
    allocate (results%status(count), stat=s(1))
    allocate (results%message(count), stat=s(2))
    allocate (results%t(count), results%q(n, count), results%p(n, count), stat=s(3))
    allocate (results%steps(count), results%impacts(count), results%newton_iterations(count), stat=s(4))
    allocate (results%impact_t(cap, count), results%impact_gap(cap, count), stat=s(5))
    allocate (results%energy_kind(count), results%energy_start(count), results%energy_end(count), &
              results%energy_change(count), stat=s(6))
    allocate (results%traj_count(count), results%traj_t(ns, count), stat=s(7))
    allocate (results%traj_q(n, ns, count), results%traj_p(n, ns, count), stat=s(8))
    allocate (results%thread(count), results%seconds(count), stat=s(9))
    if (any(s /= 0)) then
      write (message, '(a,i0,a,i0,a)') 'ensemble: out of memory for the results of ', count, &
        ' members (', ns, ' trajectory samples each)'
      stat = VCI_ERR_MEMORY
      return
    end if
    results%status = VCI_MEMBER_NOT_RUN
    results%message = ''
    results%t = nan; results%q = nan; results%p = nan
    results%steps = 0; results%impacts = 0; results%newton_iterations = 0
    results%impact_t = nan; results%impact_gap = 0
    results%energy_kind = VCI_ENERGY_DISCRETE
    results%energy_start = nan; results%energy_end = nan; results%energy_change = nan
    results%traj_count = 0; results%traj_t = nan; results%traj_q = nan; results%traj_p = nan
    results%thread = -1; results%seconds = nan
    message = ''
    stat = VCI_OK
  end subroutine vci_ensemble_results_alloc

  !> Run member `member` (a column of `table`) and store what it yields in `results`, which must hold
  !> that member (results%first <= member < results%first + results%count). Touches nothing shared
  !> but that member's column of `results`, so threads may run different members concurrently.
  !> The member's failure is its status; nothing else is reported.
  subroutine vci_ensemble_run_member(factory, config, table, member, results)
    class(vci_model_factory_t), intent(in) :: factory
    type(vci_ensemble_config_t), intent(in) :: config
    type(vci_ensemble_table_t), intent(in) :: table
    integer, intent(in) :: member
    type(vci_ensemble_results_t), intent(inout) :: results
    integer :: j
    integer(i8) :: clock0, clock1, rate
    j = member - results%first + 1
    if (j < 1 .or. j > results%count) return      ! not ours to store: a caller's bug, nothing to write
    !$ results%thread(j) = omp_get_thread_num()
    call system_clock(clock0, rate)
    call run_member_body(factory, config, table, member, j, results)
    call system_clock(clock1)
    results%seconds(j) = real(clock1 - clock0, dp) / real(max(rate, 1_i8), dp)
  end subroutine vci_ensemble_run_member

  !> Build, run and record member `member` into column j of `results`.
  subroutine run_member_body(factory, config, table, member, j, results)
    class(vci_model_factory_t), intent(in) :: factory
    type(vci_ensemble_config_t), intent(in) :: config
    type(vci_ensemble_table_t), intent(in) :: table
    integer, intent(in) :: member, j
    type(vci_ensemble_results_t), intent(inout) :: results
    class(vci_model_base_t), allocatable, target :: model
    type(vci_integrator_t) :: integ
    type(member_observer_t) :: obs
    integer :: stat, n, s
    integer(i8) :: iterations
    real(dp) :: e0, e1
    real(dp), allocatable :: params(:)
    character(len=VCI_MSG_LEN) :: msg

    n = results%n
    if (allocated(table%params)) then
      params = table%params(:, member)
    else
      allocate (params(0))   ! (zero size, tiny and fixed: no stat=)
    end if

    stat = 0
    call factory%build_model(member, params, model, stat)
    if (stat == VCI_ERR_MEMORY) then      ! (the library's prototype factories: a copy not allocated)
      write (msg, '(a,i0)') 'factory: out of memory for the model of member ', member
      call store_failure(results, j, VCI_ERR_MEMORY, msg); return
    else if (stat /= 0 .or. .not. allocated(model)) then
      write (msg, '(a,i0,a,i0)') 'factory: building the model of member ', member, ' failed with status ', stat
      call store_failure(results, j, VCI_ERR_CALLBACK, msg); return
    end if
    if (model%n /= n) then
      write (msg, '(a,i0,a,i0,a,i0)') 'factory: the model of member ', member, ' has n = ', model%n, &
        ', the table has n = ', n
      call store_failure(results, j, VCI_ERR_ARGUMENT, msg); return
    end if

    select type (mm => model)
    class is (vci_model_t)
      call integ%create(mm, config%h, stat)
      if (stat == VCI_OK .and. config%scheme >= 0) then
        write (msg, '(a,i0,a)') 'ensemble: config%scheme = ', config%scheme, &
          ' for a discrete model (schemes discretise continuous models: leave it negative)'
        call store_failure(results, j, VCI_ERR_ARGUMENT, msg); return
      end if
    class is (vci_lagrangian_t)
      call integ%create(mm, config%h, stat)
      if (stat == VCI_OK .and. config%scheme >= 0) call integ%set_scheme(config%scheme, config%stages, stat)
    class default
      call store_failure(results, j, VCI_ERR_ARGUMENT, 'factory: the model is neither a vci_model_t nor a '// &
                         'vci_lagrangian_t'); return
    end select
    if (stat == VCI_OK .and. (config%atol >= 0.0_dp .or. config%rtol >= 0.0_dp .or. config%max_iterations > 0)) &
      call integ%set_tolerances(max(config%atol, 0.0_dp), merge(config%rtol, 1.0e-12_dp, config%rtol >= 0.0_dp), &
                                merge(config%max_iterations, 30, config%max_iterations > 0), stat)
    if (stat == VCI_OK .and. config%max_impacts_per_step > 0) call integ%set_max_impacts(config%max_impacts_per_step, stat)
    if (stat == VCI_OK .and. config%impact_energy >= 0) call integ%set_impact_energy(config%impact_energy, stat)
    if (stat == VCI_OK) then
      if (config%start_kind == VCI_START_PAIR) then
        call integ%init_from_pair(table%t0(member), table%q0(:, member), table%v0(:, member), stat)
      else
        call integ%init_from_momentum(table%t0(member), table%q0(:, member), table%v0(:, member), stat)
      end if
    end if
    if (stat /= VCI_OK) then
      call integrator_extras(integ, msg, iterations)
      call store_failure(results, j, stat, msg); return
    end if

    obs%cap = results%impact_cap; obs%samples = results%samples; obs%stride = config%stride
    allocate (obs%imp_t(obs%cap), obs%imp_gap(obs%cap), obs%tr_t(obs%samples), &
              obs%tr_q(n, obs%samples), obs%tr_p(n, obs%samples), stat=s)
    if (s /= 0) then
      call store_failure(results, j, VCI_ERR_ARGUMENT, 'ensemble: out of memory for the member''s records'); return
    end if
    call integ%integrate(config%nsteps, config%direction, stat, obs)
    call integrator_extras(integ, msg, iterations)
    if (.not. obs%started) then        ! integrate refused to start: no state was reported
      call store_failure(results, j, stat, msg); return
    end if

    results%status(j) = stat
    results%message(j) = ''
    if (stat /= VCI_OK) results%message(j) = obs%message
    results%t(j) = obs%t; results%q(:, j) = obs%q; results%p(:, j) = obs%p
    results%steps(j) = obs%steps; results%impacts(j) = obs%impacts
    results%newton_iterations(j) = iterations
    results%impact_t(1:obs%kept, j) = obs%imp_t(1:obs%kept)
    results%impact_gap(1:obs%kept, j) = obs%imp_gap(1:obs%kept)
    ! H(q, p) when the model has it, else E_d of the first and last steps
    s = 0
    call model%clear_not_provided()
    call model%energy(obs%q_start, obs%p_start, e0, s)
    if (model%answered_not_provided()) then
      results%energy_kind(j) = VCI_ENERGY_DISCRETE
      if (obs%steps > 0) then
        results%energy_start(j) = obs%e_first; results%energy_end(j) = obs%e_last
      end if
    else
      results%energy_kind(j) = VCI_ENERGY_HAMILTONIAN
      if (s == 0) results%energy_start(j) = e0
      s = 0
      call model%energy(obs%q, obs%p, e1, s)
      if (s == 0) results%energy_end(j) = e1
    end if
    results%energy_change(j) = results%energy_end(j) - results%energy_start(j)
    results%traj_count(j) = obs%n_samples
    results%traj_t(1:obs%n_samples, j) = obs%tr_t(1:obs%n_samples)
    results%traj_q(:, 1:obs%n_samples, j) = obs%tr_q(:, 1:obs%n_samples)
    results%traj_p(:, 1:obs%n_samples, j) = obs%tr_p(:, 1:obs%n_samples)
  end subroutine run_member_body

  !> The message of a failed create/init/set call and the Newton iteration count (the only
  !> integrator queries of this module).
  subroutine integrator_extras(integ, message, newton_iterations)
    type(vci_integrator_t), intent(in) :: integ
    character(len=*), intent(out) :: message
    integer(i8), intent(out) :: newton_iterations
    type(vci_stats_t) :: stats
    message = integ%message()
    stats = integ%statistics()
    newton_iterations = stats%newton_iterations
  end subroutine integrator_extras

  subroutine store_failure(results, j, status, message)
    type(vci_ensemble_results_t), intent(inout) :: results
    integer, intent(in) :: j, status
    character(len=*), intent(in) :: message
    results%status(j) = status
    if (status == VCI_OK) results%status(j) = VCI_ERR_STATE   ! never record a failure as success
    results%message(j) = message
  end subroutine store_failure

  subroutine prototype_build(self, member, params, model, stat)
    class(vci_prototype_factory_t), intent(in) :: self
    integer, intent(in) :: member
    real(dp), intent(in) :: params(:)
    class(vci_model_t), allocatable, intent(out) :: model
    integer, intent(inout) :: stat
    if (.not. allocated(self%prototype)) then
      stat = VCI_ERR_ARGUMENT; return
    end if
    allocate (model, source=self%prototype, stat=stat)
    if (stat /= 0) stat = VCI_ERR_MEMORY
  end subroutine prototype_build

  !> The default build_model: the factory's discrete model (build).
  subroutine factory_build_model(self, member, params, model, stat)
    class(vci_model_factory_t), intent(in) :: self
    integer, intent(in) :: member
    real(dp), intent(in) :: params(:)
    class(vci_model_base_t), allocatable, intent(out) :: model
    integer, intent(inout) :: stat
    class(vci_model_t), allocatable :: built
    call self%build(member, params, built, stat)
    if (allocated(built)) call move_alloc(built, model)
  end subroutine factory_build_model

  subroutine lagrangian_prototype_refuse(self, member, params, model, stat)
    class(vci_lagrangian_prototype_factory_t), intent(in) :: self
    integer, intent(in) :: member
    real(dp), intent(in) :: params(:)
    class(vci_model_t), allocatable, intent(out) :: model
    integer, intent(inout) :: stat
    stat = VCI_ERR_ARGUMENT
  end subroutine lagrangian_prototype_refuse

  subroutine lagrangian_prototype_build(self, member, params, model, stat)
    class(vci_lagrangian_prototype_factory_t), intent(in) :: self
    integer, intent(in) :: member
    real(dp), intent(in) :: params(:)
    class(vci_model_base_t), allocatable, intent(out) :: model
    integer, intent(inout) :: stat
    if (.not. allocated(self%prototype)) then
      stat = VCI_ERR_ARGUMENT; return
    end if
    allocate (model, source=self%prototype, stat=stat)
    if (stat /= 0) stat = VCI_ERR_MEMORY
  end subroutine lagrangian_prototype_build

  ! --- the member's observer ---

  subroutine m_start(self, info, q, p, stat)
    class(member_observer_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
    self%started = .true.
    self%t = info%t0; self%q = q; self%p = p; self%q_start = q; self%p_start = p
    self%steps = 0; self%impacts = 0; self%kept = 0; self%n_samples = 0
    call sample(self)
  end subroutine m_start

  subroutine m_step(self, step, t, q, p, lambda, energy, stat)
    class(member_observer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    self%steps = self%steps + 1
    self%t = t; self%q = q; self%p = p
    if (self%steps == 1) self%e_first = energy
    self%e_last = energy
    if (self%stride > 0) then
      if (mod(self%steps, self%stride) == 0) call sample(self)
    end if
  end subroutine m_step

  subroutine sample(self)
    type(member_observer_t), intent(inout) :: self
    if (self%n_samples >= self%samples) return
    self%n_samples = self%n_samples + 1
    self%tr_t(self%n_samples) = self%t
    self%tr_q(:, self%n_samples) = self%q
    self%tr_p(:, self%n_samples) = self%p
  end subroutine sample

  subroutine m_impact(self, impact, stat)
    class(member_observer_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    self%impacts = self%impacts + 1
    if (self%kept < self%cap) then
      self%kept = self%kept + 1
      self%imp_t(self%kept) = impact%t
      self%imp_gap(self%kept) = impact%gap
    end if
  end subroutine m_impact

  subroutine m_finish(self, status, message, stat)
    class(member_observer_t), intent(inout) :: self
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    integer, intent(inout) :: stat
    self%status = status
    self%message = message
  end subroutine m_finish
end module vci_ensemble
