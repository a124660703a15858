!> What the example programs share: command-line flags, a summary observer that prints impacts
!> and shows progress on a terminal, reading the last state of a previous run, the run itself.
!> Trajectories go to HDF5 (.h5) when built with it (VCI_HAVE_HDF5), else to CSV; `.csv` names
!> always give CSV. `--from` reads either; `--append` continues the `--from` file itself.
module vci_example_cli
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char
  use, intrinsic :: iso_fortran_env, only: error_unit, output_unit
  use vci
#ifdef VCI_HAVE_HDF5
  use vci_hdf5_output, only: vci_hdf5_writer_t, vci_hdf5_read_checkpoint
#endif
  implicit none
  private

  !> Options common to every example.
  type, public :: example_options_t
    real(dp) :: h = 0.0_dp, t_final = 0.0_dp
    character(len=:), allocatable :: output, from
    logical :: backward = .false., quiet = .false., no_output = .false., analytic_hessian = .true.
    logical :: t_final_given = .false., h_given = .false.
    logical :: append = .false.          !< continue the --from file (HDF5) instead of a new file
    integer :: flush_every = 4096        !< HDF5: steps between flushes
    integer :: every = 0                 !< HDF5: store every k-th state (0: not given; the file's when appending, else 1)
    integer :: compress = 0              !< HDF5: gzip level of the datasets (--compress: 1), 0: none
    integer :: impact_energy = VCI_IMPACT_DISCRETE
    real(dp) :: rtol = 1.0e-12_dp
    integer :: max_impacts = 16
    integer :: step_splits = 16               !< --step-splits: the safety net's bound (1: off)
    character(len=:), allocatable :: scheme   !< --scheme: left, midpoint or lobatto (unset: the scene's default)
    integer :: stages = 2                     !< --stages: s of lobatto
    logical :: check_model = .false.          !< --check-model: compare the derivatives, do not run
    integer :: progress = -1                  !< --progress 1, --no-progress 0, else: when stderr is a terminal
    !> --start: 'exact' (q(0), p(0) = dL/dqdot(q(0), qdot(0)), at t = 0; the default with --scheme) or
    !> 'pair' (the paper's pair of configurations; the default of the hand-written L_d)
    character(len=:), allocatable :: start
    integer :: order = 4                      !< --order: of the composition (2, 4, 6, 8, 10)
  end type example_options_t

  !> Reported after every step (interval 0): ends the run after the step in which SIGINT or SIGTERM
  !> arrived; with --progress, prints a line on stderr at most twice a second (rewritten in place on
  !> a terminal).
  type, extends(vci_progress_t), public :: progress_line_t
    logical :: tty = .false.
    logical :: print = .false.           !< print the progress line
    real(dp) :: next_print = 0.5_dp      !< wall seconds of this run at which the next line is due
  contains
    procedure :: report => progress_report
  end type progress_line_t

  !> Prints one line per impact and a progress line on stderr; forwards everything to `next`.
  type, extends(vci_observer_t), public :: summary_observer_t
    class(vci_observer_t), pointer :: next => null()
    class(vci_observer_t), pointer :: watch => null()   !< also sees every step and impact (run_example's `watch`)
    integer(i8) :: impacts = 0, steps = 0, total_steps = 0
    logical :: quiet = .false., progress = .false.
    real(dp) :: h_first = 0.0_dp, h_last = 0.0_dp
    logical :: have_first = .false.
    real(dp) :: e_first = 0.0_dp, e_last = 0.0_dp
  contains
    procedure :: on_start => s_start
    procedure :: on_step => s_step
    procedure :: on_impact => s_impact
    procedure :: on_split => s_split
    procedure :: on_finish => s_finish
    procedure :: keeps_checkpoints => s_keeps_checkpoints
    procedure :: wants_checkpoint => s_wants_checkpoint
    procedure :: on_checkpoint => s_checkpoint
    procedure :: failure_cause => s_failure_cause
  end type summary_observer_t

  interface
    function c_isatty(fd) bind(C, name='isatty') result(r)
      import :: c_int
      integer(c_int), value :: fd
      integer(c_int) :: r
    end function c_isatty
    function c_path_kind(path) bind(C, name='vci_example_path_kind') result(r)   ! vci_example_path.c
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int) :: r
    end function c_path_kind
    function c_catch_signals() bind(C, name='vci_example_catch_signals') result(r)   ! vci_example_signal.c
      import :: c_int
      integer(c_int) :: r
    end function c_catch_signals
    function c_signal_caught() bind(C, name='vci_example_signal_caught') result(r)
      import :: c_int
      integer(c_int) :: r
    end function c_signal_caught
  end interface

  public :: parse_options, run_example, check_model_at_start, read_last_state, create_integrator, scheme_id, is_decimal, steps_to
  public :: print_split_steps

  ! ranges of the numeric flags (--help states them)
  real(dp), parameter :: h_max = 1.0e6_dp, t_max = 1.0e12_dp, rtol_min = 1.0e-16_dp, rtol_max = 1.0e-4_dp
  integer, parameter :: max_impacts_max = 1000000
  !> Largest --flush-every: the HDF5 writer's (its buffer holds that many rows); the same without HDF5
  integer, parameter :: flush_every_max = 1048576
  !> The program's name, for the messages of to_real/to_int (set by parse_options).
  character(len=32) :: program_name = 'vci example'
  !> Most steps a run may ask for: step indices stay exact in the float64 time grid t0 + k h.
  real(dp), parameter :: steps_max = 2.0_dp**53

#ifdef VCI_HAVE_HDF5
  character(len=*), parameter :: default_extension = '.h5'
#else
  character(len=*), parameter :: default_extension = '.csv'
#endif

contains

  !> Parse the command line. `usage` is the program-specific help text (printed by --help).
  subroutine parse_options(opts, name, usage)
    type(example_options_t), intent(inout) :: opts
    character(len=*), intent(in) :: name, usage
    integer :: i, nargs
    logical :: exists
    ! saved: a bad flag stops the program inside this loop, and LeakSanitizer (asan preset) must
    ! still find these strings reachable then
    character(len=:), allocatable, save :: arg, val
    program_name = name
    nargs = command_argument_count()
    i = 1
    do while (i <= nargs)
      arg = get_arg(i)
      select case (arg)
      case ('--help', '-h')
        write (output_unit, '(a)') usage
        write (output_unit, '(a)') 'Common flags:'
        write (output_unit, '(a)') 'Numbers are read whole (1.5, 2e-3; not 1,5), finite and in the range shown.'
        write (output_unit, '(a)') '  --h H                 step length, 0 < H <= 1e6'
        write (output_unit, '(a)') '  --t-final T           integrate up to time T (backward: down to T), |T| <= 1e12,'
        write (output_unit, '(a)') '                        at most 2^53 steps of H'
        write (output_unit, '(a)') '  --output FILE         trajectory file: .h5 (default when built with HDF5) or .csv'
        write (output_unit, '(a)') '  --no-output           write no trajectory'
        write (output_unit, '(a)') '  --backward            integrate backward in time with the (-) scheme'
        write (output_unit, '(a)') '  --from FILE           start from the last state written by a previous run (.h5 or .csv)'
        write (output_unit, '(a)') '  --append              continue the --from file (.h5, same direction) instead of a new one'
        write (output_unit, '(a)') '  --flush-every K       HDF5: write and flush every K steps, 1 <= K <= 1048576 (4096),'
        write (output_unit, '(a)') '                        and after every impact'
        write (output_unit, '(a)') '  --every K             HDF5: store every K-th state, 1 <= K <= 2^30 (1), and the last;'
        write (output_unit, '(a)') '                        impacts all (appending: the file''s K)'
        write (output_unit, '(a)') '  --compress            HDF5: gzip (level 1) with shuffle on the datasets of a new file'
        write (output_unit, '(a)') '  --impact-energy MODE  discrete (paper, default) or hamiltonian'
        write (output_unit, '(a)') '  --rtol R              Newton tolerance relative to term sizes, 1e-16 <= R <= 1e-4 (1e-12)'
        write (output_unit, '(a)') '  --max-impacts K       impacts allowed in one step, 1 <= K <= 1000000 (16)'
        write (output_unit, '(a)') '  --step-splits K       retry a step that cannot be solved as 2, 4, ... <= K equal sub-steps,'
        write (output_unit, '(a)') '                        1 <= K <= 1024 (16); 1: off, such a step ends the run'
        write (output_unit, '(a)') '  --differenced-hessian let the library difference the mixed Hessian'
        write (output_unit, '(a)') '  --scheme S            discretise the scene''s continuous L: left, midpoint, lobatto'
        write (output_unit, '(a)') '                        or composition (explicit; separable scenes: pendulum_walls)'
        write (output_unit, '(a)') '                        (default: the scene''s hand-derived L_d, as in the paper)'
        write (output_unit, '(a)') '  --stages s            lobatto: s stages, order 2s, 1 <= s <= 8 (2)'
        write (output_unit, '(a)') '  --start exact|pair    exact: (q(0), p(0) = dL/dqdot(q(0), qdot(0))) at t = 0 (default with'
        write (output_unit, '(a)') '                        --scheme); pair: the paper''s pair of configurations (default without)'
        write (output_unit, '(a)') '  --order p             composition: Verlet composed to order p = 2, 4, 6, 8, 10 (4)'
        write (output_unit, '(a)') '  --quiet               print the summary only'
        write (output_unit, '(a)') '  --check-model         compare the model''s derivatives with differences, then stop'
        write (output_unit, '(a)') '  --progress            progress on stderr (default when stderr is a terminal)'
        write (output_unit, '(a)') '  --no-progress         no progress line'
        stop
      case ('--h', '--t-final', '--output', '--from', '--impact-energy', '--rtol', '--max-impacts', '--flush-every', &
            '--step-splits', '--every', &
            '--scheme', '--stages', '--start', '--order')
        if (i == nargs) call die(name//': '//arg//' needs a value')
        i = i + 1
        val = get_arg(i)
        ! strict: `--output --quiet` must not write a file named --quiet (a negative number is a value)
        if (len(val) == 0) call die(name//': '//arg//' needs a value (got an empty one)')
        if (is_option(val)) &
          call die(name//': '//arg//' needs a value (got the option '//val//'; a file name starting with - : ./'//val//')')
        select case (arg)
        case ('--h'); opts%h = to_real(val, arg, 0.0_dp, h_max, low_open=.true.); opts%h_given = .true.
        case ('--flush-every'); opts%flush_every = to_int(val, arg, 1, flush_every_max)
        case ('--every'); opts%every = to_int(val, arg, 1, 2**30)
        case ('--t-final'); opts%t_final = to_real(val, arg, -t_max, t_max); opts%t_final_given = .true.
        case ('--output'); opts%output = val
        case ('--from'); opts%from = val
        case ('--rtol'); opts%rtol = to_real(val, arg, rtol_min, rtol_max)
        case ('--max-impacts'); opts%max_impacts = to_int(val, arg, 1, max_impacts_max)
        case ('--step-splits'); opts%step_splits = to_int(val, arg, 1, 1024)
        case ('--stages'); opts%stages = to_int(val, arg, 1, 8)
        case ('--start')
          if (val /= 'exact' .and. val /= 'pair') call die(name//': --start must be exact or pair')
          opts%start = val
        case ('--order')
          opts%order = to_int(val, arg, 2, 10)
          if (.not. any(VCI_COMPOSITION_ORDERS == opts%order)) call die(name//': --order must be 2, 4, 6, 8 or 10')
        case ('--scheme')
          if (scheme_id(val) < 0) call die(name//': --scheme must be left, midpoint, lobatto or composition')
          opts%scheme = val
        case ('--impact-energy')
          select case (val)
          case ('discrete'); opts%impact_energy = VCI_IMPACT_DISCRETE
          case ('hamiltonian'); opts%impact_energy = VCI_IMPACT_HAMILTONIAN
          case default; call die(name//': --impact-energy must be discrete or hamiltonian')
          end select
        end select
      case ('--backward'); opts%backward = .true.
      case ('--append'); opts%append = .true.
      case ('--compress'); opts%compress = 1
      case ('--quiet'); opts%quiet = .true.
      case ('--no-output'); opts%no_output = .true.
      case ('--differenced-hessian'); opts%analytic_hessian = .false.
      case ('--check-model'); opts%check_model = .true.
      case ('--progress'); opts%progress = 1
      case ('--no-progress'); opts%progress = 0
      case default
        call die(name//': unknown flag '//arg//' (see --help)')
      end select
      i = i + 1
    end do
    if (.not. (opts%h > 0.0_dp)) call die(name//': --h must be positive')
    if (.not. allocated(opts%start)) then
      ! a scheme's order shows only from the exact start; the paper's L_d starts from its pair
      if (allocated(opts%scheme)) then
        opts%start = 'exact'
      else
        opts%start = 'pair'
      end if
    end if
    if (opts%append .and. .not. allocated(opts%from)) call die(name//': --append needs --from FILE')
    if (opts%append .and. opts%no_output) call die(name//': --append and --no-output exclude each other')
    if (opts%flush_every < 1) call die(name//': --flush-every must be >= 1')
    ! --output FILE without an extension writes FILE plus the default extension; read it back the same way
    if (allocated(opts%from)) then
      inquire (file=opts%from, exist=exists)
      if (.not. exists .and. .not. has_extension(opts%from)) opts%from = opts%from//default_extension
      ! never opened when it is not a regular file: reading a FIFO blocks until a writer comes
      if (c_path_kind(opts%from//c_null_char) == 2) &
        call die(name//': --from '//opts%from//' is not a regular file (a FIFO, a device or a directory)')
    end if
  end subroutine parse_options

  !> Create, initialise and run; print the summary. `init` is called when not starting from a file.
  !> Optional: `watch` sees every step and impact of the run (beside the output file), and `report`
  !> prints the program's own lines after the summary, before the status line.
  subroutine run_example(name, model, opts, init, watch, report)
    character(len=*), intent(in) :: name
    class(vci_model_base_t), target, intent(inout) :: model
    type(example_options_t), intent(inout) :: opts
    interface
      subroutine init(integ, stat)
        import :: vci_integrator_t
        type(vci_integrator_t), intent(inout) :: integ
        integer, intent(out) :: stat
      end subroutine init
      subroutine report(integ)
        import :: vci_integrator_t
        type(vci_integrator_t), intent(in) :: integ
      end subroutine report
    end interface
    class(vci_observer_t), target, intent(inout), optional :: watch
    optional :: report
    type(vci_integrator_t), target :: integ
    type(summary_observer_t) :: summary
    type(vci_csv_writer_t), target :: csv
#ifdef VCI_HAVE_HDF5
    type(vci_hdf5_writer_t), target :: h5
#endif
    integer :: stat, dir
    integer(i8) :: nsteps, c0, c1, rate
    real(dp) :: t_first, t_last, t_target, h0, h1, e_first
    real(dp), allocatable :: q(:), p(:)
    logical :: has_h
    type(vci_stats_t) :: stats
    type(progress_line_t) :: progress

    dir = merge(-1, 1, opts%backward)
    if (allocated(opts%from)) then
      if (is_csv(opts%from)) then
        if (opts%append) call die(name//': --append needs an .h5 --from file')
        call create_integrator(name, model, opts, integ)
        allocate (q(model%n), p(model%n))
        call read_last_state(opts%from, model%n, t_first, t_last, q, p, stat)
        if (stat /= 0) call die(name//': cannot read the last state of '//opts%from)
        call integ%init_from_momentum(t_last, q, p, stat)
      else
        call start_from_h5(name, model, opts, integ, t_first, stat)
      end if
    else
      call create_integrator(name, model, opts, integ)
      call init(integ, stat)
    end if
    if (stat /= VCI_OK) call die(name//': '//integ%message())
    if (opts%check_model) call check_model_at_start(name, model, integ, opts%h)
    if (opts%impact_energy /= VCI_IMPACT_DISCRETE) then
      call integ%set_impact_energy(opts%impact_energy, stat)
      if (stat /= VCI_OK) call die(name//': '//integ%message())
    end if

    ! how far: to --t-final, or (backward from a file) back to that run's first state
    t_target = opts%t_final
    if (opts%backward .and. allocated(opts%from) .and. .not. opts%t_final_given) t_target = t_first
    if (opts%backward .and. .not. allocated(opts%from) .and. .not. opts%t_final_given) t_target = -opts%t_final
    nsteps = steps_to(name, integ%time(), t_target, opts%h, dir)

    if (.not. opts%no_output) then
      if (opts%append .and. .not. allocated(opts%output)) opts%output = opts%from
      if (.not. allocated(opts%output)) opts%output = name//merge('_backward', '         ', opts%backward)
      opts%output = trim(opts%output)
      ! a name without an extension gets the default one, unless it names an existing file
      if (.not. has_extension(opts%output) .and. c_path_kind(opts%output//c_null_char) == 0) &
        opts%output = opts%output//default_extension
      if (c_path_kind(opts%output//c_null_char) == 2) &
        call die(name//': --output '//opts%output//' is not a regular file (a device or a directory)')
      if (is_csv(opts%output)) then
        if (opts%append) call die(name//': --append writes HDF5 only (not '//opts%output//')')
        if (opts%every > 0 .or. opts%compress > 0) &
          call die(name//': --every and --compress write HDF5 only (not '//opts%output//')')
        call csv%open(opts%output, stat)
        if (stat /= VCI_OK) call die(name//': '//trim(csv%message))
        summary%next => csv
      else
#ifdef VCI_HAVE_HDF5
        ! examples replace their output unless appending; the library's default is to keep files
        if (opts%every > 0) then
          call h5%open(opts%output, stat, overwrite=.not. opts%append, append=opts%append, scene=name, &
                       flush_every=opts%flush_every, every=opts%every, compress=opts%compress)
        else
          call h5%open(opts%output, stat, overwrite=.not. opts%append, append=opts%append, scene=name, &
                       flush_every=opts%flush_every, compress=opts%compress)
        end if
        if (stat /= VCI_OK) call die(name//': '//trim(h5%message))
        summary%next => h5
#else
        call die(name//': built without HDF5; use an --output name ending in .csv')
#endif
      end if
    end if
    summary%quiet = opts%quiet
    summary%total_steps = nsteps
    if (present(watch)) summary%watch => watch
    progress%tty = c_isatty(2_c_int) == 1

    has_h = model_has_energy(model, integ)
    if (has_h) call model%energy(integ%configuration(), integ%momentum(), h0, stat)
    e_first = integ%energy()   ! NaN when starting from (q, p): no step taken yet
    write (output_unit, '(a)') 'scene: '//name//'   direction: '//trim(merge('backward', 'forward ', opts%backward))// &
      '   impact energy: '//trim(merge('hamiltonian', 'discrete   ', opts%impact_energy == VCI_IMPACT_HAMILTONIAN))
    if (allocated(opts%scheme)) write (output_unit, '(a,i0,a)') 'scheme: '//trim(vci_scheme_name(integ%scheme()))// &
      '   stages: ', integ%stages(), ''
    write (output_unit, '(a,es10.3,a,f0.6,a,f0.6,a,i0)') 'h = ', opts%h, '   t from ', integ%time(), ' to ', &
      integ%time() + dir * nsteps * opts%h, '   steps: ', nsteps
    if (allocated(opts%from)) then
      write (output_unit, '(a)') 'start: the last state of '//opts%from
    else if (opts%start == 'exact') then
      write (output_unit, '(a)') 'start: exact (q(0), p(0) = dL/dqdot(q(0), qdot(0))) at t = 0'
    else
      write (output_unit, '(a)') 'start: the paper''s pair of configurations (q0, q1)'
    end if
    call print_state('start state', integ)
    progress%print = opts%progress == 1 .or. (opts%progress == -1 .and. progress%tty)
    progress%interval = 0.0_dp   ! a report after every step: a signal ends the run after the current one
    if (c_catch_signals() /= 0) call die(name//': cannot install the SIGINT/SIGTERM handler')
    call system_clock(c0, rate)
    call integ%integrate(nsteps, dir, stat, summary, progress)
    call system_clock(c1)
    stats = integ%statistics()
    write (output_unit, '(a,i0)') 'impacts: ', stats%impacts
    write (output_unit, '(a,i0,a,es11.4)') 'steps: ', stats%steps, '   t = ', integ%time()
    if (e_first == e_first) then
      write (output_unit, '(a,es23.15,a,es23.15,a,es10.3)') 'energy E_d: start ', e_first, '  end ', integ%energy(), &
        '  change ', integ%energy() - e_first
    else
      write (output_unit, '(a,es23.15,a)') 'energy E_d: end ', integ%energy(), '  (start from (q, p): no step yet)'
    end if
    if (has_h) then
      call model%energy(integ%configuration(), integ%momentum(), h1, stat)
      write (output_unit, '(a,es23.15,a,es23.15,a,es10.3)') 'energy H(q,p): start ', h0, '  end ', h1, &
        '  change ', h1 - h0
    end if
    write (output_unit, '(a,i0,a,i0,a,i0)') 'newton: solves ', stats%newton_solves, '  iterations ', &
      stats%newton_iterations, '  least-squares fallbacks ', stats%fallbacks
    if (stats%energy_fallbacks > 0) write (output_unit, '(a,i0,a)') 'impacts that kept H (no impulse matches E_d): ', &
      stats%energy_fallbacks, ' (docs/DESIGN.md §2)'
    call print_split_steps(integ)
    write (output_unit, '(a,f0.4,a)') 'wall time: ', real(c1 - c0, dp) / real(rate, dp), ' s'
    call print_state('end state', integ)
    if (.not. opts%no_output) write (output_unit, '(a)') 'output: '//opts%output
    if (present(report)) call report(integ)
    if (integ%status() == VCI_STOPPED .and. c_signal_caught() /= 0) then
      write (output_unit, '(a)') 'status: '//interrupted_by()//'; '//integ%message()
      ! as a shell reports a program a signal ended: 128 + the signal's number (130 SIGINT, 143 SIGTERM)
      call exit_with(128 + c_signal_caught())
    end if
    if (integ%status() /= VCI_OK) then
      write (output_unit, '(a)') 'status: '//vci_status_name(integ%status())//': '//integ%message()
      stop 2
    end if
    write (output_unit, '(a)') 'status: ok'
  end subroutine run_example

  !> The safety net's line of a summary (always printed: a run that needed it says so).
  subroutine print_split_steps(integ)
    type(vci_integrator_t), intent(in) :: integ
    type(vci_stats_t) :: stats
    stats = integ%statistics()
    write (output_unit, '(a,i0,a,i0,a)') 'steps retried as equal sub-steps (safety net): ', stats%split_steps, &
      '   most sub-steps: ', stats%largest_split, '   (docs/DESIGN.md §2)'
  end subroutine print_split_steps

  !> --check-model: vci_check_model at the start state (q; for L_d the second point q + h p, for L
  !> the velocity p: any point serves, the identities checked hold everywhere); prints the report,
  !> stops with 0 when every supplied derivative agrees with its differences, else 3.
  subroutine check_model_at_start(name, model, integ, h)
    character(len=*), intent(in) :: name
    class(vci_model_base_t), intent(inout) :: model
    type(vci_integrator_t), intent(in) :: integ
    real(dp), intent(in) :: h
    type(vci_check_report_t) :: rep
    real(dp), allocatable :: q(:), v(:)
    character(len=VCI_MSG_LEN) :: msg
    integer :: stat, i
    ! allocated before the assignments: gfortran 12 warns (-Wuninitialized) about the descriptor
    ! of an unallocated array assigned from a function result
    allocate (q(model%n), v(model%n))
    q = integ%configuration(); v = integ%momentum()
    select type (model)
    class is (vci_model_t)
      v = q + h * v
    end select
    call vci_check_model(model, q, v, h, rep, stat, msg)
    if (stat /= VCI_OK) call die(name//': '//trim(msg))
    write (output_unit, '(a,es9.2,a)') 'model check of '//name//' (tolerance ', rep%tol, '):'
    do i = 1, rep%count
      write (output_unit, '(a)') '  '//trim(rep%line(i))
    end do
    write (output_unit, '(a,es9.2,a)') 'model check: '//trim(merge('passed', 'FAILED', rep%passed))// &
      ' (worst mismatch ', rep%worst, ')'
    if (.not. rep%passed) stop 3, quiet=.true.
    stop
  end subroutine check_model_at_start

  !> "progress  37.2%  step 3720000 of 10000000  t = 37.2  impacts 12  2.10E+05 steps/s  ETA 30 s"
  subroutine progress_report(self, info, stop_requested)
    class(progress_line_t), intent(inout) :: self
    type(vci_progress_info_t), intent(in) :: info
    logical, intent(inout) :: stop_requested
    character(len=200) :: line
    character(len=24) :: eta
    stop_requested = c_signal_caught() /= 0
    if (.not. self%print) return
    if (info%elapsed < self%next_print .and. info%steps_done < info%steps_total .and. .not. stop_requested) return
    self%next_print = info%elapsed + 0.5_dp
    eta = 'ETA ?'
    if (info%eta >= 0.0_dp) write (eta, '(a,i0,a)') 'ETA ', nint(info%eta, i8), ' s'
    write (line, '(a,f5.1,a,i0,a,i0,a,g0.6,a,i0,a,es9.2,a)') 'progress ', &
      100.0_dp * real(info%steps_done, dp) / real(max(1_i8, info%steps_total), dp), '%  step ', info%steps_done, &
      ' of ', info%steps_total, '  t = ', info%t, '  impacts ', info%impacts, '  ', info%steps_per_second, &
      ' steps/s  '//trim(eta)
    if (self%tty) then
      write (error_unit, '(a)', advance='no') achar(13)//trim(line)//'   '
      if (info%steps_done == info%steps_total .or. stop_requested) write (error_unit, '(a)') ''
    else
      write (error_unit, '(a)') trim(line)
      flush (error_unit)   ! gfortran buffers stderr into a file or pipe: a log's reader sees the line now
    end if
  end subroutine progress_report

  !> "interrupted by SIGTERM" (or SIGINT, or the signal's number)
  function interrupted_by() result(s)
    character(len=:), allocatable :: s
    character(len=12) :: num
    select case (c_signal_caught())
    case (2); s = 'interrupted by SIGINT'
    case (15); s = 'interrupted by SIGTERM'
    case default
      write (num, '(i0)') c_signal_caught()
      s = 'interrupted by signal '//trim(num)
    end select
  end function interrupted_by

  !> End the program with `code` (no backtrace, output flushed).
  subroutine exit_with(code)
    integer, intent(in) :: code
    flush (output_unit); flush (error_unit)
    stop code, quiet=.true.
  end subroutine exit_with

  !> Create the integrator with the command line's step length and solver settings.
  subroutine create_integrator(name, model, opts, integ)
    character(len=*), intent(in) :: name
    class(vci_model_base_t), target, intent(inout) :: model
    type(example_options_t), intent(in) :: opts
    type(vci_integrator_t), intent(inout) :: integ
    integer :: stat
    select type (model)
    class is (vci_model_t)
      call integ%create(model, opts%h, stat)
    class is (vci_lagrangian_t)
      call integ%create(model, opts%h, stat)
      if (stat == VCI_OK .and. allocated(opts%scheme)) call integ%set_scheme(scheme_id(opts%scheme), &
        merge(opts%order, opts%stages, scheme_id(opts%scheme) == VCI_SCHEME_COMPOSITION), stat)
    class default
      stat = VCI_ERR_ARGUMENT
    end select
    if (stat == VCI_OK) call integ%set_tolerances(0.0_dp, opts%rtol, 30, stat)
    if (stat == VCI_OK) call integ%set_max_impacts(opts%max_impacts, stat)
    if (stat == VCI_OK) call integ%set_step_splits(opts%step_splits, stat)
    if (stat /= VCI_OK) call die(name//': '//integ%message())
  end subroutine create_integrator

  !> Start from the last state of an .h5 file: its checkpoint (bitwise continuation) when the step
  !> length is the file's (taken from the file unless --h is given), else its last (t, q, p).
  subroutine start_from_h5(name, model, opts, integ, t_first, stat)
    character(len=*), intent(in) :: name
    class(vci_model_base_t), target, intent(inout) :: model
    type(example_options_t), intent(inout) :: opts
    type(vci_integrator_t), intent(inout) :: integ
    real(dp), intent(out) :: t_first
    integer, intent(out) :: stat
#ifdef VCI_HAVE_HDF5
    type(vci_checkpoint_t) :: cp
    character(len=VCI_MSG_LEN) :: msg
    call vci_hdf5_read_checkpoint(opts%from, cp, stat, msg, t_first=t_first)
    if (stat /= VCI_OK) call die(name//': '//trim(msg))
    if (.not. opts%h_given) opts%h = cp%h
    call create_integrator(name, model, opts, integ)
    if (cp%h == opts%h) then
      call integ%restore(cp, stat)
    else
      call integ%init_from_momentum(cp%time(), cp%q, cp%p, stat)
    end if
    if (stat /= VCI_OK) call die(name//': '//opts%from//': '//integ%message())
#else
    t_first = 0.0_dp; stat = VCI_ERR_IO
    call die(name//': built without HDF5, cannot read '//opts%from//' (use a .csv file)')
#endif
  end subroutine start_from_h5

  !> VCI_SCHEME_* of a --scheme name, -1 when unknown.
  integer function scheme_id(name)
    character(len=*), intent(in) :: name
    select case (name)
    case ('left'); scheme_id = VCI_SCHEME_LEFT
    case ('midpoint'); scheme_id = VCI_SCHEME_MIDPOINT
    case ('lobatto'); scheme_id = VCI_SCHEME_LOBATTO
    case ('composition'); scheme_id = VCI_SCHEME_COMPOSITION
    case default; scheme_id = -1
    end select
  end function scheme_id

  logical function is_csv(path)
    character(len=*), intent(in) :: path
    is_csv = .false.
    if (len(path) >= 4) is_csv = path(len(path) - 3:) == '.csv'
  end function is_csv

  logical function model_has_energy(model, integ)
    class(vci_model_base_t), intent(inout) :: model
    type(vci_integrator_t), intent(in) :: integ
    real(dp) :: e
    integer :: s
    s = 0
    call model%energy(integ%configuration(), integ%momentum(), e, s)
    model_has_energy = (s == 0)
  end function model_has_energy

  subroutine print_state(what, integ)
    character(len=*), intent(in) :: what
    type(vci_integrator_t), intent(in) :: integ
    write (output_unit, '(a,es24.16,a,*(es24.16))') what//': t = ', integ%time(), '  q =', integ%configuration()
    write (output_unit, '(a,*(es24.16))') repeat(' ', len(what) + 2)//'p =', integ%momentum()
  end subroutine print_state

  !> The first time and the last (t, q, p) of a trajectory file written by the CSV observer.
  subroutine read_last_state(path, n, t_first, t_last, q, p, stat)
    character(len=*), intent(in) :: path
    integer, intent(in) :: n
    real(dp), intent(out) :: t_first, t_last, q(:), p(:)
    integer, intent(out) :: stat
    integer :: u, ios, nrow
    integer(i8) :: step
    character(len=4096) :: line, last
    real(dp) :: vals(2 * n)
    open (newunit=u, file=path, status='old', action='read', iostat=stat)
    if (stat /= 0) return
    read (u, '(a)', iostat=stat) line   ! header
    nrow = 0
    do
      read (u, '(a)', iostat=ios) line
      if (ios /= 0) exit
      if (line(1:1) == '#') cycle
      nrow = nrow + 1
      if (nrow == 1) then
        read (line, *, iostat=stat) step, t_first
        if (stat /= 0) exit
      end if
      last = line
    end do
    close (u)
    if (stat /= 0 .or. nrow == 0) then
      stat = 1; return
    end if
    read (last, *, iostat=stat) step, t_last, vals
    q = vals(1:n); p = vals(n + 1:2 * n)
  end subroutine read_last_state

  subroutine s_start(self, info, q, p, stat)
    class(summary_observer_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
    if (associated(self%next)) call self%next%on_start(info, q, p, stat)
  end subroutine s_start

  subroutine s_step(self, step, t, q, p, lambda, energy, stat)
    class(summary_observer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    self%steps = self%steps + 1
    if (associated(self%watch)) call self%watch%on_step(step, t, q, p, lambda, energy, stat)
    if (associated(self%next)) call self%next%on_step(step, t, q, p, lambda, energy, stat)
  end subroutine s_step

  subroutine s_impact(self, impact, stat)
    class(summary_observer_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    self%impacts = self%impacts + 1
    if (.not. self%quiet) write (output_unit, '(a,i0,a,f0.12,a,i0,a,f8.6,a,es12.5)') 'impact ', self%impacts, &
      ' t=', impact%t, ' wall=', impact%gap, ' alpha=', impact%alpha, ' impulse=', impact%impulse
    if (associated(self%watch)) call self%watch%on_impact(impact, stat)
    if (associated(self%next)) call self%next%on_impact(impact, stat)
  end subroutine s_impact

  subroutine s_split(self, step, parts, stat)
    class(summary_observer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    integer, intent(in) :: parts
    integer, intent(inout) :: stat
    if (associated(self%next)) call self%next%on_split(step, parts, stat)
  end subroutine s_split

  subroutine s_finish(self, status, message, stat)
    class(summary_observer_t), intent(inout) :: self
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    integer, intent(inout) :: stat
    if (.not. associated(self%next)) return
    if (status == VCI_STOPPED .and. c_signal_caught() /= 0) then   ! the file's status_message says so
      call self%next%on_finish(status, interrupted_by()//'; '//message, stat)
    else
      call self%next%on_finish(status, message, stat)
    end if
  end subroutine s_finish

  ! checkpoints pass through to `next` (the HDF5 file stores them: --from continues bit for bit)
  pure logical function s_keeps_checkpoints(self)
    class(summary_observer_t), intent(in) :: self
    s_keeps_checkpoints = .false.
    if (associated(self%next)) s_keeps_checkpoints = self%next%keeps_checkpoints()
  end function s_keeps_checkpoints

  pure logical function s_wants_checkpoint(self)
    class(summary_observer_t), intent(in) :: self
    s_wants_checkpoint = .false.
    if (associated(self%next)) s_wants_checkpoint = self%next%wants_checkpoint()
  end function s_wants_checkpoint

  subroutine s_checkpoint(self, cp, stat)
    class(summary_observer_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: cp
    integer, intent(inout) :: stat
    if (associated(self%next)) call self%next%on_checkpoint(cp, stat)
  end subroutine s_checkpoint

  subroutine s_failure_cause(self, cause)
    class(summary_observer_t), intent(in) :: self
    character(len=*), intent(out) :: cause
    cause = ''
    if (associated(self%next)) call self%next%failure_cause(cause)
  end subroutine s_failure_cause

  function get_arg(i) result(s)
    integer, intent(in) :: i
    character(len=:), allocatable :: s
    integer :: l
    call get_command_argument(i, length=l)
    allocate (character(len=l) :: s)
    call get_command_argument(i, s)
  end function get_arg

  !> Does an argument look like a flag (--anything, or -h) rather than a value? `-3` and `-inf` are values.
  pure logical function is_option(s)
    character(len=*), intent(in) :: s
    is_option = s == '-h'
    if (len(s) >= 2) is_option = is_option .or. s(1:2) == '--'
  end function is_option

  !> Does the last component of path have an extension (a dot after its last '/')? `./run` has not.
  pure logical function has_extension(path)
    character(len=*), intent(in) :: path
    has_extension = index(path, '.', back=.true.) > index(path, '/', back=.true.) + 1
  end function has_extension

  !> Steps of length h from t_from to t_to in direction dir (0 when t_to is behind); more than 2^53
  !> is refused (step indices stay exact in the float64 time grid).
  integer(i8) function steps_to(name, t_from, t_to, h, dir)
    character(len=*), intent(in) :: name
    real(dp), intent(in) :: t_from, t_to, h
    integer, intent(in) :: dir
    character(len=160) :: msg
    if (real(dir, dp) * (t_to - t_from) / h > steps_max) then
      write (msg, '(a,es10.3,a,es10.3,a)') ': reaching t = ', t_to, ' takes more than 2^53 steps of h = ', h, &
        ' (lower --t-final or raise --h)'
      call die(name//trim(msg))
    end if
    steps_to = max(0_i8, ceiling(real(dir, dp) * (t_to - t_from) / h - 1.0e-9_dp, i8))
  end function steps_to

  !> The value of a real flag: the whole token must be one decimal number (sign, digits with at most
  !> one point, an optional exponent), finite and in [lo, hi] (lo excluded when low_open). List-directed
  !> READ alone would take `1,5` as 1 and `inf` as infinity.
  real(dp) function to_real(s, flag, lo, hi, low_open)
    character(len=*), intent(in) :: s, flag
    real(dp), intent(in) :: lo, hi
    logical, intent(in), optional :: low_open
    integer :: ios
    logical :: open_lo
    character(len=32) :: bound
    open_lo = .false.; if (present(low_open)) open_lo = low_open
    if (.not. is_decimal(s, integer_only=.false.)) call die(trim(program_name)//': invalid number for '//flag//': "'//s//'"')
    read (s, *, iostat=ios) to_real
    if (ios /= 0) call die(trim(program_name)//': invalid number for '//flag//': "'//s//'"')
    if (.not. (to_real <= huge(to_real) .and. to_real >= -huge(to_real))) &
      call die(trim(program_name)//': '//flag//' must be finite (got "'//s//'")')
    if (to_real < lo .or. to_real > hi .or. (open_lo .and. to_real == lo)) then
      write (bound, '(a,es9.2,a,es9.2,a)') merge('(', '[', open_lo), lo, ', ', hi, ']'
      call die(trim(program_name)//': '//flag//' must be in '//trim(bound)//' (got "'//s//'")')
    end if
  end function to_real

  !> The value of an integer flag: digits only (with an optional sign), in [lo, hi]; `1e20` or
  !> `2.5` are refused rather than rounded or wrapped.
  integer function to_int(s, flag, lo, hi)
    character(len=*), intent(in) :: s, flag
    integer, intent(in) :: lo, hi
    integer :: ios
    integer(i8) :: v
    character(len=48) :: bound
    if (.not. is_decimal(s, integer_only=.true.) .or. len_trim(s) > 18) &
      call die(trim(program_name)//': invalid integer for '//flag//': "'//s//'"')
    read (s, *, iostat=ios) v
    if (ios /= 0) call die(trim(program_name)//': invalid integer for '//flag//': "'//s//'"')
    if (v < lo .or. v > hi) then
      write (bound, '(a,i0,a,i0,a)') '[', lo, ', ', hi, ']'
      call die(trim(program_name)//': '//flag//' must be an integer in '//trim(bound)//' (got "'//s//'")')
    end if
    to_int = int(v)
  end function to_int

  !> Is s one decimal number: [+-] digits [. digits] [(e|E|d|D) [+-] digits], with at least one
  !> digit in the mantissa (integer_only: [+-] digits)?
  pure logical function is_decimal(s, integer_only)
    character(len=*), intent(in) :: s
    logical, intent(in) :: integer_only
    integer :: i, n, mantissa_digits, exp_digits
    logical :: seen_point, seen_exp
    is_decimal = .false.
    n = len_trim(s)
    if (n == 0) return
    i = 1
    if (s(1:1) == '+' .or. s(1:1) == '-') i = 2
    mantissa_digits = 0; exp_digits = 0; seen_point = .false.; seen_exp = .false.
    do while (i <= n)
      select case (s(i:i))
      case ('0':'9')
        if (seen_exp) then
          exp_digits = exp_digits + 1
        else
          mantissa_digits = mantissa_digits + 1
        end if
      case ('.')
        if (integer_only .or. seen_point .or. seen_exp) return
        seen_point = .true.
      case ('e', 'E', 'd', 'D')
        if (integer_only .or. seen_exp .or. mantissa_digits == 0) return
        seen_exp = .true.
        if (i < n) then
          if (s(i+1:i+1) == '+' .or. s(i+1:i+1) == '-') i = i + 1
        end if
      case default
        return
      end select
      i = i + 1
    end do
    is_decimal = mantissa_digits > 0 .and. (.not. seen_exp .or. exp_digits > 0)
  end function is_decimal

  subroutine die(msg)
    character(len=*), intent(in) :: msg
    write (error_unit, '(a)') msg
    stop 1, quiet=.true.   ! a usage error, not a crash: no backtrace
  end subroutine die
end module vci_example_cli
