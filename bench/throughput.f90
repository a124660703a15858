!> Throughput of vci against hand-specialised loops, in one process (issue 2 item 9, issue 6).
!>
!> For each scene (particle, ellipse, pendulum, with the examples' default set-ups) three variants
!> run the same trajectory: the library with the model's analytic mixed Hessian, the library
!> differencing it, and the hand loop of bench/hand_loops.f90. First the trajectories are checked
!> to be the same (impact count, impact times to 1e-10, final state to 1e-9), so that the timings
!> compare equal work; then each variant runs repeated episodes (init from the scene's pair, then
!> the scene's steps, no observer) for at least `min_time` seconds per repeat, the variants
!> interleaved, and the median time per step over the repeats is reported with the ratio
!> library/hand. Peak memory: the kernel's resident high-water mark (VmHWM) is reset through
!> /proc/self/clear_refs before each variant's run and read after it.
!>
!> Usage: vci_bench_throughput [--quick] [--repeats N] [--min-time S]
!>        vci_bench_throughput --profile SCENE VARIANT EPISODES   (one variant only, for callgrind)
!>        vci_bench_throughput --profile-steps SCENE VARIANT EPISODES   (regular and impact steps
!>          through separate procedures, for callgrind; prints how many of each)
!> Output: markdown on stdout. Exit status 1 when a trajectory check fails.
!> Records the impact times of a library run (verification only; the timed runs have no observer).
module vci_bench_impact_log
  use vci, only: dp, vci_observer_t, vci_impact_t
  use vci_bench_hand, only: max_recorded
  implicit none
  private
  type, extends(vci_observer_t), public :: impact_log_t
    integer :: n = 0
    real(dp) :: t(max_recorded) = 0.0_dp
  contains
    procedure :: on_impact => log_impact
  end type impact_log_t
contains
  subroutine log_impact(self, impact, stat)
    class(impact_log_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    self%n = self%n + 1
    if (self%n <= max_recorded) self%t(self%n) = impact%t
  end subroutine log_impact
end module vci_bench_impact_log

program throughput
  use vci_tool_args, only: arg_value
  use, intrinsic :: iso_fortran_env, only: int64, error_unit, output_unit
  use vci
  use vci_bench_stats, only: median
  use vci_scene_particle, only: particle_t, particle_on_floor
  use vci_scene_ellipse, only: ellipse_t, ellipse_model
  use vci_scene_pendulum, only: pendulum_t, pendulum_model
  use vci_bench_hand
  use vci_bench_same, only: same_ellipse, same_pendulum
  use vci_bench_impact_log, only: impact_log_t
  use vci_bench_split, only: counted_regular_step, counted_impact_step
  implicit none

  !> Scenes 4 and 5 are 2 and 3 without impacts (the ellipse dropped from high up, the pendulum in a
  !> cylinder wider than its reach): their time per step is that of a regular step.
  integer, parameter :: n_scenes = 5, n_var = 4
  character(len=13), parameter :: scene_name(n_scenes) = [character(len=13) :: 'particle', 'ellipse', &
    'pendulum', 'ellipse-free', 'pendulum-free']
  character(len=22), parameter :: var_name(n_var) = [character(len=22) :: 'library, analytic H', &
                                                     'library, differenced H', 'closed-form hand loop', &
                                                     'same-algorithm loop']
  integer, parameter :: V_LIB = 1, V_LIB_FD = 2, V_HAND = 3, V_SAME = 4
  !> The scene whose impacts a free scene leaves out (0: none).
  integer, parameter :: with_impacts(n_scenes) = [0, 0, 0, 2, 3]

  !> One scene: its default set-up and a model per library variant.
  type :: scene_t
    real(dp) :: h = 0.0_dp, t0 = 0.0_dp
    real(dp), allocatable :: q0(:), q1(:)
    integer(int64) :: nsteps = 0
    integer :: expected_impacts = 0
  end type scene_t

  type(particle_t), target :: part(2)
  type(ellipse_t), target :: ell(2)
  type(pendulum_t), target :: pend(2), pendf(2)
  type(vci_integrator_t) :: integ(n_scenes, 2)
  type(scene_t) :: sc(n_scenes)
  type(ellipse_par_t) :: epar
  type(pendulum_par_t) :: ppar, ppar_free

  integer :: repeats = 7, is, iv, ir, i, nargs, stat
  real(dp) :: min_time = 0.25_dp
  integer(int64) :: episodes(n_scenes, n_var)
  real(dp), allocatable :: tps(:, :, :)           ! seconds per step (scene, variant, repeat)
  real(dp) :: newton_per_step(n_scenes, n_var), hwm(n_scenes, n_var), rss0(n_scenes, n_var)
  real(dp) :: checksum = 0.0_dp
  logical :: all_ok
  character(len=64) :: arg
  character(len=:), allocatable :: check_report

  call setup_scenes()

  nargs = command_argument_count()
  i = 1
  do while (i <= nargs)
    call get_command_argument(i, arg)
    select case (trim(arg))
    case ('--quick')
      repeats = 3; min_time = 0.05_dp
    case ('--repeats')
      i = i + 1; call arg_value(i, '--repeats', repeats)
    case ('--min-time')
      i = i + 1; call arg_value(i, '--min-time', min_time)
    case ('--profile')
      call profile_mode(i); stop
    case ('--profile-steps')
      call profile_steps_mode(i); stop
    case ('--help', '-h')
      write (output_unit, '(a)') 'vci_bench_throughput [--quick] [--repeats N] [--min-time S]'
      write (output_unit, '(a)') 'vci_bench_throughput --profile SCENE VARIANT(1..4) EPISODES'
      write (output_unit, '(a)') 'vci_bench_throughput --profile-steps SCENE VARIANT(1..2) EPISODES'
      stop
    case default
      write (error_unit, '(a)') 'unknown argument '//trim(arg); error stop 2
    end select
    i = i + 1
  end do
  repeats = max(repeats, 1)

  ! 1. the same trajectories
  check_report = ''
  all_ok = .true.
  do is = 1, n_scenes
    call verify(is, all_ok)
  end do

  ! 2. calibrate: episodes per repeat so that one repeat lasts at least min_time
  do is = 1, n_scenes
    do iv = 1, n_var
      episodes(is, iv) = 1
      if (available(is, iv)) episodes(is, iv) = calibrate(is, iv)
    end do
  end do

  ! 3. timed repeats, variants interleaved so that drifts of the machine hit all of them alike
  allocate (tps(n_scenes, n_var, repeats))
  do ir = 1, repeats
    do is = 1, n_scenes
      do iv = 1, n_var
        tps(is, iv, ir) = 0.0_dp
        if (available(is, iv)) tps(is, iv, ir) = run_timed(is, iv, episodes(is, iv)) / real(episodes(is, iv) * sc(is)%nsteps, dp)
      end do
    end do
  end do

  ! 4. peak resident memory of each variant on its own (high-water mark reset before each run)
  do is = 1, n_scenes
    do iv = 1, n_var
      hwm(is, iv) = 0.0_dp; rss0(is, iv) = 0.0_dp; newton_per_step(is, iv) = 0.0_dp
      if (.not. available(is, iv)) cycle
      call reset_hwm()
      rss0(is, iv) = read_status_kb('VmRSS:')
      hwm(is, iv) = run_timed(is, iv, max(1_int64, episodes(is, iv) / 4))
      newton_per_step(is, iv) = newton_count(is, iv)
      hwm(is, iv) = read_status_kb('VmHWM:')
    end do
  end do

  call report()
  call impact_report()
  if (checksum /= checksum) write (error_unit, '(a)') 'checksum NaN'
  if (.not. all_ok) then
    write (error_unit, '(a)') 'vci_bench_throughput: trajectory check FAILED (see table)'
    error stop 1
  end if

contains

  !> The examples' default set-ups (examples/*.f90, docs/DESIGN.md §8).
  subroutine setup_scenes()
    real(dp) :: qd2(2), qd3(3), q2(2), q3(3)
    integer :: k, i, stat, bm
    character(len=8) :: env
    ! particle: floor, start (0, 1) with velocity (1, 0), pair q(0) -/+ (h/2) qdot, 3 s
    sc(1)%h = 1.0e-2_dp; sc(1)%t0 = -0.5_dp * sc(1)%h; sc(1)%nsteps = 300; sc(1)%expected_impacts = 3
    q2 = [0.0_dp, 1.0_dp]; qd2 = [1.0_dp, 0.0_dp]
    sc(1)%q0 = q2 - 0.5_dp * sc(1)%h * qd2; sc(1)%q1 = q2 + 0.5_dp * sc(1)%h * qd2
    ! ellipse: q(0) = (pi/2, 0, 3.5), qdot(0) = (-3, 2, 0), pair q(0) -/+ (h/2) qdot, 2 s
    sc(2)%h = 1.0e-2_dp; sc(2)%t0 = -0.5_dp * sc(2)%h; sc(2)%nsteps = 200; sc(2)%expected_impacts = 2
    q3 = [acos(-1.0_dp) / 2.0_dp, 0.0_dp, 3.5_dp]; qd3 = [-3.0_dp, 2.0_dp, 0.0_dp]
    sc(2)%q0 = q3 - 0.5_dp * sc(2)%h * qd3; sc(2)%q1 = q3 + 0.5_dp * sc(2)%h * qd3
    ! pendulum: q(0) = (0.75 pi, 0), qdot(0) = (pi/4, (pi + 0.5) pi/4), pair q0, q0 + h qdot, 5 s
    sc(3)%h = 1.0e-3_dp; sc(3)%t0 = 0.0_dp; sc(3)%nsteps = 4999; sc(3)%expected_impacts = 3
    q2 = [0.75_dp * acos(-1.0_dp), 0.0_dp]
    qd2 = [acos(-1.0_dp) / 4.0_dp, (acos(-1.0_dp) + 0.5_dp) * acos(-1.0_dp) / 4.0_dp]
    sc(3)%q0 = q2; sc(3)%q1 = q2 + sc(3)%h * qd2
    ! the same without impacts: the ellipse starts 100 m up; the pendulum's cylinder is wider than l
    sc(4) = sc(2); sc(4)%expected_impacts = 0
    sc(4)%q0(3) = sc(4)%q0(3) + 100.0_dp; sc(4)%q1(3) = sc(4)%q1(3) + 100.0_dp
    sc(5) = sc(3); sc(5)%expected_impacts = 0

    do k = 1, 2
      part(k) = particle_on_floor(1.0_dp, 9.8_dp)
      ell(k) = ellipse_model()
      pend(k) = pendulum_model()
      pendf(k) = pendulum_model(); pendf(k)%radius = 2.5_dp
    end do
    pendf(2)%analytic_hessian = .false.
    part(2)%analytic_hessian = .false.; ell(2)%analytic_hessian = .false.; pend(2)%analytic_hessian = .false.
    ! the examples' models: D1, D2, D3 and the Hessian in one call (ld_fused; the analytic variant
    ! only). VCI_BENCH_SEPARATE=1: one callback per quantity, to measure what the fused callback saves
    call get_environment_variable('VCI_BENCH_SEPARATE', env, status=stat)
    if (.not. (stat == 0 .and. env == '1')) then
      ell(1)%fused_callback = .true.; pend(1)%fused_callback = .true.; pendf(1)%fused_callback = .true.
    end if
    epar = ellipse_par_t(mass=ell(1)%mass, grav=ell(1)%grav, a=ell(1)%a, b=ell(1)%b)
    ppar = pendulum_par_t(mass=pend(1)%mass, grav=pend(1)%grav, length=pend(1)%length, radius=pend(1)%radius)
    ppar_free = ppar; ppar_free%radius = pendf(1)%radius
    do k = 1, 2
      call integ(1, k)%create(part(k), sc(1)%h, stat); call must(stat, 'create particle')
      call integ(2, k)%create(ell(k), sc(2)%h, stat); call must(stat, 'create ellipse')
      call integ(3, k)%create(pend(k), sc(3)%h, stat); call must(stat, 'create pendulum')
      call integ(4, k)%create(ell(k), sc(4)%h, stat); call must(stat, 'create ellipse-free')
      call integ(5, k)%create(pendf(k), sc(5)%h, stat); call must(stat, 'create pendulum-free')
    end do
    ! VCI_BENCH_GENERAL=1: the library without its fused regular-step solve (every sub-step on the
    ! general Newton path), to measure what the fused solve saves (tools/bench/run_bench.sh)
    call get_environment_variable('VCI_BENCH_GENERAL', env, status=stat)
    if (stat == 0 .and. env == '1') then
      do k = 1, 2
        do i = 1, size(integ, 1)
          call integ(i, k)%set_solver_paths(8, 16, fused=.false.)
        end do
      end do
    end if
    ! VCI_BENCH_POKE=0: the poke screen off (set_poke_samples(.false.)), for its cost (docs/bench/poke.md)
    call get_environment_variable('VCI_BENCH_POKE', env, status=stat)
    if (stat == 0 .and. env == '0') then
      do k = 1, 2
        do i = 1, size(integ, 1)
          call integ(i, k)%set_poke_samples(.false., stat)
        end do
      end do
    end if
    ! VCI_BENCH_WHOLE_IMPACTS=1: impact stages with the whole stage matrix factorised (the path
    ! before bordering, set_bordered_impacts(.false.)), for the before/after comparison
    call get_environment_variable('VCI_BENCH_WHOLE_IMPACTS', env, status=stat)
    if (stat == 0 .and. env == '1') then
      do k = 1, 2
        do i = 1, size(integ, 1)
          call integ(i, k)%set_bordered_impacts(.false.)
        end do
      end do
    end if
    ! VCI_BENCH_BORDER_MIN=k: border stage systems from k unknowns (default 16)
    call get_environment_variable('VCI_BENCH_BORDER_MIN', env, status=stat)
    if (stat == 0) then
      read (env, *) bm
      do k = 1, 2
        do i = 1, size(integ, 1)
          call integ(i, k)%set_bordered_impacts(.true., bm)
        end do
      end do
    end if
  end subroutine setup_scenes

  subroutine must(stat, what)
    integer, intent(in) :: stat
    character(len=*), intent(in) :: what
    if (stat /= VCI_OK) then
      write (error_unit, '(a,i0)') 'vci_bench_throughput: '//what//' failed with status ', stat
      error stop 3
    end if
  end subroutine must

  !> One hand-loop episode of scene is (closed-form loop, or the same-algorithm loop when `same`):
  !> final state and impacts.
  subroutine hand_run(is, q, p, res, same)
    integer, intent(in) :: is
    real(dp), intent(out) :: q(:), p(:)
    type(hand_result_t), intent(out) :: res
    logical, intent(in) :: same
    real(dp) :: e
    if (same) then
      select case (is)
      case (2, 4)
        call same_ellipse(epar, sc(is)%h, sc(is)%t0, sc(is)%q0, sc(is)%q1, sc(is)%nsteps, q, p, e, res)
      case (3)
        call same_pendulum(ppar, sc(3)%h, sc(3)%t0, sc(3)%q0, sc(3)%q1, sc(3)%nsteps, q, p, e, res)
      case (5)
        call same_pendulum(ppar_free, sc(5)%h, sc(5)%t0, sc(5)%q0, sc(5)%q1, sc(5)%nsteps, q, p, e, res)
      case default
        res = hand_result_t(); res%ok = .false.; q = 0.0_dp; p = 0.0_dp; e = 0.0_dp
      end select
      checksum = checksum + e
      return
    end if
    select case (is)
    case (1)
      call hand_particle(part(1)%mass, part(1)%grav, sc(1)%h, sc(1)%t0, sc(1)%q0, sc(1)%q1, sc(1)%nsteps, q, p, res)
    case (2, 4)
      call hand_ellipse(epar, sc(is)%h, sc(is)%t0, sc(is)%q0, sc(is)%q1, sc(is)%nsteps, q, p, res)
    case (3)
      call hand_pendulum(ppar, sc(3)%h, sc(3)%t0, sc(3)%q0, sc(3)%q1, sc(3)%nsteps, q, p, res)
    case (5)
      call hand_pendulum(ppar_free, sc(5)%h, sc(5)%t0, sc(5)%q0, sc(5)%q1, sc(5)%nsteps, q, p, res)
    end select
  end subroutine hand_run

  !> Is variant iv defined for scene is? (no same-algorithm loop for the particle)
  logical function available(is, iv)
    integer, intent(in) :: is, iv
    available = .not. (iv == V_SAME .and. is == 1)
  end function available

  !> One library episode: init from the pair, nsteps forward steps.
  subroutine lib_run(is, k, stat, observer)
    integer, intent(in) :: is, k
    integer, intent(out) :: stat
    class(vci_observer_t), intent(inout), optional :: observer
    call integ(is, k)%init_from_pair(sc(is)%t0, sc(is)%q0, sc(is)%q1, stat)
    if (stat /= VCI_OK) return
    call integ(is, k)%integrate(sc(is)%nsteps, 1, stat, observer)
  end subroutine lib_run

  !> Library (both variants) and the same-algorithm loop against the closed-form hand loop: impact
  !> count and times, final (q, p).
  subroutine verify(is, all_ok)
    integer, intent(in) :: is
    logical, intent(inout) :: all_ok
    type(hand_result_t) :: hres, sres
    type(impact_log_t) :: log
    real(dp) :: qh(size(sc(is)%q0)), ph(size(sc(is)%q0)), qv(size(sc(is)%q0)), pv(size(sc(is)%q0)), dt, dq
    integer :: k, j, nimp, nv
    logical :: ok
    character(len=256) :: line
    call hand_run(is, qh, ph, hres, .false.)
    do k = 1, n_var
      if (k == V_HAND .or. .not. available(is, k)) cycle
      if (k == V_SAME) then
        call hand_run(is, qv, pv, sres, .true.)
        log = impact_log_t()
        log%n = sres%n_impacts; log%t = sres%t_impact
        stat = merge(VCI_OK, VCI_ERR_NEWTON, sres%ok)
      else
        log = impact_log_t()
        call lib_run(is, k, stat, log)
        qv = integ(is, k)%configuration(); pv = integ(is, k)%momentum()
      end if
      nv = log%n
      ok = stat == VCI_OK .and. hres%ok .and. nv == hres%n_impacts .and. nv == sc(is)%expected_impacts
      dt = 0.0_dp
      nimp = min(nv, hres%n_impacts, max_recorded)
      do j = 1, nimp
        dt = max(dt, abs(log%t(j) - hres%t_impact(j)))
      end do
      dq = max(maxval(abs(qv - qh) / max(1.0_dp, abs(qh))), maxval(abs(pv - ph) / max(1.0_dp, abs(ph))))
      ok = ok .and. dt <= 1.0e-10_dp .and. dq <= 1.0e-9_dp
      all_ok = all_ok .and. ok
      write (line, '(a," | ",a," | ",i0," / ",i0," | ",es8.1," | ",es8.1," | ",a)') trim(scene_name(is)), &
        trim(var_name(k)), nv, hres%n_impacts, dt, dq, trim(merge('yes', 'NO ', ok))
      check_report = check_report//'| '//trim(line)//' |'//new_line('a')
    end do
  end subroutine verify

  real(dp) function now()
    integer(int64) :: c, r
    call system_clock(c, r)
    now = real(c, dp) / real(r, dp)
  end function now

  !> Wall time of `neps` episodes of variant iv of scene is.
  real(dp) function run_timed(is, iv, neps) result(seconds)
    integer, intent(in) :: is, iv
    integer(int64), intent(in) :: neps
    integer(int64) :: e
    real(dp) :: t_start, q(3), p(3)
    type(hand_result_t) :: hres
    integer :: n
    n = size(sc(is)%q0)
    t_start = now()
    if (iv == V_HAND .or. iv == V_SAME) then
      do e = 1, neps
        call hand_run(is, q(1:n), p(1:n), hres, iv == V_SAME)
        checksum = checksum + q(1)
      end do
    else
      do e = 1, neps
        call lib_run(is, iv, stat)
        call must(stat, 'library run')
        q(1:n) = integ(is, iv)%configuration()
        checksum = checksum + q(1)
      end do
    end if
    seconds = now() - t_start
  end function run_timed

  !> Episodes per repeat such that a repeat lasts at least min_time.
  integer(int64) function calibrate(is, iv) result(neps)
    integer, intent(in) :: is, iv
    real(dp) :: t
    neps = 1
    do
      t = run_timed(is, iv, neps)
      if (t >= 0.2_dp * min_time) exit
      neps = neps * 4
    end do
    neps = max(1_int64, ceiling(1.1_dp * min_time / t * real(neps, dp), int64))
  end function calibrate

  !> Newton iterations (Jacobian evaluations + polishing steps) per step, one episode.
  real(dp) function newton_count(is, iv)
    integer, intent(in) :: is, iv
    integer(int64) :: before
    type(hand_result_t) :: hres
    type(vci_stats_t) :: stats
    real(dp) :: q(3), p(3)
    integer :: n
    n = size(sc(is)%q0)
    if (iv == V_HAND .or. iv == V_SAME) then
      call hand_run(is, q(1:n), p(1:n), hres, iv == V_SAME)
      newton_count = real(hres%newton_iterations, dp) / real(sc(is)%nsteps, dp)
    else
      stats = integ(is, iv)%statistics()
      before = stats%newton_iterations
      call lib_run(is, iv, stat)
      stats = integ(is, iv)%statistics()
      newton_count = real(stats%newton_iterations - before, dp) / real(sc(is)%nsteps, dp)
    end if
  end function newton_count

  subroutine reset_hwm()
    integer :: u, ios
    open (newunit=u, file='/proc/self/clear_refs', action='write', iostat=ios)
    if (ios /= 0) return
    write (u, '(a)', iostat=ios) '5'
    close (u, iostat=ios)
  end subroutine reset_hwm

  !> A "Key:  value kB" line of /proc/self/status, in kB (-1 when unavailable).
  real(dp) function read_status_kb(key) result(kb)
    character(len=*), intent(in) :: key
    character(len=256) :: line
    integer :: u, ios
    kb = -1.0_dp
    open (newunit=u, file='/proc/self/status', action='read', iostat=ios)
    if (ios /= 0) return
    do
      read (u, '(a)', iostat=ios) line
      if (ios /= 0) exit
      if (line(1:len(key)) == key) then
        read (line(len(key) + 1:), *, iostat=ios) kb
        if (ios /= 0) kb = -1.0_dp
        exit
      end if
    end do
    close (u)
  end function read_status_kb


  subroutine report()
    real(dp) :: med(n_scenes, n_var), spread
    integer :: u
    character(len=16) :: same_col
    u = output_unit
    do is = 1, n_scenes
      do iv = 1, n_var
        med(is, iv) = 0.0_dp
        if (available(is, iv)) med(is, iv) = median(tps(is, iv, :))
      end do
    end do
    write (u, '(a)') '### Time per step'
    write (u, '(a)') ''
    write (u, '(a,i0,a,f4.2,a)') 'Median of ', repeats, ' repeats, each at least ', min_time, &
      ' s of repeated episodes (init from the pair + the scene''s steps, no observer). '// &
      'Ratios = time per step / that of the closed-form hand loop (the floor) and of the same-algorithm '// &
      'hand loop (the yardstick: bench/same_loops.f90), same run.'
    write (u, '(a)') ''
    write (u, '(a)') '| scene | steps/episode | variant | ns/step (median) | spread (max-min)/median | steps/s '// &
      '| Newton it./step | ratio to closed form | ratio to same algorithm |'
    write (u, '(a)') '|---|---:|---|---:|---:|---:|---:|---:|---:|'
    do is = 1, n_scenes
      do iv = 1, n_var
        if (.not. available(is, iv)) cycle
        spread = (maxval(tps(is, iv, :)) - minval(tps(is, iv, :))) / med(is, iv)
        same_col = 'n/a'
        if (available(is, V_SAME)) write (same_col, '(f6.2)') med(is, iv) / med(is, V_SAME)
        write (u, '("| ",a," | ",i0," | ",a," | ",f9.1," | ",f5.2," | ",es9.3," | ",f5.2," | ",f6.2," | ",a," |")') &
          trim(scene_name(is)), sc(is)%nsteps, trim(var_name(iv)), 1.0e9_dp * med(is, iv), spread, &
          1.0_dp / med(is, iv), newton_per_step(is, iv), med(is, iv) / med(is, V_HAND), trim(adjustl(same_col))
      end do
    end do
    write (u, '(a)') ''
    write (u, '(a)') '### Peak resident memory'
    write (u, '(a)') ''
    write (u, '(a)') 'VmHWM of this process after resetting the high-water mark (/proc/self/clear_refs) and '// &
      'running one variant alone; the resident size at the reset (code, runtime, all variants'' '// &
      'data) is the floor. Ratio = variant / closed-form hand loop.'
    write (u, '(a)') ''
    write (u, '(a)') '| scene | variant | VmRSS at reset (kB) | VmHWM after run (kB) | growth (kB) | ratio to hand |'
    write (u, '(a)') '|---|---|---:|---:|---:|---:|'
    do is = 1, n_scenes
      do iv = 1, n_var
        if (.not. available(is, iv)) cycle
        write (u, '("| ",a," | ",a," | ",i0," | ",i0," | ",i0," | ",f5.3," |")') trim(scene_name(is)), &
          trim(var_name(iv)), nint(rss0(is, iv)), nint(hwm(is, iv)), nint(hwm(is, iv) - rss0(is, iv)), &
          hwm(is, iv) / hwm(is, V_HAND)
      end do
    end do
    write (u, '(a)') ''
    write (u, '(a)') '### Same trajectories (checked before timing)'
    write (u, '(a)') ''
    write (u, '(a)') 'Required: the impact count of the example, impact times within 1e-10 s, final state within '// &
      '1e-9 (relative to max(1, |value|)) of the closed-form hand loop; otherwise the run fails.'
    write (u, '(a)') ''
    write (u, '(a)') '| scene | variant | impacts (variant / closed form) | max abs. diff. of impact times (s) | '// &
      'max rel. diff. of final (q, p) | same |'
    write (u, '(a)') '|---|---|---:|---:|---:|---|'
    write (u, '(a)', advance='no') check_report
  end subroutine report

  !> Regular and impact steps of the library, timed one by one (system_clock around each step) over
  !> repeated episodes of the scenes with impacts; medians of each kind.
  subroutine impact_report()
    integer, parameter :: cap = 400000
    real(dp), allocatable :: treg(:), timp(:)
    integer :: nreg, nimp, k, ise, ivar
    integer(int64) :: c0, c1, rate, e, neps
    real(dp) :: mreg, mimp
    allocate (treg(cap), timp(2000))
    write (output_unit, '(a)') ''
    write (output_unit, '(a)') '### Regular and impact steps of the library'
    write (output_unit, '(a)') ''
    write (output_unit, '(a)') 'Each step of repeated episodes timed on its own (system_clock around integ%step; '// &
      'includes the clock''s own cost, ~20 ns); medians over the steps with and without an impact.'
    write (output_unit, '(a)') ''
    write (output_unit, '(a)') '| scene | variant | regular steps timed | impact steps timed | regular step (ns) '// &
      '| impact step (ns) | impact / regular |'
    write (output_unit, '(a)') '|---|---|---:|---:|---:|---:|---:|'
    do ise = 2, 3
      do ivar = V_LIB, V_LIB_FD
        nreg = 0; nimp = 0
        neps = max(1_int64, min(cap / sc(ise)%nsteps, 2000_int64 / max(1, sc(ise)%expected_impacts)))
        do e = 1, neps
          call integ(ise, ivar)%init_from_pair(sc(ise)%t0, sc(ise)%q0, sc(ise)%q1, stat)
          do k = 1, int(sc(ise)%nsteps)
            call system_clock(c0, rate)
            call integ(ise, ivar)%step(1, stat)
            call system_clock(c1)
            call must(stat, 'library step')
            if (integ(ise, ivar)%impact_count() > 0) then
              if (nimp < size(timp)) nimp = nimp + 1
              timp(nimp) = real(c1 - c0, dp) / real(rate, dp)
            else
              if (nreg < cap) nreg = nreg + 1
              treg(nreg) = real(c1 - c0, dp) / real(rate, dp)
            end if
          end do
        end do
        mreg = median(treg(1:nreg)); mimp = median(timp(1:max(1, nimp)))
        write (output_unit, '("| ",a," | ",a," | ",i0," | ",i0," | ",f9.1," | ",f10.1," | ",f7.2," |")') &
          trim(scene_name(ise)), trim(var_name(ivar)), nreg, nimp, 1.0e9_dp * mreg, 1.0e9_dp * mimp, mimp / mreg
      end do
    end do
  end subroutine impact_report

  !> --profile SCENE VARIANT EPISODES: run one variant only (for valgrind --tool=callgrind).
  subroutine profile_mode(i)
    integer, intent(inout) :: i
    character(len=64) :: a1, a2, a3
    integer :: iv_, is_
    integer(int64) :: neps
    real(dp) :: t
    call get_command_argument(i + 1, a1); call get_command_argument(i + 2, a2); call get_command_argument(i + 3, a3)
    is_ = findloc(scene_name, trim(a1), dim=1)
    call arg_value(i + 2, 'VARIANT', iv_); call arg_value(i + 3, 'EPISODES', neps)
    if (is_ < 1 .or. iv_ < 1 .or. iv_ > n_var) error stop 'usage: --profile SCENE VARIANT EPISODES'
    t = run_timed(is_, iv_, neps)
    write (output_unit, '(a,1x,a,1x,f9.1,a,f8.3)') trim(scene_name(is_)), trim(var_name(iv_)), &
      1.0e9_dp * t / real(neps * sc(is_)%nsteps, dp), ' ns/step; Newton it./step', newton_count(is_, iv_)
  end subroutine profile_mode

  !> --profile-steps SCENE VARIANT EPISODES: a first episode finds which steps have an impact; then
  !> the episodes take those steps through counted_impact_step and the others through
  !> counted_regular_step (bench/step_split.f90), so that callgrind counts each kind apart. Prints
  !> the number of steps of each kind.
  subroutine profile_steps_mode(i)
    integer, intent(inout) :: i
    character(len=64) :: a1, a2, a3
    integer :: iv_, is_, k, nreg, nimp
    integer(int64) :: neps, e
    logical, allocatable :: hit(:)
    call get_command_argument(i + 1, a1); call get_command_argument(i + 2, a2); call get_command_argument(i + 3, a3)
    is_ = findloc(scene_name, trim(a1), dim=1)
    call arg_value(i + 2, 'VARIANT', iv_); call arg_value(i + 3, 'EPISODES', neps)
    if (is_ < 1 .or. iv_ < V_LIB .or. iv_ > V_LIB_FD) error stop 'usage: --profile-steps SCENE VARIANT(1..2) EPISODES'
    allocate (hit(sc(is_)%nsteps))
    call integ(is_, iv_)%init_from_pair(sc(is_)%t0, sc(is_)%q0, sc(is_)%q1, stat)
    call must(stat, 'init')
    do k = 1, int(sc(is_)%nsteps)
      call integ(is_, iv_)%step(1, stat)
      call must(stat, 'library step')
      hit(k) = integ(is_, iv_)%impact_count() > 0
    end do
    nreg = 0; nimp = 0
    do e = 1, neps
      call integ(is_, iv_)%init_from_pair(sc(is_)%t0, sc(is_)%q0, sc(is_)%q1, stat)
      call must(stat, 'init')
      do k = 1, int(sc(is_)%nsteps)
        if (hit(k)) then
          call counted_impact_step(integ(is_, iv_), stat); nimp = nimp + 1
        else
          call counted_regular_step(integ(is_, iv_), stat); nreg = nreg + 1
        end if
        call must(stat, 'library step')
        if (integ(is_, iv_)%impact_count() > 0 .neqv. hit(k)) error stop 'profile-steps: the episodes differ'
      end do
    end do
    write (output_unit, '(a,1x,i0,1x,a,1x,i0)') 'regular', nreg, 'impact', nimp
  end subroutine profile_steps_mode
end program throughput
