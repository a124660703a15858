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

  public :: momentum_terms, kinetic_and_floor, jacobian_sizes, equilibrate, scaled_merit

contains

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
end module vci_kernels
