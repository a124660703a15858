!> Status codes shared by the Fortran API and the C ABI (values match include/vci.h).
module vci_status
  implicit none
  private

  integer, parameter, public :: VCI_OK = 0                    !< success
  integer, parameter, public :: VCI_ERR_ARGUMENT = 1          !< bad input from the caller
  integer, parameter, public :: VCI_ERR_CALLBACK = 2          !< a user callback reported failure
  integer, parameter, public :: VCI_ERR_NONFINITE = 3         !< NaN or Inf produced by a callback or a solve
  integer, parameter, public :: VCI_ERR_NEWTON = 4            !< Newton did not converge
  integer, parameter, public :: VCI_ERR_IMPACT = 5            !< impact stages had no admissible solution
  integer, parameter, public :: VCI_ERR_TOO_MANY_IMPACTS = 6  !< impact bound in one step exceeded (contact, chatter)
  integer, parameter, public :: VCI_ERR_INADMISSIBLE = 7      !< a state lies outside the admissible set
  integer, parameter, public :: VCI_ERR_IO = 8                !< output could not be written
  integer, parameter, public :: VCI_ERR_STATE = 9             !< call out of order (e.g. step before init)
  integer, parameter, public :: VCI_ERR_MEMORY = 10           !< an allocation failed (sizes too large for this machine)
  integer, parameter, public :: VCI_STOPPED = 11              !< the caller stopped the run (progress callback)

  !> Longest message kept by the library.
  integer, parameter, public :: VCI_MSG_LEN = 512

  !> The descriptions of VCI_OK .. VCI_STOPPED (vci_status_name, and C's vci_status_string).
  character(len=*), parameter, public :: VCI_STATUS_NAMES(0:11) = [character(len=36) :: &
    'ok', 'invalid argument', 'user callback failed', 'non-finite value', &
    'Newton iteration did not converge', 'impact could not be resolved', 'too many impacts in one step', &
    'state outside the admissible set', 'input/output error', 'call out of order', 'out of memory', &
    'stopped by the caller']

  public :: vci_status_name

contains

  !> A short, fixed description of a status code ('unknown status' for other values).
  !> The result's length is a specification expression, not deferred: gfortran 12 keeps a
  !> deferred-length result's length in a static per call site, which races across threads.
  pure function vci_status_name(status) result(name)
    integer, intent(in) :: status
    character(len=merge(len_trim(VCI_STATUS_NAMES(min(max(status, 0), ubound(VCI_STATUS_NAMES, 1)))), &
                        len('unknown status'), status >= 0 .and. status <= ubound(VCI_STATUS_NAMES, 1))) :: name
    if (status >= lbound(VCI_STATUS_NAMES, 1) .and. status <= ubound(VCI_STATUS_NAMES, 1)) then
      name = VCI_STATUS_NAMES(status)
    else
      name = 'unknown status'
    end if
  end function vci_status_name
end module vci_status
