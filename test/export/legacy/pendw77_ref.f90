!> The expected numbers of pendw77.f (legacy_pendulum_walls), computed here and never pasted: the
!> exact state of the walled pendulum (theta'' = -9.8 sin theta, walls at +-1 rad, theta(0) = 0,
!> theta'(0) = 4, m = l = 1) at t = 200 * 0.05 and its impact count, from the independent
!> reference test/support/vci_ref_pendulum_walls.f90 (elliptic functions in quad precision; it does
!> not use the library). Writes t, theta, theta' and the impact count to the file named by
!> argument 1, one per line.
program pendw77_ref
  use vci_ref_pendulum_walls, only: pendulum_walls_params, pendulum_walls_exact
  use iso_fortran_env, only: real64
  implicit none
  integer, parameter :: dp = real64
  type(pendulum_walls_params) :: params
  character(len=512) :: path
  real(dp) :: t, theta, omega
  integer :: n_impacts, stat, unit
  call get_command_argument(1, path)
  if (len_trim(path) == 0) error stop 'usage: vci_legacy_pendw_ref FILE'
  params%g = 9.8_dp; params%ell = 1.0_dp; params%theta_w = 1.0_dp
  t = 0.0_dp + 200 * 0.05_dp   ! the integrator's t0 + k h after 200 steps of h = 0.05
  call pendulum_walls_exact(params, 0.0_dp, 4.0_dp, t, theta, omega, n_impacts, stat=stat)
  if (stat /= 0) error stop 'pendw77_ref: the exact reference failed'
  open (newunit=unit, file=trim(path), status='replace', action='write')
  write (unit, '(es25.17)') t, theta, omega
  write (unit, '(i0)') n_impacts
  close (unit)
end program pendw77_ref
