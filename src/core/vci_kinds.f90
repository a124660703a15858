!> Real kind used everywhere in vci.
module vci_kinds
  use, intrinsic :: iso_fortran_env, only: real64, int64
  implicit none
  private
  !> Double precision; the only real kind in the library.
  integer, parameter, public :: dp = real64
  !> Counters that can exceed 2**31 in long runs.
  integer, parameter, public :: i8 = int64
end module vci_kinds
