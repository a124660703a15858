!> Model sizes the library accepts, checked before anything is allocated.
!>
!> Newton's matrices are dense, (n + m + 1)^2 entries, and LAPACK addresses them with default
!> (32-bit) integers, so n + m + 1 <= 46340 (46340^2 < 2^31). C callbacks index their n x n,
!> n x m and n x n_gaps arrays with `int` arithmetic (hess[i + n*j], dg[i + n*j]), so n * n_gaps
!> must fit an int as well. Within these bounds, an allocation that fails gives VCI_ERR_MEMORY.
module vci_limits
  use vci_kinds, only: i8
  implicit none
  private

  !> Largest n + m + 1 (unknowns of a stage-1 or stage-2 system).
  integer, parameter, public :: VCI_MAX_UNKNOWNS = 46340

  public :: vci_size_problem

contains

  !> Why the sizes are refused, or '' when they are fine. (A fixed-length result: gfortran keeps
  !> the length of a deferred-length function result in a static variable, which is not
  !> thread-safe, and this runs in concurrent C calls.)
  pure function vci_size_problem(n, m, n_gaps) result(why)
    integer, intent(in) :: n, m, n_gaps
    character(len=80) :: why
    why = ''
    if (n < 1 .or. m < 0 .or. m > n .or. n_gaps < 0) then
      why = 'need n >= 1, 0 <= m <= n, n_gaps >= 0'
    else if (int(n, i8) + m + 1 > VCI_MAX_UNKNOWNS) then
      why = 'need n + m + 1 <= 46340 (dense Newton matrices with 32-bit LAPACK indices)'
    else if (int(n, i8) * n_gaps > int(huge(1), i8)) then
      why = 'need n * n_gaps < 2^31 (the gap gradients are indexed with int)'
    end if
  end function vci_size_problem
end module vci_limits
