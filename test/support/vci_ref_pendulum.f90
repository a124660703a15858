!> High-accuracy reference for the pendulum in a cylinder (docs/DESIGN.md §8): q = (θ, φ),
!> L = ½mℓ²(θ̇² + φ̇² sin²θ) − m g ℓ cos θ, constraint φ̇ = f(θ) θ̇ with f = π + cos²θ, wall gap
!> R² − ℓ² sin²θ >= 0. Independent of the vci library.
!>
!> The constraint is closed: f dθ − dφ = d(Φ(θ) − φ) with Φ(θ) = (π + ½)θ + ¼ sin 2θ, so the motion
!> stays on φ = Φ(θ) + const and has one degree of freedom. Lagrange–d'Alembert with multiplier λ,
!>   θ: mℓ²θ̈ − mℓ²φ̇² sinθ cosθ − mgℓ sinθ = λ f,     φ: d/dt(mℓ² sin²θ φ̇) = −λ,
!> with φ̇ = f θ̇ and λ eliminated gives
!>   A(θ) θ̈ + ½A'(θ) θ̇² = (g/ℓ) sinθ,   A = 1 + f² sin²θ,   ½A' = f sinθ cosθ (f − 2 sin²θ),
!> which is also the Euler–Lagrange equation of L_r = ½mℓ²A(θ)θ̇² − mgℓ cosθ; its energy
!> ½mℓ²Aθ̇² + mgℓ cosθ is conserved. At the wall the only velocity on the constraint that keeps the
!> energy (other than passing through) is θ̇ → −θ̇, with φ̇ = f θ̇ following.
!>
!> The 1-DOF equation is integrated with the 4-stage Gauss–Legendre method (order 8) on a fixed
!> grid, with compensated summation of the increments; a wall event is polished by re-integrating
!> from the start of its step with a single step of adjusted length (safeguarded Newton).
module vci_ref_pendulum
  use iso_fortran_env, only: real64
  implicit none
  private

  integer, parameter :: dp = real64
  real(dp), parameter :: pi = acos(-1.0_dp)

  public :: pendulum_params, pendulum_exact, pendulum_energy

  !> Model parameters (defaults: the paper's) and the step of the internal integrator.
  type :: pendulum_params
    real(dp) :: m = 1.0_dp        !< mass
    real(dp) :: g = 9.8_dp        !< gravitational acceleration
    real(dp) :: ell = 2.0_dp      !< length
    real(dp) :: radius = 1.5_dp   !< cylinder radius R
    !> Internal Gauss–Legendre step. At 5e-3 the paper's run has its impact times within 1e-13
    !> of quadrature over 100 s (rounding-limited; 1e-2 gives 5e-13, 2e-2 gives 4e-9).
    real(dp) :: step = 5.0e-3_dp
  end type pendulum_params

  !> Status values of pendulum_exact.
  integer, parameter, public :: pendulum_ok = 0
  integer, parameter, public :: pendulum_solve_failed = 1      !< stage iteration did not converge
  integer, parameter, public :: pendulum_event_failed = 2      !< wall polish failed, or wall
                                                               !< re-reached within a step of an impact
  integer, parameter, public :: pendulum_too_many_impacts = 3

  integer, parameter :: max_stage_iter = 60, max_polish = 100, max_impacts = 1000000

  !> Butcher tableau of the 4-stage Gauss–Legendre method.
  type :: gauss4
    real(dp) :: a(4, 4), b(4), c(4)
  end type gauss4

contains

  !> Energy ½mℓ²A(θ)θ̇² + mgℓ cosθ of the motion on the constraint.
  pure real(dp) function pendulum_energy(par, theta, thetadot) result(e)
    type(pendulum_params), intent(in) :: par
    real(dp), intent(in) :: theta, thetadot
    e = 0.5_dp*par%m*par%ell**2*(1.0_dp + (f(theta)*sin(theta))**2)*thetadot**2 &
        + par%m*par%g*par%ell*cos(theta)
  end function pendulum_energy

  !> State at t_final and every wall impact time in (0, t_final], from θ(0) = theta0,
  !> θ̇(0) = thetadot0, φ(0) = phi0 (and φ̇(0) = f(θ0) θ̇(0) implied), inside the cylinder.
  !> φ̇ at t_final is f(theta)*thetadot. A start on the wall moving out bounces at t = 0 (not
  !> listed). Walls are detected by the gap's sign at the grid points (spacing par%step): a turn
  !> that only grazes the wall between two of them is not seen. With the default step the
  !> impact times of the paper's run agree with quadrature to 1e-13 over 100 s (docs/DESIGN.md §8
  !> scene; tools/reference/references.py). On a nonzero status the outputs hold the state
  !> reached so far.
  subroutine pendulum_exact(par, theta0, thetadot0, phi0, t_final, theta, phi, thetadot, &
                            impact_times, n_impacts, status)
    type(pendulum_params), intent(in) :: par
    real(dp), intent(in) :: theta0, thetadot0, phi0, t_final
    real(dp), intent(out) :: theta, phi, thetadot
    real(dp), allocatable, intent(out) :: impact_times(:)
    integer, intent(out) :: n_impacts
    integer, intent(out), optional :: status
    type(gauss4) :: gl
    real(dp), allocatable :: times(:)
    real(dp) :: y(2), comp(2), dy(2), t, t_seg, t_next, sigma, g_end
    integer :: k, info
    logical :: just_reflected

    gl = gauss4_tableau()
    allocate (times(16))
    n_impacts = 0
    info = pendulum_ok
    y = [theta0, thetadot0]
    comp = 0.0_dp
    if (gap(par, y(1)) <= 0.0_dp .and. gap_slope(par, y(1))*y(2) < 0.0_dp) y(2) = -y(2)
    just_reflected = .false.
    t = 0.0_dp
    t_seg = 0.0_dp
    k = 0

    do while (t < t_final)
      ! Grid points counted from the last impact, so that t carries one rounding only.
      t_next = min(t_seg + real(k + 1, dp)*par%step, t_final)
      call gl_step(gl, par, y - comp, t_next - t, dy, info)
      if (info /= pendulum_ok) exit
      g_end = gap(par, y(1) + (dy(1) - comp(1)))
      if (g_end >= 0.0_dp) then
        call add_compensated(y, comp, dy)
        t = t_next
        k = k + 1
        just_reflected = .false.
        cycle
      end if
      if (just_reflected) then
        info = pendulum_event_failed
        exit
      end if
      if (n_impacts == max_impacts) then
        info = pendulum_too_many_impacts
        exit
      end if
      call locate_wall(gl, par, y, comp, t_next - t, g_end, sigma, dy, info)
      if (info /= pendulum_ok) exit
      call add_compensated(y, comp, dy)
      t = t + sigma
      y(2) = -y(2)
      comp(2) = -comp(2)
      n_impacts = n_impacts + 1
      if (n_impacts > size(times)) call grow(times)
      times(n_impacts) = t
      t_seg = t
      k = 0
      just_reflected = .true.
    end do

    theta = y(1) - comp(1)
    thetadot = y(2) - comp(2)
    phi = phi0 + big_phi(theta) - big_phi(theta0)
    impact_times = times(:n_impacts)
    if (present(status)) status = info
  end subroutine pendulum_exact

  !> f(θ) = π + cos²θ.
  pure elemental real(dp) function f(theta)
    real(dp), intent(in) :: theta
    f = pi + cos(theta)**2
  end function f

  !> Φ(θ) = ∫ f dθ = (π + ½)θ + ¼ sin 2θ.
  pure elemental real(dp) function big_phi(theta)
    real(dp), intent(in) :: theta
    big_phi = (pi + 0.5_dp)*theta + 0.25_dp*sin(2.0_dp*theta)
  end function big_phi

  pure real(dp) function gap(par, theta)
    type(pendulum_params), intent(in) :: par
    real(dp), intent(in) :: theta
    gap = par%radius**2 - (par%ell*sin(theta))**2
  end function gap

  pure real(dp) function gap_slope(par, theta)
    type(pendulum_params), intent(in) :: par
    real(dp), intent(in) :: theta
    gap_slope = -par%ell**2*sin(2.0_dp*theta)
  end function gap_slope

  !> Right-hand side of the first-order system for (θ, θ̇).
  pure function rhs(par, y) result(dydt)
    type(pendulum_params), intent(in) :: par
    real(dp), intent(in) :: y(2)
    real(dp) :: dydt(2)
    real(dp) :: s, c, ff, a, half_da
    s = sin(y(1))
    c = cos(y(1))
    ff = pi + c**2
    a = 1.0_dp + (ff*s)**2
    half_da = ff*s*c*(ff - 2.0_dp*s**2)
    dydt = [y(2), (par%g/par%ell*s - half_da*y(2)**2)/a]
  end function rhs

  !> Gauss–Legendre nodes on [0, 1] (roots of the shifted Legendre P4) and weights in closed
  !> form; a(i, j) = ∫_0^{c_i} ℓ_j with ℓ_j the Lagrange basis on the nodes, integrated exactly by
  !> the same 4-point rule scaled to [0, c_i] (ℓ_j has degree 3).
  pure function gauss4_tableau() result(gl)
    type(gauss4) :: gl
    real(dp) :: x_in, x_out, w_in, w_out
    integer :: i, j, k
    x_in = sqrt((15.0_dp - 2.0_dp*sqrt(30.0_dp))/35.0_dp)
    x_out = sqrt((15.0_dp + 2.0_dp*sqrt(30.0_dp))/35.0_dp)
    w_in = (18.0_dp + sqrt(30.0_dp))/72.0_dp
    w_out = (18.0_dp - sqrt(30.0_dp))/72.0_dp
    gl%c = 0.5_dp*[1.0_dp - x_out, 1.0_dp - x_in, 1.0_dp + x_in, 1.0_dp + x_out]
    gl%b = [w_out, w_in, w_in, w_out]
    do i = 1, 4
      do j = 1, 4
        gl%a(i, j) = 0.0_dp
        do k = 1, 4
          gl%a(i, j) = gl%a(i, j) + gl%c(i)*gl%b(k)*lagrange(gl%c, j, gl%c(i)*gl%c(k))
        end do
      end do
    end do
  end function gauss4_tableau

  pure real(dp) function lagrange(nodes, j, x)
    real(dp), intent(in) :: nodes(:), x
    integer, intent(in) :: j
    integer :: m
    lagrange = 1.0_dp
    do m = 1, size(nodes)
      if (m /= j) lagrange = lagrange*(x - nodes(m))/(nodes(j) - nodes(m))
    end do
  end function lagrange

  !> Increment dy of one Gauss–Legendre step of length h from y. The stage equations
  !> K_i = F(y + h Σ_j a_ij K_j) are solved by fixed-point iteration (a contraction for h well
  !> below the motion's time scale) until the update reaches rounding level or stops shrinking
  !> near it.
  pure subroutine gl_step(gl, par, y, h, dy, info)
    type(gauss4), intent(in) :: gl
    type(pendulum_params), intent(in) :: par
    real(dp), intent(in) :: y(2), h
    real(dp), intent(out) :: dy(2)
    integer, intent(inout) :: info
    real(dp) :: kk(2, 4), k_new(2, 4), change, change_old, scale
    integer :: i, it

    kk = spread(rhs(par, y), 2, 4)
    change_old = huge(1.0_dp)
    do it = 1, max_stage_iter
      do i = 1, 4
        k_new(:, i) = rhs(par, y + h*matmul(kk, gl%a(i, :)))
      end do
      change = maxval(abs(k_new - kk))
      kk = k_new
      scale = epsilon(1.0_dp)*maxval(abs(kk))
      if (change <= 2.0_dp*scale) exit
      if (it > 3 .and. change >= change_old) then
        ! Stalled: rounding noise is fine, anything larger means the step is too long.
        if (change > 1.0e3_dp*scale) info = pendulum_solve_failed
        exit
      end if
      change_old = change
    end do
    if (it > max_stage_iter) info = pendulum_solve_failed
    dy = h*matmul(kk, gl%b)
  end subroutine gl_step

  !> Kahan summation y <- y + dy; y − comp is the accurate value. Needs IEEE arithmetic as
  !> written (no -ffast-math, which would reassociate it away).
  pure subroutine add_compensated(y, comp, dy)
    real(dp), intent(inout) :: y(2), comp(2)
    real(dp), intent(in) :: dy(2)
    real(dp) :: corrected(2), sum_(2)
    corrected = dy - comp
    sum_ = y + corrected
    comp = (sum_ - y) - corrected
    y = sum_
  end subroutine add_compensated

  !> Step length sigma in (0, h) at which the gap along the numerical flow from (y, comp)
  !> vanishes (gap > 0 at 0, g_hi < 0 at h), and the increment dy of that step. Newton on sigma
  !> with d gap/d sigma ≈ gap'(θ) θ̇ at the step end, bisection whenever it leaves the bracket.
  pure subroutine locate_wall(gl, par, y, comp, h, g_hi, sigma, dy, info)
    type(gauss4), intent(in) :: gl
    type(pendulum_params), intent(in) :: par
    real(dp), intent(in) :: y(2), comp(2), h, g_hi
    real(dp), intent(out) :: sigma, dy(2)
    integer, intent(inout) :: info
    real(dp) :: lo, hi, s_new, g_lo, g_s, ys(2)
    integer :: it

    lo = 0.0_dp
    hi = h
    g_lo = gap(par, y(1) - comp(1))
    sigma = h*g_lo/(g_lo - g_hi)
    do it = 1, max_polish
      call gl_step(gl, par, y - comp, sigma, dy, info)
      ys = y + (dy - comp)
      g_s = gap(par, ys(1))
      if (g_s > 0.0_dp) then
        lo = sigma
      else
        hi = sigma
      end if
      s_new = sigma - g_s/(gap_slope(par, ys(1))*ys(2))
      if (.not. (s_new > lo .and. s_new < hi)) s_new = 0.5_dp*(lo + hi)
      if (abs(s_new - sigma) <= 2.0_dp*epsilon(1.0_dp)*sigma &
          .or. hi - lo <= 2.0_dp*spacing(hi)) exit
      sigma = s_new
    end do
    if (it > max_polish) info = pendulum_event_failed
  end subroutine locate_wall

  pure subroutine grow(a)
    real(dp), allocatable, intent(inout) :: a(:)
    real(dp), allocatable :: tmp(:)
    allocate (tmp(2*size(a)))
    tmp(:size(a)) = a
    call move_alloc(tmp, a)
  end subroutine grow

end module vci_ref_pendulum
