!> Kepler's problem below a straight wall (issue 27's third scene): L = |v|^2/2 + 1/|q| (mu = 1,
!> attracting centre at the origin), admissible set q2 <= w, elastic impact v2 -> -v2 on q2 = w.
!> The wall does not pass through the centre, so each impact changes the orbit (energy is kept,
!> angular momentum is not); w is chosen so every orbit keeps its pericentre well away from the
!> centre (kepler_wall_exact reports the smallest pericentre met).
!>
!> Two references, independent of each other and of the vci library (quad precision inside):
!> - kepler_wall_exact: closed form. Between impacts the orbit's elements (a, e, perifocal
!>   basis P, Q) give q(E) = a (cos E - e) P + b sin E Q and t(E) from Kepler's equation
!>   E - e sin E = n t + M0. The wall is A cos E + B sin E = C in the eccentric anomaly, solved in
!>   closed form (E = phi - acos(C / R), the outward crossing); the state at a time by Newton on
!>   Kepler's equation.
!> - kepler_wall_rk4: classical Runge-Kutta on q'' = -q/|q|^3 with a fixed small step, each impact
!>   located by bisection on the length of the step from the last grid point that crosses the wall.
!> test_kepler_wall_reference checks one against the other.
module vci_kepler_wall
  use vci
  use iso_fortran_env, only: real128
  use vci_test_kepler, only: kepler_t
  implicit none
  private

  integer, parameter :: qp = real128
  real(qp), parameter :: pi_q = 3.14159265358979323846264338327950288_qp

  !> Kepler's problem (vci_test_kepler's model) with the wall q2 <= w.
  type, extends(kepler_t), public :: kepler_wall_t
    real(dp) :: w = 0.5_dp   !< the wall's height
  contains
    procedure :: gaps => kw_gaps, gap_gradients => kw_gap_gradients, energy => kw_energy
  end type kepler_wall_t

  public :: kepler_wall_exact, kepler_wall_rk4

contains

  subroutine kw_gaps(self, q, g, stat)
    class(kepler_wall_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = self%w - q(2)
  end subroutine kw_gaps

  subroutine kw_gap_gradients(self, q, dg, stat)
    class(kepler_wall_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg(:, 1) = [0.0_dp, -1.0_dp]
  end subroutine kw_gap_gradients

  subroutine kw_energy(self, q, p, e, stat)
    class(kepler_wall_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * sum(p**2) - 1.0_dp / norm2(q)
  end subroutine kw_energy

  !> Closed-form state at time t >= 0 from (q0, v0) at t = 0 below the wall q2 <= w (bound orbits
  !> only), the impacts met (n_impacts, their times in `times` up to its size) and the smallest
  !> pericentre distance a (1 - e) of the orbits flown.
  subroutine kepler_wall_exact(w, q0, v0, t, q, v, n_impacts, times, min_pericentre)
    real(dp), intent(in) :: w, q0(2), v0(2), t
    real(dp), intent(out) :: q(2), v(2)
    integer, intent(out) :: n_impacts
    real(dp), intent(out) :: times(:)
    real(dp), intent(out) :: min_pericentre
    real(qp) :: qq(2), vv(2), tt, a, e, b, n, pp(2), qb(2), r, hm, ev(2), e0, m0, aa, bb, cc, rr, phi, es, dt
    real(qp) :: ww
    qq = real(q0, qp); vv = real(v0, qp); tt = 0; ww = real(w, qp)
    n_impacts = 0; times = 0; min_pericentre = huge(1.0_dp)
    do
      ! elements of the orbit through (qq, vv)
      r = norm2(qq)
      a = -1 / (sum(vv**2) - 2 / r)
      hm = qq(1) * vv(2) - qq(2) * vv(1)
      ev = [vv(2) * hm, -vv(1) * hm] - qq / r
      e = norm2(ev)
      pp = ev / e
      qb = sign(1.0_qp, hm) * [-pp(2), pp(1)]
      b = a * sqrt(1 - e**2)
      n = a**(-1.5_qp)
      min_pericentre = min(min_pericentre, real(a * (1 - e), dp))
      e0 = atan2(sum(qq * vv) / sqrt(a), 1 - r / a)   ! e sin E, e cos E
      m0 = e0 - e * sin(e0)
      ! outward crossing of the wall: A cos E + B sin E = C, dy/dE > 0 at E = phi - acos(C/R)
      aa = a * pp(2); bb = b * qb(2); cc = ww + a * e * pp(2)
      rr = hypot(aa, bb)
      dt = huge(1.0_qp)
      if (abs(cc) < rr) then
        phi = atan2(bb, aa)
        es = phi - acos(cc / rr)
        ! the first crossing after E0 (a start on the wall moving inwards excludes E0 itself)
        es = es - 2 * pi_q * floor((es - e0) / (2 * pi_q))
        if (es - e0 < 1.0e-25_qp) es = es + 2 * pi_q
        dt = (es - e * sin(es) - m0) / n
      end if
      if (tt + dt > real(t, qp)) then
        call orbit_state(a, e, b, n, pp, qb, m0 + n * (real(t, qp) - tt), qq, vv)
        exit
      end if
      call orbit_state(a, e, b, n, pp, qb, es - e * sin(es), qq, vv)
      qq(2) = ww; vv(2) = -vv(2)
      tt = tt + dt
      n_impacts = n_impacts + 1
      if (n_impacts <= size(times)) times(n_impacts) = real(tt, dp)
    end do
    q = real(qq, dp); v = real(vv, dp)
  end subroutine kepler_wall_exact

  !> State on the orbit (a, e, b, n, P, Q) at mean anomaly m (Newton on Kepler's equation).
  subroutine orbit_state(a, e, b, n, pp, qb, m, q, v)
    real(qp), intent(in) :: a, e, b, n, pp(2), qb(2), m
    real(qp), intent(out) :: q(2), v(2)
    real(qp) :: ea, f
    integer :: it
    ea = m + e * sin(m)
    do it = 1, 60
      f = (ea - e * sin(ea) - m) / (1 - e * cos(ea))
      ea = ea - f
      if (abs(f) < 1.0e-32_qp * max(1.0_qp, abs(m))) exit
    end do
    q = a * (cos(ea) - e) * pp + b * sin(ea) * qb
    v = n * a / (1 - e * cos(ea)) * (-sin(ea) * pp + sqrt(1 - e**2) * cos(ea) * qb)
  end subroutine orbit_state

  !> The same motion by classical Runge-Kutta (step k) in quad precision; an impact is located by
  !> bisecting the length s of one RK step from the last grid point (the RK step of length s is the
  !> motion to O(s^5)), reflected, and the run goes on from there on the grid shifted to the impact.
  subroutine kepler_wall_rk4(w, q0, v0, t, k, q, v, n_impacts, times)
    real(dp), intent(in) :: w, q0(2), v0(2), t, k
    real(dp), intent(out) :: q(2), v(2)
    integer, intent(out) :: n_impacts
    real(dp), intent(out) :: times(:)
    real(qp) :: y(4), y1(4), tt, hq, lo, hi, mid, ww
    integer :: it
    y = [real(q0, qp), real(v0, qp)]; tt = 0; ww = real(w, qp)
    n_impacts = 0; times = 0
    do while (tt < real(t, qp))
      hq = min(real(k, qp), real(t, qp) - tt)
      y1 = rk4(y, hq)
      if (y1(2) > ww) then
        lo = 0; hi = hq
        do it = 1, 120
          mid = 0.5_qp * (lo + hi)
          if (rk4_y(y, mid) > ww) then
            hi = mid
          else
            lo = mid
          end if
        end do
        y1 = rk4(y, hi); y1(2) = ww; y1(4) = -y1(4)
        hq = hi
        n_impacts = n_impacts + 1
        if (n_impacts <= size(times)) times(n_impacts) = real(tt + hq, dp)
      end if
      y = y1; tt = tt + hq
    end do
    q = real(y(1:2), dp); v = real(y(3:4), dp)
  end subroutine kepler_wall_rk4

  real(qp) function rk4_y(y, h)
    real(qp), intent(in) :: y(4), h
    real(qp) :: z(4)
    z = rk4(y, h)
    rk4_y = z(2)
  end function rk4_y

  function rk4(y, h) result(z)
    real(qp), intent(in) :: y(4), h
    real(qp) :: z(4), k1(4), k2(4), k3(4), k4(4)
    k1 = f(y); k2 = f(y + 0.5_qp * h * k1); k3 = f(y + 0.5_qp * h * k2); k4 = f(y + h * k3)
    z = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
  end function rk4

  function f(y) result(d)
    real(qp), intent(in) :: y(4)
    real(qp) :: d(4)
    d = [y(3:4), -y(1:2) / norm2(y(1:2))**3]
  end function f
end module vci_kepler_wall
