!> The one adapter between foreign callbacks (C functions behind vci.h, the legacy MODEL routine)
!> and the core's callback contract, shared by vci_capi and vci_legacy.
!>
!> The contract (SUNDIALS style): a callback returns 0 on success, a positive code for a
!> recoverable failure (at a trial point of Newton's line search the solver backs off; elsewhere
!> the step fails) and a negative code for an unrecoverable one (the step fails at once). The
!> adapter passes the code through as the model procedure's `stat` ("not provided" has a channel of
!> its own, vci_model_base: an absent foreign callback calls `not_provided`, so no code can mean it) and
!> keeps the name and code of the last failing call, so that a failure the core reports as
!> VCI_ERR_CALLBACK or VCI_ERR_NONFINITE can name the foreign callback. The record belongs to one
!> integrator and is cleared at the start of every call and after every accepted step: a code
!> absorbed by the line search is never reported for a later failure.
module vci_callback_adapter
  use vci_status, only: VCI_ERR_CALLBACK, VCI_ERR_NONFINITE
  implicit none
  private

  type, public :: vci_callback_record_t
    integer :: code = 0                   !< code of the last failing call (0: none since cleared)
    character(len=64) :: failed = ''      !< its name, e.g. 'the C callback d1_ld'
    character(len=64) :: nonfinite = ''   !< the last callback that returned NaN/Inf with code 0
  contains
    procedure :: clear => record_clear
    procedure :: note => record_note
    procedure :: annotate => record_annotate
  end type vci_callback_record_t

contains

  subroutine record_clear(self)
    class(vci_callback_record_t), intent(inout) :: self
    self%code = 0; self%failed = ''; self%nonfinite = ''
  end subroutine record_clear

  !> After a foreign callback returned `code` with outputs that are `finite` or not: set the model
  !> procedure's stat (the code itself; 0 stays 0) and remember a failure.
  subroutine record_note(self, code, name, finite, stat)
    class(vci_callback_record_t), intent(inout) :: self
    integer, intent(in) :: code
    character(len=*), intent(in) :: name
    logical, intent(in) :: finite
    integer, intent(inout) :: stat
    if (code /= 0) then
      self%code = code
      self%failed = name
      stat = code
    else if (.not. finite) then
      self%nonfinite = name
    end if
  end subroutine record_note

  !> Name the foreign callback in the message of a failure that one caused.
  subroutine record_annotate(self, status, message)
    class(vci_callback_record_t), intent(in) :: self
    integer, intent(in) :: status
    character(len=*), intent(inout) :: message
    character(len=16) :: k
    if (status == VCI_ERR_CALLBACK .and. self%code /= 0) then
      write (k, '(i0)') self%code
      message = trim(message)//' ('//trim(self%failed)//' returned '//trim(k)//')'
    else if (status == VCI_ERR_NONFINITE .and. self%nonfinite /= '') then
      message = trim(message)//' ('//trim(self%nonfinite)//' returned NaN or Inf)'
    end if
  end subroutine record_annotate
end module vci_callback_adapter
