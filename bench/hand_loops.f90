!> Hand-specialised loops for the paper's three scenes, written from docs/DESIGN.md §1–2 without the
!> library: no model type, no callbacks, no generic Newton, no LAPACK. They are the yardstick of
!> bench/throughput.f90 (issue 2, item 9) and must follow the same trajectories as the library
!> (the same discrete equations, solved to round-off), so that the timing compares equal work.
!>
!> - particle, ellipse: midpoint L_d with gravity. The regular step and the momentum update are
!>   closed form; stage 1 (reach the wall) is closed form for the particle and a safeguarded
!>   scalar Newton on alpha for the ellipse (positions are closed-form in alpha); stage 2 (energy
!>   equation) is a quadratic in the impulse mu, solved in closed form for the reflected root.
!> - pendulum: L_d anchored at q with the constraint omega_d. The regular step is a 3x3 Newton
!>   with the analytic Jacobian (hand-written elimination); the impact is closed form (the wall
!>   fixes theta~, stage 1 is then a quadratic in the sub-step length, stage 2 a square root).
module vci_bench_hand
  use, intrinsic :: iso_fortran_env, only: real64, int64
  implicit none
  private

  integer, parameter :: dp = real64
  real(dp), parameter :: pi = acos(-1.0_dp)
  integer, parameter, public :: max_recorded = 64   !< impact times kept per run

  !> What a run hands back: impacts (time, fraction alpha, impulse) and Newton work.
  type, public :: hand_result_t
    integer :: n_impacts = 0
    real(dp) :: t_impact(max_recorded) = 0.0_dp, alpha(max_recorded) = 0.0_dp, impulse(max_recorded) = 0.0_dp
    integer(int64) :: newton_iterations = 0
    logical :: ok = .true.
  end type hand_result_t

  type, public :: ellipse_par_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp, a = 1.0_dp, b = 0.5_dp
  end type ellipse_par_t

  type, public :: pendulum_par_t
    real(dp) :: mass = 1.0_dp, grav = 9.8_dp, length = 2.0_dp, radius = 1.5_dp
  end type pendulum_par_t

  public :: hand_particle, hand_ellipse, hand_pendulum, ellipse_impacts, pendulum_impacts, solve3

contains

  pure subroutine record(res, t, alpha, mu)
    type(hand_result_t), intent(inout) :: res
    real(dp), intent(in) :: t, alpha, mu
    res%n_impacts = res%n_impacts + 1
    if (res%n_impacts <= max_recorded) then
      res%t_impact(res%n_impacts) = t; res%alpha(res%n_impacts) = alpha; res%impulse(res%n_impacts) = mu
    end if
  end subroutine record

  !> The larger-magnitude root of a mu^2 + b mu + c = 0 (no cancellation): the reflection, never the
  !> pass-through root near 0.
  pure real(dp) function big_root(a, b, c)
    real(dp), intent(in) :: a, b, c
    big_root = -(b + sign(sqrt(max(b * b - 4.0_dp * a * c, 0.0_dp)), b)) / (2.0_dp * a)
  end function big_root

  ! ------------------------------------------------------------------------------------------
  !> Bouncing particle (mass m, gravity g, floor y >= 0). Starts from the pair (q0 at t0, q1 at
  !> t0 + h), takes nsteps forward steps; returns the final (q, p).
  subroutine hand_particle(m, g, h, t0, q0, q1, nsteps, q, p, res)
    real(dp), intent(in) :: m, g, h, t0, q0(2), q1(2)
    integer(int64), intent(in) :: nsteps
    real(dp), intent(out) :: q(2), p(2)
    type(hand_result_t), intent(out) :: res
    integer(int64) :: k
    real(dp) :: a(2), pa(2), qn(2), tau, used, tk, t1, qt(2), pm(2), em, t2, w(2), mu, qa, qb, qc
    integer :: nimp
    q = q1
    p = m * (q1 - q0) / h; p(2) = p(2) - 0.5_dp * h * m * g     ! D2 L_d(q0, q1, h)
    do k = 1, nsteps
      ! regular step: m (q+ - q)/h = p - (h/2) m g e_y, p+ = p - h m g e_y
      qn(1) = q(1) + h * p(1) / m
      qn(2) = q(2) + h * (p(2) / m - 0.5_dp * h * g)
      if (qn(2) >= 0.0_dp) then
        q = qn; p(2) = p(2) - h * m * g
        cycle
      end if
      tk = t0 + real(k, dp) * h
      a = q; pa = p; tau = h; used = 0.0_dp; nimp = 0
      do while (qn(2) < 0.0_dp)
        nimp = nimp + 1
        if (nimp > 16) then
          res%ok = .false.; return
        end if
        ! stage 1: y(t1) = a_y + t1 pa_y/m - g t1^2/2 = 0, the positive root
        qa = 0.5_dp * g; qb = -pa(2) / m; qc = -a(2)
        if (qb > 0.0_dp) then
          t1 = 2.0_dp * qc / (-qb - sqrt(qb * qb - 4.0_dp * qa * qc))
        else
          t1 = (-qb + sqrt(qb * qb - 4.0_dp * qa * qc)) / (2.0_dp * qa)
        end if
        qt(1) = a(1) + t1 * pa(1) / m
        qt(2) = 0.0_dp
        pm = pa; pm(2) = pa(2) - t1 * m * g                          ! D2 L_d(a, qt, t1)
        em = 0.5_dp * m * ((qt(1) - a(1))**2 + (qt(2) - a(2))**2) / t1**2 + 0.5_dp * m * g * (a(2) + qt(2))
        ! stage 2 over t2: w = m (q+ - qt)/t2 = pm + mu e_y - (t2/2) m g e_y; E_d(mu) = em
        t2 = (1.0_dp - t1 / tau) * tau
        w = pm; w(2) = w(2) - 0.5_dp * t2 * m * g
        ! E_d = |w|^2/(2m) + m g qt_y + g t2 w_y / 2, quadratic in mu
        mu = big_root(0.5_dp / m, w(2) / m + 0.5_dp * g * t2, &
                      0.5_dp * (w(1)**2 + w(2)**2) / m + m * g * qt(2) + 0.5_dp * g * t2 * w(2) - em)
        w(2) = w(2) + mu
        qn = qt + t2 * w / m
        call record(res, tk + used + t1, (used + t1) / h, mu)
        used = used + t1
        a = qt; pa = pm; pa(2) = pa(2) + mu; tau = t2
      end do
      q = qn
      p = w; p(2) = w(2) - 0.5_dp * tau * m * g                   ! D2 L_d(qt, q+, t2)
    end do
  end subroutine hand_particle

  ! ------------------------------------------------------------------------------------------
  !> Bouncing ellipse, q = (theta, x, y), M = diag(I, m, m), wall g = y - phi(theta).
  subroutine hand_ellipse(par, h, t0, q0, q1, nsteps, q, p, res)
    type(ellipse_par_t), intent(in) :: par
    real(dp), intent(in) :: h, t0, q0(3), q1(3)
    integer(int64), intent(in) :: nsteps
    real(dp), intent(out) :: q(3), p(3)
    type(hand_result_t), intent(out) :: res
    integer(int64) :: k
    real(dp) :: minv(3), mm(3), m, g, a2, b2, hg, qn(3), qt(3), t2, w(3)
    m = par%mass; g = par%grav; a2 = par%a**2; b2 = par%b**2
    mm = [m * (a2 + b2) / 4.0_dp, m, m]
    minv = 1.0_dp / mm
    hg = 0.5_dp * h * m * g
    q = q1
    p = mm * (q1 - q0) / h; p(3) = p(3) - hg
    do k = 1, nsteps
      ! regular step: M (q+ - q)/h = p - (h/2) m g e_y; p+ = p - h m g e_y
      w = p; w(3) = w(3) - hg
      qn = q + h * minv * w
      if (qn(3) - sqrt(a2 * sin(qn(1))**2 + b2 * cos(qn(1))**2) >= 0.0_dp) then
        q = qn; p = w; p(3) = w(3) - hg
        cycle
      end if
      call ellipse_impacts(par, h, t0 + real(k, dp) * h, q, p, res, qt, t2)
      if (.not. res%ok) return
    end do
  end subroutine hand_ellipse

  !> The impacts of one ellipse step from (q, p) (whose regular end is beyond the wall): stage 1 by a
  !> scalar Newton on alpha, stage 2 in closed form, repeated while the end is beyond the wall.
  !> Returns the new (q, p), and the last sub-step's start qt and length t2.
  subroutine ellipse_impacts(par, h, tk, q, p, res, qt, t2)
    type(ellipse_par_t), intent(in) :: par
    real(dp), intent(in) :: h, tk
    real(dp), intent(inout) :: q(3), p(3)
    type(hand_result_t), intent(inout) :: res
    real(dp), intent(out) :: qt(3), t2
    real(dp) :: minv(3), mm(3), m, g, a2, b2, qn(3), a(3), pa(3), tau, used, alpha, pm(3), em
    real(dp) :: t1, w(3), nrm(3), s, c, phi, mu, ca, cb, cc
    integer :: nimp
    m = par%mass; g = par%grav; a2 = par%a**2; b2 = par%b**2
    mm = [m * (a2 + b2) / 4.0_dp, m, m]
    minv = 1.0_dp / mm
    a = q; pa = p; tau = h; used = 0.0_dp; nimp = 0
    do
      nimp = nimp + 1
      if (nimp > 16) then
        res%ok = .false.; return
      end if
      alpha = stage1_ellipse(a, pa, tau, minv, g, a2, b2, res%newton_iterations)
      if (alpha < 0.0_dp) then
        res%ok = .false.; return
      end if
      t1 = alpha * tau
      qt = a + t1 * minv * pa; qt(3) = qt(3) - 0.5_dp * g * t1**2
      pm = pa; pm(3) = pa(3) - t1 * m * g                           ! D2 L_d(a, qt, t1)
      em = 0.5_dp * sum(mm * (qt - a)**2) / t1**2 + 0.5_dp * m * g * (a(3) + qt(3))
      ! stage 2: w = M (q+ - qt)/t2 = pm + mu n - (t2/2) m g e_y, E_d(qt, q+, t2) = em
      s = sin(qt(1)); c = cos(qt(1)); phi = sqrt(a2 * s**2 + b2 * c**2)
      nrm = [-(a2 - b2) * s * c / phi, 0.0_dp, 1.0_dp]
      t2 = (1.0_dp - alpha) * tau
      w = pm; w(3) = w(3) - 0.5_dp * t2 * m * g
      ! E_d = w.M^-1.w/2 + m g qt_y + g t2 w_y/2
      ca = 0.5_dp * sum(minv * nrm**2)
      cb = sum(minv * nrm * w) + 0.5_dp * g * t2 * nrm(3)
      cc = 0.5_dp * sum(minv * w**2) + m * g * qt(3) + 0.5_dp * g * t2 * w(3) - em
      mu = big_root(ca, cb, cc)
      w = w + mu * nrm
      qn = qt + t2 * minv * w
      call record(res, tk + used + t1, (used + t1) / h, mu)
      used = used + t1
      if (qn(3) - sqrt(a2 * sin(qn(1))**2 + b2 * cos(qn(1))**2) >= 0.0_dp) exit
      a = qt; pa = pm + mu * nrm; tau = t2
    end do
    q = qn
    p = w; p(3) = w(3) - 0.5_dp * t2 * m * g                       ! D2 L_d(qt, q+, t2)
  end subroutine ellipse_impacts

  !> First alpha in (0, 1] with g(q~(alpha)) = 0 for the ellipse, q~(alpha) the free flight from
  !> (a, pa) over alpha tau: bracket by sampling, then Newton kept inside the bracket (bisection
  !> otherwise). Returns -1 when no root is found.
  real(dp) function stage1_ellipse(a, pa, tau, minv, g, a2, b2, iters) result(alpha)
    real(dp), intent(in) :: a(3), pa(3), tau, minv(3), g, a2, b2
    integer(int64), intent(inout) :: iters
    real(dp) :: lo, hi, gv, dg, step, v(3)
    integer :: i
    v = tau * minv * pa
    lo = 0.0_dp; hi = 1.0_dp
    do i = 1, 8
      alpha = real(i, dp) / 8.0_dp
      call ellipse_gap_at(a, v, tau, g, a2, b2, alpha, gv, dg)
      if (gv < 0.0_dp) then
        hi = alpha; exit
      end if
      lo = alpha
    end do
    alpha = 0.5_dp * (lo + hi)
    do i = 1, 60
      call ellipse_gap_at(a, v, tau, g, a2, b2, alpha, gv, dg)
      iters = iters + 1
      if (gv > 0.0_dp) then
        lo = alpha
      else
        hi = alpha
      end if
      step = gv / dg
      if (alpha - step > lo .and. alpha - step < hi .and. dg /= 0.0_dp) then
        alpha = alpha - step
      else
        step = alpha - 0.5_dp * (lo + hi)
        alpha = 0.5_dp * (lo + hi)
      end if
      if (abs(step) <= 4.0_dp * epsilon(1.0_dp) * alpha) exit
    end do
    if (.not. (alpha > 0.0_dp .and. alpha <= 1.0_dp)) alpha = -1.0_dp
  end function stage1_ellipse

  !> Gap of the ellipse along the free flight and its derivative in alpha.
  pure subroutine ellipse_gap_at(a, v, tau, g, a2, b2, al, gv, dg)
    real(dp), intent(in) :: a(3), v(3), tau, g, a2, b2, al
    real(dp), intent(out) :: gv, dg
    real(dp) :: th, y, s, c, ph
    th = a(1) + al * v(1)
    y = a(3) + al * v(3) - 0.5_dp * g * (al * tau)**2
    s = sin(th); c = cos(th); ph = sqrt(a2 * s**2 + b2 * c**2)
    gv = y - ph
    dg = v(3) - g * al * tau**2 - (a2 - b2) * s * c / ph * v(1)
  end subroutine ellipse_gap_at

  ! ------------------------------------------------------------------------------------------
  !> Nonholonomic pendulum in a cylinder, q = (theta, phi), f = pi + cos^2 theta, wall
  !> g = R^2 - l^2 sin^2 theta. Regular step: unknowns (theta+, phi+, lambda),
  !>   R1 = D1_1 L_d(q, q+, h) + p1 - f(theta) lambda,  R2 = D1_2 L_d + p2 + lambda,
  !>   R3 = (f(theta)(theta+ - theta) - (phi+ - phi))/h,
  !> solved by Newton with the analytic 3x3 Jacobian from the extrapolated guess.
  subroutine hand_pendulum(par, h, t0, q0, q1, nsteps, q, p, res)
    type(pendulum_par_t), intent(in) :: par
    real(dp), intent(in) :: h, t0, q0(2), q1(2)
    integer(int64), intent(in) :: nsteps
    real(dp), intent(out) :: q(2), p(2)
    type(hand_result_t), intent(out) :: res
    integer(int64) :: k
    real(dp) :: ml2, mgl, s, c, f, d1, d2, r(3), jac(3, 3), dx(3), x(3), vel(2), lam
    real(dp) :: qn(2), dnorm
    integer :: it
    ml2 = par%mass * par%length**2; mgl = par%mass * par%grav * par%length
    q = q1
    s = sin(q0(1))
    p = [ml2 * (q1(1) - q0(1)) / h, ml2 * (q1(2) - q0(2)) * s**2 / h]   ! D2 L_d(q0, q1, h)
    vel = (q1 - q0) / h
    lam = 0.0_dp
    do k = 1, nsteps
      s = sin(q(1)); c = cos(q(1)); f = pi + c**2
      x = [q(1) + h * vel(1), q(2) + h * vel(2), lam]
      do it = 1, 30
        d1 = x(1) - q(1); d2 = x(2) - q(2)
        r(1) = -ml2 * d1 / h + ml2 * d2**2 * s * c / h + h * mgl * s + p(1) - f * x(3)
        r(2) = -ml2 * d2 * s**2 / h + p(2) + x(3)
        r(3) = (f * d1 - d2) / h
        jac(1, :) = [-ml2 / h, 2.0_dp * ml2 * d2 * s * c / h, -f]
        jac(2, :) = [0.0_dp, -ml2 * s**2 / h, 1.0_dp]
        jac(3, :) = [f / h, -1.0_dp / h, 0.0_dp]
        call solve3(jac, r, dx)
        x = x - dx
        res%newton_iterations = res%newton_iterations + 1
        ! quadratic convergence: once the update is 1e-9 of the motion, x is exact to round-off
        dnorm = abs(x(1) - q(1)) + abs(x(2) - q(2))
        if (abs(dx(1)) + abs(dx(2)) <= 1.0e-9_dp * dnorm) exit
      end do
      qn = x(1:2)
      lam = x(3)
      if (par%radius**2 - par%length**2 * sin(qn(1))**2 >= 0.0_dp) then
        p = [ml2 * (qn(1) - q(1)) / h, ml2 * (qn(2) - q(2)) * s**2 / h]   ! D2 L_d(q, q+, h)
        vel = (qn - q) / h
        q = qn
        cycle
      end if
      call pendulum_impacts(par, h, t0 + real(k, dp) * h, q, p, qn, lam, vel, res)
      if (.not. res%ok) return
    end do
  end subroutine hand_pendulum

  !> The impacts of one pendulum step from (q, p) whose regular end qn is beyond the wall: the wall
  !> fixes theta~, stage 1 is a quadratic in the sub-step length, stage 2 a square root. Returns the
  !> new (q, p), the multiplier and the last sub-step's velocity.
  subroutine pendulum_impacts(par, h, tk, q, p, qn, lam, vel, res)
    type(pendulum_par_t), intent(in) :: par
    real(dp), intent(in) :: h, tk
    real(dp), intent(inout) :: q(2), p(2), qn(2)
    real(dp), intent(out) :: lam, vel(2)
    type(hand_result_t), intent(inout) :: res
    real(dp) :: ml2, mgl, s, c, f, d1, d2, used, tau, s0, a(2), pa(2), thw, t1, t2, qa, qb, qc, qt(2), pm(2)
    real(dp) :: em, st, ct, ft, nrm1, e1, mu, lamt, pn(2)
    integer :: nimp
    integer(int64) :: jw
    ml2 = par%mass * par%length**2; mgl = par%mass * par%grav * par%length
    s0 = asin(par%radius / par%length)
    a = q; pa = p; tau = h; used = 0.0_dp; nimp = 0
    do
      nimp = nimp + 1
      if (nimp > 16) then
        res%ok = .false.; return
      end if
      ! stage 1: the wall fixes theta~ (first root of sin^2 = (R/l)^2 from a(1) towards qn(1));
      ! omega_d = 0 fixes phi~; the momentum row is then a quadratic in the sub-step length t1.
      jw = floor(qn(1) / pi, int64)
      if (qn(1) > a(1)) then
        thw = real(jw, dp) * pi + s0
      else
        thw = real(jw + 1, dp) * pi - s0
      end if
      s = sin(a(1)); c = cos(a(1)); f = pi + c**2
      d1 = thw - a(1); d2 = f * d1
      qa = mgl * s; qb = pa(1) + f * pa(2); qc = ml2 * (-d1 + d2**2 * s * c - f * d2 * s**2)
      t1 = -2.0_dp * qc / (qb + sign(sqrt(max(qb * qb - 4.0_dp * qa * qc, 0.0_dp)), qb))
      if (.not. (t1 > 0.0_dp .and. t1 <= tau)) then
        res%ok = .false.; return
      end if
      qt = [thw, a(2) + d2]
      pm = [ml2 * d1 / t1, ml2 * d2 * s**2 / t1]                       ! D2 L_d(a, qt, t1)
      em = 0.5_dp * ml2 * (d1**2 + d2**2 * s**2) / t1**2 + mgl * c      ! E_d(a, qt, t1)
      ! stage 2 from qt over t2: omega_d: d2 = f~ d1; energy: d1^2 from E_d(qt, q+, t2) = em;
      ! the reflected root leaves the wall (grad g . d > 0)
      st = sin(thw); ct = cos(thw); ft = pi + ct**2
      t2 = (1.0_dp - t1 / tau) * tau
      nrm1 = -2.0_dp * par%length**2 * st * ct
      e1 = 2.0_dp * (em - mgl * ct) * t2**2 / (ml2 * (1.0_dp + ft**2 * st**2))
      d1 = sign(sqrt(max(e1, 0.0_dp)), nrm1); d2 = ft * d1
      lamt = ml2 * d2 * st**2 / t2 - pm(2)
      ! momentum row 1 gives the impulse: D1_1 L_d(qt, q+, t2) + pm1 - f~ lambda~ + mu n1 = 0
      mu = -(-ml2 * d1 / t2 + ml2 * d2**2 * st * ct / t2 + t2 * mgl * st + pm(1) - ft * lamt) / nrm1
      qn = qt + [d1, d2]
      pn = [ml2 * d1 / t2, ml2 * d2 * st**2 / t2]                       ! D2 L_d(qt, q+, t2)
      call record(res, tk + used + t1, (used + t1) / h, mu)
      used = used + t1
      if (par%radius**2 - par%length**2 * sin(qn(1))**2 >= 0.0_dp) exit
      a = qt; pa = pm + [mu * nrm1, 0.0_dp]; tau = t2
    end do
    lam = lamt
    vel = (qn - qt) / t2
    q = qn; p = pn
  end subroutine pendulum_impacts

  !> x = A^-1 b for 3x3 A by Gaussian elimination with partial pivoting.
  pure subroutine solve3(a_in, b_in, x)
    real(dp), intent(in) :: a_in(3, 3), b_in(3)
    real(dp), intent(out) :: x(3)
    real(dp) :: a(3, 3), b(3), t(3), tb, l
    integer :: i, j, piv
    a = a_in; b = b_in
    do j = 1, 2
      piv = j
      do i = j + 1, 3
        if (abs(a(i, j)) > abs(a(piv, j))) piv = i
      end do
      if (piv /= j) then
        t = a(j, :); a(j, :) = a(piv, :); a(piv, :) = t
        tb = b(j); b(j) = b(piv); b(piv) = tb
      end if
      do i = j + 1, 3
        l = a(i, j) / a(j, j)
        a(i, j:3) = a(i, j:3) - l * a(j, j:3)
        b(i) = b(i) - l * b(j)
      end do
    end do
    x(3) = b(3) / a(3, 3)
    x(2) = (b(2) - a(2, 3) * x(3)) / a(2, 2)
    x(1) = (b(1) - a(1, 2) * x(2) - a(1, 3) * x(3)) / a(1, 1)
  end subroutine solve3
end module vci_bench_hand
