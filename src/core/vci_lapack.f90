!> Explicit interfaces to the few LAPACK routines vci calls, so argument mistakes fail at compile time.
module vci_lapack
  use vci_kinds, only: dp
  implicit none
  private
  public :: dgetrf, dgetrs, dgelsd

  interface
    subroutine dgetrf(m, n, a, lda, ipiv, info)
      import :: dp
      integer, intent(in) :: m, n, lda
      real(dp), intent(inout) :: a(lda, *)
      integer, intent(out) :: ipiv(*), info
    end subroutine dgetrf
    subroutine dgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
      import :: dp
      character(len=1), intent(in) :: trans
      integer, intent(in) :: n, nrhs, lda, ldb
      real(dp), intent(in) :: a(lda, *)
      integer, intent(in) :: ipiv(*)
      real(dp), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dgetrs
    subroutine dgelsd(m, n, nrhs, a, lda, b, ldb, s, rcond, rank, work, lwork, iwork, info)
      import :: dp
      integer, intent(in) :: m, n, nrhs, lda, ldb, lwork
      real(dp), intent(inout) :: a(lda, *), b(ldb, *)
      real(dp), intent(out) :: s(*)
      real(dp), intent(in) :: rcond
      integer, intent(out) :: rank, info
      real(dp), intent(inout) :: work(*)
      integer, intent(inout) :: iwork(*)
    end subroutine dgelsd
  end interface
end module vci_lapack
