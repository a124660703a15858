!> An observer that writes a run as CSV: one row per state (step, t, q, p, lambda, E_d) in FILE and
!> one row per impact in FILE.impacts.csv (step, t, alpha, gap, impulse, energies, condition). Full precision (17 significant digits), so a run can be
!> continued or reversed from its last row like init_from_momentum; it stores no checkpoint
!> (keeps_checkpoints is false), so such a continuation is not bit for bit. Replaced by the HDF5
!> observer when that is built.
!>
!> The rows are formatted here and written through C stdio (vci_text_file.c): gfortran's own file
!> writes drop a failed write (a full disk) without an error, and the run reported success beside a
!> truncated file. A failed write or close is VCI_ERR_IO with a message naming the file and the
!> cause; nothing more is written after it.
module vci_csv_output
  use, intrinsic :: iso_c_binding, only: c_ptr, c_null_ptr, c_associated, c_int, c_char, c_null_char
  use vci_kinds, only: dp, i8
  use vci_status, only: VCI_OK, VCI_ERR_IO, VCI_MSG_LEN
  use vci_observer, only: vci_observer_t, vci_run_info_t, vci_impact_t
  implicit none
  private

  !> The CSV observer: `call w%open(path, stat)`, then pass it to `integrate`; rows of t, q, p (and
  !> lambda, E_d) in PATH, the impacts in PATH.impacts.csv.
  type, extends(vci_observer_t), public :: vci_csv_writer_t
    character(len=:), allocatable :: path       !< the trajectory file
    logical :: opened = .false.                 !< both files are open
    integer :: n = 0                            !< configuration size of the run
    integer :: m = 0                            !< constraints of the run
    character(len=VCI_MSG_LEN) :: message = ''  !< what went wrong, naming the file
    integer(i8) :: split_steps = 0              !< steps of this run the safety net split
    integer :: largest_split = 0                !< most equal sub-steps of one of them
    type(c_ptr), private :: file = c_null_ptr, impact_file = c_null_ptr   ! C stdio streams
    logical, private :: failed = .false.                                   ! a write failed (message)
    character(len=:), allocatable, private :: line                         ! one row, formatted
  contains
    !> Open FILE (and FILE.impacts.csv) for writing; stat = VCI_ERR_IO with a message if impossible.
    procedure :: open => csv_open
    !> Write the header and the start state.
    procedure :: on_start => csv_start
    !> Write an accepted step's state.
    procedure :: on_step => csv_step
    !> Write an impact to the impact file.
    procedure :: on_impact => csv_impact
    !> Count a step the safety net split (the last line of FILE says how many).
    procedure :: on_split => csv_split
    !> Close both files (VCI_ERR_IO when what was written did not all reach them).
    procedure :: on_finish => csv_finish
    !> No: CSV holds the state, not the solver memory a bitwise restart needs (vci_checkpoint).
    procedure :: keeps_checkpoints => csv_keeps_checkpoints
    !> The message of the last failure (naming the file and the cause).
    procedure :: failure_cause => csv_failure_cause
  end type vci_csv_writer_t

  character(len=*), parameter :: realfmt = 'es25.17e3'
  integer, parameter :: real_width = 25

  interface   ! src/io/vci_text_file.c
    type(c_ptr) function c_text_open(path, err) bind(C, name='vci_text_open')
      import :: c_ptr, c_char, c_int
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int), intent(out) :: err
    end function c_text_open
    integer(c_int) function c_text_put(file, line, length) bind(C, name='vci_text_put')
      import :: c_ptr, c_char, c_int
      type(c_ptr), value :: file
      character(kind=c_char), intent(in) :: line(*)
      integer(c_int), value :: length
    end function c_text_put
    integer(c_int) function c_text_close(file) bind(C, name='vci_text_close')
      import :: c_ptr, c_int
      type(c_ptr), value :: file
    end function c_text_close
    subroutine c_text_reason(code, buf, size) bind(C, name='vci_text_reason')
      import :: c_char, c_int
      integer(c_int), value :: code, size
      character(kind=c_char), intent(out) :: buf(*)
    end subroutine c_text_reason
  end interface

contains

  !> No: CSV holds the state, not the solver memory a bitwise restart needs (vci_checkpoint).
  pure logical function csv_keeps_checkpoints(self)
    class(vci_csv_writer_t), intent(in) :: self
    csv_keeps_checkpoints = .false.
  end function csv_keeps_checkpoints

  subroutine csv_failure_cause(self, cause)
    class(vci_csv_writer_t), intent(in) :: self
    character(len=*), intent(out) :: cause
    cause = self%message
  end subroutine csv_failure_cause

  !> Open FILE (and FILE.impacts.csv) for writing; stat = VCI_ERR_IO with a message if impossible.
  subroutine csv_open(self, path, stat)
    class(vci_csv_writer_t), intent(inout) :: self
    character(len=*), intent(in) :: path
    integer, intent(out) :: stat
    integer(c_int) :: err, e2
    if (self%opened) call close_files(self, err)
    self%path = path
    self%failed = .false.; self%message = ''
    self%file = c_text_open(path//c_null_char, err)
    if (err == 0) self%impact_file = c_text_open(path//'.impacts.csv'//c_null_char, err)
    if (err /= 0) then
      if (c_associated(self%file)) e2 = c_text_close(self%file)
      self%file = c_null_ptr
      self%message = 'cannot open '//path//' for writing: '//reason(err)
      stat = VCI_ERR_IO; return
    end if
    self%opened = .true.
    stat = VCI_OK
  end subroutine csv_open

  subroutine csv_start(self, info, q, p, stat)
    class(vci_csv_writer_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
    integer :: i, ios
    character(len=:), allocatable :: head
    if (.not. self%opened) then
      stat = VCI_ERR_IO; return
    end if
    self%n = info%n; self%m = info%m
    self%split_steps = 0; self%largest_split = 0
    ! one row: the step (at most 20 characters) and 2n + m + 2 numbers, each after a comma
    if (allocated(self%line)) deallocate (self%line)
    allocate (character(len=21 + (real_width + 1) * (2 * info%n + info%m + 2)) :: self%line, stat=ios)
    if (ios /= 0) then
      call write_failed(self, 'cannot allocate a row of the file (out of memory)', stat); return
    end if
    head = 'step,t'
    do i = 1, info%n
      head = head//',q'//itoa(i)
    end do
    do i = 1, info%n
      head = head//',p'//itoa(i)
    end do
    do i = 1, info%m
      head = head//',lambda'//itoa(i)
    end do
    call put(self, self%file, head//',energy', stat)
    call put(self, self%impact_file, 'step,t,alpha,gap,impulse,energy_before,energy_after,condition', stat)
    call write_row(self, info%step0, info%t0, q, p, [(0.0_dp, i=1, info%m)], 0.0_dp, stat)
  end subroutine csv_start

  subroutine csv_step(self, step, t, q, p, lambda, energy, stat)
    class(vci_csv_writer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    call write_row(self, step, t, q, p, lambda, energy, stat)
  end subroutine csv_step

  subroutine write_row(self, step, t, q, p, lambda, energy, stat)
    type(vci_csv_writer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    integer :: ios
    if (self%failed .or. .not. self%opened) then
      stat = VCI_ERR_IO; return
    end if
    write (self%line, '(i0,*(:,",",'//realfmt//'))', iostat=ios) step, t, q, p, lambda, energy
    if (ios /= 0) then
      call write_failed(self, 'a row does not fit its buffer', stat); return
    end if
    call put(self, self%file, self%line(1:len_trim(self%line)), stat)
  end subroutine write_row

  subroutine csv_impact(self, impact, stat)
    class(vci_csv_writer_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    character(len=8 * (real_width + 1) + 60) :: row
    integer :: ios
    if (self%failed .or. .not. self%opened) then
      stat = VCI_ERR_IO; return
    end if
    ! condition: the impact condition that fixed the impulse (0 discrete, 1 Hamiltonian: also where
    ! the discrete one had no solution); the energies are E_d or H accordingly
    write (row, '(i0,2(",",'//realfmt//'),",",i0,3(",",'//realfmt//'),",",i0)', iostat=ios) impact%step, impact%t, &
      impact%alpha, impact%gap, impact%impulse, impact%energy_before, impact%energy_after, impact%condition
    if (ios /= 0) then
      call write_failed(self, 'an impact row does not fit its buffer', stat); return
    end if
    call put(self, self%impact_file, row(1:len_trim(row)), stat)
  end subroutine csv_impact

  subroutine csv_split(self, step, parts, stat)
    class(vci_csv_writer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    integer, intent(in) :: parts
    integer, intent(inout) :: stat
    self%split_steps = self%split_steps + 1
    self%largest_split = max(self%largest_split, parts)
  end subroutine csv_split

  subroutine csv_finish(self, status, message, stat)
    class(vci_csv_writer_t), intent(inout) :: self
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    integer, intent(inout) :: stat
    character(len=64) :: note
    integer(c_int) :: err
    integer :: s
    if (.not. self%opened) return
    s = VCI_OK
    ! only when the net split a step: files of runs without splits keep their old layout
    if (self%split_steps > 0) then
      write (note, '(a,i0,a,i0)') '# split steps: ', self%split_steps, ', most sub-steps: ', self%largest_split
      call put(self, self%file, trim(note), s)
    end if
    if (status /= VCI_OK) call put(self, self%file, '# stopped: '//message, s)
    call close_files(self, err)
    if (err /= 0 .and. .not. self%failed) call write_failed(self, 'writing failed: '//reason(err), s)
    if (self%failed) stat = VCI_ERR_IO
  end subroutine csv_finish

  !> Both streams closed (flushing them): err = the first failure's errno, 0 if none.
  subroutine close_files(self, err)
    type(vci_csv_writer_t), intent(inout) :: self
    integer(c_int), intent(out) :: err
    integer(c_int) :: e2
    err = 0; e2 = 0
    if (c_associated(self%file)) err = c_text_close(self%file)
    if (c_associated(self%impact_file)) e2 = c_text_close(self%impact_file)
    if (err == 0) err = e2
    self%file = c_null_ptr; self%impact_file = c_null_ptr
    self%opened = .false.
  end subroutine close_files

  !> One line to a stream; a failure is kept (message, no more writes) and returned as VCI_ERR_IO.
  subroutine put(self, file, text, stat)
    type(vci_csv_writer_t), intent(inout) :: self
    type(c_ptr), intent(in) :: file
    character(len=*), intent(in) :: text
    integer, intent(inout) :: stat
    integer(c_int) :: err
    if (self%failed) then
      stat = VCI_ERR_IO; return
    end if
    err = c_text_put(file, text, int(len(text), c_int))
    if (err /= 0) call write_failed(self, 'writing failed: '//reason(err), stat)
  end subroutine put

  subroutine write_failed(self, cause, stat)
    type(vci_csv_writer_t), intent(inout) :: self
    character(len=*), intent(in) :: cause
    integer, intent(inout) :: stat
    self%failed = .true.
    self%message = self%path//': '//cause
    stat = VCI_ERR_IO
  end subroutine write_failed

  !> The system's text for an errno value (strerror).
  function reason(code) result(text)
    integer(c_int), intent(in) :: code
    character(len=128) :: text
    character(kind=c_char) :: buf(128)
    integer :: i
    call c_text_reason(code, buf, size(buf, kind=c_int))
    text = ''
    do i = 1, size(buf)
      if (buf(i) == c_null_char) exit
      text(i:i) = buf(i)
    end do
  end function reason

  pure function itoa(i) result(s)
    integer, intent(in) :: i
    character(len=:), allocatable :: s
    character(len=12) :: buf
    write (buf, '(i0)') i
    s = trim(buf)
  end function itoa
end module vci_csv_output
