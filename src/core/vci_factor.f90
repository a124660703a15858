!> One interface for the factors of Newton matrices (issue 28): whatever the structure — dense, a
!> band with a dense border (vci_banded), a sparse pattern (vci_sparse, KLU) — a factorisation is
!> a vci_factor_t that solves with itself any number of times. Newton keeps its last factors as
!> one of these (the chord and polish steps solve through `solve` alone), and an impact stage's
!> bordered solve (vci_bordered) eliminates its extra row and column with its block's factors of
!> any of these kinds. Each kind factorises with its own arguments (the structure it needs); the
!> matrix it factorises is the row-equilibrated diag(rw) A, so `solve` takes rw-scaled right-hand
!> sides. This module also holds the dense kind, for a block that declares no structure.
module vci_factor
  use vci_kinds, only: dp
  use vci_lapack, only: dgetrf, dgetrs
  use vci_kernels, only: small_lu, small_lu_solve, pivots_regular
  implicit none
  private

  !> Factors of a (row-equilibrated) matrix: b := matrix^{-1} b with `solve`.
  type, abstract, public :: vci_factor_t
    logical :: ready = .false.  !< the last factorisation succeeded (solve uses it)
  contains
    !> b(1:n) := matrix^{-1} b with the factors (n the factorised matrix's unknowns).
    procedure(factor_solve_iface), deferred :: solve
  end type vci_factor_t

  abstract interface
    !> b := matrix^{-1} b (size(b): the factorised matrix's unknowns).
    subroutine factor_solve_iface(self, b)
      import :: vci_factor_t, dp
      class(vci_factor_t), intent(inout) :: self
      real(dp), intent(inout) :: b(:)
    end subroutine factor_solve_iface
  end interface

  !> Dense LU with partial pivoting of diag(rw) A: the in-line LU up to small_max unknowns (no
  !> LAPACK call, as vci_newton's small systems), dgetrf/dgetrs above.
  type, extends(vci_factor_t), public :: vci_dense_lu_t
    integer :: n = 0                      !< unknowns of the factorised matrix
    real(dp), allocatable, private :: lu(:, :)
    integer, allocatable, private :: ipiv(:)
    logical, private :: small = .true.
  contains
    !> Factorise diag(rw) jac(1:n, 1:n); info /= 0: singular, or no workspace.
    procedure :: factor => dense_factor
    !> b(1:n) := (diag(rw) A)^{-1} b.
    procedure :: solve => dense_solve
  end type vci_dense_lu_t

contains

  !> Factorise diag(rw) A, A = jac(1:n, 1:n) (copied: jac is not changed; the caller has checked
  !> that it is finite). info: 0 done; -1 no workspace; > 0 numerically singular (a pivot below
  !> 1e-14 of the largest, vci_newton's test of dense LU).
  subroutine dense_factor(self, n, jac, ld, rw, small_max, info)
    class(vci_dense_lu_t), intent(inout) :: self
    integer, intent(in) :: n, ld, small_max
    real(dp), intent(in) :: jac(ld, *), rw(*)
    integer, intent(out) :: info
    integer :: i, j, st
    self%ready = .false.
    info = -1
    if (n < 1) return
    if (allocated(self%lu)) then
      if (size(self%lu, 1) < n) deallocate (self%lu, self%ipiv)
    end if
    if (.not. allocated(self%lu)) then
      allocate (self%lu(n, n), stat=st)
      if (st /= 0) return
      allocate (self%ipiv(n), stat=st)
      if (st /= 0) then
        deallocate (self%lu); return
      end if
    end if
    do j = 1, n
      do i = 1, n
        self%lu(i, j) = rw(i) * jac(i, j)
      end do
    end do
    self%n = n
    self%small = n <= small_max
    if (self%small) then
      call small_lu(n, self%lu, self%ipiv, info)
    else
      call dgetrf(n, n, self%lu, size(self%lu, 1), self%ipiv, info)
    end if
    if (info /= 0) return
    if (.not. pivots_regular(n, size(self%lu, 1), self%lu)) then
      info = 1; return
    end if
    self%ready = .true.
  end subroutine dense_factor

  !> b(1:n) := (diag(rw) A)^{-1} b with the factors of the last successful factor.
  subroutine dense_solve(self, b)
    class(vci_dense_lu_t), intent(inout) :: self
    real(dp), intent(inout) :: b(:)
    integer :: info
    if (self%small) then
      call small_lu_solve(self%n, self%lu, self%ipiv, b)
    else
      call dgetrs('N', self%n, 1, self%lu, size(self%lu, 1), self%ipiv, b, size(b), info)
    end if
  end subroutine dense_solve
end module vci_factor
