!> One run of a Kepler scene of docs/STABILITY.md's "Long steps" (test/stability/vci_long_cases.f90),
!> step by step: time, q, p, H - H0 and the impacts of each step (alpha, the point on the wall, p-
!> and p+, the condition and its energies; alpha, q, p-, p+ to 17 digits on the line `full alpha`),
!> the state to 17 digits on the line `full`, and the steps
!> the safety net split so far. Usage (from the build directory):
!>
!>   bin/vci_long_steps_trace SCENE STAGES H SPLITS WALLS [REST]
!>
!> SCENE 2 (Kepler in the circle) or 4 (Kepler below the wall), STAGES of the lobatto scheme (0: midpoint), step
!> H, the net's bound SPLITS (1: off), WALLS 1 (the scene) or 0 (its free flight), REST 1: the first
!> step's predictor starts at rest (a checkpoint with velocity 0). Issue 27's
!> analysis of the rows that end with status 0 far off reads these traces.
program vci_long_steps_trace
  use vci
  use vci_long_cases
  use vci_test_kepler, only: kepler_t
  use vci_kepler_wall, only: kepler_wall_t
  use vci_checkpoint, only: vci_checkpoint_t
  use vci_tool_args, only: arg_value, bad_argument
  implicit none
  class(vci_lagrangian_t), allocatable, target :: model
  type(vci_integrator_t) :: integ
  type(vci_impact_t) :: imp
  type(vci_stats_t) :: st
  type(vci_checkpoint_t) :: cp
  real(dp), allocatable :: q0(:), p0(:), q(:), p(:)
  real(dp) :: h, h0, hh
  integer :: scene, stages, splits, stat, k, nsteps, i, walls
  character(len=32) :: arg
  if (command_argument_count() < 5) then
    write (*, '(a)') 'usage: vci_long_steps_trace SCENE(2|4) STAGES H SPLITS WALLS(0|1)'
    stop 2
  end if
  call arg_value(1, 'SCENE', scene)
  call arg_value(2, 'STAGES', stages)
  call arg_value(3, 'H', h)
  call arg_value(4, 'SPLITS', splits)
  call arg_value(5, 'WALLS', walls)
  call get_command_argument(1, arg)
  if (scene /= LONG_KEPLER_CIRCLE .and. scene /= LONG_KEPLER_WALL) call bad_argument('SCENE', trim(arg), '2 or 4')
  call get_command_argument(5, arg)
  if (walls /= 0 .and. walls /= 1) call bad_argument('WALLS', trim(arg), '0 or 1')
  call get_command_argument(3, arg)
  if (.not. (h > 0.0_dp)) call bad_argument('H', trim(arg), 'positive')
  if (scene == LONG_KEPLER_WALL .and. walls == 1) then
    allocate (kepler_wall_t :: model)
    select type (model)
    type is (kepler_wall_t)
      model%w = kepler_wall_w
    end select
    model%n_gaps = 1
  else if (scene == LONG_KEPLER_CIRCLE .and. walls == 1) then
    allocate (kepler_circle_t :: model); model%n_gaps = 1
  else
    allocate (kepler_t :: model)
  end if
  model%n = 2
  call long_start(scene, q0, p0)
  call integ%create(model, h, stat)
  if (stat == VCI_OK .and. stages == 0) call integ%set_scheme(VCI_SCHEME_MIDPOINT, 1, stat)
  if (stat == VCI_OK .and. stages > 0) call integ%set_scheme(VCI_SCHEME_LOBATTO, stages, stat)
  if (stat == VCI_OK) call integ%set_step_splits(splits, stat)
  if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q0, p0, stat)
  if (stat == VCI_OK .and. command_argument_count() >= 6) then
    call get_command_argument(6, arg)
    if (trim(arg) == '1') then
      ! REST 1: the predictor starts the first step at rest (a checkpoint with velocity 0), as in
      ! test_kepler_spurious_root_reversal: its Newton solve is damped and the reversal check runs
      cp = integ%checkpoint()
      cp%velocity = 0.0_dp
      call integ%restore(cp, stat)
    end if
  end if
  if (stat /= VCI_OK) then
    write (*, '(a,i0,a,a)') 'status ', stat, ' ', trim(integ%message())
    stop 1
  end if
  h0 = 0.5_dp * sum(p0**2) - 1 / norm2(q0)
  ! counted in real before it becomes an integer: nint of a larger quotient wraps (h = 1e-12: 0 steps, exit 0)
  if (.not. (long_t_final(scene) / h <= 1.0e7_dp)) then
    write (*, '(a,es10.3,a)') 'vci_long_steps_trace: h = ', h, ' takes more than 1e7 steps (one line each); raise H'
    stop 2
  end if
  nsteps = nint(long_t_final(scene) / h)
  do k = 1, nsteps
    call integ%step(1, stat)
    q = integ%configuration(); p = integ%momentum()
    hh = 0.5_dp * sum(p**2) - 1 / norm2(q); st = integ%statistics()
    write (*, '(i4,f8.3,a,2f9.4,a,2f9.4,a,es10.2,a,i2,a,i0)') k, integ%time(), ' q', q, ' p', p, ' H-H0', hh - h0, &
      ' imp', integ%impact_count(), ' split', st%split_steps
    write (*, '(a,4es25.17)') '  full', q, p
    do i = 1, integ%impact_count()
      imp = integ%impact(i)
      write (*, '(a,f8.4,a,2f9.4,a,2f9.4,a,2f9.4,a,i0,a,2es11.3)') '    alpha', imp%alpha, ' q', imp%q, ' p-', imp%p_before, &
        ' p+', imp%p_after, ' cond ', imp%condition, ' E-/E+', imp%energy_before, imp%energy_after
      write (*, '(a,7es25.17)') '    full alpha q p- p+', imp%alpha, imp%q, imp%p_before, imp%p_after
    end do
    if (stat /= 0) then
      print *, 'status', stat, trim(integ%message()); exit
    end if
  end do
end program vci_long_steps_trace
