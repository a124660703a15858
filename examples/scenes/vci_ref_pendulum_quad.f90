!> Reference for the planar pendulum θ̈ = −k sin θ (k = g/l), free or between elastic walls at ±θ_w,
!> for motions without turning points in free flight (a rotating free pendulum, or a walled one with
!> enough energy to reach the walls): then t(θ) = ∫ dθ / |θ̇(θ)| with |θ̇| = sqrt(2(e + k cos θ)) > 0
!> has a smooth integrand, evaluated by composite 16-point Gauss–Legendre quadrature (error far below
!> 1e-15 for the parameters used), and θ(t) by Newton on t(θ). Independent of the vci library.
!> Walls: impact times t_1 + j T_w (T_w = t(−θ_w → θ_w)), θ̇ → −θ̇ at each.
module vci_ref_pendulum_quad
  use iso_fortran_env, only: real64
  implicit none
  private
  integer, parameter :: dp = real64

  type, public :: pendulum_quad_t
    real(dp) :: k = 9.8_dp           !< g / l
    real(dp) :: theta_wall = 0.0_dp  !< 0: no walls
    real(dp) :: theta0 = 0.0_dp, omega0 = 0.0_dp
  end type pendulum_quad_t

  public :: pendulum_quad_state, pendulum_quad_impacts

  real(dp), parameter :: pi = acos(-1.0_dp)

contains

  pure real(dp) function speed(par, e, theta)
    type(pendulum_quad_t), intent(in) :: par
    real(dp), intent(in) :: e, theta
    speed = sqrt(2.0_dp * (e + par%k * cos(theta)))
  end function speed

  !> ∫_a^b dθ / speed (b may be below a: then negative); panels of width <= 0.05.
  pure real(dp) function travel(par, e, a, b) result(t)
    type(pendulum_quad_t), intent(in) :: par
    real(dp), intent(in) :: e, a, b
    real(dp), parameter :: x(8) = [0.0950125098376374_dp, 0.2816035507792589_dp, 0.4580167776572274_dp, &
                                   0.6178762444026438_dp, 0.7554044083550030_dp, 0.8656312023878318_dp, &
                                   0.9445750230732326_dp, 0.9894009349916499_dp]
    real(dp), parameter :: w(8) = [0.1894506104550685_dp, 0.1826034150449236_dp, 0.1691565193950025_dp, &
                                   0.1495959888165767_dp, 0.1246289712555339_dp, 0.0951585116824928_dp, &
                                   0.0622535239386479_dp, 0.0271524594117541_dp]
    integer :: np, i, j
    real(dp) :: hw, mid
    np = max(1, ceiling(abs(b - a) / 0.05_dp))
    hw = 0.5_dp * (b - a) / np
    t = 0.0_dp
    do i = 1, np
      mid = a + (2 * i - 1) * hw
      do j = 1, 8
        t = t + w(j) * (1.0_dp / speed(par, e, mid - hw * x(j)) + 1.0_dp / speed(par, e, mid + hw * x(j)))
      end do
    end do
    t = t * hw
  end function travel

  !> θ with travel(start -> θ) = tau in direction dir (+1/-1).
  pure real(dp) function invert(par, e, start, dir, tau) result(theta)
    type(pendulum_quad_t), intent(in) :: par
    real(dp), intent(in) :: e, start, tau
    integer, intent(in) :: dir
    integer :: it
    real(dp) :: f
    theta = start + dir * speed(par, e, start) * tau
    do it = 1, 60
      f = real(dir, dp) * travel(par, e, start, theta) - tau
      theta = theta - dir * f * speed(par, e, theta)
      if (abs(f) < 1.0e-16_dp * max(1.0_dp, tau)) exit
    end do
  end function invert

  !> Impact times in (0, t_final] (walls only).
  subroutine pendulum_quad_impacts(par, t_final, times, n)
    type(pendulum_quad_t), intent(in) :: par
    real(dp), intent(in) :: t_final
    real(dp), allocatable, intent(out) :: times(:)
    integer, intent(out) :: n
    real(dp) :: e, t1, tw
    integer :: dir, j
    e = 0.5_dp * par%omega0**2 - par%k * cos(par%theta0)
    dir = merge(1, -1, par%omega0 >= 0.0_dp)
    t1 = dir * travel(par, e, par%theta0, dir * par%theta_wall)
    tw = travel(par, e, -par%theta_wall, par%theta_wall)
    n = 0
    if (t1 <= t_final) n = 1 + floor((t_final - t1) / tw)
    allocate (times(n))
    do j = 1, n
      times(j) = t1 + (j - 1) * tw
    end do
  end subroutine pendulum_quad_impacts

  !> θ(t) and θ̇(t).
  subroutine pendulum_quad_state(par, t, theta, omega)
    type(pendulum_quad_t), intent(in) :: par
    real(dp), intent(in) :: t
    real(dp), intent(out) :: theta, omega
    real(dp) :: e, t1, tw, tau
    integer :: dir, j, dj
    e = 0.5_dp * par%omega0**2 - par%k * cos(par%theta0)
    dir = merge(1, -1, par%omega0 >= 0.0_dp)
    if (par%theta_wall <= 0.0_dp) then
      theta = invert(par, e, par%theta0, dir, t)
      omega = dir * speed(par, e, theta)
      return
    end if
    t1 = dir * travel(par, e, par%theta0, dir * par%theta_wall)
    if (t < t1) then
      theta = invert(par, e, par%theta0, dir, t)
      omega = dir * speed(par, e, theta)
      return
    end if
    tw = travel(par, e, -par%theta_wall, par%theta_wall)
    j = floor((t - t1) / tw)
    tau = t - t1 - j * tw
    dj = dir * (-1)**j            ! the wall of impact j+1 is at dj * theta_wall; then moving -dj
    theta = invert(par, e, dj * par%theta_wall, -dj, tau)
    omega = -dj * speed(par, e, theta)
  end subroutine pendulum_quad_state
end module vci_ref_pendulum_quad
