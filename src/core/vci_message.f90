!> Messages built from parts of any length (a file's path, a model's or a solver's cause) put into
!> the fixed buffers the library keeps (VCI_MSG_LEN). An internal write whose record is longer than
!> its buffer stops the program ("End of record"), so messages are concatenated as text instead:
!> numbers through vci_int_text / vci_real_text, the whole cut to its buffer by vci_set_message.
!> Results have fixed lengths (trim them): gfortran 12 keeps a deferred-length function result's
!> length in a static per call site, which races across threads.
module vci_message
  use vci_kinds, only: dp, i8
  implicit none
  private

  !> What ends a message that was cut to its buffer.
  character(len=*), parameter, public :: VCI_MSG_CUT = ' [...]'

  public :: vci_set_message, vci_int_text, vci_real_text

  !> An integer (default or 64-bit) as text, left-adjusted (format i0).
  interface vci_int_text
    module procedure int_text, i8_text
  end interface vci_int_text

contains

  !> buf = text, or, when text is longer than buf, its start followed by VCI_MSG_CUT.
  pure subroutine vci_set_message(buf, text)
    character(len=*), intent(out) :: buf
    character(len=*), intent(in) :: text
    if (len(text) <= len(buf)) then
      buf = text
    else if (len(buf) <= len(VCI_MSG_CUT)) then
      buf = text
    else
      buf = text(1:len(buf) - len(VCI_MSG_CUT))//VCI_MSG_CUT
    end if
  end subroutine vci_set_message

  pure function int_text(i) result(s)
    integer, intent(in) :: i
    character(len=24) :: s
    write (s, '(i0)') i
  end function int_text

  pure function i8_text(i) result(s)
    integer(i8), intent(in) :: i
    character(len=24) :: s
    write (s, '(i0)') i
  end function i8_text

  !> A real in the edit descriptor fmt (say '(es14.7)', at most 40 characters wide), as an internal
  !> write puts it in a message (its field's leading blanks kept: messages read as before).
  pure function vci_real_text(x, fmt) result(s)
    real(dp), intent(in) :: x
    character(len=*), intent(in) :: fmt
    character(len=40) :: s
    integer :: ios
    write (s, fmt, iostat=ios) x
    if (ios /= 0) s = '?'
  end function vci_real_text
end module vci_message
