!> Reference numbers for separable_test.c (capi_separable), computed here and never pasted: the
!> walled pendulum (theta'' = -9.8 sin theta, walls at +-1 rad, theta(0) = 0, theta'(0) = 4, 10 s,
!> 18 impacts) as the Fortran separable scene (examples/scenes/vci_scene_pendulum_walls_sep.f90)
!> with the order-6 composition at h = 0.1, 0.05, 0.025, and the exact state at t = 10
!> (test/support/vci_ref_pendulum_walls.f90). Writes, to the file named by argument 1, one line
!> per step size (h, theta, p, impacts) and then the exact (theta, p, impacts).
program separable_ref
  use vci
  use vci_scene_pendulum_walls_sep, only: pendulum_walls_sep_t, pendulum_walls_sep_model
  use vci_ref_pendulum_walls, only: pendulum_walls_params, pendulum_walls_exact
  implicit none
  type(pendulum_walls_sep_t), target :: model
  type(vci_integrator_t) :: integ
  type(pendulum_walls_params) :: params
  type(vci_stats_t) :: stats
  character(len=512) :: path
  real(dp), parameter :: steps(3) = [0.1_dp, 0.05_dp, 0.025_dp]
  real(dp) :: q(1), p(1), theta, omega
  real(dp), allocatable :: times(:)
  integer :: stat, unit, n_exact, j
  call get_command_argument(1, path)
  if (len_trim(path) == 0) error stop 'usage: vci_separable_ref FILE'
  open (newunit=unit, file=trim(path), status='replace', action='write')
  do j = 1, 3
    model = pendulum_walls_sep_model(.true.)
    call integ%create(model, steps(j), stat)
    if (stat == VCI_OK) call integ%set_scheme(VCI_SCHEME_COMPOSITION, 6, stat)
    if (stat == VCI_OK) call integ%init_from_momentum(0.0_dp, [0.0_dp], [4.0_dp], stat)
    if (stat == VCI_OK) call integ%integrate(int(nint(10.0_dp / steps(j)), i8), 1, stat)
    if (stat /= VCI_OK) then
      print '(a)', 'separable_ref: '//integ%message()
      error stop 1
    end if
    q = integ%configuration(); p = integ%momentum(); stats = integ%statistics()
    write (unit, '(3es25.17,1x,i0)') steps(j), q(1), p(1), stats%impacts
  end do
  params%g = 9.8_dp; params%ell = 1.0_dp; params%theta_w = 1.0_dp
  call pendulum_walls_exact(params, 0.0_dp, 4.0_dp, 10.0_dp, theta, omega, n_exact, times, stat)
  if (stat /= 0) error stop 'separable_ref: the exact reference failed'
  write (unit, '(2es25.17,1x,i0)') theta, omega, n_exact
  close (unit)
  deallocate (times)
end program separable_ref
