!> The same-algorithm hand loop of the Lobatto scheme (issue 26 item 7): the yardstick of the
!> library's regular Lobatto step. It does what the library's regular step does, written for the
!> pendulum theta'' = -(g/l) sin theta (n = 1) with no model type, no callbacks and no LAPACK:
!>
!> - unknowns the stage increments y_i - a (i = 1..s); the start from the quadratic through the last
!>   three points at every node after two steps (src/integrate/vci_predictor.f90), before that the
!>   chord a + c_i h v;
!> - the residual rows p_a + F_0 and F_j (j = 1..s-1), F_j = h b_j dL/dq_j + sum_i b_i D_ij dL/dqdot_i,
!>   with the library's row scales (the terms' sizes, 4 (s + 1) ulps of them and 8 ulps of
!>   sum_j |J_ij| |x_j|) and convergence test max_i |r_i| / (rtol scale_i) <= 1; a start at round-off
!>   (merit <= 1e-3) kept;
!> - Newton with the analytic Jacobian, rows equilibrated, LU with partial pivoting, the Armijo
!>   backtracking test, and the polishing chord step;
!> - the gap test (|theta| <= wall), the new momentum from the impulse p_a + h sum_j b_j dL/dq_j, and
!>   E_d = sum_j b_j E(y_j, V_j) (the library reports it every step).
!>
!> Regular steps only (the walls are far enough for the run not to reach them).
module vci_bench_hand_lobatto
  use, intrinsic :: iso_fortran_env, only: real64, int64
  use vci_bench_same, only: lu_small, lu_small_solve, merit   ! (the same LU and merit as the other hand loops)
  implicit none
  private

  integer, parameter :: dp = real64
  integer, parameter :: smax = 6
  real(dp), parameter :: rtol = 1.0e-12_dp   ! (merit's, in bench/same_loops.f90)

  public :: hand_lobatto_steps, lobatto_nodes_weights

contains

  !> Lobatto nodes c(0:s), weights b(0:s) and the differentiation matrix d(0:s, 0:s)
  !> (d(i, j) = l_j'(c_i), l_j the Lagrange basis), for s = 1 .. 4 (the nodes in closed form).
  subroutine lobatto_nodes_weights(s, c, b, d)
    integer, intent(in) :: s
    real(dp), intent(out) :: c(0:s), b(0:s), d(0:s, 0:s)
    integer :: i, j, k
    real(dp) :: w(0:s)
    select case (s)
    case (1)
      c = [0.0_dp, 1.0_dp]; b = [0.5_dp, 0.5_dp]
    case (2)
      c = [0.0_dp, 0.5_dp, 1.0_dp]; b = [1.0_dp, 4.0_dp, 1.0_dp] / 6.0_dp
    case (3)
      c = [0.0_dp, 0.5_dp - 0.5_dp / sqrt(5.0_dp), 0.5_dp + 0.5_dp / sqrt(5.0_dp), 1.0_dp]
      b = [1.0_dp, 5.0_dp, 5.0_dp, 1.0_dp] / 12.0_dp
    case (4)
      c = [0.0_dp, 0.5_dp - 0.5_dp * sqrt(3.0_dp / 7.0_dp), 0.5_dp, 0.5_dp + 0.5_dp * sqrt(3.0_dp / 7.0_dp), 1.0_dp]
      b = [9.0_dp, 49.0_dp, 64.0_dp, 49.0_dp, 9.0_dp] / 180.0_dp
    case default
      error stop 'hand_lobatto: s = 1 .. 4'
    end select
    ! barycentric weights; d(i, j) = (w_j / w_i) / (c_i - c_j), d(i, i) = -sum_(j /= i) d(i, j)
    do i = 0, s
      w(i) = 1.0_dp
      do k = 0, s
        if (k /= i) w(i) = w(i) / (c(i) - c(k))
      end do
    end do
    do i = 0, s
      d(i, i) = 0.0_dp
      do j = 0, s
        if (j == i) cycle
        d(i, j) = (w(j) / w(i)) / (c(i) - c(j))
        d(i, i) = d(i, i) - d(i, j)
      end do
    end do
  end subroutine lobatto_nodes_weights

  !> nsteps regular Lobatto-s steps of the pendulum (k = g/l) from (theta0, p0) with step h; the
  !> final state, E_d of the last step and the Newton iterations (with the polish).
  subroutine hand_lobatto_steps(s, k, wall, h, theta0, p0, nsteps, theta, p, e, iterations, ok)
    integer, intent(in) :: s
    real(dp), intent(in) :: k, wall, h, theta0, p0
    integer(int64), intent(in) :: nsteps
    real(dp), intent(out) :: theta, p, e
    integer(int64), intent(out) :: iterations
    logical, intent(out) :: ok
    real(dp) :: c(0:smax), b(0:smax), d(0:smax, 0:smax), x(smax), r(smax), sc(smax), jac(smax, smax)
    real(dp) :: lu(smax, smax), w(smax), dx(smax), xt(smax), rt(smax), sct(smax), jscale(smax)
    real(dp) :: y(0:smax), v(0:smax), lq(0:smax), a, pa, vel, vel_before, phi, phit, step, t
    integer :: piv(smax), it, ib, i, j, jj, depth
    integer(int64) :: st
    logical :: factored
    call lobatto_nodes_weights(s, c(0:s), b(0:s), d(0:s, 0:s))
    theta = theta0; p = p0; e = 0.0_dp
    vel = p0; vel_before = 0.0_dp; depth = 0
    iterations = 0; ok = .true.
    do st = 1, nsteps
      a = theta; pa = p
      do i = 1, s
        if (depth >= 2) then
          x(i) = h * (c(i) * vel + (0.5_dp * c(i) * (c(i) + 1.0_dp)) * (vel - vel_before))
        else
          x(i) = h * c(i) * vel
        end if
      end do
      jscale(1:s) = 0.0_dp
      factored = .false.
      call resid(x, r, sc)
      phi = merit(r(1:s), sc(1:s))
      do it = 1, 30
        if (phi <= 1.0_dp .and. (it > 1 .or. phi <= 1.0e-3_dp)) exit
        iterations = iterations + 1
        ! dF_j/dy_k = h b_j (-k cos y_j) delta_jk + (1/h) sum_i b_i D_ij D_ik   (rows j = 0..s-1)
        do jj = 1, s
          do i = 1, s
            t = 0.0_dp
            do j = 0, s
              t = t + b(j) * d(j, jj - 1) * d(j, i)
            end do
            jac(jj, i) = t / h
          end do
          if (jj - 1 >= 1) jac(jj, jj - 1) = jac(jj, jj - 1) - h * b(jj - 1) * k * cos(y(jj - 1))
        end do
        do i = 1, s
          jscale(i) = sum(abs(jac(i, 1:s)) * abs(x(1:s)))
          w(i) = 1.0_dp / maxval(abs(jac(i, 1:s)))
          lu(i, 1:s) = jac(i, 1:s) * w(i)
          dx(i) = r(i) * w(i)
        end do
        factored = lu_small(s, lu, piv)
        if (.not. factored) then
          ok = .false.; return
        end if
        call lu_small_solve(s, lu, piv, dx)
        step = 1.0_dp
        do ib = 0, 12
          xt(1:s) = x(1:s) - step * dx(1:s)
          call resid(xt, rt, sct)
          phit = merit(rt(1:s), sct(1:s))
          if (phit < (1.0_dp - 1.0e-4_dp * step) * phi) exit
          step = 0.5_dp * step
        end do
        if (ib > 12) then
          ok = .false.; return
        end if
        x(1:s) = xt(1:s); r(1:s) = rt(1:s); sc(1:s) = sct(1:s); phi = phit
      end do
      if (phi > 1.0_dp) then
        ok = .false.; return
      end if
      if (factored .and. phi > 0.0_dp) then      ! polishing chord step
        dx(1:s) = r(1:s) * w(1:s)
        call lu_small_solve(s, lu, piv, dx)
        xt(1:s) = x(1:s) - dx(1:s)
        call resid(xt, rt, sct)
        iterations = iterations + 1
        if (merit(rt(1:s), sct(1:s)) <= phi) x(1:s) = xt(1:s)
      end if
      call nodes(x)                                 ! (the library evaluates the solution once more)
      if (abs(y(s)) > wall) then
        ok = .false.; return                        ! an impact: not this loop's business
      end if
      p = pa
      e = 0.0_dp
      do j = 0, s
        p = p - h * b(j) * k * sin(y(j))
        e = e + b(j) * (0.5_dp * v(j)**2 - k * cos(y(j)))
      end do
      vel_before = vel
      vel = x(s) / h
      depth = min(depth + 1, 3)
      theta = a + x(s)
    end do

  contains

    subroutine nodes(xx)
      real(dp), intent(in) :: xx(:)
      integer :: ii, jn
      y(0) = a
      do ii = 1, s
        y(ii) = a + xx(ii)
      end do
      do ii = 0, s
        t = 0.0_dp
        do jn = 1, s
          t = t + d(ii, jn) * xx(jn)
        end do
        v(ii) = t / h
      end do
    end subroutine nodes

    !> Rows p_a + F_0, F_1 .. F_(s-1) and the library's row scales.
    subroutine resid(xx, rr, ss)
      real(dp), intent(in) :: xx(:)
      real(dp), intent(out) :: rr(:), ss(:)
      integer :: ii, jn
      real(dp) :: f, fs, wgt
      call nodes(xx)
      do ii = 0, s
        lq(ii) = -k * sin(y(ii))
      end do
      do jn = 0, s - 1
        f = h * b(jn) * lq(jn)
        fs = abs(f)
        do ii = 0, s
          wgt = b(ii) * d(ii, jn)
          f = f + wgt * v(ii)
          fs = fs + abs(wgt) * abs(v(ii))
        end do
        if (jn == 0) then
          f = f + pa; fs = fs + abs(pa)
        end if
        rr(jn + 1) = f
        ss(jn + 1) = fs * (1.0_dp + real(4 * (s + 1), dp) * epsilon(1.0_dp) / rtol) + &
                     (8.0_dp * epsilon(1.0_dp) / rtol) * jscale(jn + 1)
      end do
    end subroutine resid
  end subroutine hand_lobatto_steps
end module vci_bench_hand_lobatto
