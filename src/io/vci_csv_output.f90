!> An observer that writes a run as CSV: one row per state (step, t, q, p, lambda, E_d) in FILE and
!> one row per impact in FILE.impacts.csv (step, t, alpha, gap, impulse, energies, condition). Full precision (17 significant digits), so a run can be
!> continued or reversed from its last row like init_from_momentum; it stores no checkpoint
!> (keeps_checkpoints is false), so such a continuation is not bit for bit. Replaced by the HDF5
!> observer when that is built.
module vci_csv_output
  use vci_kinds, only: dp, i8
  use vci_status, only: VCI_OK, VCI_ERR_IO, VCI_MSG_LEN
  use vci_observer, only: vci_observer_t, vci_run_info_t, vci_impact_t
  implicit none
  private

  !> The CSV observer: `call w%open(path, stat)`, then pass it to `integrate`; rows of t, q, p (and
  !> lambda, E_d) in PATH, the impacts in PATH.impacts.csv.
  type, extends(vci_observer_t), public :: vci_csv_writer_t
    character(len=:), allocatable :: path       !< the trajectory file
    integer :: unit = 0                         !< its unit
    integer :: impact_unit = 0                  !< the unit of PATH.impacts.csv
    logical :: opened = .false.                 !< both files are open
    integer :: n = 0                            !< configuration size of the run
    integer :: m = 0                            !< constraints of the run
    character(len=VCI_MSG_LEN) :: message = ''  !< what went wrong, naming the file
    integer(i8) :: split_steps = 0              !< steps of this run the safety net split
    integer :: largest_split = 0                !< most equal sub-steps of one of them
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
    !> Close both files.
    procedure :: on_finish => csv_finish
    !> No: CSV holds the state, not the solver memory a bitwise restart needs (vci_checkpoint).
    procedure :: keeps_checkpoints => csv_keeps_checkpoints
  end type vci_csv_writer_t

  character(len=*), parameter :: realfmt = 'es25.17e3'

contains

  !> No: CSV holds the state, not the solver memory a bitwise restart needs (vci_checkpoint).
  pure logical function csv_keeps_checkpoints(self)
    class(vci_csv_writer_t), intent(in) :: self
    csv_keeps_checkpoints = .false.
  end function csv_keeps_checkpoints

  !> Open FILE (and FILE.impacts.csv) for writing; stat = VCI_ERR_IO with a message if impossible.
  subroutine csv_open(self, path, stat)
    class(vci_csv_writer_t), intent(inout) :: self
    character(len=*), intent(in) :: path
    integer, intent(out) :: stat
    integer :: ios
    character(len=256) :: iomsg
    self%path = path
    open (newunit=self%unit, file=path, status='replace', action='write', iostat=ios, iomsg=iomsg)
    if (ios == 0) open (newunit=self%impact_unit, file=path//'.impacts.csv', status='replace', &
                        action='write', iostat=ios, iomsg=iomsg)
    if (ios /= 0) then
      self%message = 'cannot open '//path//' for writing: '//trim(iomsg)
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
    integer :: i
    character(len=:), allocatable :: head
    if (.not. self%opened) then
      stat = VCI_ERR_IO; return
    end if
    self%n = info%n; self%m = info%m
    self%split_steps = 0; self%largest_split = 0
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
    write (self%unit, '(a)') head//',energy'
    write (self%impact_unit, '(a)') 'step,t,alpha,gap,impulse,energy_before,energy_after,condition'
    call write_row(self, info%step0, info%t0, q, p, [(0.0_dp, i=1, info%m)], 0.0_dp)
  end subroutine csv_start

  subroutine csv_step(self, step, t, q, p, lambda, energy, stat)
    class(vci_csv_writer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    call write_row(self, step, t, q, p, lambda, energy)
  end subroutine csv_step

  subroutine write_row(self, step, t, q, p, lambda, energy)
    type(vci_csv_writer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    write (self%unit, '(i0,*(:,",",'//realfmt//'))') step, t, q, p, lambda, energy
  end subroutine write_row

  subroutine csv_impact(self, impact, stat)
    class(vci_csv_writer_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    ! condition: the impact condition that fixed the impulse (0 discrete, 1 Hamiltonian: also where
    ! the discrete one had no solution); the energies are E_d or H accordingly
    write (self%impact_unit, '(i0,2(",",'//realfmt//'),",",i0,3(",",'//realfmt//'),",",i0)') impact%step, impact%t, &
      impact%alpha, impact%gap, impact%impulse, impact%energy_before, impact%energy_after, impact%condition
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
    ! only when the net split a step: files of runs without splits keep their old layout
    if (self%opened .and. self%split_steps > 0) write (self%unit, '(a,i0,a,i0)') &
      '# split steps: ', self%split_steps, ', most sub-steps: ', self%largest_split
    if (status /= VCI_OK) write (self%unit, '(a)') '# stopped: '//message
    if (self%opened) close (self%unit)
    if (self%opened) close (self%impact_unit)
    self%opened = .false.
  end subroutine csv_finish

  pure function itoa(i) result(s)
    integer, intent(in) :: i
    character(len=:), allocatable :: s
    character(len=12) :: buf
    write (buf, '(i0)') i
    s = trim(buf)
  end function itoa
end module vci_csv_output
