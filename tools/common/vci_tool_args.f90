!> Checked command-line numbers for the developer tools (tools/, bench/): a missing or malformed
!> argument ends the program with a message naming it and exit status 2, instead of a Fortran
!> runtime error ("Bad real number in item 1 of list input") or a silently partial read (`1,5` as
!> 1, `2.5` cut to an integer). The grammar is the examples' (vci_example_cli's is_decimal).
module vci_tool_args
  use, intrinsic :: iso_fortran_env, only: error_unit
  use vci_kinds, only: dp, i8
  use vci_example_cli, only: is_decimal
  implicit none
  private
  public :: arg_value, text_value, bad_argument, usage_error

  !> arg_value(i, what, x): command-line argument i (what: its name in a message) into x.
  interface arg_value
    module procedure arg_real, arg_int, arg_i8
  end interface arg_value
  !> text_value(text, what, x): the same for a piece of an argument (e.g. the value of --max=N).
  interface text_value
    module procedure text_real, text_int, text_i8
  end interface text_value

contains

  subroutine arg_real(i, what, x)
    integer, intent(in) :: i
    character(len=*), intent(in) :: what
    real(dp), intent(out) :: x
    call text_real(argument(i, what), what, x)
  end subroutine arg_real

  subroutine arg_int(i, what, x)
    integer, intent(in) :: i
    character(len=*), intent(in) :: what
    integer, intent(out) :: x
    call text_int(argument(i, what), what, x)
  end subroutine arg_int

  subroutine arg_i8(i, what, x)
    integer, intent(in) :: i
    character(len=*), intent(in) :: what
    integer(i8), intent(out) :: x
    call text_i8(argument(i, what), what, x)
  end subroutine arg_i8

  !> A finite decimal number ([+-] digits [. digits] [e [+-] digits]).
  subroutine text_real(s, what, x)
    character(len=*), intent(in) :: s, what
    real(dp), intent(out) :: x
    integer :: ios
    x = 0.0_dp
    if (.not. is_decimal(s, integer_only=.false.)) call bad_argument(what, s, 'a number')
    read (s, *, iostat=ios) x
    if (ios /= 0) call bad_argument(what, s, 'a number')
    if (.not. (abs(x) <= huge(x))) call bad_argument(what, s, 'a finite number')
  end subroutine text_real

  subroutine text_int(s, what, x)
    character(len=*), intent(in) :: s, what
    integer, intent(out) :: x
    integer(i8) :: v
    call text_i8(s, what, v)
    if (v < -huge(x) .or. v > huge(x)) call bad_argument(what, s, 'an integer of at most 9 digits')
    x = int(v)
  end subroutine text_int

  !> Digits with an optional sign, at most 18 of them (no wrap).
  subroutine text_i8(s, what, x)
    character(len=*), intent(in) :: s, what
    integer(i8), intent(out) :: x
    integer :: ios
    x = 0
    if (.not. is_decimal(s, integer_only=.true.) .or. len_trim(s) > 18) call bad_argument(what, s, 'an integer')
    read (s, *, iostat=ios) x
    if (ios /= 0) call bad_argument(what, s, 'an integer')
  end subroutine text_i8

  !> Argument i whole; missing: the program stops naming it.
  function argument(i, what) result(s)
    integer, intent(in) :: i
    character(len=*), intent(in) :: what
    character(len=:), allocatable :: s
    integer :: n, st
    call get_command_argument(i, length=n, status=st)
    if (st > 0 .or. i > command_argument_count()) call usage_error(what//' (argument '//int_text(i)//') is missing')
    allocate (character(len=n) :: s)
    call get_command_argument(i, s)
  end function argument

  !> "PROGRAM: WHAT must be EXPECTED (got "TEXT")" on stderr, exit status 2 (a usage error).
  subroutine bad_argument(what, text, expected)
    character(len=*), intent(in) :: what, text, expected
    call usage_error(what//' must be '//expected//' (got "'//text//'")')
  end subroutine bad_argument

  !> "PROGRAM: MESSAGE" on stderr, exit status 2.
  subroutine usage_error(message)
    character(len=*), intent(in) :: message
    character(len=256) :: prog
    integer :: k
    call get_command_argument(0, prog)
    k = index(prog, '/', back=.true.)
    write (error_unit, '(a)') trim(prog(k + 1:))//': '//message
    stop 2, quiet=.true.
  end subroutine usage_error

  pure function int_text(i) result(s)
    integer, intent(in) :: i
    character(len=:), allocatable :: s
    character(len=12) :: b
    write (b, '(i0)') i
    s = trim(b)
  end function int_text
end module vci_tool_args
