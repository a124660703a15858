!> Same-algorithm hand loops (issue 14, item 1): the yardstick a library step should be compared
!> with. Each regular step does what the library's regular step does, written by hand for one scene
!> with no model type, no callbacks and no LAPACK:
!>
!> - the library's predictor (src/integrate/vci_predictor.f90, vci_predict_start): after two regular steps the quadratic
!>   extrapolation q_k + h (2 v_k - v_{k-1}) (v the steps' velocities), before that q_k + h v_k; the
!>   multiplier extrapolated linearly after two and quadratically after three regular steps; the
!>   history reset at impacts. A start within the tolerance is kept only at round-off (merit <= 1e-3);
!> - the residual of DESIGN.md §1 with the library's per-row scales (the row's terms, the kinetic
!>   term |J||x - a| once a Jacobian is known, a few ulps of sum_j |J_ij||x_j|) and its convergence
!>   test max_i |r_i| / (rtol scale_i) <= 1;
!> - Newton with the analytic Jacobian (constraint row included), rows equilibrated, an LU with
!>   partial pivoting written out for n + m unknowns, the Armijo backtracking test, and the polishing
!>   chord step that takes the solution to about machine precision;
!> - the gap test, the new momentum D2 L_d and the discrete energy E_d = -D3 L_d (the library
!>   reports it every step), the velocity for the next guess.
!>
!> Impacts use the closed-form code of bench/hand_loops.f90: they are rare and are timed apart
!> (bench/throughput.f90 separates the regular-step and the impact cost).
module vci_bench_same
  use, intrinsic :: iso_fortran_env, only: real64, int64
  use vci_bench_hand, only: hand_result_t, ellipse_par_t, pendulum_par_t, ellipse_impacts, pendulum_impacts
  implicit none
  private

  integer, parameter :: dp = real64
  real(dp), parameter :: pi = acos(-1.0_dp)
  real(dp), parameter :: rtol = 1.0e-12_dp
  real(dp), parameter :: floor_factor = 8.0_dp * epsilon(1.0_dp) / rtol   ! the round-off floor, in rtol units

  public :: same_ellipse, same_pendulum
  public :: lu_small, lu_small_solve, merit   ! (the Lobatto hand loop's too: bench/hand_lobatto.f90)

contains

  !> LU with partial pivoting of a(1:n, 1:n) in place; false when a pivot is below 1e-14 of the largest.
  logical function lu_small(n, a, piv) result(ok)
    integer, intent(in) :: n
    real(dp), intent(inout) :: a(:, :)
    integer, intent(out) :: piv(:)
    integer :: i, j, k, p
    real(dp) :: t, dmin, dmax
    do j = 1, n
      p = j
      do i = j + 1, n
        if (abs(a(i, j)) > abs(a(p, j))) p = i
      end do
      piv(j) = p
      if (p /= j) then
        do k = 1, n
          t = a(j, k); a(j, k) = a(p, k); a(p, k) = t
        end do
      end if
      if (a(j, j) == 0.0_dp) cycle
      do i = j + 1, n
        a(i, j) = a(i, j) / a(j, j)
        do k = j + 1, n
          a(i, k) = a(i, k) - a(i, j) * a(j, k)
        end do
      end do
    end do
    dmin = huge(1.0_dp); dmax = 0.0_dp
    do i = 1, n
      dmin = min(dmin, abs(a(i, i))); dmax = max(dmax, abs(a(i, i)))
    end do
    ok = dmin > 1.0e-14_dp * dmax
  end function lu_small

  pure subroutine lu_small_solve(n, a, piv, b)
    integer, intent(in) :: n
    real(dp), intent(in) :: a(:, :)
    integer, intent(in) :: piv(:)
    real(dp), intent(inout) :: b(:)
    integer :: i, k
    real(dp) :: t
    do i = 1, n
      if (piv(i) /= i) then
        t = b(i); b(i) = b(piv(i)); b(piv(i)) = t
      end if
    end do
    do i = 2, n
      do k = 1, i - 1
        b(i) = b(i) - a(i, k) * b(k)
      end do
    end do
    do i = n, 1, -1
      do k = i + 1, n
        b(i) = b(i) - a(i, k) * b(k)
      end do
      b(i) = b(i) / a(i, i)
    end do
  end subroutine lu_small_solve

  pure real(dp) function merit(r, sc)
    real(dp), intent(in) :: r(:), sc(:)
    integer :: i
    merit = 0.0_dp
    do i = 1, size(r)
      merit = max(merit, abs(r(i)) / max(rtol * sc(i), tiny(1.0_dp)))
    end do
  end function merit

  ! ------------------------------------------------------------------------------------------
  !> Ellipse, midpoint L_d with gravity, x = q_{k+1} (3 unknowns).
  subroutine same_ellipse(par, h, t0, q0, q1, nsteps, q, p, e, res)
    type(ellipse_par_t), intent(in) :: par
    real(dp), intent(in) :: h, t0, q0(3), q1(3)
    integer(int64), intent(in) :: nsteps
    real(dp), intent(out) :: q(3), p(3), e
    type(hand_result_t), intent(out) :: res
    integer(int64) :: k
    real(dp) :: mm(3), hg, mg, a2, b2, x(3), a(3), vel(3), r(3), sc(3), jac(3, 3), lu(3, 3), w(3), dx(3)
    real(dp) :: xt(3), rt(3), sct(3), jscale(3), jabs(3), phi, phit, step, qt(3), t2, vel_before(3)
    integer :: piv(3), it, ib, i, depth
    logical :: known, factored
    mm = [par%mass * (par%a**2 + par%b**2) / 4.0_dp, par%mass, par%mass]
    mg = par%mass * par%grav; hg = 0.5_dp * h * mg
    a2 = par%a**2; b2 = par%b**2
    q = q1
    p = mm * (q1 - q0) / h; p(3) = p(3) - hg
    vel = (q1 - q0) / h
    vel_before = 0.0_dp; depth = 0
    jscale = 0.0_dp
    do k = 1, nsteps
      a = q
      if (depth >= 2) then
        x = a + h * (2.0_dp * vel - vel_before)
      else
        x = a + h * vel
      end if
      known = .false.; factored = .false.
      call resid(x, r, sc)
      phi = merit(r, sc)
      do it = 1, 30
        if (phi <= 1.0_dp .and. (it > 1 .or. phi <= 1.0e-3_dp)) exit
        res%newton_iterations = res%newton_iterations + 1
        jac = 0.0_dp
        do i = 1, 3
          jac(i, i) = -mm(i) / h
        end do
        do i = 1, 3
          jscale(i) = sum(abs(jac(i, :)) * abs(x))
          jabs(i) = abs(jac(i, i))
          w(i) = 1.0_dp / maxval(abs(jac(i, :)))
          lu(i, :) = jac(i, :) * w(i)
          dx(i) = r(i) * w(i)
        end do
        known = .true.
        factored = lu_small(3, lu, piv)
        if (.not. factored) then
          res%ok = .false.; return
        end if
        call lu_small_solve(3, lu, piv, dx)
        step = 1.0_dp
        do ib = 0, 12
          xt = x - step * dx
          call resid(xt, rt, sct)
          phit = merit(rt, sct)
          if (phit < (1.0_dp - 1.0e-4_dp * step) * phi) exit
          step = 0.5_dp * step
        end do
        if (ib > 12) then
          res%ok = .false.; return
        end if
        x = xt; r = rt; sc = sct; phi = phit
      end do
      if (phi > 1.0_dp) then
        res%ok = .false.; return
      end if
      if (factored .and. phi > 0.0_dp) then      ! polishing chord step
        dx = r * w
        call lu_small_solve(3, lu, piv, dx)
        xt = x - dx
        call resid(xt, rt, sct)
        res%newton_iterations = res%newton_iterations + 1
        if (merit(rt, sct) <= phi) x = xt
      end if
      if (x(3) - sqrt(a2 * sin(x(1))**2 + b2 * cos(x(1))**2) >= 0.0_dp) then
        p = mm * (x - a) / h; p(3) = p(3) - hg                                    ! D2 L_d(a, x, h)
        e = 0.5_dp * sum(mm * (x - a)**2) / h**2 + 0.5_dp * mg * (a(3) + x(3))    ! -D3 L_d
        vel_before = vel
        vel = (x - a) / h
        depth = min(depth + 1, 3)
        q = x
        cycle
      end if
      call ellipse_impacts(par, h, t0 + real(k, dp) * h, q, p, res, qt, t2)
      if (.not. res%ok) return
      depth = 0
      vel = (q - qt) / t2
      e = 0.5_dp * sum(mm * (q - qt)**2) / t2**2 + 0.5_dp * mg * (qt(3) + q(3))
    end do

  contains

    !> r = D1 L_d(a, x, h) + p and the library's row scales.
    subroutine resid(xx, rr, ss)
      real(dp), intent(in) :: xx(3)
      real(dp), intent(out) :: rr(3), ss(3)
      real(dp) :: d1(3)
      d1 = -mm * (xx - a) / h; d1(3) = d1(3) - hg
      rr = d1 + p
      ss = abs(d1) + abs(p)
      if (known) ss = ss + jabs * abs(xx - a)
      ss = ss + floor_factor * jscale
    end subroutine resid
  end subroutine same_ellipse

  ! ------------------------------------------------------------------------------------------
  !> The paper's pendulum, L_d anchored at q, omega_d = (f(th)(v_th - th) - (v_ph - ph))/h,
  !> x = (theta_{k+1}, phi_{k+1}, lambda).
  subroutine same_pendulum(par, h, t0, q0, q1, nsteps, q, p, e, res)
    type(pendulum_par_t), intent(in) :: par
    real(dp), intent(in) :: h, t0, q0(2), q1(2)
    integer(int64), intent(in) :: nsteps
    real(dp), intent(out) :: q(2), p(2), e
    type(hand_result_t), intent(out) :: res
    integer(int64) :: k
    real(dp) :: ml2, mgl, s, c, f, x(3), a(2), vel(2), lam, r(3), sc(3), jac(3, 3), lu(3, 3), w(3), dx(3)
    real(dp) :: xt(3), rt(3), sct(3), jscale(3), jabs(2, 2), phi, phit, step, qn(2), d(2), vel_before(2)
    real(dp) :: lam_before, lam_before2, lam_guess
    integer :: piv(3), it, ib, i, depth
    logical :: known, factored
    ml2 = par%mass * par%length**2; mgl = par%mass * par%grav * par%length
    q = q1
    s = sin(q0(1))
    p = [ml2 * (q1(1) - q0(1)) / h, ml2 * (q1(2) - q0(2)) * s**2 / h]   ! D2 L_d(q0, q1, h)
    vel = (q1 - q0) / h
    lam = 0.0_dp
    vel_before = 0.0_dp; lam_before = 0.0_dp; lam_before2 = 0.0_dp; depth = 0
    jscale = 0.0_dp
    do k = 1, nsteps
      a = q
      s = sin(a(1)); c = cos(a(1)); f = pi + c**2
      lam_guess = lam
      if (depth >= 3) then
        lam_guess = 3.0_dp * (lam - lam_before) + lam_before2
      else if (depth == 2) then
        lam_guess = 2.0_dp * lam - lam_before
      end if
      if (depth >= 2) then
        x = [a(1) + h * (2.0_dp * vel(1) - vel_before(1)), a(2) + h * (2.0_dp * vel(2) - vel_before(2)), lam_guess]
      else
        x = [a(1) + h * vel(1), a(2) + h * vel(2), lam_guess]
      end if
      known = .false.; factored = .false.
      call resid(x, r, sc)
      phi = merit(r, sc)
      do it = 1, 30
        if (phi <= 1.0_dp .and. (it > 1 .or. phi <= 1.0e-3_dp)) exit
        res%newton_iterations = res%newton_iterations + 1
        jac(1, :) = [-ml2 / h, 2.0_dp * ml2 * (x(2) - a(2)) * s * c / h, -f]
        jac(2, :) = [0.0_dp, -ml2 * s**2 / h, 1.0_dp]
        jac(3, :) = [f / h, -1.0_dp / h, 0.0_dp]
        do i = 1, 3
          jscale(i) = sum(abs(jac(i, :)) * abs(x))
          w(i) = 1.0_dp / maxval(abs(jac(i, :)))
          lu(i, :) = jac(i, :) * w(i)
          dx(i) = r(i) * w(i)
        end do
        jabs = abs(jac(1:2, 1:2))
        known = .true.
        factored = lu_small(3, lu, piv)
        if (.not. factored) then
          res%ok = .false.; return
        end if
        call lu_small_solve(3, lu, piv, dx)
        step = 1.0_dp
        do ib = 0, 12
          xt = x - step * dx
          call resid(xt, rt, sct)
          phit = merit(rt, sct)
          if (phit < (1.0_dp - 1.0e-4_dp * step) * phi) exit
          step = 0.5_dp * step
        end do
        if (ib > 12) then
          res%ok = .false.; return
        end if
        x = xt; r = rt; sc = sct; phi = phit
      end do
      if (phi > 1.0_dp) then
        res%ok = .false.; return
      end if
      if (factored .and. phi > 0.0_dp) then      ! polishing chord step
        dx = r * w
        call lu_small_solve(3, lu, piv, dx)
        xt = x - dx
        call resid(xt, rt, sct)
        res%newton_iterations = res%newton_iterations + 1
        if (merit(rt, sct) <= phi) x = xt
      end if
      qn = x(1:2)
      if (par%radius**2 - par%length**2 * sin(qn(1))**2 >= 0.0_dp) then
        d = qn - a
        p = [ml2 * d(1) / h, ml2 * d(2) * s**2 / h]                       ! D2 L_d(a, qn, h)
        e = 0.5_dp * ml2 * (d(1)**2 + d(2)**2 * s**2) / h**2 + mgl * c    ! -D3 L_d
        vel_before = vel
        vel = d / h
        lam_before2 = lam_before; lam_before = lam
        depth = min(depth + 1, 3)
        lam = x(3)
        q = qn
        cycle
      end if
      ! (E_d of an impact step is not computed here: impacts are timed apart)
      call pendulum_impacts(par, h, t0 + real(k, dp) * h, q, p, qn, lam, vel, res)
      if (.not. res%ok) return
      depth = 0
    end do

  contains

    !> Momentum rows D1 L_d(a, x) + p - Omega(a) lambda, the constraint row, and the library's scales.
    subroutine resid(xx, rr, ss)
      real(dp), intent(in) :: xx(3)
      real(dp), intent(out) :: rr(3), ss(3)
      real(dp) :: d1(2), dd(2)
      dd = xx(1:2) - a
      d1(1) = -ml2 * dd(1) / h + ml2 * dd(2)**2 * s * c / h + h * mgl * s
      d1(2) = -ml2 * dd(2) * s**2 / h
      rr(1) = d1(1) + p(1) - f * xx(3)
      rr(2) = d1(2) + p(2) + xx(3)
      ss(1) = abs(d1(1)) + abs(p(1)) + f * abs(xx(3))
      ss(2) = abs(d1(2)) + abs(p(2)) + abs(xx(3))
      rr(3) = (f * dd(1) - dd(2)) / h
      ss(3) = abs(rr(3)) + (f * abs(dd(1)) + abs(dd(2))) / h
      if (known) ss(1:2) = ss(1:2) + matmul(jabs, abs(dd))
      ss = ss + floor_factor * jscale
    end subroutine resid
  end subroutine same_pendulum
end module vci_bench_same
