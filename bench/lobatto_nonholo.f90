!> Regular and impact steps of the Lobatto scheme with a nonholonomic constraint (issue 25): the
!> paper's pendulum in the cylinder (examples/scenes/vci_scene_pendulum.f90, n = 2, m = 1) from the
!> exact start of docs/RESULTS.md (theta = 3 pi/4, phi = 0, thetadot = pi/4, phidot = f thetadot),
!> T = 5 s (3 impacts), Newton rtol 1e-14 as the results' Lobatto rows (or RTOL), with s stages and
!> step h.
!>
!>   vci_bench_lobatto_nonholo [S [H [EPISODES [PART [RTOL]]]]]   (defaults 3, 0.05, 50, all, 1e-14; PART = run:
!>                                                        the episodes only, for callgrind; PART =
!>                                                        whole: whole runs timed as the results
!>                                                        driver times them, see whole_runs)
!>
!> A first pass finds which steps have an impact; the episodes take those through
!> counted_impact_step and the others through counted_regular_step (bench/step_split.f90), so that
!> callgrind counts each kind apart (tools/bench/run_bench.sh --lobatto). Printed: ns per regular and
!> per impact step (medians of 5 repeats), their ratio, the impact steps' share of the run's time,
!> Newton iterations per solve (with the polish) and the final configuration (the same trajectory
!> before and after a change of the step's arithmetic, to solver tolerance).
program bench_lobatto_nonholo
  use vci_tool_args, only: arg_value
  use, intrinsic :: iso_fortran_env, only: output_unit
  use vci
  use vci_bench_stats, only: median
  use vci_scene_pendulum, only: pendulum_lagrangian_t, pendulum_lagrangian_model, pendulum_f
  use vci_bench_split, only: counted_regular_step, counted_impact_step
  implicit none
  integer, parameter :: nrep = 5
  real(dp), parameter :: pi = acos(-1.0_dp), t_end = 5.0_dp
  type(pendulum_lagrangian_t), target :: pend
  type(vci_integrator_t) :: integ
  type(vci_stats_t) :: st
  logical, allocatable :: hit(:)
  integer :: s, neps, stat, k, ep, nreg, nimp, rep, nsteps
  integer(i8) :: c0, c1, rate, treg, timp
  real(dp) :: h, t_reg(nrep), t_imp(nrep), q0(2), p0(2), qd0(2), rtol
  character(len=32) :: arg, part
  s = 3; h = 0.05_dp; neps = 50; part = 'all'; rtol = 1.0e-14_dp
  if (command_argument_count() >= 1) then
    call arg_value(1, 'S', s)
  end if
  if (command_argument_count() >= 2) then
    call arg_value(2, 'H', h)
  end if
  if (command_argument_count() >= 3) then
    call arg_value(3, 'EPISODES', neps)
  end if
  if (command_argument_count() >= 4) call get_command_argument(4, part)
  if (command_argument_count() >= 5) then
    call arg_value(5, 'RTOL', rtol)
  end if
  nsteps = nint(t_end / h); h = t_end / nsteps
  q0 = [0.75_dp * pi, 0.0_dp]
  qd0 = [pi / 4.0_dp, pendulum_f(q0(1)) * pi / 4.0_dp]
  pend = pendulum_lagrangian_model()
  p0 = pend%mass * pend%length**2 * [qd0(1), sin(q0(1))**2 * qd0(2)]
  if (part == 'whole') then
    call whole_runs(); stop
  end if
  call integ%create(pend, h, stat)
  if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_LOBATTO, s, stat)
  if (stat == VCI_OK) call integ%set_tolerances(0.0_dp, rtol, 30, stat)
  ! VCI_BENCH_POKE=0: the poke screen off (set_poke_samples(.false.)), for its cost (docs/bench/poke.md)
  call get_environment_variable('VCI_BENCH_POKE', arg, status=k)
  if (stat == VCI_OK .and. k == 0 .and. trim(arg) == '0') call integ%set_poke_samples(.false., stat)
  if (stat == VCI_OK) call integ%set_impact_energy(VCI_IMPACT_HAMILTONIAN, stat)
  call must(stat)
  allocate (hit(nsteps))
  call integ%init_from_momentum(0.0_dp, q0, p0, stat); call must(stat)
  do k = 1, nsteps
    call integ%step(1, stat); call must(stat)
    hit(k) = integ%impact_count() > 0
  end do
  call system_clock(count_rate=rate)
  do rep = 1, nrep
    nreg = 0; nimp = 0; treg = 0; timp = 0
    do ep = 1, neps
      call integ%init_from_momentum(0.0_dp, q0, p0, stat); call must(stat)
      do k = 1, nsteps
        call system_clock(c0)
        if (hit(k)) then
          call counted_impact_step(integ, stat); nimp = nimp + 1
          call system_clock(c1); timp = timp + (c1 - c0)
        else
          call counted_regular_step(integ, stat); nreg = nreg + 1
          call system_clock(c1); treg = treg + (c1 - c0)
        end if
        call must(stat)
        if (integ%impact_count() > 0 .neqv. hit(k)) error stop 'lobatto_nonholo: the episodes differ'
      end do
    end do
    t_reg(rep) = 1.0e9_dp * real(treg, dp) / real(rate, dp) / max(1, nreg)
    t_imp(rep) = 1.0e9_dp * real(timp, dp) / real(rate, dp) / max(1, nimp)
    if (part == 'run') exit
  end do
  if (part == 'run') then
    write (output_unit, '(a,i0,a,i0)') 'regular ', nreg, ' impact ', nimp   ! (for callgrind's counts)
    stop
  end if
  st = integ%statistics()
  write (output_unit, '(a,i0,a,es9.2,a,i0,a,i0,a,i0)') 'nonholonomic pendulum, lobatto s = ', s, '  h = ', h, &
    ':  regular steps ', nreg, '  impact steps ', nimp, '  episodes ', neps
  write (output_unit, '(a,f10.1,a,f10.1,a,f6.2,a,f5.1,a)') 'ns/regular step ', median(t_reg), '   ns/impact step ', &
    median(t_imp), '   impact/regular ', median(t_imp) / median(t_reg), '   impact share ', &
    100.0_dp * nimp * median(t_imp) / (nimp * median(t_imp) + nreg * median(t_reg)), ' %'
  write (output_unit, '(a,f6.3)') 'Newton iterations per solve (with the polish, last episode) ', &
    real(st%newton_iterations, dp) / max(1.0_dp, real(st%newton_solves, dp))
  write (output_unit, '(a,2es24.16)') 'final configuration ', integ%configuration()
contains
  !> Whole runs as tools/results/vci_results_driver times a row (create, set_scheme, tolerances,
  !> init_from_momentum, integrate over T; CPU time by cpu_time, median of repeats until they sum to
  !> 0.1 s, at least 9, at most 2001), at step sizes between the driver's, with the `discrete` and the
  !> `hamiltonian` condition. One line per run: s, condition, h, steps, CPU ms, repeats, final
  !> configuration (bench/nonholo_vs_cvode.sh compares it with the exact reference and CVODE-Adams's
  !> sweep), Newton iterations per solve (with the polish), impacts of the last repeat and rtol.
  subroutine whole_runs()
    integer, parameter :: max_rep = 2001
    real(dp) :: cpus(max_rep), c0, c1, total
    integer :: mode, nrep_w, stat_w
    type(vci_integrator_t) :: w
    do mode = 1, 2
      total = 0.0_dp; nrep_w = 0
      do while (nrep_w < max_rep .and. (nrep_w < 9 .or. total < 0.1_dp))
        call cpu_time(c0)
        call w%create(pend, h, stat_w)
        if (stat_w == VCI_OK) call w%set_scheme(VCI_SCHEME_LOBATTO, s, stat_w)
        if (stat_w == VCI_OK) call w%set_tolerances(0.0_dp, rtol, 30, stat_w)
        if (stat_w == VCI_OK) call w%set_impact_energy(merge(VCI_IMPACT_DISCRETE, VCI_IMPACT_HAMILTONIAN, mode == 1), &
                                                       stat_w)
        if (stat_w == VCI_OK) call w%init_from_momentum(0.0_dp, q0, p0, stat_w)
        if (stat_w == VCI_OK) call w%integrate(int(nsteps, i8), 1, stat_w)
        call cpu_time(c1)
        if (stat_w /= VCI_OK) then
          write (output_unit, '(a)') 'lobatto_nonholo: '//w%message()
          error stop 1
        end if
        nrep_w = nrep_w + 1; cpus(nrep_w) = c1 - c0; total = total + (c1 - c0)
      end do
      st = w%statistics()
      write (output_unit, '(a,i0,1x,a,es12.5,i7,es13.5,i6,2es25.16,f7.3,i4,es9.1)') 'whole ', s, &
        trim(merge('discrete   ', 'hamiltonian', mode == 1)), h, nsteps, 1.0e3_dp * median(cpus(1:nrep_w)), nrep_w, &
        w%configuration(), real(st%newton_iterations, dp) / max(1.0_dp, real(st%newton_solves, dp)), int(st%impacts), &
        rtol
    end do
  end subroutine whole_runs

  subroutine must(st_)
    integer, intent(in) :: st_
    if (st_ /= VCI_OK) then
      write (output_unit, '(a)') 'lobatto_nonholo: '//integ%message()
      error stop 1
    end if
  end subroutine must

end program bench_lobatto_nonholo
