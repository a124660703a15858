!> Exact event-driven reference for the bouncing ellipse (docs/DESIGN.md §8): q = (θ, x, y), free flight
!> under gravity, floor gap g(q) = y − φ(θ) with φ(θ) = sqrt(a² sin²θ + b² cos²θ), frictionless
!> elastic impacts. Independent of the vci library.
!>
!> The motion is chaotic: a rounding error made at one impact grows about tenfold per impact. In
!> double precision the impact times drift from the exact ones by ~1e-13 after five impacts and
!> ~1e-9 after eleven, and the drift depends on compiler flags. So the computation runs in quad
!> precision internally (kind wp; double where the compiler has no quad) from the double inputs
!> taken exactly, and only the results are rounded to double.
module vci_ref_ellipse
  use iso_fortran_env, only: real64, real128
  implicit none
  private

  integer, parameter :: dp = real64
  integer, parameter :: wp = merge(real128, real64, real128 > 0)

  public :: ellipse_params, ellipse_exact, ellipse_energy, ellipse_support

  !> Model parameters; the defaults are the paper's.
  type :: ellipse_params
    real(dp) :: m = 1.0_dp    !< mass
    real(dp) :: g = 9.8_dp    !< gravitational acceleration
    real(dp) :: a = 1.0_dp    !< semi-axis along the body's θ = π/2 direction
    real(dp) :: b = 0.5_dp    !< the other semi-axis
  end type ellipse_params

  !> Status values of ellipse_exact.
  integer, parameter, public :: ellipse_ok = 0
  integer, parameter, public :: ellipse_search_failed = 1    !< root search hit its iteration cap
  integer, parameter, public :: ellipse_too_many_impacts = 2 !< impact cap hit (persistent contact)

  integer, parameter :: max_march = 1000000, max_polish = 200, max_impacts = 1000000

  !> The parameters in working precision, with the inertia.
  type :: model
    real(wp) :: m, g, a, b, inertia
  end type model

contains

  !> Height of the lowest point of the ellipse below its centre, φ(θ).
  pure elemental real(dp) function ellipse_support(par, theta) result(phi)
    type(ellipse_params), intent(in) :: par
    real(dp), intent(in) :: theta
    phi = sqrt((par%a*sin(theta))**2 + (par%b*cos(theta))**2)
  end function ellipse_support

  !> Total energy ½(I θ̇² + m ẋ² + m ẏ²) + m g y, I = m(a² + b²)/4.
  pure real(dp) function ellipse_energy(par, q, qdot) result(e)
    type(ellipse_params), intent(in) :: par
    real(dp), intent(in) :: q(3), qdot(3)
    e = 0.5_dp*par%m*((par%a**2 + par%b**2)/4.0_dp*qdot(1)**2 + qdot(2)**2 + qdot(3)**2) &
        + par%m*par%g*q(3)
  end function ellipse_energy

  !> State at t_final and every impact time in (0, t_final], from (q0, qdot0) at t = 0 with
  !> gap(q0) >= 0. Impacts are located to the working precision; the impact map is
  !> p⁺ = p⁻ + μ∇g, ∇g = (−φ'(θ), 0, 1), with μ keeping the kinetic energy. If the start touches
  !> the floor moving down it bounces at t = 0 (not listed). normal_speeds(k) = −ġ just before
  !> impact k. On a nonzero status the outputs hold the state reached so far.
  subroutine ellipse_exact(par, q0, qdot0, t_final, q, qdot, impact_times, n_impacts, &
                           normal_speeds, status)
    type(ellipse_params), intent(in) :: par
    real(dp), intent(in) :: q0(3), qdot0(3), t_final
    real(dp), intent(out) :: q(3), qdot(3)
    real(dp), allocatable, intent(out) :: impact_times(:)
    integer, intent(out) :: n_impacts
    real(dp), allocatable, intent(out), optional :: normal_speeds(:)
    integer, intent(out), optional :: status
    type(model) :: md
    real(wp), allocatable :: times(:), speeds(:)
    real(wp) :: t, tf, tau, x(3), v(3)
    logical :: leaving, found
    integer :: info

    md = model(real(par%m, wp), real(par%g, wp), real(par%a, wp), real(par%b, wp), &
               real(par%m, wp)*(real(par%a, wp)**2 + real(par%b, wp)**2)/4)
    allocate (times(16), speeds(16))
    n_impacts = 0
    info = ellipse_ok
    t = 0
    tf = real(t_final, wp)
    x = real(q0, wp)
    v = real(qdot0, wp)
    if (gap(md, x) <= 0 .and. gap_rate(md, x(1), v) < 0) call reflect(md, x, v)
    leaving = gap(md, x) <= 0

    do
      call next_impact(md, x, v, tf - t, leaving, tau, found, info)
      if (info /= ellipse_ok .or. .not. found) exit
      if (n_impacts == max_impacts) then
        info = ellipse_too_many_impacts
        exit
      end if
      call flight(md, x, v, tau)
      t = t + tau
      n_impacts = n_impacts + 1
      if (n_impacts > size(times)) then
        call grow(times)
        call grow(speeds)
      end if
      times(n_impacts) = t
      speeds(n_impacts) = -gap_rate(md, x(1), v)
      call reflect(md, x, v)
      leaving = .true.
    end do
    if (info == ellipse_ok) call flight(md, x, v, tf - t)

    q = real(x, dp)
    qdot = real(v, dp)
    impact_times = real(times(:n_impacts), dp)
    if (present(normal_speeds)) normal_speeds = real(speeds(:n_impacts), dp)
    if (present(status)) status = info
  end subroutine ellipse_exact

  pure real(wp) function support(md, theta)
    type(model), intent(in) :: md
    real(wp), intent(in) :: theta
    support = sqrt((md%a*sin(theta))**2 + (md%b*cos(theta))**2)
  end function support

  pure real(wp) function gap(md, q)
    type(model), intent(in) :: md
    real(wp), intent(in) :: q(3)
    gap = q(3) - support(md, q(1))
  end function gap

  !> φ'(θ) = (a² − b²) sinθ cosθ / φ.
  pure real(wp) function support_slope(md, theta)
    type(model), intent(in) :: md
    real(wp), intent(in) :: theta
    support_slope = (md%a**2 - md%b**2)*sin(theta)*cos(theta)/support(md, theta)
  end function support_slope

  !> ġ = ẏ − φ'(θ) θ̇.
  pure real(wp) function gap_rate(md, theta, qdot)
    type(model), intent(in) :: md
    real(wp), intent(in) :: theta, qdot(3)
    gap_rate = qdot(3) - support_slope(md, theta)*qdot(1)
  end function gap_rate

  !> Closed-form free flight over a time tau: θ and x linear, y a parabola.
  pure subroutine flight(md, q, qdot, tau)
    type(model), intent(in) :: md
    real(wp), intent(inout) :: q(3), qdot(3)
    real(wp), intent(in) :: tau
    q(1:2) = q(1:2) + qdot(1:2)*tau
    q(3) = q(3) + qdot(3)*tau - md%g*tau**2/2
    qdot(3) = qdot(3) - md%g*tau
  end subroutine flight

  !> Elastic impact. With n = ∇g and M = diag(I, m, m), v⁺ = v⁻ + μ M⁻¹n; keeping vᵀMv gives
  !> 2μ n·v⁻ + μ² nᵀM⁻¹n = 0, so the nonzero root is μ = −2 n·v⁻ / (nᵀM⁻¹n), and n·v⁺ = −n·v⁻.
  pure subroutine reflect(md, q, qdot)
    type(model), intent(in) :: md
    real(wp), intent(in) :: q(3)
    real(wp), intent(inout) :: qdot(3)
    real(wp) :: n(3), minv(3), mu
    n = [-support_slope(md, q(1)), 0.0_wp, 1.0_wp]
    minv = [1/md%inertia, 1/md%m, 1/md%m]
    mu = -2*dot_product(n, qdot)/dot_product(n, minv*n)
    qdot = qdot + mu*minv*n
  end subroutine reflect

  !> First root tau in (0, window] of the gap along the free flight from (q, qdot), if any.
  !>
  !> Along the flight G(s) = y(s) − φ(θ(s)) has |G''| = |−g − θ̇² φ''| <= K (see curvature_bound).
  !> Hence G(s0 + s) >= G + G' s − K s²/2, so G > 0 up to the positive root of that lower
  !> bound: marching by that root never skips a root. Once G' < 0 and G'² >= 2 K G, the upper
  !> bound G + G' s + K s²/2 has a root s_up, and on [s0, s0 + s_up] G' <= G' + K s_up < 0: the
  !> root there is the first one and unique, and a safeguarded Newton iteration finds it.
  !> leaving: the flight starts on the floor just after an impact (G(0) = 0 up to rounding).
  !> A tangential touch (G and G' both vanishing) is stepped over by at most s_min; it skips
  !> only a penetration shallower than K s_min²/2, which carries no impulse to speak of.
  pure subroutine next_impact(md, q, qdot, window, leaving, tau, found, info)
    type(model), intent(in) :: md
    real(wp), intent(in) :: q(3), qdot(3), window
    logical, intent(in) :: leaving
    real(wp), intent(out) :: tau
    logical, intent(out) :: found
    integer, intent(inout) :: info
    real(wp) :: k, s, g0, g1, s_low, s_up, s_min
    integer :: it

    found = .false.
    tau = 0
    k = md%g + qdot(1)**2*curvature_bound(md)
    s_min = 8*epsilon(1.0_wp)*max(1.0_wp, window)
    s = 0
    do it = 1, max_march
      call gap_along(md, q, qdot, s, g0, g1)
      if (it == 1 .and. leaving) g0 = 0
      if (g0 <= 0 .and. g1 < 0) then
        ! Only rounding can put the march at or past a root: it is the root.
        tau = s
        found = tau <= window
        return
      end if
      if (g1 < 0 .and. g1**2 >= 2*k*g0) then
        s_up = (-g1 - sqrt(g1**2 - 2*k*g0))/k
        call polish(md, q, qdot, s, s + s_up, tau, info)
        found = tau <= window
        return
      end if
      s_low = (g1 + sqrt(g1**2 + 2*k*max(g0, 0.0_wp)))/k
      if (s + s_low > window) return
      s = s + max(s_low, s_min)
      if (s > window) return
    end do
    info = ellipse_search_failed
  end subroutine next_impact

  !> Bound on |φ''|: φ'' = ((a² − b²) cos 2θ − φ'²)/φ with φ >= min(a, b) and
  !> |φ'| <= |a² − b²| / (2 min(a, b)).
  pure real(wp) function curvature_bound(md)
    type(model), intent(in) :: md
    real(wp) :: c, r
    c = abs(md%a**2 - md%b**2)
    r = min(md%a, md%b)
    curvature_bound = (c + (c/(2*r))**2)/r
  end function curvature_bound

  !> Gap and its rate at flight time s from (q, qdot).
  pure subroutine gap_along(md, q, qdot, s, g0, g1)
    type(model), intent(in) :: md
    real(wp), intent(in) :: q(3), qdot(3), s
    real(wp), intent(out) :: g0, g1
    real(wp) :: qs(3), vs(3)
    qs = q
    vs = qdot
    call flight(md, qs, vs, s)
    g0 = gap(md, qs)
    g1 = gap_rate(md, qs(1), vs)
  end subroutine gap_along

  !> Root of the strictly decreasing gap on [lo, hi] (G(lo) > 0 >= G(hi)): Newton, falling back
  !> to bisection whenever a Newton step leaves the bracket.
  pure subroutine polish(md, q, qdot, lo_in, hi_in, root, info)
    type(model), intent(in) :: md
    real(wp), intent(in) :: q(3), qdot(3), lo_in, hi_in
    real(wp), intent(out) :: root
    integer, intent(inout) :: info
    real(wp) :: lo, hi, s, s_new, g0, g1
    integer :: it

    lo = lo_in
    hi = hi_in
    s = lo
    do it = 1, max_polish
      call gap_along(md, q, qdot, s, g0, g1)
      if (g0 > 0) then
        lo = s
      else
        hi = s
      end if
      s_new = s - g0/g1
      if (.not. (s_new > lo .and. s_new < hi)) s_new = (lo + hi)/2
      if (abs(s_new - s) <= 2*epsilon(1.0_wp)*abs(s_new) .or. hi - lo <= 2*spacing(hi)) then
        s = s_new
        exit
      end if
      s = s_new
    end do
    if (it > max_polish) info = ellipse_search_failed
    root = s
  end subroutine polish

  pure subroutine grow(a)
    real(wp), allocatable, intent(inout) :: a(:)
    real(wp), allocatable :: tmp(:)
    allocate (tmp(2*size(a)))
    tmp(:size(a)) = a
    call move_alloc(tmp, a)
  end subroutine grow

end module vci_ref_ellipse
