!> Kepler's problem below a straight wall (issue 27): L = |v|²/2 + 1/|q| (vci_test_kepler's kepler_t,
!> n = 2) with the wall q₂ <= c (gap c - q₂ >= 0), and its reference, the Kepler flow in closed form
!> (Lagrange's f and g functions in the eccentric anomaly) between elastic reflections (v₂ -> -v₂),
!> each impact time found on that closed form. Independent of the vci library's integrators.
module vci_test_kepler_line
  use vci
  use vci_test_kepler, only: kepler_t
  implicit none
  private

  type, extends(kepler_t), public :: kepler_line_t
    real(dp) :: wall = 0.8_dp   !< c: the wall is the line q₂ = c, the motion below it
  contains
    procedure :: gaps, gap_gradients, energy
  end type kepler_line_t

  public :: kepler_line_model, kepler_flow, kepler_line_exact

contains

  function kepler_line_model(wall) result(model)
    real(dp), intent(in) :: wall
    type(kepler_line_t) :: model
    model%n = 2
    model%n_gaps = 1
    model%wall = wall
  end function kepler_line_model

  subroutine gaps(self, q, g, stat)
    class(kepler_line_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: g(:)
    integer, intent(inout) :: stat
    g(1) = self%wall - q(2)
  end subroutine gaps

  subroutine gap_gradients(self, q, dg, stat)
    class(kepler_line_t), intent(inout) :: self
    real(dp), intent(in) :: q(:)
    real(dp), intent(out) :: dg(:, :)
    integer, intent(inout) :: stat
    dg(:, 1) = [0.0_dp, -1.0_dp]
  end subroutine gap_gradients

  subroutine energy(self, q, p, e, stat)
    class(kepler_line_t), intent(inout) :: self
    real(dp), intent(in) :: q(:), p(:)
    real(dp), intent(out) :: e
    integer, intent(inout) :: stat
    e = 0.5_dp * sum(p**2) - 1.0_dp / norm2(q)
  end subroutine energy

  !> The Kepler flow (mu = 1, a bound orbit) from (q0, v0) over dt: the change x of eccentric anomaly
  !> solves n dt = x - (1 - r0/a) sin x + (q0.v0/sqrt a)(1 - cos x), i.e. n dt = x - e (sin(E0 + x)
  !> - sin E0), whose root lies within 2e < 2 of n dt: Newton kept in that bracket (bisection when it
  !> leaves it). Then q = f q0 + g v0, v = f' q0 + g' v0.
  subroutine kepler_flow(q0, v0, dt, q, v)
    real(dp), intent(in) :: q0(2), v0(2), dt
    real(dp), intent(out) :: q(2), v(2)
    real(dp) :: r0, a, sqa, mm, sig, x, lo, hi, fx, dfx, r, f, g, fd, gd
    integer :: it
    r0 = norm2(q0)
    a = -1.0_dp / (sum(v0**2) - 2.0_dp / r0)
    sqa = sqrt(a); mm = 1.0_dp / (a * sqa); sig = dot_product(q0, v0)
    lo = mm * dt - 2.0_dp; hi = mm * dt + 2.0_dp; x = mm * dt
    do it = 1, 200
      fx = x - (1.0_dp - r0 / a) * sin(x) + sig / sqa * (1.0_dp - cos(x)) - mm * dt
      if (fx > 0.0_dp) then
        hi = x
      else
        lo = x
      end if
      dfx = 1.0_dp - (1.0_dp - r0 / a) * cos(x) + sig / sqa * sin(x)     ! r / a > 0
      x = x - fx / dfx
      if (.not. (x > lo .and. x < hi)) x = 0.5_dp * (lo + hi)
      if (abs(fx) <= 4.0_dp * epsilon(1.0_dp) * max(1.0_dp, abs(mm * dt)) .or. hi - lo <= 4.0_dp * spacing(x)) exit
    end do
    r = a + (r0 - a) * cos(x) + sig * sqa * sin(x)
    f = 1.0_dp - a / r0 * (1.0_dp - cos(x)); g = dt - (x - sin(x)) / mm
    fd = -sqa * sin(x) / (r * r0); gd = 1.0_dp - a / r * (1.0_dp - cos(x))
    q = f * q0 + g * v0; v = fd * q0 + gd * v0
  end subroutine kepler_flow

  !> The state at time t of the motion from (q0, v0) at t = 0 below the wall q₂ <= c: the Kepler flow
  !> from the last impact, sampled every 1e-3 for the first crossing of q₂ = c, the crossing time by
  !> bisection on the flow to rounding, v₂ -> -v₂ there. n_impacts: the impacts in (0, t]. A return
  !> to the wall within 1e-3 of time that rises above it and leaves again (a graze of that scale)
  !> would be missed; the tests compare the impact count with vci's.
  subroutine kepler_line_exact(q0, v0, c, t, q, v, n_impacts)
    real(dp), intent(in) :: q0(2), v0(2), c, t
    real(dp), intent(out) :: q(2), v(2)
    integer, intent(out) :: n_impacts
    real(dp), parameter :: ds = 1.0e-3_dp
    real(dp) :: t_seg, qs(2), vs(2), s, s_prev, lo, hi, mid
    integer :: it
    t_seg = 0.0_dp; qs = q0; vs = v0; n_impacts = 0
    s = 0.0_dp
    do
      s_prev = s
      s = min(s + ds, t - t_seg)
      call kepler_flow(qs, vs, s, q, v)
      if (q(2) > c) then
        lo = s_prev; hi = s        ! q₂(lo) <= c < q₂(hi)
        do it = 1, 200
          mid = 0.5_dp * (lo + hi)
          if (mid <= lo .or. mid >= hi) exit
          call kepler_flow(qs, vs, mid, q, v)
          if (q(2) > c) then
            hi = mid
          else
            lo = mid
          end if
        end do
        call kepler_flow(qs, vs, lo, q, v)
        t_seg = t_seg + lo; qs = [q(1), c]; vs = [v(1), -v(2)]
        n_impacts = n_impacts + 1
        s = 0.0_dp
        cycle
      end if
      if (t_seg + s >= t) exit
    end do
  end subroutine kepler_line_exact
end module vci_test_kepler_line
