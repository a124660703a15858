!> Regular and impact steps of the Lobatto scheme (issue 26 items 2 and 7): the walled pendulum of
!> examples/pendulum_walls.f90 (n = 1, walls at +-1 rad, theta(0) = 0, p(0) = 4) with Lobatto s
!> stages, h = 0.1, rtol 1e-12, for 10 s (18 impacts), and beside it the same pendulum without walls
!> through the library and through the same-algorithm hand loop (bench/hand_lobatto.f90).
!>
!>   vci_bench_lobatto_steps [S [EPISODES [PART]]]   (defaults 4, 200, all; PART = walled, free or
!>                                                   hand runs that part alone, for callgrind)
!>
!> Walled: a first pass finds which steps have an impact; the episodes take those through
!> counted_impact_step and the others through counted_regular_step (bench/step_split.f90), so that
!> callgrind counts each kind apart. Free: episodes of 100 steps through counted_steps (library) and
!> hand_lobatto_steps (hand loop). tools/bench/run_bench.sh runs the parts under callgrind and
!> prints instructions per step; this program prints ns per step (medians of 5 repeats).
program bench_lobatto_steps
  use vci_tool_args, only: arg_value
  use, intrinsic :: iso_fortran_env, only: output_unit
  use vci
  use vci_bench_stats, only: median
  use vci_scene_pendulum_walls, only: pendulum_walls_t, pendulum_walls_model
  use vci_bench_split, only: counted_regular_step, counted_impact_step, counted_steps
  use vci_bench_hand_lobatto, only: hand_lobatto_steps
  implicit none
  integer, parameter :: nsteps = 100, nrep = 5
  real(dp), parameter :: h = 0.1_dp
  type(pendulum_walls_t), target :: walled, free
  type(vci_integrator_t) :: integ, integ_free
  type(vci_stats_t) :: st
  logical :: hit(nsteps), ok
  integer :: s, neps, stat, k, ep, nreg, nimp, rep
  integer(i8) :: c0, c1, rate, treg, timp, its
  real(dp) :: t_reg(nrep), t_imp(nrep), t_free(nrep), t_hand(nrep), th, ph, eh, iters_free
  character(len=32) :: arg, part
  s = 4; neps = 200; part = 'all'
  if (command_argument_count() >= 1) then
    call arg_value(1, 'S', s)
  end if
  if (command_argument_count() >= 2) then
    call arg_value(2, 'EPISODES', neps)
  end if
  if (command_argument_count() >= 3) call get_command_argument(3, part)
  walled = pendulum_walls_model(.true.)
  free = pendulum_walls_model(.false.)
  call setup(integ, walled)
  call setup(integ_free, free)
  ! first pass: which steps of the walled run have an impact
  call integ%init_from_momentum(0.0_dp, [0.0_dp], [4.0_dp], stat); call must(stat, integ)
  do k = 1, nsteps
    call integ%step(1, stat); call must(stat, integ)
    hit(k) = integ%impact_count() > 0
  end do
  call system_clock(count_rate=rate)
  do rep = 1, nrep
    if (part == 'all' .or. part == 'walled') then
      nreg = 0; nimp = 0; treg = 0; timp = 0
      do ep = 1, neps
        call integ%init_from_momentum(0.0_dp, [0.0_dp], [4.0_dp], stat); call must(stat, integ)
        do k = 1, nsteps
          call system_clock(c0)
          if (hit(k)) then
            call counted_impact_step(integ, stat); nimp = nimp + 1
            call system_clock(c1); timp = timp + (c1 - c0)
          else
            call counted_regular_step(integ, stat); nreg = nreg + 1
            call system_clock(c1); treg = treg + (c1 - c0)
          end if
          call must(stat, integ)
          if (integ%impact_count() > 0 .neqv. hit(k)) error stop 'lobatto_steps: the episodes differ'
        end do
      end do
      t_reg(rep) = 1.0e9_dp * real(treg, dp) / real(rate, dp) / nreg
      t_imp(rep) = 1.0e9_dp * real(timp, dp) / real(rate, dp) / nimp
    end if
    if (part == 'all' .or. part == 'free') then
      call system_clock(c0)
      do ep = 1, neps
        call integ_free%init_from_momentum(0.0_dp, [0.0_dp], [4.0_dp], stat); call must(stat, integ_free)
        call counted_steps(integ_free, int(nsteps, i8), stat); call must(stat, integ_free)
      end do
      call system_clock(c1)
      t_free(rep) = 1.0e9_dp * real(c1 - c0, dp) / real(rate, dp) / (neps * nsteps)
    end if
    if (part == 'all' .or. part == 'hand') then
      call system_clock(c0)
      do ep = 1, neps
        call hand_lobatto_steps(s, 9.8_dp, 10.0_dp, h, 0.0_dp, 4.0_dp, int(nsteps, i8), th, ph, eh, its, ok)
        if (.not. ok) error stop 'lobatto_steps: the hand loop failed'
      end do
      call system_clock(c1)
      t_hand(rep) = 1.0e9_dp * real(c1 - c0, dp) / real(rate, dp) / (neps * nsteps)
    end if
  end do
  if (part == 'walled') write (output_unit, '(a,i0,a,i0)') 'regular ', nrep * nreg, ' impact ', nrep * nimp   ! (callgrind's counts: every repeat)
  if (part /= 'all') stop
  ! the hand loop and the library reach the same free state (solver tolerance)
  call integ_free%init_from_momentum(0.0_dp, [0.0_dp], [4.0_dp], stat)
  call counted_steps(integ_free, int(nsteps, i8), stat); call must(stat, integ_free)
  st = integ_free%statistics()
  iters_free = real(st%newton_iterations, dp) / max(1.0_dp, real(st%newton_solves, dp))
  call hand_lobatto_steps(s, 9.8_dp, 10.0_dp, h, 0.0_dp, 4.0_dp, int(nsteps, i8), th, ph, eh, its, ok)
  write (output_unit, '(a,i0,a,i0,a,i0,a,i0)') 'lobatto s = ', s, '   walled: regular steps ', nreg, '   impact steps ', &
    nimp, '   episodes ', neps
  write (output_unit, '(a,f10.1,a,f10.1,a,f6.2)') 'walled, ns/regular step ', median(t_reg), '   ns/impact step ', &
    median(t_imp), '   impact/regular ', median(t_imp) / median(t_reg)
  write (output_unit, '(a,f10.1,a,f10.1,a,f6.2)') 'free, ns/step: library ', median(t_free), '   hand loop ', &
    median(t_hand), '   library/hand ', median(t_free) / median(t_hand)
  write (output_unit, '(a,f6.3,a,f6.3)') 'free, Newton iterations per step (with the polish): library ', iters_free, &
    '   hand loop ', real(its, dp) / nsteps
  write (output_unit, '(a,2es10.2)') 'free, final state library - hand (theta, p): ', &
    abs(integ_free%configuration() - th), abs(integ_free%momentum() - ph)
contains
  subroutine setup(ig, model)
    type(vci_integrator_t), intent(inout) :: ig
    type(pendulum_walls_t), target, intent(inout) :: model
    integer :: st_
    call ig%create(model, h, st_)
    if (st_ == VCI_OK) call ig%set_scheme(VCI_SCHEME_LOBATTO, s, st_)
    if (st_ == VCI_OK) call ig%set_tolerances(0.0_dp, 1.0e-12_dp, 30, st_)
    call must(st_, ig)
    ! VCI_BENCH_WHOLE_IMPACTS=1: impact stages with the whole stage matrix factorised (the path
    ! before bordering, set_bordered_impacts(.false.)), for the before/after comparison
    call get_environment_variable('VCI_BENCH_WHOLE_IMPACTS', arg, status=st_)
    if (st_ == 0 .and. trim(arg) == '1') call ig%set_bordered_impacts(.false.)
    ! VCI_BENCH_BORDER_MIN=k: border stage systems from k unknowns (default 16)
    call get_environment_variable('VCI_BENCH_BORDER_MIN', arg, status=st_)
    if (st_ == 0) then
      read (arg, *) st_
      call ig%set_bordered_impacts(.true., st_)
    end if
    ! VCI_BENCH_POKE=0: the poke screen off (set_poke_samples(.false.)), for its cost (docs/bench/poke.md)
    call get_environment_variable('VCI_BENCH_POKE', arg, status=st_)
    if (st_ == 0 .and. trim(arg) == '0') call ig%set_poke_samples(.false., st_)
    ! VCI_BENCH_REUSE_MIN=k: Newton keeps factors across solves from k unknowns (an experiment)
    call get_environment_variable('VCI_BENCH_REUSE_MIN', arg, status=st_)
    if (st_ == 0) then
      read (arg, *) st_
      call ig%set_solver_paths(8, st_, .true.)
    end if
  end subroutine setup

  subroutine must(st_, ig)
    integer, intent(in) :: st_
    type(vci_integrator_t), intent(inout) :: ig
    if (st_ /= VCI_OK) then
      write (output_unit, '(a)') 'lobatto_steps: '//ig%message()
      error stop 1
    end if
  end subroutine must

end program bench_lobatto_steps
