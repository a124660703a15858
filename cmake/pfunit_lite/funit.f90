!> Minimal stand-in for pFUnit 4's `funit` module, used when pFUnit is not
!> installed.  Code converted by pf2f90.py calls these assertions with an
!> extra `location='file.pf:line'` argument; argument order and keyword names
!> (expected, actual, tolerance=, message=) follow pFUnit 4 so the same .pf
!> files build with both.  See docs/TESTING.md for the supported subset.
!>
!> Rule for every real comparison: NaN never passes.  Checks are written as
!> "pass if <condition holds>", and every ordered comparison with NaN is false.
module funit
  use, intrinsic :: iso_fortran_env, only: real64, output_unit
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use, intrinsic :: iso_c_binding, only: c_int, c_funptr, c_funloc
  implicit none
  private

  public :: assertEqual, assertTrue, assertFalse
  public :: assertLessThan, assertLessThanOrEqual
  public :: assertGreaterThan, assertGreaterThanOrEqual
  public :: assertRelativelyEqual, assertIsFinite
  public :: anyExceptions
  ! Used by the generated driver program only.
  public :: funit_run, funit_summary, funit_test_proc

  abstract interface
    subroutine funit_test_proc()
    end subroutine funit_test_proc
  end interface

  interface assertEqual
    module procedure equal_real, equal_real_1d, equal_real_scalar_1d
    module procedure equal_int, equal_int_1d, equal_logical, equal_string
  end interface assertEqual

  interface assertLessThan
    module procedure less_real, less_int
  end interface assertLessThan

  interface assertLessThanOrEqual
    module procedure less_equal_real, less_equal_int
  end interface assertLessThanOrEqual

  interface assertGreaterThan
    module procedure greater_real, greater_int
  end interface assertGreaterThan

  interface assertGreaterThanOrEqual
    module procedure greater_equal_real, greater_equal_int
  end interface assertGreaterThanOrEqual

  interface assertRelativelyEqual
    module procedure rel_equal_real, rel_equal_real_1d
  end interface assertRelativelyEqual

  ! pFUnit 4 has scalar versions only.
  interface assertIsFinite
    module procedure finite_real
  end interface assertIsFinite

  ! State of the test being run (reset by funit_run) and of the whole program.
  integer :: failures_in_test = 0
  character(len=:), allocatable :: first_failure
  integer :: n_passed = 0, n_failed = 0

  ! Exit guard: code under test that ends the process (a STOP in a library, LAPACK's XERBLA)
  ! must not pass for a success. An atexit handler turns any exit before funit_summary into a
  ! failure with status 70.
  logical :: guard_registered = .false., summary_done = .false.
  character(len=:), allocatable :: running_test
  interface
    integer(c_int) function c_atexit(handler) bind(C, name='atexit')
      import :: c_int, c_funptr
      type(c_funptr), value :: handler
    end function c_atexit
    subroutine c_exit_now(code) bind(C, name='_exit')
      import :: c_int
      integer(c_int), value :: code
    end subroutine c_exit_now
  end interface

contains

  ! ---------------------------------------------------------------- helpers

  !> Record a failed assertion; only the first message of a test is kept.
  subroutine fail(assertion, detail, message, location)
    character(len=*), intent(in) :: assertion, detail
    character(len=*), intent(in), optional :: message, location
    character(len=:), allocatable :: text

    failures_in_test = failures_in_test + 1
    if (failures_in_test > 1) return
    text = assertion // ': ' // detail
    if (present(message)) text = message // ': ' // text
    if (present(location)) text = location // ': ' // text
    first_failure = text
  end subroutine fail

  !> True if a equals b within tol.  The exact test comes first so that equal
  !> infinities pass (Inf - Inf is NaN); it uses <= and >= rather than ==
  !> because both are false for NaN and gfortran's -Wcompare-reals stays quiet.
  elemental logical function within(e, a, tol)
    real(real64), intent(in) :: e, a, tol
    within = (e <= a .and. e >= a) .or. abs(e - a) <= tol
  end function within

  function r2s(x) result(s)
    real(real64), intent(in) :: x
    character(len=:), allocatable :: s
    character(len=48) :: buf
    write (buf, '(g0)') x
    s = trim(buf)
  end function r2s

  function i2s(i) result(s)
    integer, intent(in) :: i
    character(len=:), allocatable :: s
    character(len=24) :: buf
    write (buf, '(i0)') i
    s = trim(buf)
  end function i2s

  real(real64) function tol_or_zero(tolerance)
    real(real64), intent(in), optional :: tolerance
    tol_or_zero = 0.0_real64
    if (present(tolerance)) tol_or_zero = tolerance
  end function tol_or_zero

  logical function same_size(n_expected, n_actual, assertion, message, location)
    integer, intent(in) :: n_expected, n_actual
    character(len=*), intent(in) :: assertion
    character(len=*), intent(in), optional :: message, location
    same_size = n_expected == n_actual
    if (.not. same_size) call fail(assertion, 'expected size ' // i2s(n_expected) // &
         ' but found size ' // i2s(n_actual), message, location)
  end function same_size

  ! ------------------------------------------------------------ assertEqual

  subroutine equal_real(expected, actual, tolerance, message, location)
    real(real64), intent(in) :: expected, actual
    real(real64), intent(in), optional :: tolerance
    character(len=*), intent(in), optional :: message, location
    real(real64) :: tol
    tol = tol_or_zero(tolerance)
    if (.not. within(expected, actual, tol)) call fail('assertEqual', &
         'expected <' // r2s(expected) // '> but found <' // r2s(actual) // &
         '>, |difference| > tolerance ' // r2s(tol), message, location)
  end subroutine equal_real

  subroutine equal_real_1d(expected, actual, tolerance, message, location)
    real(real64), intent(in) :: expected(:), actual(:)
    real(real64), intent(in), optional :: tolerance
    character(len=*), intent(in), optional :: message, location
    real(real64) :: tol
    integer :: i
    if (.not. same_size(size(expected), size(actual), 'assertEqual', message, location)) return
    tol = tol_or_zero(tolerance)
    do i = 1, size(actual)
      if (.not. within(expected(i), actual(i), tol)) then
        call fail('assertEqual', 'at index ' // i2s(i) // ' expected <' // r2s(expected(i)) // &
             '> but found <' // r2s(actual(i)) // '>, |difference| > tolerance ' // r2s(tol), &
             message, location)
        return
      end if
    end do
  end subroutine equal_real_1d

  !> Scalar expected value compared with every element (as pFUnit allows).
  subroutine equal_real_scalar_1d(expected, actual, tolerance, message, location)
    real(real64), intent(in) :: expected, actual(:)
    real(real64), intent(in), optional :: tolerance
    character(len=*), intent(in), optional :: message, location
    call equal_real_1d(spread(expected, 1, size(actual)), actual, tolerance, message, location)
  end subroutine equal_real_scalar_1d

  subroutine equal_int(expected, actual, message, location)
    integer, intent(in) :: expected, actual
    character(len=*), intent(in), optional :: message, location
    if (expected /= actual) call fail('assertEqual', 'expected <' // i2s(expected) // &
         '> but found <' // i2s(actual) // '>', message, location)
  end subroutine equal_int

  subroutine equal_int_1d(expected, actual, message, location)
    integer, intent(in) :: expected(:), actual(:)
    character(len=*), intent(in), optional :: message, location
    integer :: i
    if (.not. same_size(size(expected), size(actual), 'assertEqual', message, location)) return
    do i = 1, size(actual)
      if (expected(i) /= actual(i)) then
        call fail('assertEqual', 'at index ' // i2s(i) // ' expected <' // i2s(expected(i)) // &
             '> but found <' // i2s(actual(i)) // '>', message, location)
        return
      end if
    end do
  end subroutine equal_int_1d

  subroutine equal_logical(expected, actual, message, location)
    logical, intent(in) :: expected, actual
    character(len=*), intent(in), optional :: message, location
    character(len=*), parameter :: names(0:1) = ['.false.', '.true. ']
    if (expected .neqv. actual) call fail('assertEqual', 'expected <' // &
         trim(names(merge(1, 0, expected))) // '> but found <' // &
         trim(names(merge(1, 0, actual))) // '>', message, location)
  end subroutine equal_logical

  !> Fortran string comparison: trailing blanks are not significant.
  subroutine equal_string(expected, actual, message, location)
    character(len=*), intent(in) :: expected, actual
    character(len=*), intent(in), optional :: message, location
    if (expected /= actual) call fail('assertEqual', 'expected <"' // expected // &
         '"> but found <"' // actual // '">', message, location)
  end subroutine equal_string

  ! ---------------------------------------------------- assertTrue / False

  subroutine assertTrue(condition, message, location)
    logical, intent(in) :: condition
    character(len=*), intent(in), optional :: message, location
    if (.not. condition) call fail('assertTrue', 'condition is false', message, location)
  end subroutine assertTrue

  subroutine assertFalse(condition, message, location)
    logical, intent(in) :: condition
    character(len=*), intent(in), optional :: message, location
    if (condition) call fail('assertFalse', 'condition is true', message, location)
  end subroutine assertFalse

  ! ---------------------------------------------------------- comparisons
  ! As in pFUnit, real comparisons take an optional tolerance that widens
  ! the accepted range: lhs < rhs + tolerance, lhs > rhs - tolerance.

  subroutine less_real(lhs, rhs, tolerance, message, location)
    real(real64), intent(in) :: lhs, rhs
    real(real64), intent(in), optional :: tolerance
    character(len=*), intent(in), optional :: message, location
    if (.not. (lhs < rhs + tol_or_zero(tolerance))) call fail('assertLessThan', &
         '<' // r2s(lhs) // '> is not less than <' // r2s(rhs) // '>', message, location)
  end subroutine less_real

  subroutine less_equal_real(lhs, rhs, tolerance, message, location)
    real(real64), intent(in) :: lhs, rhs
    real(real64), intent(in), optional :: tolerance
    character(len=*), intent(in), optional :: message, location
    if (.not. (lhs <= rhs + tol_or_zero(tolerance))) call fail('assertLessThanOrEqual', &
         '<' // r2s(lhs) // '> is not less than or equal to <' // r2s(rhs) // '>', message, location)
  end subroutine less_equal_real

  subroutine greater_real(lhs, rhs, tolerance, message, location)
    real(real64), intent(in) :: lhs, rhs
    real(real64), intent(in), optional :: tolerance
    character(len=*), intent(in), optional :: message, location
    if (.not. (lhs > rhs - tol_or_zero(tolerance))) call fail('assertGreaterThan', &
         '<' // r2s(lhs) // '> is not greater than <' // r2s(rhs) // '>', message, location)
  end subroutine greater_real

  subroutine greater_equal_real(lhs, rhs, tolerance, message, location)
    real(real64), intent(in) :: lhs, rhs
    real(real64), intent(in), optional :: tolerance
    character(len=*), intent(in), optional :: message, location
    if (.not. (lhs >= rhs - tol_or_zero(tolerance))) call fail('assertGreaterThanOrEqual', &
         '<' // r2s(lhs) // '> is not greater than or equal to <' // r2s(rhs) // '>', message, location)
  end subroutine greater_equal_real

  subroutine less_int(lhs, rhs, message, location)
    integer, intent(in) :: lhs, rhs
    character(len=*), intent(in), optional :: message, location
    if (.not. (lhs < rhs)) call fail('assertLessThan', &
         '<' // i2s(lhs) // '> is not less than <' // i2s(rhs) // '>', message, location)
  end subroutine less_int

  subroutine less_equal_int(lhs, rhs, message, location)
    integer, intent(in) :: lhs, rhs
    character(len=*), intent(in), optional :: message, location
    if (.not. (lhs <= rhs)) call fail('assertLessThanOrEqual', &
         '<' // i2s(lhs) // '> is not less than or equal to <' // i2s(rhs) // '>', message, location)
  end subroutine less_equal_int

  subroutine greater_int(lhs, rhs, message, location)
    integer, intent(in) :: lhs, rhs
    character(len=*), intent(in), optional :: message, location
    if (.not. (lhs > rhs)) call fail('assertGreaterThan', &
         '<' // i2s(lhs) // '> is not greater than <' // i2s(rhs) // '>', message, location)
  end subroutine greater_int

  subroutine greater_equal_int(lhs, rhs, message, location)
    integer, intent(in) :: lhs, rhs
    character(len=*), intent(in), optional :: message, location
    if (.not. (lhs >= rhs)) call fail('assertGreaterThanOrEqual', &
         '<' // i2s(lhs) // '> is not greater than or equal to <' // i2s(rhs) // '>', message, location)
  end subroutine greater_equal_int

  ! -------------------------------------------------- assertRelativelyEqual
  ! Passes if |expected - actual| <= tolerance * |expected|.  A non-finite
  ! expected value only matches itself (otherwise Inf <= tol*Inf would pass).
  ! A zero expected value fails, as in pFUnit ("zero denominator").

  elemental logical function rel_within(e, a, tol)
    real(real64), intent(in) :: e, a, tol
    rel_within = within(e, a, 0.0_real64) .or. &
         (ieee_is_finite(e) .and. abs(e - a) <= tol * abs(e))
  end function rel_within

  subroutine rel_equal_real(expected, actual, tolerance, message, location)
    real(real64), intent(in) :: expected, actual, tolerance
    character(len=*), intent(in), optional :: message, location
    if (within(expected, 0.0_real64, 0.0_real64)) then
      call fail('assertRelativelyEqual', 'zero denominator (expected = 0)', message, location)
      return
    end if
    if (.not. rel_within(expected, actual, tolerance)) call fail('assertRelativelyEqual', &
         'expected <' // r2s(expected) // '> but found <' // r2s(actual) // &
         '>, relative difference > tolerance ' // r2s(tolerance), message, location)
  end subroutine rel_equal_real

  subroutine rel_equal_real_1d(expected, actual, tolerance, message, location)
    real(real64), intent(in) :: expected(:), actual(:), tolerance
    character(len=*), intent(in), optional :: message, location
    integer :: i
    if (.not. same_size(size(expected), size(actual), 'assertRelativelyEqual', message, location)) return
    if (any(within(expected, 0.0_real64, 0.0_real64))) then
      call fail('assertRelativelyEqual', 'zero denominator (an expected element = 0)', message, location)
      return
    end if
    do i = 1, size(actual)
      if (.not. rel_within(expected(i), actual(i), tolerance)) then
        call fail('assertRelativelyEqual', 'at index ' // i2s(i) // ' expected <' // &
             r2s(expected(i)) // '> but found <' // r2s(actual(i)) // &
             '>, relative difference > tolerance ' // r2s(tolerance), message, location)
        return
      end if
    end do
  end subroutine rel_equal_real_1d

  ! --------------------------------------------------------- assertIsFinite

  subroutine finite_real(x, message, location)
    real(real64), intent(in) :: x
    character(len=*), intent(in), optional :: message, location
    if (.not. ieee_is_finite(x)) call fail('assertIsFinite', '<' // r2s(x) // &
         '> is not finite', message, location)
  end subroutine finite_real

  ! ------------------------------------------------------------ test runner

  !> True once an assertion of the current test has failed; generated code
  !> checks it after every assertion and returns from the test.
  logical function anyExceptions()
    anyExceptions = failures_in_test > 0
  end function anyExceptions

  !> Run one test with optional set-up/tear-down and print PASS/FAIL.
  subroutine funit_run(name, test, before, after)
    character(len=*), intent(in) :: name
    procedure(funit_test_proc) :: test
    procedure(funit_test_proc), optional :: before, after

    if (.not. guard_registered) then
      guard_registered = c_atexit(c_funloc(exit_guard)) == 0
    end if
    running_test = name
    failures_in_test = 0
    first_failure = ''
    if (present(before)) call before()
    if (failures_in_test == 0) call test()
    ! Tear-down runs even after a failure, like pFUnit's @after.
    if (present(after)) call after()

    if (failures_in_test == 0) then
      n_passed = n_passed + 1
      write (output_unit, '(a)') 'PASS ' // name
    else
      n_failed = n_failed + 1
      if (failures_in_test > 1) first_failure = first_failure // ' (+' // &
           i2s(failures_in_test - 1) // ' more failures)'
      write (output_unit, '(a)') 'FAIL ' // name // ': ' // first_failure
    end if
    flush (output_unit)
  end subroutine funit_run

  !> Print "N passed, M failed"; a nonzero exit status tells CTest about failures.
  subroutine funit_summary()
    summary_done = .true.
    write (output_unit, '(i0, a, i0, a)') n_passed, ' passed, ', n_failed, ' failed'
    flush (output_unit)
    if (n_failed > 0) error stop 1
  end subroutine funit_summary

  !> atexit handler: an exit before the summary is a failure (the test under way ended the process).
  subroutine exit_guard() bind(C)
    if (summary_done) return
    write (output_unit, '(a)') 'FAIL the process exited during test '//running_test// &
      ' (a STOP or exit in the code under test)'
    flush (output_unit)
    call c_exit_now(70_c_int)
  end subroutine exit_guard

end module funit
