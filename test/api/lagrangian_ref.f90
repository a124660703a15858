!> Reference numbers for lagrangian_test.c (capi_lagrangian), computed here and never pasted: the
!> walled pendulum (theta'' = -9.8 sin theta, walls at +-1 rad, theta(0) = 0, theta'(0) = 4) run
!> through the Fortran API with the scene's own model (examples/scenes/vci_scene_pendulum_walls.f90)
!> and the settings of examples/pendulum_walls.f90 (lobatto s = 4, h = 0.05, rtol = 1e-15, 200
!> steps), and the exact state at the same time (test/support/vci_ref_pendulum_walls.f90, elliptic
!> functions in quad precision). Writes one line per quantity to the file named by argument 1.
program lagrangian_ref
  use vci
  use vci_scene_pendulum_walls, only: pendulum_walls_t, pendulum_walls_model
  use vci_ref_pendulum_walls, only: pendulum_walls_params, pendulum_walls_exact
  implicit none
  type(pendulum_walls_t), target :: model
  type(vci_integrator_t) :: integ
  type(pendulum_walls_params) :: params
  character(len=512) :: path
  real(dp) :: q(1), p(1), theta, omega
  real(dp), allocatable :: times(:)
  integer :: stat, unit, n_exact
  integer(i8) :: k, impacts
  type(vci_stats_t) :: stats
  call get_command_argument(1, path)
  if (len_trim(path) == 0) error stop 'usage: vci_lagrangian_ref FILE'
  model = pendulum_walls_model(.true.)
  call integ%create(model, 5.0e-2_dp, stat)
  if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_LOBATTO, 4, stat)
  if (stat == VCI_OK) call integ%set_tolerances(0.0_dp, 1.0e-15_dp, 30, stat)
  if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, [0.0_dp], [4.0_dp], stat)
  do k = 1, 200
    if (stat /= VCI_OK) exit
    call integ%step(1, stat)
  end do
  if (stat /= VCI_OK) then
    print '(a)', 'lagrangian_ref: '//integ%message()
    error stop 1
  end if
  q = integ%configuration(); p = integ%momentum()
  stats = integ%statistics(); impacts = stats%impacts
  params%g = 9.8_dp; params%ell = 1.0_dp; params%theta_w = 1.0_dp
  call pendulum_walls_exact(params, 0.0_dp, 4.0_dp, integ%time(), theta, omega, n_exact, times, stat)
  if (stat /= 0) error stop 'lagrangian_ref: the exact reference failed'
  open (newunit=unit, file=trim(path), status='replace', action='write')
  write (unit, '(es25.17)') integ%time(), q(1), p(1), theta, omega
  write (unit, '(i0)') impacts, n_exact
  close (unit)
  deallocate (times)   ! main-program allocatables are not freed at its end (LeakSanitizer)
end program lagrangian_ref
