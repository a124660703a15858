!> The paper's nonholonomic pendulum of docs/STABILITY.md's "Long steps" (LONG_NH_PENDULUM) with
!> Lobatto, step by step: before each step, where the step's own discrete motion goes: the ends of
!> walls-free steps of length j h / 16 (j = 1 .. 16) from the step's start (the trajectory stage 1
!> brackets on; the sub-step's stage points are not sampled), their least gap and the first j beyond
!> the wall; then the walled step (net as given), its impacts and the steps the net split so far.
!> Then the reference's impact times (vci_ref_pendulum). Usage (from the build directory):
!>
!>   bin/vci_nh_pendulum_steps STAGES H SPLITS
!>
!> It tells whether an impact of a long-step run is a crossing of the coarse discrete motion.
program vci_nh_pendulum_steps
  use vci
  use vci_long_cases, only: LONG_NH_PENDULUM, long_start, long_t_final
  use vci_scene_pendulum, only: pendulum_lagrangian_t, pendulum_lagrangian_model
  use vci_ref_pendulum, only: pendulum_params, pendulum_exact
  use vci_tool_args, only: arg_value, bad_argument
  implicit none
  type(pendulum_lagrangian_t), target :: walled, free
  type(vci_integrator_t) :: integ, probe
  type(vci_impact_t) :: imp
  type(vci_stats_t) :: st
  type(pendulum_params) :: ref
  real(dp), allocatable :: q0(:), p0(:), q(:), p(:), times(:)
  real(dp) :: h, g(1), gmin, gend, h0, e, th, om, thd
  integer :: stages, splits, stat, k, j, i, nsteps, jfirst, nimp
  character(len=32) :: arg
  if (command_argument_count() < 3) then
    write (*, '(a)') 'usage: vci_nh_pendulum_steps STAGES H SPLITS'
    stop 2
  end if
  call arg_value(1, 'STAGES', stages)
  call arg_value(2, 'H', h)
  call arg_value(3, 'SPLITS', splits)
  call get_command_argument(1, arg)
  if (stages < 1 .or. stages > 8) call bad_argument('STAGES', trim(arg), 'in [1, 8]')
  call get_command_argument(2, arg)
  if (.not. (h > 0.0_dp .and. long_t_final(LONG_NH_PENDULUM) / h <= 1.0e5_dp)) &
    call bad_argument('H', trim(arg), 'positive, at most 1e5 steps to t = 5')
  walled = pendulum_lagrangian_model()
  free = walled; free%n_gaps = 0
  call long_start(LONG_NH_PENDULUM, q0, p0)
  call integ%create(walled, h, stat)
  if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_LOBATTO, stages, stat)
  if (stat == VCI_OK) call integ%set_step_splits(splits, stat)
  if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, q0, p0, stat)
  if (stat /= VCI_OK) then
    write (*, '(a)') 'status '//trim(integ%message()); stop 1
  end if
  stat = 0
  call walled%energy(q0, p0, h0, stat)
  nsteps = nint(long_t_final(LONG_NH_PENDULUM) / h)
  do k = 1, nsteps
    q = integ%configuration(); p = integ%momentum()
    ! the step's coarse discrete motion, without walls, from the same (t, q, p)
    gmin = huge(1.0_dp); jfirst = 0
    do j = 1, 16
      call probe%create(free, h * j / 16.0_dp, stat)
      if (stat == VCI_OK) call probe%set_scheme(VCI_SCHEME_LOBATTO, stages, stat)
      if (stat == VCI_OK) call probe%init_from_momentum(integ%time(), q, p, stat)
      if (stat == VCI_OK) call probe%step(1, stat)
      if (stat /= VCI_OK) exit
      call walled%gaps(probe%configuration(), g, stat)
      gmin = min(gmin, g(1)); gend = g(1)
      if (g(1) < 0.0_dp .and. jfirst == 0) jfirst = j
    end do
    if (stat /= VCI_OK) then
      write (*, '(a,i3,a,i0,a)') 'step', k, ': the walls-free step of ', j, '/16 h failed: '//trim(probe%message())
    else
      write (*, '(a,i3,a,f7.3,a,es10.2,a,i0,a,es10.2)') 'step', k, ' from t', integ%time(), &
        '  coarse motion: least gap', gmin, ', first end beyond the wall at j/16 = ', jfirst, ', gap at j = 16', gend
    end if
    call integ%step(1, stat)
    st = integ%statistics()
    i = 0
    call walled%energy(integ%configuration(), integ%momentum(), e, i)   ! (the state kept when the step failed)
    write (*, '(a,i0,a,i0,a,i0,a,es10.2)') '   walled step: status ', stat, ', impacts ', integ%impact_count(), &
      ', steps split so far ', st%split_steps, ', H - H0 ', e - h0
    do i = 1, integ%impact_count()
      imp = integ%impact(i)
      write (*, '(a,f9.5,a,f8.5,a,es10.2)') '     impact at t', imp%t, '  alpha', imp%alpha, '  impulse', imp%impulse
    end do
    if (stat /= VCI_OK) then
      write (*, '(a)') '   '//trim(integ%message()); exit
    end if
  end do
  call pendulum_exact(ref, q0(1), p0(1) / (ref%m * ref%ell**2), q0(2), long_t_final(LONG_NH_PENDULUM), th, om, thd, &
                      times, nimp)
  write (*, '(a,i0,a,*(f9.5))') 'reference: ', nimp, ' impacts at t', times(1:nimp)
end program vci_nh_pendulum_steps
