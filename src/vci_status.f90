!> Status codes shared by the Fortran API and the C ABI (values match include/vci.h).
module vci_status
  implicit none
  private

  integer, parameter, public :: VCI_OK = 0
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

  !> Returned by the default (not overridden) optional model procedures. Never escapes the library.
  integer, parameter, public :: VCI_NOT_PROVIDED = -1

  !> Longest message kept by the library.
  integer, parameter, public :: VCI_MSG_LEN = 512

  public :: vci_status_name

contains

  !> A short, fixed description of a status code.
  pure function vci_status_name(status) result(name)
    integer, intent(in) :: status
    character(len=:), allocatable :: name
    select case (status)
    case (VCI_OK);                   name = 'ok'
    case (VCI_ERR_ARGUMENT);         name = 'invalid argument'
    case (VCI_ERR_CALLBACK);         name = 'user callback failed'
    case (VCI_ERR_NONFINITE);        name = 'non-finite value'
    case (VCI_ERR_NEWTON);           name = 'Newton iteration did not converge'
    case (VCI_ERR_IMPACT);           name = 'impact could not be resolved'
    case (VCI_ERR_TOO_MANY_IMPACTS); name = 'too many impacts in one step'
    case (VCI_ERR_INADMISSIBLE);     name = 'state outside the admissible set'
    case (VCI_ERR_IO);               name = 'input/output error'
    case (VCI_ERR_STATE);            name = 'call out of order'
    case (VCI_ERR_MEMORY);           name = 'out of memory'
    case default;                    name = 'unknown status'
    end select
  end function vci_status_name
end module vci_status
