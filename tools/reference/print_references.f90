!> Prints the reference solutions of the three scenes (docs/DESIGN.md §8) with self-checks.
!>   print_references          human-readable summary
!>   print_references times    one "name count value ..." line per series, read by
!>                             tools/reference/references.py
program print_references
  use iso_fortran_env, only: real64, int64
  use vci_ref_particle, only: particle_exact
  use vci_ref_ellipse, only: ellipse_params, ellipse_exact, ellipse_energy
  use vci_ref_pendulum, only: pendulum_params, pendulum_exact, pendulum_energy
  implicit none

  integer, parameter :: dp = real64
  real(dp), parameter :: pi = acos(-1.0_dp)
  real(dp), parameter :: ell_q0(3) = [pi/2, 0.0_dp, 3.5_dp]
  real(dp), parameter :: ell_v0(3) = [-3.0_dp, 2.0_dp, 0.0_dp]
  real(dp), parameter :: pen_theta0 = 0.75_dp*pi, pen_thetadot0 = pi/4
  ! Independent values from tools/reference/references.py (mpmath, 40 digits, the same double
  ! inputs): the first 7 ellipse impacts (event by event), the pendulum's first impact t1 and
  ! its wall-to-wall transit time (quadrature; the impacts are at t1 + k transit).
  real(dp), parameter :: ell_mp(7) = [0.7505502519170109501071601_dp, &
    1.152508123001762568325881_dp, 2.324423316964847376401767_dp, &
    3.75117892989995001663587_dp, 4.834752798541385540184441_dp, &
    5.942895120344768061222637_dp, 7.354430968719726330119444_dp]
  real(dp), parameter :: pen_t1 = 1.23260159696178838650314_dp
  real(dp), parameter :: pen_transit = 1.315919052795016419565854_dp
  character(len=16) :: mode

  mode = ''
  if (command_argument_count() >= 1) call get_command_argument(1, mode)
  if (mode == 'times') then
    call print_times()
  else
    call particle_summary()
    call ellipse_summary()
    call pendulum_summary()
  end if

contains

  subroutine print_times()
    type(ellipse_params) :: ep
    type(pendulum_params) :: pp
    real(dp), allocatable :: times(:)
    real(dp) :: q(3), qdot(3), theta, phi, thetadot
    integer :: n

    call ellipse_exact(ep, ell_q0, ell_v0, 25.0_dp, q, qdot, times, n)
    call print_series('ellipse_25', times)
    call pendulum_exact(pp, pen_theta0, pen_thetadot0, 0.0_dp, 100.0_dp, theta, phi, thetadot, &
                        times, n)
    call print_series('pendulum_100', times)
    call pendulum_exact(pp, pen_theta0, pen_thetadot0, 0.0_dp, 5.0_dp, theta, phi, thetadot, &
                        times, n)
    call print_series('pendulum_state_5', [theta, phi, thetadot])
  end subroutine print_times

  subroutine print_series(name, values)
    character(len=*), intent(in) :: name
    real(dp), intent(in) :: values(:)
    integer :: i
    write (*, '(a, 1x, i0)', advance='no') name, size(values)
    do i = 1, size(values)
      write (*, '(1x, es24.16e3)', advance='no') values(i)
    end do
    write (*, *)
  end subroutine print_series

  real(dp) function seconds_since(c0)
    integer(int64), intent(in) :: c0
    integer(int64) :: c1, rate
    call system_clock(c1, rate)
    seconds_since = real(c1 - c0, dp)/real(rate, dp)
  end function seconds_since

  subroutine particle_summary()
    real(dp), allocatable :: times(:)
    real(dp) :: x, y, vx, vy
    integer :: n, i

    call particle_exact(1.0_dp, 1.0_dp, 0.0_dp, 9.8_dp, 3.0_dp, x, y, vx, vy, times, n)
    write (*, '(a)') '== particle: y0 = 1, v0 = (1, 0), g = 9.8, t = 3'
    write (*, '(a, i0, a)') '   ', n, ' impacts at'
    write (*, '(4x, es23.16)') (times(i), i = 1, n)
    write (*, '(a, 4es24.16)') '   (x, y, vx, vy)(3) =', x, y, vx, vy
    write (*, '(a, es10.2)') '   energy error =', &
      abs(0.5_dp*(vx**2 + vy**2) + 9.8_dp*y - (0.5_dp + 9.8_dp))
  end subroutine particle_summary

  subroutine ellipse_summary()
    type(ellipse_params) :: ep
    real(dp), allocatable :: times(:), speeds(:), times_b(:)
    real(dp) :: q(3), qdot(3), qb(3), qdotb(3), elapsed
    integer :: n, nb, i, status
    integer(int64) :: c0

    write (*, '(/, a)') '== ellipse: q(0) = (pi/2, 0, 3.5), qdot(0) = (-3, 2, 0), paper parameters'
    call system_clock(c0)
    call ellipse_exact(ep, ell_q0, ell_v0, 25.0_dp, q, qdot, times, n, speeds, status)
    elapsed = seconds_since(c0)
    write (*, '(a, i0, a, es9.2, a)') '   status ', status, ', time for 25 s ', elapsed, ' s'
    write (*, '(a, i0, a, i0)') '   impacts in 2 s: ', count(times <= 2.0_dp), ', in 25 s: ', n
    write (*, '(a)') '    k   impact time              normal speed'
    do i = 1, min(n, 8)
      write (*, '(3x, i2, 2x, es23.16, 2x, f10.6)') i, times(i), speeds(i)
    end do
    write (*, '(a, es10.2)') '   max |impact time - 40-digit value| over the first 7 =', &
      maxval(abs(times(:7) - ell_mp))
    write (*, '(a, es10.2)') '   |energy(25) - energy(0)| =', &
      abs(ellipse_energy(ep, q, qdot) - ellipse_energy(ep, ell_q0, ell_v0))
    ! Chaos: the impact sequence of a start perturbed by 1e-14 in y(0).
    call ellipse_exact(ep, ell_q0 + [0.0_dp, 0.0_dp, 1.0e-14_dp], ell_v0, 25.0_dp, qb, qdotb, &
                       times_b, nb)
    write (*, '(a, i0, a, es9.2)') '   y(0) + 1e-14: ', nb, &
      ' impacts in 25 s; the 6th impact moves by ', abs(times_b(6) - times(6))
  end subroutine ellipse_summary

  subroutine pendulum_summary()
    type(pendulum_params) :: pp, pp_half
    real(dp), allocatable :: times(:), times_half(:)
    real(dp) :: theta, phi, thetadot, e0, th2, ph2, td2, elapsed
    integer :: n, n_half, i, status
    integer(int64) :: c0

    write (*, '(/, a)') '== pendulum in a cylinder: theta(0) = 0.75 pi, thetadot(0) = pi/4, ' // &
      'paper parameters'
    e0 = pendulum_energy(pp, pen_theta0, pen_thetadot0)
    call system_clock(c0)
    call pendulum_exact(pp, pen_theta0, pen_thetadot0, 0.0_dp, 5.0_dp, theta, phi, thetadot, &
                        times, n, status)
    elapsed = seconds_since(c0)
    write (*, '(a, es9.2, a, i0, a, es9.2, a)') '   step ', pp%step, ', status ', status, &
      ', time for 5 s ', elapsed, ' s'
    write (*, '(a, i0, a)') '   ', n, ' impacts in 5 s at'
    write (*, '(4x, es23.16)') (times(i), i = 1, n)
    write (*, '(a, 3es24.16)') '   (theta, phi, thetadot)(5) =', theta, phi, thetadot
    write (*, '(a, es10.2)') '   |energy(5) - energy(0)| =', &
      abs(pendulum_energy(pp, theta, thetadot) - e0)

    call system_clock(c0)
    call pendulum_exact(pp, pen_theta0, pen_thetadot0, 0.0_dp, 100.0_dp, theta, phi, thetadot, &
                        times, n, status)
    elapsed = seconds_since(c0)
    write (*, '(a, i0, a, i0, a, es9.2, a)') '   impacts in 100 s: ', n, ' (status ', status, &
      ', time ', elapsed, ' s)'
    write (*, '(a, es10.2)') '   |energy(100) - energy(0)| =', &
      abs(pendulum_energy(pp, theta, thetadot) - e0)
    write (*, '(a, es10.2)') '   max |impact time - quadrature value| over 100 s =', &
      maxval(abs(times - [(pen_t1 + i*pen_transit, i = 0, n - 1)]))

    ! Accuracy: the same run with half the internal step.
    pp_half%step = pp%step/2
    call pendulum_exact(pp_half, pen_theta0, pen_thetadot0, 0.0_dp, 100.0_dp, th2, ph2, td2, &
                        times_half, n_half)
    if (n_half == n) then
      write (*, '(a, es10.2)') '   step halved: max |impact time change| over 100 s =', &
        maxval(abs(times_half - times))
      write (*, '(a, 3es10.2)') '   step halved: change of (theta, phi, thetadot)(100) =', &
        abs(th2 - theta), abs(ph2 - phi), abs(td2 - thetadot)
    else
      write (*, '(a, i0)') '   step halved: the impact count changes to ', n_half
    end if
  end subroutine pendulum_summary

end program print_references
