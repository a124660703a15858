!> Exact references for the Python tests (python/tests), from the project's own reference modules
!> in test/support (which never use the library). Prints with 17 significant digits.
!>   vci_python_ref walls THETA0 OMEGA0 THETA_W T
!>     the pendulum theta'' = -9.8 sin theta between elastic walls at +-THETA_W (l = 1, g = 9.8):
!>     line 1: theta omega n_impacts; then one impact time a line.
!>   vci_python_ref paper THETA0 THETADOT0 PHI0 T
!>     the paper's nonholonomic pendulum in the cylinder (m = 1, g = 9.8, l = 2, R = 1.5):
!>     line 1: theta phi thetadot n_impacts; then one impact time a line.
program vci_python_ref
  use iso_fortran_env, only: dp => real64, error_unit
  use vci_ref_pendulum_walls, only: pendulum_walls_params, pendulum_walls_exact, pendulum_walls_ok
  use vci_ref_pendulum, only: pendulum_params, pendulum_exact, pendulum_ok
  implicit none
  character(len=32) :: what, arg
  real(dp) :: x(4), theta, omega, phi
  real(dp), allocatable :: times(:)
  integer :: i, n_impacts, stat
  type(pendulum_walls_params) :: pw
  type(pendulum_params) :: pp

  if (command_argument_count() /= 5) then
    write (error_unit, '(a)') 'usage: vci_python_ref walls|paper X1 X2 X3 T'
    error stop 2
  end if
  call get_command_argument(1, what)
  do i = 1, 4
    call get_command_argument(i + 1, arg)
    read (arg, *) x(i)
  end do
  select case (trim(what))
  case ('walls')
    pw%theta_w = x(3)
    call pendulum_walls_exact(pw, x(1), x(2), x(4), theta, omega, n_impacts, times, stat)
    if (stat /= pendulum_walls_ok) error stop 1
    print '(2es26.17e3,i8)', theta, omega, n_impacts
  case ('paper')
    call pendulum_exact(pp, x(1), x(2), x(3), x(4), theta, phi, omega, times, n_impacts, stat)
    if (stat /= pendulum_ok) error stop 1
    print '(3es26.17e3,i8)', theta, phi, omega, n_impacts
  case default
    write (error_unit, '(a)') 'vci_python_ref: unknown reference '//trim(what)
    error stop 2
  end select
  do i = 1, n_impacts
    print '(es26.17e3)', times(i)
  end do
end program vci_python_ref
