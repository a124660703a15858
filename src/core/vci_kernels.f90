!> The hot loops of a step (residual rows and their sizes, the Jacobian's sizes, Newton's row
!> equilibration and merit) as leaf routines on explicit-shape arrays.
!>
!> Why a module of its own: written on the components of a polymorphic object (self%d1(i), ...),
!> gfortran reloads each array's descriptor at every element, because a store through one dummy
!> may, for all it knows, change another's descriptor; at n = 2 or 3 that bookkeeping cost more than
!> the arithmetic (docs/bench/throughput.md, profile). Here the arrays are plain explicit-shape
!> dummies, so the loops compile to straight arithmetic. The callers pass contiguous arrays (whole
!> allocatables or leading sections of them), so nothing is copied in; the one array that is a
!> section with gaps (the Jacobian in jacobian_sizes) is assumed-shape instead
!> (test/alloc/test_alloc_free.pf counts the step loop's heap allocations).
module vci_kernels
  use vci_kinds, only: dp
  implicit none
  private

  public :: band_jacobian_sizes, invert_row_sizes, border_row_maxima
  public :: momentum_terms, kinetic_and_floor, jacobian_sizes, equilibrate, scaled_merit, small_lu, small_lu_solve
  public :: substep_rows, substep_direction, pivots_regular
  public :: lobatto_nodes, lobatto_forces, lobatto_blocks, total_of

contains

  !> Row equilibration of a structured matrix from its rows' largest entries rw: total = their sum
  !> (or the first non-finite one, returned at once: max() may have dropped a NaN, so test here
  !> too); rw(i) := 1 / rw(i), 1 for an empty row.
  pure subroutine invert_row_sizes(n, rw, total)
    integer, intent(in) :: n
    real(dp), intent(inout) :: rw(n)
    real(dp), intent(out) :: total
    integer :: i
    total = 0.0_dp
    do i = 1, n
      if (.not. (rw(i) <= huge(1.0_dp))) then
        total = rw(i); return
      end if
      total = total + rw(i)
      if (rw(i) > 0.0_dp) then
        rw(i) = 1.0_dp / rw(i)
      else
        rw(i) = 1.0_dp
      end if
    end do
  end subroutine invert_row_sizes

  !> rw(i) := max(rw(i), the largest |entry| of row i in the border) for a structured nb x nb block
  !> bordered by nx - nb rows (rows(k, j), j <= nb) and columns (cols(i, k), i <= nx): the part of
  !> the row sizes that the band and the sparse matrix share.
  pure subroutine border_row_maxima(nb, nx, rows, cols, rw)
    integer, intent(in) :: nb, nx
    real(dp), intent(in) :: rows(:, :), cols(:, :)
    real(dp), intent(inout) :: rw(:)
    integer :: i, j, k
    do j = 1, nb
      do k = 1, nx - nb
        rw(nb + k) = max(rw(nb + k), abs(rows(k, j)))
      end do
    end do
    do k = 1, nx - nb
      do i = 1, nx
        rw(i) = max(rw(i), abs(cols(i, k)))
      end do
    end do
  end subroutine border_row_maxima

  !> r(i) = d1(i) + pa(i) - sum_mu omega(i, mu) lambda(mu), sc(i) = the sum of those terms' sizes.
  pure subroutine momentum_terms(n, m, d1, pa, omega, lambda, r, sc)
    integer, intent(in) :: n, m
    real(dp), intent(in) :: d1(n), pa(n), omega(n, m), lambda(m)
    real(dp), intent(out) :: r(n), sc(n)
    integer :: i, mu
    do i = 1, n
      r(i) = d1(i) + pa(i)
      sc(i) = abs(d1(i)) + abs(pa(i))
    end do
    do mu = 1, m
      do i = 1, n
        r(i) = r(i) - omega(i, mu) * lambda(mu)
        sc(i) = sc(i) + abs(omega(i, mu)) * abs(lambda(mu))
      end do
    end do
  end subroutine momentum_terms

  !> The sizes the row terms do not show: sum_j jabs(i, j) motion(j) for the momentum rows i <= n
  !> (the kinetic term, when with_kinetic) and, for every row, fl * jscale(i) (the round-off floor).
  pure subroutine kinetic_and_floor(n, nx, ld, jabs, motion, with_kinetic, fl, jscale, sc)
    integer, intent(in) :: n, nx, ld
    real(dp), intent(in) :: jabs(ld, *), motion(n), fl, jscale(nx)
    logical, intent(in) :: with_kinetic
    real(dp), intent(inout) :: sc(nx)
    integer :: i, j
    if (with_kinetic) then
      do j = 1, n
        do i = 1, n
          sc(i) = sc(i) + jabs(i, j) * motion(j)
        end do
      end do
    end if
    do i = 1, nx
      sc(i) = sc(i) + fl * jscale(i)
    end do
  end subroutine kinetic_and_floor

  !> jabs = |jac| and jscale(i) = sum_j |jac(i, j)| size(j) (size: |position| or |unknown|).
  !> jac is assumed-shape: Newton's matrix is the leading nx x nx block of a larger array, which an
  !> explicit-shape dummy would receive as a packed copy on the heap at every Jacobian.
  pure subroutine jacobian_sizes(nx, jac, sizes, lda, jabs, jscale)
    integer, intent(in) :: nx, lda
    real(dp), intent(in) :: jac(:, :), sizes(nx)
    real(dp), intent(inout) :: jabs(lda, *)
    real(dp), intent(out) :: jscale(nx)
    integer :: i, j
    real(dp) :: s
    jscale = 0.0_dp
    do j = 1, nx
      do i = 1, nx
        s = abs(jac(i, j))
        jabs(i, j) = s
        jscale(i) = jscale(i) + s * sizes(j)
      end do
    end do
  end subroutine jacobian_sizes

  !> jacobian_sizes for a matrix whose leading nb x nb block vanishes outside |i - j| <= bw (a declared
  !> band, vci_banded): the band and the dense border only, O(nx bw + nx (nx - nb)); jabs is written
  !> there alone (its other entries are not read by band-aware callers).
  pure subroutine band_jacobian_sizes(nx, nb, bw, jac, sizes, lda, jabs, jscale)
    integer, intent(in) :: nx, nb, bw, lda
    real(dp), intent(in) :: jac(:, :), sizes(nx)
    real(dp), intent(inout) :: jabs(lda, *)
    real(dp), intent(out) :: jscale(nx)
    integer :: i, j
    real(dp) :: s
    jscale = 0.0_dp
    do j = 1, nx
      if (j <= nb) then
        do i = max(1, j - bw), min(nb, j + bw)
          s = abs(jac(i, j))
          jabs(i, j) = s
          jscale(i) = jscale(i) + s * sizes(j)
        end do
        do i = nb + 1, nx
          s = abs(jac(i, j))
          jabs(i, j) = s
          jscale(i) = jscale(i) + s * sizes(j)
        end do
      else
        do i = 1, nx
          s = abs(jac(i, j))
          jabs(i, j) = s
          jscale(i) = jscale(i) + s * sizes(j)
        end do
      end if
    end do
  end subroutine band_jacobian_sizes

  !> Rows equilibrated by their largest entry (so rows in different units pivot fairly): jac is
  !> scaled in place, lu receives a copy to factorise, dx = r w and rw the weights w.
  pure subroutine equilibrate(n, ld, jac, lu, r, dx, rw)
    integer, intent(in) :: n, ld
    real(dp), intent(inout) :: jac(ld, *)
    real(dp), intent(out) :: lu(ld, *)
    real(dp), intent(in) :: r(n)
    real(dp), intent(out) :: dx(n), rw(n)
    integer :: i, j
    rw(1:n) = 0.0_dp
    do j = 1, n
      do i = 1, n
        rw(i) = max(rw(i), abs(jac(i, j)))
      end do
    end do
    do i = 1, n
      if (rw(i) > 0.0_dp) then
        rw(i) = 1.0_dp / rw(i)
      else
        rw(i) = 1.0_dp
      end if
      dx(i) = r(i) * rw(i)
    end do
    do j = 1, n
      do i = 1, n
        jac(i, j) = jac(i, j) * rw(i)
        lu(i, j) = jac(i, j)
      end do
    end do
  end subroutine equilibrate

  !> max_i |r_i| / (atol + rtol sc_i): <= 1 means converged; huge when not finite.
  pure real(dp) function scaled_merit(n, r, sc, atol, rtol) result(phi)
    integer, intent(in) :: n
    real(dp), intent(in) :: r(n), sc(n), atol, rtol
    integer :: i
    phi = 0.0_dp
    do i = 1, n
      phi = max(phi, abs(r(i)) / max(atol + rtol * sc(i), tiny(1.0_dp)))
    end do
    if (.not. (phi <= huge(1.0_dp))) phi = huge(1.0_dp)
  end function scaled_merit

  !> Right-looking LU with partial pivoting (the pivot is the first largest |entry| of the column, as
  !> LAPACK's idamax picks it); ipiv as LAPACK's. Stops at an exact zero pivot (info = its column).
  pure subroutine small_lu(n, a, ipiv, info)
    integer, intent(in) :: n
    real(dp), intent(inout) :: a(:, :)
    integer, intent(inout) :: ipiv(:)
    integer, intent(out) :: info
    integer :: i, j, k, p
    real(dp) :: t, piv_inv
    info = 0
    do j = 1, n
      p = j
      do i = j + 1, n
        if (abs(a(i, j)) > abs(a(p, j))) p = i
      end do
      ipiv(j) = p
      if (a(p, j) == 0.0_dp) then
        if (info == 0) info = j
        cycle
      end if
      if (p /= j) then
        do k = 1, n
          t = a(j, k); a(j, k) = a(p, k); a(p, k) = t
        end do
      end if
      piv_inv = 1.0_dp / a(j, j)
      do i = j + 1, n
        a(i, j) = a(i, j) * piv_inv
      end do
      do k = j + 1, n
        t = a(j, k)
        do i = j + 1, n
          a(i, k) = a(i, k) - a(i, j) * t
        end do
      end do
    end do
  end subroutine small_lu

  pure subroutine small_lu_solve(n, a, ipiv, b)
    integer, intent(in) :: n
    real(dp), intent(in) :: a(:, :)
    integer, intent(in) :: ipiv(:)
    real(dp), intent(inout) :: b(:)
    integer :: i, k
    real(dp) :: t
    do i = 1, n
      if (ipiv(i) /= i) then
        t = b(i); b(i) = b(ipiv(i)); b(ipiv(i)) = t
      end if
    end do
    do k = 1, n                 ! L y = b (unit diagonal), column by column
      t = b(k)
      do i = k + 1, n
        b(i) = b(i) - a(i, k) * t
      end do
    end do
    do k = n, 1, -1             ! U x = y
      b(k) = b(k) / a(k, k)
      t = b(k)
      do i = 1, k - 1
        b(i) = b(i) - a(i, k) * t
      end do
    end do
  end subroutine small_lu_solve

  !> The regular sub-step's rows from the callbacks' values, their sizes and merit in one call (the
  !> fused solve, vci_scheme_discrete_fused): on entry d1 = s D1 L^s(a, b) and r(n+1:n+m) = omega_d;
  !> x = [b or the increment, lambda]. kin(j) = |b_j - a_j|; ok false if any r_i or sc_i is NaN/Inf.
  pure subroutine substep_rows(n, m, x, a, increments, d1, pa, omega, tau, jac_known, ld, jabs, fl, &
                               jscale, atol, rtol, r, sc, kin, phi, ok)
    integer, intent(in) :: n, m, ld
    real(dp), intent(in) :: x(n + m), a(n), d1(n), pa(n), omega(n, m), tau, jabs(ld, *), fl, &
                            jscale(n + m), atol, rtol
    logical, intent(in) :: increments, jac_known
    real(dp), intent(inout) :: r(n + m)
    real(dp), intent(out) :: sc(n + m), kin(n), phi
    logical, intent(out) :: ok
    integer :: i, mu
    real(dp) :: ol, s
    if (increments) then
      do i = 1, n
        kin(i) = abs(x(i))
      end do
    else
      do i = 1, n
        kin(i) = abs(x(i) - a(i))
      end do
    end if
    call momentum_terms(n, m, d1, pa, omega, x(n + 1:n + m), r, sc)
    do mu = 1, m
      ol = 0.0_dp
      do i = 1, n
        ol = ol + abs(omega(i, mu)) * kin(i)
      end do
      sc(n + mu) = abs(r(n + mu)) + ol / tau
    end do
    call kinetic_and_floor(n, n + m, ld, jabs, kin, jac_known, fl, jscale, sc)
    phi = 0.0_dp; s = 0.0_dp
    do i = 1, n + m          ! scaled_merit, and the finiteness sum in the same pass
      phi = max(phi, abs(r(i)) / max(atol + rtol * sc(i), tiny(1.0_dp)))
      s = s + r(i) + sc(i)
    end do
    ok = abs(s) <= huge(1.0_dp)
  end subroutine substep_rows

  !> The Newton direction of the fused solve: from the Jacobian jac (n x n; scaled in place) and the
  !> unknowns' sizes, the round-off sizes jabs and jscale (as jacobian_sizes), the equilibrated LU
  !> factors lu, ipiv and row weights rw, and dx = J^{-1} r. ok false when a value is not finite or
  !> the matrix is numerically singular (pivot ratio below 1e-14, as vci_newton's test).
  pure subroutine substep_direction(n, jac, sizes, lda, jabs, jscale, r, lu, ipiv, rw, dx, ok)
    integer, intent(in) :: n, lda
    real(dp), intent(inout) :: jac(n, n)
    real(dp), intent(in) :: sizes(n), r(n)
    real(dp), intent(inout) :: jabs(lda, *)
    real(dp), intent(out) :: jscale(n), lu(n, n), rw(n), dx(n)
    integer, intent(inout) :: ipiv(n)
    logical, intent(out) :: ok
    integer :: i, j, info
    real(dp) :: s
    call jacobian_sizes(n, jac, sizes, lda, jabs, jscale)
    call equilibrate(n, n, jac, lu, r, dx, rw)
    s = 0.0_dp
    do j = 1, n
      do i = 1, n
        s = s + lu(i, j)
      end do
      s = s + dx(j)
    end do
    ok = .false.
    if (.not. abs(s) <= huge(1.0_dp)) return
    call small_lu(n, lu, ipiv, info)
    if (info /= 0 .or. .not. pivots_regular(n, n, lu)) return
    call small_lu_solve(n, lu, ipiv, dx)
    s = 0.0_dp
    do i = 1, n
      s = s + dx(i)
    end do
    ok = abs(s) <= huge(1.0_dp)
  end subroutine substep_direction

  !> Is the factorised matrix numerically regular: smallest |U(i, i)| above 1e-14 of the largest?
  pure logical function pivots_regular(n, ld, lu) result(ok)
    integer, intent(in) :: n, ld
    real(dp), intent(in) :: lu(ld, *)
    integer :: i
    real(dp) :: dmin, dmax
    dmin = huge(1.0_dp); dmax = 0.0_dp
    do i = 1, n
      dmin = min(dmin, abs(lu(i, i))); dmax = max(dmax, abs(lu(i, i)))
    end do
    ok = dmin > 1.0e-14_dp * dmax
  end function pivots_regular
  !> The Lobatto scheme's nodes from the stage increments dx(:, j) = y_j - a (j = 1..s): positions
  !> y(:, 0) = a, y(:, j) = a + dx(:, j), and velocities v(:, i) = c sum_j d(i, j) dx(:, j) (c = dir/tau;
  !> d the differentiation matrix on the nodes 0..s, whose rows sum to zero). The velocities take
  !> the increments themselves: no position is subtracted, so |q| does not round them.
  pure subroutine lobatto_nodes(n, s, c, d, a, dx, y, v)
    integer, intent(in) :: n, s
    real(dp), intent(in) :: c, d(0:s, 0:s), a(n), dx(n, s)
    real(dp), intent(out) :: y(n, 0:s), v(n, 0:s)
    integer :: i, j, l
    real(dp) :: t
    do l = 1, n
      y(l, 0) = a(l)
    end do
    do j = 1, s
      do l = 1, n
        y(l, j) = a(l) + dx(l, j)
      end do
    end do
    do i = 0, s
      do l = 1, n
        t = 0.0_dp
        do j = 1, s
          t = t + d(i, j) * dx(l, j)
        end do
        v(l, i) = c * t
      end do
    end do
  end subroutine lobatto_nodes

  !> The Lobatto scheme's node forces F_j = tau b_j lq_j + dir sum_i bd(i, j) lv_i (j = 0..s) and
  !> fs(:, j) the sum of their terms' sizes; bd(i, j) = b_i d(i, j), the rule's, formed once (dir = +-1
  !> times it is the product dir b_i d(i, j) to the bit).
  pure subroutine lobatto_forces(n, s, tau, dsign, b, bd, lq, lv, f, fs)
    integer, intent(in) :: n, s
    real(dp), intent(in) :: tau, dsign, b(0:s), bd(0:s, 0:s), lq(n, 0:s), lv(n, 0:s)
    real(dp), intent(out) :: f(n, 0:s), fs(n, 0:s)
    integer :: i, j, l
    real(dp) :: t, ts
    do j = 0, s
      do l = 1, n
        t = tau * b(j) * lq(l, j)
        ts = abs(t)
        do i = 0, s
          t = t + (dsign * bd(i, j)) * lv(l, i)
          ts = ts + abs(bd(i, j)) * abs(lv(l, i))
        end do
        f(l, j) = t
        fs(l, j) = ts
      end do
    end do
  end subroutine lobatto_forces

  !> The Lobatto scheme's Jacobian blocks dF_j/dy_k (rows of node j = j0..s-1, row block j at
  !> jac(j n + 1 : (j + 1) n, :); columns of stage k = 1..s), added to jac:
  !>   tau b_j hqq_j d_jk + dir b_j d(j, k) hqv_j + dir b_k d(k, j) hqv_k^T + (1/tau) sum_i w(i, j, k) hvv_i,
  !> w(i, j, k) = b_i d(i, j) d(i, k) (the rule's, computed once), row block 0 (the momentum rows)
  !> times dir. jac is assumed-shape: Newton's matrix is a section of a larger array (an
  !> explicit-shape dummy would copy it).
  pure subroutine lobatto_blocks(n, s, j0, tau, dsign, b, d, w, hqq, hqv, hvv, jac)
    integer, intent(in) :: n, s, j0
    real(dp), intent(in) :: tau, dsign, b(0:s), d(0:s, 0:s), w(0:s, 0:s - 1, s)
    real(dp), intent(in) :: hqq(n, n, 0:s), hqv(n, n, 0:s), hvv(n, n, 0:s)
    real(dp), intent(inout) :: jac(:, :)
    integer :: i, j, k, r, c, r0, c0
    real(dp) :: rs, wq, wa, wb, t, rst
    do k = 1, s
      c0 = (k - 1) * n
      do j = j0, s - 1
        r0 = j * n
        rs = 1.0_dp
        if (j == 0) rs = dsign
        wq = 0.0_dp
        if (j == k) wq = rs * tau * b(j)
        wa = rs * dsign * b(j) * d(j, k)
        wb = rs * dsign * b(k) * d(k, j)
        rst = rs / tau   ! (no array of weights here: an automatic array is a malloc in gfortran)
        do c = 1, n
          do r = 1, n
            t = wq * hqq(r, c, j) + wa * hqv(r, c, j) + wb * hqv(c, r, k)
            do i = 0, s
              t = t + (rst * w(i, j, k)) * hvv(r, c, i)
            end do
            jac(r0 + r, c0 + c) = jac(r0 + r, c0 + c) + t
          end do
        end do
      end do
    end do
  end subroutine lobatto_blocks

  !> The sum of a(1:m) (finite exactly when every element is, barring overflow of the sum, which
  !> callers treat as non-finite): one test for a whole array of callback values, explicit-shape so
  !> that it compiles to a plain loop where sum() over a polymorphic object's component did not
  !> (570 instructions for three 5-element sums in the Lobatto Jacobian; docs/bench/lobatto.md).
  pure real(dp) function total_of(m, a) result(t)
    integer, intent(in) :: m
    real(dp), intent(in) :: a(m)
    integer :: i
    t = 0.0_dp
    do i = 1, m
      t = t + a(i)
    end do
  end function total_of
end module vci_kernels
