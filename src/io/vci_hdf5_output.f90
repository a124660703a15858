!> An observer that streams a run into one HDF5 file (layout: docs/OUTPUT.md), and the reader that
!> takes the last state of such a file for a restart.
!>
!> Streaming: steps are kept in a buffer of `flush_every` rows; when it is full, and after every
!> impact, the rows are appended to chunked extendible datasets and the file is flushed (H5Fflush).
!> Between flushes the file is not touched, so a killed run leaves a file that opens and holds every
!> step up to the last flush. Memory does not grow with the number of steps.
!>
!> Restart: the writer keeps checkpoints (keeps_checkpoints) without knowing the driver: before a
!> report that will flush it asks for one (wants_checkpoint), the driver hands it over
!> (on_checkpoint), and the flush stores it in `/checkpoint` with the row it is the state of;
!> `vci_hdf5_read_checkpoint` + `restore` then continue the run bit for bit, and
!> `open(..., append=.true.)` continues the same file.
!>
!> Nothing here stops or prints (HDF5's own error printing is switched off); failures give
!> VCI_ERR_IO and a message naming the file and the cause. Files are input like any other: every
!> rank, shape, size and type read from one is checked before it is used (a foreign or damaged
!> file gives VCI_ERR_IO, never a crash or an allocation the file's numbers dictate).
module vci_hdf5_output
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use hdf5
  use vci_kinds, only: dp, i8
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use vci_status, only: VCI_OK, VCI_ERR_IO, VCI_ERR_MEMORY, VCI_MSG_LEN
  use vci_message, only: vci_set_message, vci_int_text
  use vci_limits, only: vci_size_problem
  use vci_observer, only: vci_observer_t, vci_run_info_t, vci_impact_t
  use vci_h5_io
  use vci_checkpoint, only: vci_checkpoint_t, vci_checkpoint_from_state, VCI_CHECKPOINT_VERSION, VCI_CHECKPOINT_OLDEST
  use vci_checkpoint, only: vci_checkpoint_record_size
  use vci_integrator, only: vci_scheme_name
  implicit none
  private

  !> Value of the root attribute `status` while a run is being written. A file that still says so
  !> after the run was not closed (the process was killed); its data are valid up to `steps_completed`.
  integer, parameter, public :: VCI_HDF5_RUNNING = -1

  !> Written as the root attribute `vci_version`.
  character(len=*), parameter, public :: VCI_HDF5_LIBRARY_VERSION = VCI_VERSION_STRING

  !> Default number of steps between flushes.
  integer, parameter, public :: VCI_HDF5_FLUSH_EVERY = 4096
  !> Most steps between flushes (the buffer holds that many rows of t, q, p, energy, lambda).
  integer, parameter, public :: VCI_HDF5_FLUSH_MAX = 1048576
  !> Largest `every` (store every k-th state): 2^30, far beyond any useful thinning.
  integer, parameter, public :: VCI_HDF5_EVERY_MAX = 2**30

  ! rows per chunk: states and steps, impacts (few, so small chunks)
  integer, parameter :: chunk_rows = 1024, impact_chunk_rows = 64

  !> The HDF5 observer. Use: `call w%open(path, stat)`, then `call integ%integrate(nsteps, dir,
  !> stat, w)`; the file is closed by the run's end (on_finish).
  type, extends(vci_observer_t), public :: vci_hdf5_writer_t
    character(len=VCI_MSG_LEN) :: message = ''   !< what went wrong, naming the file
    character(len=:), allocatable :: path         !< the file
    character(len=:), allocatable :: scene        !< root attribute `scene`
    integer :: flush_every = VCI_HDF5_FLUSH_EVERY  !< steps between flushes
    logical :: flush_on_impact = .true.           !< flush after the step of every impact
    logical :: append = .false.                   !< continuing an existing file
    logical :: is_open = .false.                  !< a file is open
    integer, private :: every = 1                 !< store the states whose index is a multiple of it (open)
    integer, private :: deflate = 0               !< gzip level of new datasets, 0: none (open)
    type(vci_checkpoint_t), private :: cp          !< the driver's latest checkpoint (on_checkpoint)
    logical, private :: have_cp = .false.
    logical, private :: discarded = .false.       !< writes failed (a full disk): nothing more reaches the file
    integer(i8), private :: last_step = 0          !< index of the last state reported (on_start, on_step)
    real(dp), private :: t_start = 0.0_dp          !< time of the run's start state (index step0)
    integer(hid_t), private :: file = -1, g_imp = -1, g_cp = -1
    integer(hid_t), private :: d_t = -1, d_q = -1, d_p = -1, d_e = -1, d_l = -1, d_k = -1
    integer(hid_t), private :: d_it = -1, d_is = -1, d_ia = -1, d_ig = -1, d_iq = -1, d_ii = -1
    integer, private :: n = 0, m = 0, n_gaps = 0, direction = 1
    logical, private :: started = .false., flush_pending = .false.
    real(dp), private :: h = 0.0_dp
    integer(i8), private :: rows = 0, steps = 0, impacts = 0   ! already in the file
    integer(i8), private :: split_steps = 0   ! steps the safety net split (attribute split_steps)
    integer, private :: largest_split = 0     ! most equal sub-steps of one (attribute largest_split)
    integer(i8), private :: row_start = 0, step0 = 0           ! row and integrator index of the start state
    ! file index (steps of h from row 0) of the start state, and of the last row on disk
    integer(i8), private :: base = 0, last_index = 0
    ! the last state reported, when it is not stored (every > 1): stored as the file's last row if
    ! the run ends there
    logical, private :: last_stored = .true.
    real(dp), private :: lt = 0.0_dp, le = 0.0_dp
    real(dp), allocatable, private :: lq(:), lp(:), ll(:)
    ! buffered states (ns of them), steps (ne) and impacts (ni), not yet in the file
    integer, private :: ns = 0, ne = 0, ni = 0
    real(dp), allocatable, private :: bt(:), bq(:, :), bp(:, :), be(:), bl(:, :)
    real(dp), allocatable, private :: it(:), ia(:), iq(:, :), ii(:)
    integer(i8), allocatable, private :: is(:)
    integer, allocatable, private :: ig(:)
    integer(i8), allocatable, private :: bk(:)    ! file index of each buffered state (/step, every > 1)
    real(dp), allocatable, private :: cp_rec(:)   !< the file's checkpoint, when it is valid (reading)
    integer, private :: cp_version = 0            !< its layout version (attribute /checkpoint version)
    logical, private :: cp_version_written = .false.   !< this session wrote /checkpoint's version
  contains
    !> Open PATH for a run: a new file, or an existing one kept (VCI_ERR_IO) unless `overwrite` or `append`.
    procedure :: open => w_open
    !> Close the file without a run end (when a run could not start). Safe to call twice.
    procedure :: close => w_close
    !> The run starts: write the run's attributes and its start state.
    procedure :: on_start => w_start
    !> Buffer an accepted step; flush every flush_every steps and after an impact.
    procedure :: on_step => w_step
    !> Buffer an impact.
    procedure :: on_impact => w_impact
    !> Count a step the safety net split (attributes split_steps, largest_split, at each flush).
    procedure :: on_split => w_split
    !> The run ended: write what is buffered, the status and its message, and close the file.
    procedure :: on_finish => w_finish
    !> Yes: every flush stores the checkpoint of its last row, so a restart is bitwise.
    procedure :: keeps_checkpoints => w_keeps_checkpoints
    !> Before on_start, and before an on_step that flushes (a full buffer, or an impact in the step).
    procedure :: wants_checkpoint => w_wants_checkpoint
    !> Keep the driver's checkpoint for the next flush (stored only if it is the state of its last row).
    procedure :: on_checkpoint => w_checkpoint
    !> The message of the last failure (naming the file and the cause).
    procedure :: failure_cause => w_failure_cause
  end type vci_hdf5_writer_t

  public :: vci_hdf5_read_checkpoint, vci_hdf5_close_file

contains

  !> The root attribute `start`: how the run began (vci_run_info_t%start).
  pure function start_name(kind) result(name)
    integer, intent(in) :: kind
    character(len=10) :: name
    select case (kind)
    case (1); name = 'pair'
    case (2); name = 'momentum'
    case (3); name = 'checkpoint'
    case default; name = 'unknown'
    end select
  end function start_name

  !> Open PATH for a run. A new file is created; an existing one is kept (VCI_ERR_IO) unless
  !> `overwrite`. With `append`, PATH must exist and the run must continue its last state in the same
  !> direction. `scene` names the model (root attribute), `flush_every` sets the flush interval.
  !> `every` = k stores every k-th state (those whose index from row 0 is a multiple of k, and the
  !> run's last state); impacts are all stored. Appending keeps the file's k (a different `every`
  !> is refused). `compress` = 1..9: gzip level (with shuffle) of a new file's row datasets.
  subroutine w_open(self, path, stat, overwrite, append, scene, flush_every, every, compress)
    class(vci_hdf5_writer_t), intent(inout) :: self
    character(len=*), intent(in) :: path
    integer, intent(out) :: stat
    logical, intent(in), optional :: overwrite, append
    character(len=*), intent(in), optional :: scene
    integer, intent(in), optional :: flush_every, every, compress
    logical :: exists, replace
    integer :: err, every_asked
    character(len=256) :: cause

    stat = VCI_OK
    self%message = ''
    if (self%is_open) call w_close(self)
    self%path = path
    self%append = .false.
    if (present(append)) self%append = append
    replace = .false.
    if (present(overwrite)) replace = overwrite
    if (present(scene)) then
      self%scene = scene
    else if (.not. allocated(self%scene)) then
      self%scene = ''
    end if
    if (present(flush_every)) then
      if (flush_every < 1 .or. flush_every > VCI_HDF5_FLUSH_MAX) then
        call fail(self, 'flush_every must be in [1, 1048576]', stat); return
      end if
      self%flush_every = flush_every
    end if
    every_asked = 0
    if (present(every)) then
      if (every < 1 .or. every > VCI_HDF5_EVERY_MAX) then
        call fail(self, 'every must be in [1, 2^30]', stat); return
      end if
      every_asked = every
    end if
    self%every = max(1, every_asked)
    self%deflate = 0
    if (present(compress)) then
      if (compress < 0 .or. compress > 9) then
        call fail(self, 'compress must be a gzip level in [0, 9] (0: none)', stat); return
      end if
      self%deflate = compress
    end if
    self%started = .false.; self%flush_pending = .false.
    self%ns = 0; self%ne = 0; self%ni = 0
    self%have_cp = .false.; self%discarded = .false.; self%cp_version_written = .false.

    call h5open_f(err)
    if (err == 0) call h5eset_auto_f(0, err)   ! the library never prints
    if (err /= 0) then
      call fail(self, 'the HDF5 library could not be initialised', stat); return
    end if

    inquire (file=path, exist=exists)
    if (self%append) then
      if (.not. exists) then
        call fail(self, 'cannot append: the file does not exist', stat); return
      end if
      if (h5io_path_kind(path) /= 1) then     ! never opened: opening a FIFO blocks
        call fail(self, 'cannot append: not a regular file (a FIFO, a device or a directory)', stat); return
      end if
      call h5fopen_f(path, H5F_ACC_RDWR_F, self%file, err)
      if (err /= 0) then
        call fail(self, 'cannot open for appending (not an HDF5 file, or not writable)', stat); return
      end if
      self%is_open = .true.
      ! a run killed inside a flush may have left datasets pointing past the recorded end of the file
      call h5io_allocate_to_file_end(self%file, stat, self%message, self%path)
      if (stat == VCI_OK) call open_existing(self, stat)
      if (stat == VCI_OK .and. every_asked > 0 .and. every_asked /= self%every) then
        call vci_set_message(self%message, self%path//': cannot append: the file stores every '// &
          trim(vci_int_text(self%every))//'-th state, not every '//trim(vci_int_text(every_asked))//'-th')
        stat = VCI_ERR_IO
      end if
      if (stat /= VCI_OK) call w_close(self)
      return
    end if

    if (exists .and. .not. replace) then
      call fail(self, 'the file exists and is kept (pass overwrite=.true. to replace it)', stat); return
    end if
    call h5fcreate_f(path, H5F_ACC_TRUNC_F, self%file, err)
    if (err /= 0) then
      cause = h5io_os_cause()   ! HDF5's record of the OS's reason, else the Fortran runtime's
      if (len_trim(cause) == 0) cause = os_reason(path)
      call fail(self, 'cannot create the file: '//trim(cause), stat); return
    end if
    self%is_open = .true.
    call h5io_put_attr(self%file, 'vci_version', VCI_HDF5_LIBRARY_VERSION, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'scene', self%scene, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'created', iso_now(), stat, self%message, self%path)
    call h5io_put_attr(self%file, 'status', VCI_HDF5_RUNNING, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'status_message', 'opened, no run yet', stat, self%message, self%path)
    if (stat == VCI_OK) call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
    if (stat == VCI_OK .and. err /= 0) then
      call fail(self, 'flush after creation failed: '//trim(h5io_os_cause()), stat)
      call h5io_discard_writes(self%file)
      self%discarded = .true.
    end if
    if (stat /= VCI_OK) call w_close(self)
  end subroutine w_open

  !> Yes: every flush stores the checkpoint of its last row, so a restart is bitwise.
  pure logical function w_keeps_checkpoints(self)
    class(vci_hdf5_writer_t), intent(in) :: self
    w_keeps_checkpoints = .true.
  end function w_keeps_checkpoints

  !> Before on_start, and before an on_step that flushes (a full buffer, or an impact in the step).
  pure logical function w_wants_checkpoint(self)
    class(vci_hdf5_writer_t), intent(in) :: self
    w_wants_checkpoint = self%is_open .and. (.not. self%started .or. &
      (stored_index(self, self%last_step + self%direction) .and. (self%ne + 1 >= self%flush_every .or. self%flush_pending)))
  end function w_wants_checkpoint

  !> Keep the driver's checkpoint for the next flush (stored only if it is the state of its last row).
  subroutine w_checkpoint(self, cp, stat)
    class(vci_hdf5_writer_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: cp
    integer, intent(inout) :: stat
    integer :: s
    self%have_cp = .false.
    if (.not. allocated(cp%q)) return   ! (an empty checkpoint, of a failed checkpoint(): none to store)
    ! a copy with stat= (intrinsic assignment ends the program when memory runs out, issue 24)
    call self%cp%copy_from(cp, s)
    self%have_cp = s == VCI_OK
    if (s /= VCI_OK) then
      write (self%message, '(a,i0,a)') 'no memory to keep the checkpoint of step ', cp%step, ' for the next flush'
      stat = VCI_ERR_MEMORY
    end if
  end subroutine w_checkpoint

  !> The message of the last failure (naming the file and the cause).
  subroutine w_failure_cause(self, cause)
    class(vci_hdf5_writer_t), intent(in) :: self
    character(len=*), intent(out) :: cause
    cause = self%message
  end subroutine w_failure_cause

  !> Close the file without a run end (e.g. when a run could not start). Safe to call twice.
  !> What HDF5 holds is flushed first; then the descriptor goes to the sink, so that the close
  !> itself writes nothing to the disk (it rewrites the superblock when HDF5 gives back the unused
  !> end of its metadata block): a full disk there failed the close after the file's last flush,
  !> and HDF5's own close of the half-closed file at exit crashed the process (SIGSEGV).
  subroutine w_close(self)
    class(vci_hdf5_writer_t), intent(inout) :: self
    integer :: err
    if (self%is_open) then
      call flush_into_sink(self%file, self%discarded, err)
      self%discarded = .true.
    end if
    call h5io_close_dset(self%d_t); call h5io_close_dset(self%d_q); call h5io_close_dset(self%d_p)
    call h5io_close_dset(self%d_e); call h5io_close_dset(self%d_l); call h5io_close_dset(self%d_k)
    call h5io_close_dset(self%d_it); call h5io_close_dset(self%d_is); call h5io_close_dset(self%d_ia)
    call h5io_close_dset(self%d_ig); call h5io_close_dset(self%d_iq); call h5io_close_dset(self%d_ii)
    if (self%g_imp >= 0) call h5gclose_f(self%g_imp, err)
    if (self%g_cp >= 0) call h5gclose_f(self%g_cp, err)
    self%g_imp = -1; self%g_cp = -1
    if (self%is_open) call h5fclose_f(self%file, err)
    self%file = -1
    self%is_open = .false.; self%started = .false.
  end subroutine w_close

  !> Reopen the datasets of an existing file and read what on_start will check.
  subroutine open_existing(self, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer, intent(inout) :: stat
    character(len=:), allocatable :: dirname
    integer :: err
    logical :: ex
    integer(i8) :: rows_t, rows_q, rows_p, rows_e, rows_l, rows_k, row_cp
    call h5io_get_attr(self%file, 'n', self%n, stat, self%message, self%path)
    call h5io_get_attr(self%file, 'm', self%m, stat, self%message, self%path)
    call h5io_get_attr(self%file, 'n_gaps', self%n_gaps, stat, self%message, self%path)
    call h5io_get_attr(self%file, 'h', self%h, stat, self%message, self%path)
    call h5io_get_attr(self%file, 'direction', dirname, stat, self%message, self%path)
    if (stat /= VCI_OK) return
    if (dirname /= 'forward' .and. dirname /= 'backward') then
      call fail(self, 'attribute direction is neither forward nor backward', stat); return
    end if
    self%direction = merge(-1, 1, dirname == 'backward')
    if (vci_size_problem(self%n, self%m, self%n_gaps) /= '') then
      call fail(self, 'attributes n, m, n_gaps are no model sizes ('//trim(vci_size_problem(self%n, self%m, &
                self%n_gaps))//')', stat); return
    end if
    if (.not. (ieee_is_finite(self%h) .and. self%h > 0.0_dp)) then
      call fail(self, 'attribute h is not a positive finite step length', stat); return
    end if
    ! split counts: absent in files written before them (0: as if none was split)
    self%split_steps = 0; self%largest_split = 0
    call h5aexists_f(self%file, 'split_steps', ex, err)
    if (err == 0 .and. ex) call h5io_get_attr(self%file, 'split_steps', self%split_steps, stat, self%message, self%path)
    call h5aexists_f(self%file, 'largest_split', ex, err)
    if (err == 0 .and. ex) call h5io_get_attr(self%file, 'largest_split', self%largest_split, stat, self%message, self%path)
    ! every: absent in files written before it existed (every state stored)
    self%every = 1
    call h5aexists_f(self%file, 'every', ex, err)
    if (err == 0 .and. ex) call h5io_get_attr(self%file, 'every', self%every, stat, self%message, self%path)
    if (stat /= VCI_OK) return
    if (self%every < 1 .or. self%every > VCI_HDF5_EVERY_MAX) then
      call fail(self, 'attribute every is not in [1, 2^30]', stat); return
    end if
    call h5io_open_dset(self%file, 't', self%d_t, stat, self%message, self%path)
    call h5io_open_dset(self%file, 'q', self%d_q, stat, self%message, self%path)
    call h5io_open_dset(self%file, 'p', self%d_p, stat, self%message, self%path)
    call h5io_open_dset(self%file, 'energy', self%d_e, stat, self%message, self%path)
    if (self%m > 0) call h5io_open_dset(self%file, 'lambda', self%d_l, stat, self%message, self%path)
    ! shapes: rows of n values (Fortran order: the row index is the last dimension)
    rows_t = h5io_rows(self%d_t, 't', 0, stat, self%message, self%path)
    rows_q = h5io_rows(self%d_q, 'q', self%n, stat, self%message, self%path)
    rows_p = h5io_rows(self%d_p, 'p', self%n, stat, self%message, self%path)
    rows_e = h5io_rows(self%d_e, 'energy', 0, stat, self%message, self%path)
    rows_l = huge(1_i8)
    if (self%m > 0) rows_l = h5io_rows(self%d_l, 'lambda', self%m, stat, self%message, self%path)
    rows_k = huge(1_i8)
    if (self%every > 1) then
      call h5io_open_dset(self%file, 'step', self%d_k, stat, self%message, self%path)
      rows_k = h5io_rows(self%d_k, 'step', 0, stat, self%message, self%path)
      rows_t = min(rows_t, rows_k)
    end if
    if (stat /= VCI_OK) return
    ! Trust the steps that steps_completed (written last at every flush) vouches for: a file whose
    ! run was killed during a flush may hold a few more rows, which are dropped here.
    call h5io_get_attr(self%file, 'steps_completed', self%steps, stat, self%message, self%path)
    if (stat /= VCI_OK) return
    self%steps = min(self%steps, rows_e, rows_t - 1, rows_q - 1, rows_p - 1, rows_l)
    if (self%steps < 0) then
      call fail(self, 'the file holds no state (/t is empty)', stat); return
    end if
    ! A checkpoint that is the state of a row on disk decides where the file ends: the run
    ! continues from it bit for bit. A kill between the checkpoint and steps_completed (written
    ! together at every flush, in an order HDF5 decides) leaves the checkpoint one flush ahead of
    ! or behind steps_completed; either way its row and every row before it are complete.
    call h5lexists_f(self%file, 'checkpoint', ex, err)
    if (err == 0 .and. ex) call h5gopen_f(self%file, 'checkpoint', self%g_cp, err)
    if (allocated(self%cp_rec)) deallocate (self%cp_rec)
    if (self%g_cp >= 0) then
      row_cp = checkpoint_row(self, min(rows_t, rows_q, rows_p) - 1, min(rows_e, rows_l), stat)
      if (stat /= VCI_OK) return
      if (row_cp >= 0) self%steps = row_cp
    end if
    self%rows = self%steps + 1
    ! the index of the last row: its row number unless states were thinned (every > 1: /step)
    self%last_index = self%rows - 1
    if (self%every > 1) then
      call h5io_read_i8(self%d_k, self%rows - 1, self%last_index, stat, self%message, self%path)
      if (stat /= VCI_OK) return
      if (self%last_index < self%rows - 1 .or. self%last_index > 2_i8**53) then
        call fail(self, 'dataset step holds no state index in its last row', stat); return
      end if
    end if
    if (self%n_gaps > 0) then
      call h5gopen_f(self%file, 'impacts', self%g_imp, err)
      if (err /= 0) then
        call fail(self, 'cannot append: group /impacts missing', stat); return
      end if
      call h5io_open_dset(self%g_imp, 'time', self%d_it, stat, self%message, self%path)
      call h5io_open_dset(self%g_imp, 'step', self%d_is, stat, self%message, self%path)
      call h5io_open_dset(self%g_imp, 'alpha', self%d_ia, stat, self%message, self%path)
      call h5io_open_dset(self%g_imp, 'gap_index', self%d_ig, stat, self%message, self%path)
      call h5io_open_dset(self%g_imp, 'q', self%d_iq, stat, self%message, self%path)
      call h5io_open_dset(self%g_imp, 'impulse', self%d_ii, stat, self%message, self%path)
      if (stat /= VCI_OK) return
      self%impacts = trusted_impacts(self, stat)
      if (stat /= VCI_OK) return
    end if
    if (self%append) call truncate_to_trusted(self, stat)
  end subroutine open_existing

  !> The row of /checkpoint/record when it is a valid checkpoint of that row (its layout version is
  !> this library's, its time, q and p are the row's, the row is within max_row and its step within
  !> max_steps), else -1; kept in cp_rec. A checkpoint of a newer layout than this library knows
  !> refuses the file (stat): a newer vci wrote it, and this one would continue it differently.
  integer(i8) function checkpoint_row(self, max_row, max_steps, stat) result(row)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer(i8), intent(in) :: max_row, max_steps
    integer, intent(inout) :: stat
    real(dp), allocatable :: rec(:), qr(:, :), pr(:, :)
    real(dp) :: tr(1), t_cp
    integer :: n, s, st
    logical :: ex_version
    row = -1
    ! the layout version; files written before it was stored hold version 3 (the last unversioned)
    s = VCI_OK
    self%cp_version = 3
    call h5aexists_f(self%g_cp, 'version', ex_version, st)
    if (st == 0 .and. ex_version) call h5io_get_attr(self%g_cp, 'version', self%cp_version, s, self%message, self%path)
    if (s /= VCI_OK) then
      self%message = ''; return      ! unreadable: no usable checkpoint, the last row serves
    end if
    if (self%cp_version > VCI_CHECKPOINT_VERSION) then
      call vci_set_message(self%message, self%path//': its checkpoint has layout version '// &
        trim(vci_int_text(self%cp_version))//', newer than this library''s '// &
        trim(vci_int_text(VCI_CHECKPOINT_VERSION))//' (written by a newer vci: continue it with that one)')
      stat = VCI_ERR_IO; return
    end if
    ! a layout older than from_record reads: the last row serves
    if (self%cp_version < VCI_CHECKPOINT_OLDEST) return
    n = self%n
    allocate (rec(1 + vci_checkpoint_record_size(n, self%m, self%cp_version)), qr(n, 1), pr(n, 1), stat=st)
    if (st /= 0) return
    s = VCI_OK
    call h5io_get_vector(self%g_cp, 'record', rec, s, self%message, self%path)
    if (s /= VCI_OK) then
      self%message = ''; return      ! no usable checkpoint: not an error, the last row serves
    end if
    ! [row, k, t0, h, energy, e_arrive, e_dir, q(n), p(n), vel(n), lambda(m)]; energy and e_arrive
    ! may be NaN (not known yet), everything else is finite; row, k, e_dir are integers
    if (.not. (all(ieee_is_finite(rec(1:4))) .and. ieee_is_finite(rec(7)) .and. all(ieee_is_finite(rec(8:))))) return
    if (rec(1) /= aint(rec(1)) .or. rec(2) /= aint(rec(2)) .or. abs(rec(2)) > 2.0_dp**62) return
    if (rec(1) < 0.0_dp .or. rec(1) > real(min(max_row, max_steps), dp)) return
    if (rec(7) /= -1.0_dp .and. rec(7) /= 0.0_dp .and. rec(7) /= 1.0_dp) return
    if (rec(4) /= self%h) return
    call h5io_read_row(self%d_q, n, int(rec(1), i8), qr, s, self%message, self%path)
    call h5io_read_row(self%d_p, n, int(rec(1), i8), pr, s, self%message, self%path)
    call h5io_read_row(self%d_t, 0, int(rec(1), i8), tr, s, self%message, self%path)
    if (s /= VCI_OK) then
      self%message = ''; return
    end if
    if (any(qr(:, 1) /= rec(8:7 + n)) .or. any(pr(:, 1) /= rec(8 + n:7 + 2 * n))) return
    ! its time t0 + k h must be the row's t (both are the driver's t0 + k h; a few ulps allow for
    ! rounding): a damaged step index or t0 would restart the run at another time
    t_cp = rec(3) + rec(2) * rec(4)
    if (.not. ieee_is_finite(t_cp)) return
    if (.not. abs(t_cp - tr(1)) <= 4 * epsilon(1.0_dp) * (abs(rec(3)) + abs(rec(2) * rec(4)))) return
    row = int(rec(1), i8)
    call move_alloc(rec, self%cp_rec)
  end function checkpoint_row

  !> Impacts within the trusted steps (their step starts before the last trusted row).
  integer(i8) function trusted_impacts(self, stat) result(k)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer, intent(inout) :: stat
    integer(i8), allocatable :: steps(:)
    integer(i8) :: n_step
    integer :: err
    k = 0
    n_step = h5io_rows(self%d_is, 'impacts/step', 0, stat, self%message, self%path)
    k = min(n_step, h5io_rows(self%d_it, 'impacts/time', 0, stat, self%message, self%path), &
            h5io_rows(self%d_ia, 'impacts/alpha', 0, stat, self%message, self%path), h5io_rows(self%d_ig, &
                'impacts/gap_index', 0, stat, self%message, self%path), &
            h5io_rows(self%d_iq, 'impacts/q', self%n, stat, self%message, self%path), h5io_rows(self%d_ii, &
                'impacts/impulse', 0, stat, self%message, self%path))
    if (stat /= VCI_OK) then
      k = 0; return
    end if
    allocate (steps(n_step), stat=err)
    if (err /= 0) then
      k = 0
      call fail(self, '/impacts/step is too long to read', stat); return
    end if
    err = 0
    if (n_step > 0) call h5dread_f(self%d_is, h5kind_to_type(i8, H5_INTEGER_KIND), steps, [int(n_step, hsize_t)], err)
    if (err /= 0) then
      ! a run killed inside a flush: the dataset's new extent reached the disk, the chunk of its new
      ! rows not (beyond the file's end of allocation); the rows before it are readable
      k = readable_impacts_before(self, k)
      return
    end if
    k = count(steps(1:k) < self%last_index)
  end function trusted_impacts

  !> Of the first n rows of /impacts/step, how many are readable with a step before the last trusted
  !> row: a prefix, as the steps do not decrease and only rows after the last complete flush can be
  !> unreadable. Bisection, one row read per halving.
  integer(i8) function readable_impacts_before(self, n) result(k)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer(i8), intent(in) :: n
    integer(i8) :: hi, mid, step
    integer :: s
    character(len=VCI_MSG_LEN) :: ignored
    k = 0; hi = n                      ! rows [0, k) are in, rows [hi, n) are not
    do while (k < hi)
      mid = k + (hi - k) / 2
      s = VCI_OK
      call h5io_read_i8(self%d_is, mid, step, s, ignored, self%path)
      if (s == VCI_OK .and. step < self%last_index) then
        k = mid + 1
      else
        hi = mid
      end if
    end do
  end function readable_impacts_before

  !> Appending: cut every dataset to the trusted lengths before new rows follow.
  subroutine truncate_to_trusted(self, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer, intent(inout) :: stat
    if (self%every > 1) call cut_rows(self, self%d_k, 'step', 0, self%rows, stat)
    call cut_rows(self, self%d_t, 't', 0, self%rows, stat)
    call cut_rows(self, self%d_q, 'q', self%n, self%rows, stat)
    call cut_rows(self, self%d_p, 'p', self%n, self%rows, stat)
    call cut_rows(self, self%d_e, 'energy', 0, self%steps, stat)
    if (self%m > 0) call cut_rows(self, self%d_l, 'lambda', self%m, self%steps, stat)
    if (self%n_gaps > 0) then
      call cut_rows(self, self%d_it, 'impacts/time', 0, self%impacts, stat)
      call cut_rows(self, self%d_is, 'impacts/step', 0, self%impacts, stat)
      call cut_rows(self, self%d_ia, 'impacts/alpha', 0, self%impacts, stat)
      call cut_rows(self, self%d_ig, 'impacts/gap_index', 0, self%impacts, stat)
      call cut_rows(self, self%d_iq, 'impacts/q', self%n, self%impacts, stat)
      call cut_rows(self, self%d_ii, 'impacts/impulse', 0, self%impacts, stat)
    end if
  end subroutine truncate_to_trusted

  !> Cut dataset NAME (rows of WIDTH values, 0: of one) to its first ROWS rows. HDF5 cannot when a
  !> run killed inside the flush that wrote the dataset's first chunk left its object header
  !> pointing at a chunk index that never reached the disk (the dataset can then be neither cut,
  !> written nor deleted): a status naming it, so the run is restarted into a new file.
  subroutine cut_rows(self, dset, name, width, rows, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer(hid_t), intent(in) :: dset
    character(len=*), intent(in) :: name
    integer, intent(in) :: width
    integer(i8), intent(in) :: rows
    integer, intent(inout) :: stat
    integer :: err
    if (stat /= VCI_OK) return
    if (width > 0) then
      call h5dset_extent_f(dset, [int(width, hsize_t), int(rows, hsize_t)], err)
    else
      call h5dset_extent_f(dset, [int(rows, hsize_t)], err)
    end if
    if (err /= 0) call fail(self, 'cannot append: cannot cut /'//name//' back to its '//trim(vci_int_text(rows))// &
      ' trusted rows (its chunk index is unreadable, as a run killed inside a flush can leave it); '// &
      'restart from the file into a new one', stat)
  end subroutine cut_rows

  subroutine w_start(self, info, q, p, stat)
    class(vci_hdf5_writer_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
    integer :: s
    s = VCI_OK
    if (.not. self%is_open) then
      if (len_trim(self%message) == 0) self%message = 'HDF5 output: no file open (call open first)'
      stat = VCI_ERR_IO; return
    end if
    if (self%started) then
      call fail(self, 'one file holds one run (open it again with append=.true. to continue)', s)
    else if (self%append) then
      call start_append(self, info, q, p, s)
    else
      call start_new(self, info, s)
    end if
    if (s == VCI_OK) call alloc_buffers(self, s)
    if (s == VCI_OK) then
      self%step0 = info%step0
      self%last_step = info%step0
      self%t_start = info%t0
      self%started = .true.
      self%last_stored = .true.
      if (.not. self%append) call buffer_state(self, info%t0, q, p, 0_i8)
      call h5io_put_attr(self%file, 'status', VCI_HDF5_RUNNING, s, self%message, self%path)
      call h5io_put_attr(self%file, 'status_message', 'running (not closed yet)', s, self%message, self%path)
      if (s == VCI_OK) call flush_file(self, s)
    end if
    if (s /= VCI_OK) then
      call w_close(self)
      stat = VCI_ERR_IO
    end if
  end subroutine w_start

  !> A new file: the run's attributes, empty datasets, the /impacts and /checkpoint groups.
  subroutine start_new(self, info, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    integer, intent(inout) :: stat
    integer :: err
    self%n = info%n; self%m = info%m; self%n_gaps = info%n_gaps
    self%direction = info%direction; self%h = info%h
    self%rows = 0; self%steps = 0; self%impacts = 0; self%row_start = 0; self%base = 0; self%last_index = 0
    self%split_steps = 0; self%largest_split = 0
    call h5io_put_attr(self%file, 'direction', trim(merge('forward ', 'backward', info%direction > 0)), stat, &
        self%message, self%path)
    call h5io_put_attr(self%file, 'h', info%h, stat, self%message, self%path)
    call h5io_put_attr(self%file, 't0', info%t0, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'n', info%n, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'm', info%m, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'n_gaps', info%n_gaps, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'steps_completed', 0_i8, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'every', self%every, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'compression', self%deflate, stat, self%message, self%path)
    ! how the run was made (provenance)
    call h5io_put_attr(self%file, 'scheme', trim(vci_scheme_name(info%scheme)), stat, self%message, self%path)
    call h5io_put_attr(self%file, 'stages', info%stages, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'impact_condition', trim(merge('hamiltonian', 'discrete   ', info%impact_energy == 1)), &
        stat, self%message, self%path)
    call h5io_put_attr(self%file, 'rtol', info%rtol, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'atol', info%atol, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'max_impacts', info%max_impacts, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'start', trim(start_name(info%start)), stat, self%message, self%path)
    call h5io_put_attr(self%file, 'resumes', '', stat, self%message, self%path)
    call h5io_make_rows(self%file, 't', 0, chunk_rows, H5T_IEEE_F64LE, self%d_t, stat, self%message, self%path, &
        self%deflate)
    call h5io_make_rows(self%file, 'q', info%n, chunk_rows, H5T_IEEE_F64LE, self%d_q, stat, self%message, self%path, &
        self%deflate)
    call h5io_make_rows(self%file, 'p', info%n, chunk_rows, H5T_IEEE_F64LE, self%d_p, stat, self%message, self%path, &
        self%deflate)
    call h5io_make_rows(self%file, 'energy', 0, chunk_rows, H5T_IEEE_F64LE, self%d_e, stat, self%message, self%path, &
        self%deflate)
    if (info%m > 0) call h5io_make_rows(self%file, 'lambda', info%m, chunk_rows, H5T_IEEE_F64LE, self%d_l, &
        stat, self%message, self%path, self%deflate)
    if (self%every > 1) call h5io_make_rows(self%file, 'step', 0, chunk_rows, H5T_STD_I64LE, self%d_k, &
        stat, self%message, self%path, self%deflate)
    call describe(self, self%d_t, 'the model''s time unit', 'time of each stored state')
    call describe(self, self%d_q, 'the model''s coordinates', 'configuration of each stored state')
    call describe(self, self%d_p, 'the model''s momentum (dL/dqdot)', 'momentum of each stored state')
    call describe(self, self%d_e, 'the model''s energy', 'E_d of the step arriving at row i+1')
    if (info%m > 0) call describe(self, self%d_l, 'the constraints'' multipliers', &
        'multipliers of the step arriving at row i+1')
    if (self%every > 1) call describe(self, self%d_k, 'steps of h', 'index of each stored state from t[0]')
    if (stat /= VCI_OK) return
    if (info%n_gaps > 0) then
      call h5gcreate_f(self%file, 'impacts', self%g_imp, err)
      if (err /= 0) then
        call fail(self, 'cannot create group /impacts', stat); return
      end if
      call h5io_make_rows(self%g_imp, 'time', 0, impact_chunk_rows, H5T_IEEE_F64LE, self%d_it, stat, &
          self%message, self%path, self%deflate)
      call h5io_make_rows(self%g_imp, 'step', 0, impact_chunk_rows, H5T_STD_I64LE, self%d_is, stat, &
          self%message, self%path, self%deflate)
      call h5io_make_rows(self%g_imp, 'alpha', 0, impact_chunk_rows, H5T_IEEE_F64LE, self%d_ia, stat, &
          self%message, self%path, self%deflate)
      call h5io_make_rows(self%g_imp, 'gap_index', 0, impact_chunk_rows, H5T_STD_I32LE, self%d_ig, stat, &
          self%message, self%path, self%deflate)
      call h5io_make_rows(self%g_imp, 'q', info%n, impact_chunk_rows, H5T_IEEE_F64LE, self%d_iq, stat, &
          self%message, self%path, self%deflate)
      call h5io_make_rows(self%g_imp, 'impulse', 0, impact_chunk_rows, H5T_IEEE_F64LE, self%d_ii, stat, &
          self%message, self%path, self%deflate)
      call describe(self, self%d_it, 'the model''s time unit', 'impact time')
      call describe(self, self%d_is, 'steps of h', 'index of the state the impact''s step started from')
      call describe(self, self%d_ia, 'fraction of h', 'fraction of that step, from its start in the direction of motion')
      call describe(self, self%d_ig, 'wall number, 1-based', 'the wall reached: 1-based as the Fortran model numbers '// &
          'its gaps (the C impact callback passes it 0-based, as an index into g[])')
      call describe(self, self%d_iq, 'the model''s coordinates', 'configuration on the wall')
      call describe(self, self%d_ii, 'the model''s momentum per unit gap gradient', &
          'normal impulse: p after - p before = impulse * grad g')
      call h5io_put_attr(self%d_ig, 'base', 1, stat, self%message, self%path)
    end if
  end subroutine start_new

  !> Appending: the run must continue the file's last state, same sizes, step and direction.
  subroutine start_append(self, info, q, p, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    real(dp), intent(in) :: q(:), p(:)
    integer, intent(inout) :: stat
    real(dp) :: t_last(1), q_last(info%n, 1)
    if (info%n /= self%n .or. info%m /= self%m .or. info%n_gaps /= self%n_gaps .or. info%h /= self%h) then
      call fail(self, 'cannot append: the run''s n, m, n_gaps or h differ from the file''s', stat); return
    end if
    if (info%direction /= self%direction) then
      call fail(self, 'cannot append: the run goes the other way in time (write the reversal to a new file)', stat)
      return
    end if
    call h5io_read_row(self%d_t, 0, self%rows - 1, t_last, stat, self%message, self%path)
    call h5io_read_row(self%d_q, info%n, self%rows - 1, q_last, stat, self%message, self%path)
    if (stat /= VCI_OK) return
    if (t_last(1) /= info%t0 .or. any(q_last(:, 1) /= q)) then
      call fail(self, 'cannot append: the run does not start from the file''s last state', stat); return
    end if
    self%row_start = self%rows - 1
    self%base = self%last_index
    call note_resume(self, info, stat)
  end subroutine start_append

  !> Appending: one more line in the root attribute `resumes`, "<when> from index <k> (t = <t>)".
  subroutine note_resume(self, info, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    type(vci_run_info_t), intent(in) :: info
    integer, intent(inout) :: stat
    character(len=:), allocatable :: old
    character(len=120) :: line
    logical :: ex
    integer :: err
    character(len=VCI_MSG_LEN) :: scratch
    integer :: s
    old = ''
    s = VCI_OK
    call h5aexists_f(self%file, 'resumes', ex, err)
    ! an older file has none; an unreadable one is started afresh (it is a record, not data)
    if (err == 0 .and. ex) call h5io_get_attr(self%file, 'resumes', old, s, scratch, self%path)
    if (s /= VCI_OK) old = ''
    write (line, '(a,i0,a,es24.17,a)') iso_now()//' from index ', self%last_index, ' (t = ', info%t0, ')'
    if (len_trim(old) > 0) then
      old = trim(old)//new_line('a')//trim(line)
    else
      old = trim(line)
    end if
    if (len(old) > 4000) old = old(len(old) - 3999:)   ! the reader takes strings of up to 4096 bytes: the latest
    call h5io_put_attr(self%file, 'resumes', old, stat, self%message, self%path)
  end subroutine note_resume

  !> The attributes `units` and `description` of a dataset (none when it was not created). Best
  !> effort: a failure here neither fails the run nor replaces the writer's message (it replaced
  !> the cause of a failed start, "cannot create dataset t", with "cannot write attribute units").
  subroutine describe(self, dset, units, description)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer(hid_t), intent(in) :: dset
    character(len=*), intent(in) :: units, description
    integer :: s
    character(len=VCI_MSG_LEN) :: scratch
    if (dset < 0) return
    s = VCI_OK
    call h5io_put_attr(dset, 'units', units, s, scratch, self%path)
    call h5io_put_attr(dset, 'description', description, s, scratch, self%path)
  end subroutine describe

  subroutine alloc_buffers(self, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer, intent(inout) :: stat
    integer :: c, s1, s2
    c = self%flush_every + 1      ! (flush_every <= VCI_HDF5_FLUSH_MAX: no overflow)
    ! one at a time: an allocation that failed half-way may have left some unallocated
    if (allocated(self%bt)) deallocate (self%bt)
    if (allocated(self%bq)) deallocate (self%bq)
    if (allocated(self%bp)) deallocate (self%bp)
    if (allocated(self%be)) deallocate (self%be)
    if (allocated(self%bl)) deallocate (self%bl)
    if (allocated(self%bk)) deallocate (self%bk)
    if (allocated(self%lq)) deallocate (self%lq)
    if (allocated(self%lp)) deallocate (self%lp)
    if (allocated(self%ll)) deallocate (self%ll)
    allocate (self%bt(c), self%bq(self%n, c), self%bp(self%n, c), self%be(c), self%bl(self%m, c), self%bk(c), &
              self%lq(self%n), self%lp(self%n), self%ll(self%m), stat=s1)
    if (allocated(self%it)) deallocate (self%it)
    if (allocated(self%is)) deallocate (self%is)
    if (allocated(self%ia)) deallocate (self%ia)
    if (allocated(self%ig)) deallocate (self%ig)
    if (allocated(self%iq)) deallocate (self%iq)
    if (allocated(self%ii)) deallocate (self%ii)
    allocate (self%it(16), self%is(16), self%ia(16), self%ig(16), self%iq(self%n, 16), self%ii(16), stat=s2)
    if (s1 /= 0 .or. s2 /= 0) call fail(self, 'no memory for a buffer of flush_every rows (lower flush_every)', stat)
  end subroutine alloc_buffers

  subroutine buffer_state(self, t, q, p, index)
    type(vci_hdf5_writer_t), intent(inout) :: self
    real(dp), intent(in) :: t, q(:), p(:)
    integer(i8), intent(in) :: index     ! file index: steps of h from row 0
    self%ns = self%ns + 1
    self%bt(self%ns) = t; self%bq(:, self%ns) = q; self%bp(:, self%ns) = p; self%bk(self%ns) = index
  end subroutine buffer_state

  !> The file index (steps of h from row 0) of the integrator's state `step`.
  pure integer(i8) function file_index(self, step)
    type(vci_hdf5_writer_t), intent(in) :: self
    integer(i8), intent(in) :: step
    file_index = self%base + (step - self%step0) * self%direction
  end function file_index

  !> Is the integrator's state `step` one the file stores (its file index a multiple of every)?
  pure logical function stored_index(self, step)
    type(vci_hdf5_writer_t), intent(in) :: self
    integer(i8), intent(in) :: step
    stored_index = modulo(file_index(self, step), int(self%every, i8)) == 0
  end function stored_index

  subroutine w_step(self, step, t, q, p, lambda, energy, stat)
    class(vci_hdf5_writer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    integer, intent(inout) :: stat
    if (.not. self%started) then
      stat = VCI_ERR_IO; return
    end if
    if (.not. continues_run(self, step, t, stat)) return
    self%last_step = step
    self%last_stored = stored_index(self, step)
    if (.not. self%last_stored) then   ! kept aside: the file's last row if the run ends here
      self%lt = t; self%lq = q; self%lp = p; self%le = energy
      if (self%m > 0) self%ll = lambda
      return
    end if
    call buffer_step(self, t, q, p, lambda, energy)
    if (self%ne >= self%flush_every .or. self%flush_pending) then
      call flush_file(self, stat)
      if (stat /= VCI_OK .and. stat /= VCI_ERR_MEMORY) stat = VCI_ERR_IO   ! (no memory for its checkpoint stays so)
    end if
  end subroutine w_step

  !> A stored state: its row, and the E_d and multipliers of the step that arrived at it.
  subroutine buffer_step(self, t, q, p, lambda, energy)
    type(vci_hdf5_writer_t), intent(inout) :: self
    real(dp), intent(in) :: t, q(:), p(:), lambda(:), energy
    call buffer_state(self, t, q, p, file_index(self, self%last_step))
    self%ne = self%ne + 1
    self%be(self%ne) = energy
    if (self%m > 0) self%bl(:, self%ne) = lambda
  end subroutine buffer_step

  !> A step belongs in the file only if it continues its last state: the next index in the file's
  !> direction, at the time that index has (t = t0 + index h, up to rounding). Stepping the other
  !> way, or from a state the driver was re-initialised with, is refused (VCI_ERR_IO): /t would
  !> A step the safety net split: counted; the attributes split_steps and largest_split are written
  !> with steps_completed at every flush (the steps counted are those flushed with it).
  subroutine w_split(self, step, parts, stat)
    class(vci_hdf5_writer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    integer, intent(in) :: parts
    integer, intent(inout) :: stat
    self%split_steps = self%split_steps + 1
    self%largest_split = max(self%largest_split, parts)
  end subroutine w_split

  !> turn back, /impacts/step would name wrong rows and the new start would be missing.
  logical function continues_run(self, step, t, stat) result(ok)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer(i8), intent(in) :: step
    real(dp), intent(in) :: t
    integer, intent(inout) :: stat
    real(dp) :: t_want
    character(len=200) :: why
    ! the driver's t = t0 + k h and t_start + (k - k0) h differ by rounding of the terms' sizes
    t_want = self%t_start + real(step - self%step0, dp) * self%h
    ok = step == self%last_step + self%direction .and. &
         abs(t - t_want) <= 64 * epsilon(1.0_dp) * (abs(t) + abs(self%t_start) + abs(real(step - self%step0, dp) * self%h))
    if (ok) return
    write (why, '(a,i0,a,es12.5,a,i0,a)') 'refused: the step to index ', step, ' (t = ', t, &
      ') does not continue the file''s last state (index ', self%last_step, ', '// &
      trim(merge('forward ', 'backward', self%direction > 0))//')'
    call fail(self, trim(why)//'; stepping the other way or re-initialising mid-file needs a new file', stat)
  end function continues_run

  subroutine w_impact(self, impact, stat)
    class(vci_hdf5_writer_t), intent(inout) :: self
    type(vci_impact_t), intent(in) :: impact
    integer, intent(inout) :: stat
    if (.not. self%started) then
      stat = VCI_ERR_IO; return
    end if
    if (impact%step /= self%last_step) then   ! a step that does not start from the file's last state
      call fail(self, 'refused: an impact in a step that does not start from the file''s last state; '// &
                'stepping the other way or re-initialising mid-file needs a new file', stat)
      return
    end if
    if (self%ni == size(self%it)) then
      call grow_impacts(self, stat)
      if (stat /= VCI_OK) return
    end if
    self%ni = self%ni + 1
    self%it(self%ni) = impact%t
    ! the row of /t the step started from: t(step) and t(step + 1) bracket the impact
    self%is(self%ni) = file_index(self, impact%step)
    self%ia(self%ni) = impact%alpha
    self%ig(self%ni) = impact%gap
    self%iq(:, self%ni) = impact%q
    self%ii(self%ni) = impact%impulse
    if (self%flush_on_impact) self%flush_pending = .true.
  end subroutine w_impact

  !> Twice the room for the impacts buffered until the next flush; all or nothing (VCI_ERR_IO with
  !> a message when memory is short: an allocate without stat= ended the program).
  subroutine grow_impacts(self, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer, intent(inout) :: stat
    real(dp), allocatable :: t1(:), a1(:), j1(:), q2(:, :)
    integer(i8), allocatable :: l1(:)
    integer, allocatable :: i1(:)
    integer :: k, err
    k = size(self%it)
    allocate (t1(2 * k), a1(2 * k), j1(2 * k), l1(2 * k), i1(2 * k), q2(self%n, 2 * k), stat=err)
    if (err /= 0) then
      call fail(self, 'no memory for more than '//trim(vci_int_text(k))//' impacts between two flushes '// &
                '(lower flush_every, or keep flush_on_impact)', stat)
      return
    end if
    t1(1:k) = self%it; call move_alloc(t1, self%it)
    a1(1:k) = self%ia; call move_alloc(a1, self%ia)
    j1(1:k) = self%ii; call move_alloc(j1, self%ii)
    l1(1:k) = self%is; call move_alloc(l1, self%is)
    i1(1:k) = self%ig; call move_alloc(i1, self%ig)
    q2(:, 1:k) = self%iq; call move_alloc(q2, self%iq)
  end subroutine grow_impacts

  !> The run ended: write what is buffered, the status and its message, and close the file.
  subroutine w_finish(self, status, message, stat)
    class(vci_hdf5_writer_t), intent(inout) :: self
    integer, intent(in) :: status
    character(len=*), intent(in) :: message
    integer, intent(inout) :: stat
    integer :: s
    if (.not. self%started) then
      call w_close(self); return
    end if
    if (self%discarded) then     ! the message says why; the file holds the steps of its last flush
      call w_close(self)
      stat = VCI_ERR_IO; return
    end if
    s = VCI_OK
    ! the run's last state is always stored: the file ends where the run did, and continues from there
    if (.not. self%last_stored) then
      call buffer_step(self, self%lt, self%lq, self%lp, self%ll, self%le)
      self%last_stored = .true.
    end if
    call flush_file(self, s)
    ! The run's end after everything it vouches for is on disk, in two flushes of its own: the
    ! message first (status still `running`), then the status alone, rewritten in place (the last
    ! write to the file). A flush is several writes (the superblock last), and a full disk at a
    ! later write of one that also held status 0 left `ok` beside a run that returned VCI_ERR_IO;
    ! now any failed write leaves `running` (as a killed run), never a status the run did not have.
    if (status == VCI_OK .and. len_trim(message) == 0) then
      call h5io_put_attr(self%file, 'status_message', 'ok', s, self%message, self%path)
    else
      call h5io_put_attr(self%file, 'status_message', trim(message), s, self%message, self%path)
    end if
    call flush_or_discard(self, s)
    call h5io_put_attr(self%file, 'status', status, s, self%message, self%path)
    call flush_or_discard(self, s)
    call w_close(self)
    if (s /= VCI_OK) stat = VCI_ERR_IO
  end subroutine w_finish

  !> H5Fflush when nothing failed yet; a failed flush sends every later write to the sink.
  subroutine flush_or_discard(self, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer, intent(inout) :: stat
    integer :: err
    if (stat /= VCI_OK) return
    call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
    if (err /= 0) then
      call fail(self, 'H5Fflush failed: '//trim(h5io_os_cause()), stat)
      call h5io_discard_writes(self%file)
      self%discarded = .true.
    end if
  end subroutine flush_or_discard

  !> Append the buffered rows, store the checkpoint and steps_completed, H5Fflush.
  subroutine flush_file(self, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    integer, intent(inout) :: stat
    if (stat /= VCI_OK) return
    if (self%ns > 0) then
      if (self%every > 1) call h5io_append_rows(self%d_k, 0, self%rows, self%bk(1:self%ns), self%ns, stat, &
          self%message, self%path)
      call h5io_append_rows(self%d_t, 0, self%rows, self%bt(1:self%ns), self%ns, stat, self%message, self%path)
      call h5io_append_rows(self%d_q, self%n, self%rows, self%bq(:, 1:self%ns), self%ns, stat, self%message, self%path)
      call h5io_append_rows(self%d_p, self%n, self%rows, self%bp(:, 1:self%ns), self%ns, stat, self%message, self%path)
    end if
    if (self%ne > 0) then
      call h5io_append_rows(self%d_e, 0, self%steps, self%be(1:self%ne), self%ne, stat, self%message, self%path)
      if (self%m > 0) call h5io_append_rows(self%d_l, self%m, self%steps, self%bl(:, 1:self%ne), self%ne, &
          stat, self%message, self%path)
    end if
    if (self%ni > 0) then
      call h5io_append_rows(self%d_it, 0, self%impacts, self%it(1:self%ni), self%ni, stat, self%message, self%path)
      call h5io_append_rows(self%d_is, 0, self%impacts, self%is(1:self%ni), self%ni, stat, self%message, self%path)
      call h5io_append_rows(self%d_ia, 0, self%impacts, self%ia(1:self%ni), self%ni, stat, self%message, self%path)
      call h5io_append_rows(self%d_ig, 0, self%impacts, self%ig(1:self%ni), self%ni, stat, self%message, self%path)
      call h5io_append_rows(self%d_iq, self%n, self%impacts, self%iq(:, 1:self%ni), self%ni, stat, &
          self%message, self%path)
      call h5io_append_rows(self%d_ii, 0, self%impacts, self%ii(1:self%ni), self%ni, stat, self%message, self%path)
    end if
    ! two phases: the rows reach the disk before the checkpoint and steps_completed that vouch for
    ! them. Row datasets have no chunk cache (vci_h5_io): the rows' raw data went to the disk above,
    ! so a full disk is caught there, before HDF5's metadata flush
    if (stat /= VCI_OK) then
      call h5io_discard_writes(self%file)   ! the disk keeps the last complete flush
      self%discarded = .true.
      return
    end if
    call flush_or_discard(self, stat)       ! (failed: the disk keeps the last complete flush)
    if (stat /= VCI_OK) return
    self%rows = self%rows + self%ns; self%steps = self%steps + self%ne; self%impacts = self%impacts + self%ni
    self%ns = 0; self%ne = 0; self%ni = 0
    self%flush_pending = .false.
    ! steps_completed last: it marks what a reader of a killed run's file can trust
    if (self%have_cp) then
      if (self%cp%step == self%last_step) call put_checkpoint(self, self%cp, stat)
      self%have_cp = .false.
    end if
    call h5io_put_attr(self%file, 'split_steps', self%split_steps, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'largest_split', self%largest_split, stat, self%message, self%path)
    call h5io_put_attr(self%file, 'steps_completed', self%steps, stat, self%message, self%path)
    call flush_or_discard(self, stat)
  end subroutine flush_file

  !> /checkpoint/record: the file's last row followed by the checkpoint's record (vci_checkpoint:
  !> to_record), as one float64 vector written in one piece, so a kill cannot leave half of it.
  subroutine put_checkpoint(self, cp, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    type(vci_checkpoint_t), intent(in) :: cp
    integer, intent(inout) :: stat
    integer :: err
    logical :: ex
    real(dp), allocatable :: rec(:)
    if (stat /= VCI_OK) return
    if (self%g_cp < 0) then
      call h5gcreate_f(self%file, 'checkpoint', self%g_cp, err)
      if (err /= 0) then
        call fail(self, 'cannot create group /checkpoint', stat); return
      end if
    end if
    ! each vector allocated with stat= (an n-sized temporary ended the program when memory ran out)
    call cp%record_into(rec, stat, lead=real(self%rows - 1, dp))
    if (stat /= VCI_OK) then
      call no_memory_for(self, 'record', cp, stat); return
    end if
    call h5io_put_vector(self%g_cp, 'record', rec, stat, self%message, self%path)
    ! the record's layout version: a reader takes the record only in the layout it knows. Made anew
    ! once a file (an appended file's attribute may be of another type, or absent)
    if (.not. self%cp_version_written) then
      call h5aexists_f(self%g_cp, 'version', ex, err)
      if (err == 0 .and. ex) call h5adelete_f(self%g_cp, 'version', err)
      call h5io_put_attr(self%g_cp, 'version', VCI_CHECKPOINT_VERSION, stat, self%message, self%path)
      self%cp_version_written = stat == VCI_OK
    end if
    ! Newton's kept factors beside it (tied to it by the step: a kill between the two writes leaves
    ! factors of another step, which the reader ignores)
    if (stat /= VCI_OK) return
    call cp%factors_record_into(rec, stat)
    if (stat /= VCI_OK) then
      call no_memory_for(self, 'factors', cp, stat); return
    end if
    call h5io_put_vector(self%g_cp, 'factors', rec, stat, self%message, self%path)
    ! (version 4) the scheme's start memory likewise
    if (stat /= VCI_OK) return
    call cp%start_record_into(rec, stat)
    if (stat /= VCI_OK) then
      call no_memory_for(self, 'start', cp, stat); return
    end if
    call h5io_put_vector(self%g_cp, 'start', rec, stat, self%message, self%path)
  end subroutine put_checkpoint

  !> The flush fails with VCI_ERR_MEMORY: no room for a checkpoint's vector /checkpoint/<what>.
  subroutine no_memory_for(self, what, cp, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    character(len=*), intent(in) :: what
    type(vci_checkpoint_t), intent(in) :: cp
    integer, intent(inout) :: stat
    character(len=40) :: step
    write (step, '(i0)') cp%step
    call fail(self, 'no memory for /checkpoint/'//what//' of step '//trim(step), stat)
    stat = VCI_ERR_MEMORY
  end subroutine no_memory_for

  !> /checkpoint/factors into cp (Newton's kept factors, vci_checkpoint: factors_record), when it is
  !> there, of cp's step and of a size the model's can have (a Lobatto system has at most
  !> 8 n + m + 2 unknowns); else cp keeps none and the restart is correct but not bitwise.
  subroutine get_factors(r, cp)
    type(vci_hdf5_writer_t), intent(inout) :: r
    type(vci_checkpoint_t), intent(inout) :: cp
    integer(hid_t) :: dset
    integer(i8) :: length, nf_max
    integer :: err, e2, s, st
    logical :: ex
    real(dp), allocatable :: rec(:)
    character(len=VCI_MSG_LEN) :: scratch
    call h5lexists_f(r%g_cp, 'factors', ex, err)
    if (err /= 0 .or. .not. ex) return
    call h5dopen_f(r%g_cp, 'factors', dset, err)
    if (err /= 0) return
    s = VCI_OK
    length = h5io_rows(dset, 'factors', 0, s, scratch, r%path)
    call h5dclose_f(dset, e2)
    nf_max = 8_i8 * r%n + r%m + 2_i8
    if (s /= VCI_OK .or. length < 3_i8 .or. length > 3_i8 + 2_i8 * nf_max + nf_max**2) return
    allocate (rec(length), stat=st)
    if (st /= 0) return
    call h5io_get_vector(r%g_cp, 'factors', rec, s, scratch, r%path)
    if (s == VCI_OK) call cp%from_factors_record(rec, s)
  end subroutine get_factors

  !> /checkpoint/start into cp (the scheme's start memory, vci_checkpoint: start_record), when it is
  !> there, of cp's step and of a size a scheme can have (Lobatto s <= 8: 1 + 9 n + 8 m values);
  !> else cp has none and the next step starts as after an initialisation (a constrained Lobatto
  !> run then continues to solver tolerance, not bit for bit; files of layout 3 have none).
  subroutine get_start(r, cp)
    type(vci_hdf5_writer_t), intent(inout) :: r
    type(vci_checkpoint_t), intent(inout) :: cp
    integer(hid_t) :: dset
    integer(i8) :: length
    integer :: err, e2, s, st
    logical :: ex
    real(dp), allocatable :: rec(:)
    character(len=VCI_MSG_LEN) :: scratch
    call h5lexists_f(r%g_cp, 'start', ex, err)
    if (err /= 0 .or. .not. ex) return
    call h5dopen_f(r%g_cp, 'start', dset, err)
    if (err /= 0) return
    s = VCI_OK
    length = h5io_rows(dset, 'start', 0, s, scratch, r%path)
    call h5dclose_f(dset, e2)
    if (s /= VCI_OK .or. length < 2_i8 .or. length > 3_i8 + 9_i8 * r%n + 8_i8 * r%m) return
    allocate (rec(length), stat=st)
    if (st /= 0) return
    call h5io_get_vector(r%g_cp, 'start', rec, s, scratch, r%path)
    if (s == VCI_OK) call cp%from_start_record(rec, s)
  end subroutine get_start

  !> The state a restart from PATH starts with, as a checkpoint for `integ%restore`. With a
  !> /checkpoint group (written when the driver handed checkpoints over) the restart is bitwise; without one
  !> it is the last row (t, q, p, lambda) with index 0 at that time, like init_from_momentum.
  !> Optional: t_first (time of row 0), direction (+1/-1), message (why stat /= 0).
  subroutine vci_hdf5_read_checkpoint(path, cp, stat, message, t_first, direction)
    character(len=*), intent(in) :: path
    type(vci_checkpoint_t), intent(out) :: cp
    integer, intent(out) :: stat
    character(len=*), intent(out), optional :: message
    real(dp), intent(out), optional :: t_first
    integer, intent(out), optional :: direction
    type(vci_hdf5_writer_t) :: r   ! reuses the writer's helpers for reading
    integer :: err, n, s, st
    logical :: ex, use_cp
    real(dp), allocatable :: rec(:)
    real(dp) :: buf(1)
    real(dp), allocatable :: row(:, :)

    stat = VCI_OK
    r%path = path
    call h5open_f(err)
    if (err == 0) call h5eset_auto_f(0, err)
    inquire (file=path, exist=ex)
    if (.not. ex) then
      call fail(r, 'cannot read: the file does not exist', stat)
    else if (h5io_path_kind(path) /= 1) then     ! never opened: opening a FIFO blocks
      call fail(r, 'cannot read: not a regular file (a FIFO, a device or a directory)', stat)
    else
      call h5fopen_f(path, H5F_ACC_RDONLY_F, r%file, err)
      if (err /= 0) call fail(r, 'cannot open: not an HDF5 file or not readable', stat)
    end if
    if (stat == VCI_OK) then
      r%is_open = .true.
      call open_existing(r, stat)
    end if
    if (stat == VCI_OK .and. present(t_first)) call h5io_read_row(r%d_t, 0, 0_i8, buf, stat, r%message, r%path)
    if (stat == VCI_OK .and. present(t_first)) t_first = buf(1)
    if (present(direction)) direction = r%direction
    ! the checkpoint counts only if it is the state of a row on disk (open_existing checked it)
    use_cp = stat == VCI_OK .and. allocated(r%cp_rec)
    if (use_cp) then
      n = r%n
      call move_alloc(r%cp_rec, rec)
      call cp%from_record(rec(2:), n, r%m, r%cp_version, s)
      if (s == VCI_ERR_MEMORY) then
        call fail(r, 'out of memory for its checkpoint', stat); stat = VCI_ERR_MEMORY
      end if
      use_cp = s == VCI_OK
      if (use_cp) call get_factors(r, cp)
      if (use_cp) call get_start(r, cp)
    end if
    if (.not. use_cp .and. stat == VCI_OK) then
      allocate (row(max(r%n, r%m, 1), 3), stat=st)
      if (st /= 0) call fail(r, 'out of memory', stat)
    end if
    if (.not. use_cp .and. stat == VCI_OK) then
      call h5io_read_row(r%d_t, 0, r%rows - 1, buf, stat, r%message, r%path)
      call h5io_read_row(r%d_q, r%n, r%rows - 1, row(1:r%n, 1:1), stat, r%message, r%path)
      call h5io_read_row(r%d_p, r%n, r%rows - 1, row(1:r%n, 2:2), stat, r%message, r%path)
      row(1:r%m, 3) = 0.0_dp
      if (r%steps > 0 .and. r%m > 0) call h5io_read_row(r%d_l, r%m, r%steps - 1, row(1:r%m, 3:3), stat, &
          r%message, r%path)
      if (stat == VCI_OK) then
        cp = vci_checkpoint_from_state(buf(1), r%h, row(1:r%n, 1), row(1:r%n, 2), row(1:r%m, 3), s)
        if (s /= VCI_OK) then
          call fail(r, 'out of memory for its last state', stat); stat = VCI_ERR_MEMORY
        end if
      end if
      if (r%steps > 0 .and. stat == VCI_OK) then
        call h5io_read_row(r%d_e, 0, r%steps - 1, buf, stat, r%message, r%path); cp%step_energy = buf(1)
      end if
    end if
    call w_close(r)
    if (present(message)) message = r%message
  end subroutine vci_hdf5_read_checkpoint

  ! The HDF5 helpers (attributes, row datasets, vectors) are vci_h5_io's, shared with the ensemble file.

  !> Close an HDF5 file a caller opened itself (h5fopen_f or h5fcreate_f, the default sec2 driver;
  !> its other objects closed first) so that a full disk is a status, never a crash, as this
  !> module's writer closes its own: what HDF5 holds is flushed (err = the flush's failure, else 0;
  !> `failed`: a write before already failed, nothing more is flushed), then the descriptor goes to
  !> a sink, so that the close writes nothing (it rewrites the superblock) and HDF5 1.10, which
  !> cannot close a file whose metadata flush failed, does not crash at exit (docs/OUTPUT.md). The
  !> file on disk keeps what reached it.
  subroutine vci_hdf5_close_file(file, err, failed)
    integer(hid_t), intent(in) :: file
    integer, intent(out) :: err
    logical, intent(in), optional :: failed
    integer :: e2
    logical :: before
    before = .false.
    if (present(failed)) before = failed
    call flush_into_sink(file, before, err)
    call h5fclose_f(file, e2)
  end subroutine vci_hdf5_close_file

  !> Before a close: what HDF5 holds flushed (err = the flush's failure, else 0; failed: a write
  !> already failed, err = -1 and nothing flushed), then the descriptor to a sink and a flush that
  !> failed half-way completed into it, so that the close writes nothing.
  subroutine flush_into_sink(file, failed, err)
    integer(hid_t), intent(in) :: file
    logical, intent(in) :: failed
    integer, intent(out) :: err
    integer :: e2
    err = -1
    if (.not. failed) call h5fflush_f(file, H5F_SCOPE_GLOBAL_F, err)
    call h5io_discard_writes(file)
    call h5fflush_f(file, H5F_SCOPE_GLOBAL_F, e2)
  end subroutine flush_into_sink

  subroutine fail(self, cause, stat)
    type(vci_hdf5_writer_t), intent(inout) :: self
    character(len=*), intent(in) :: cause
    integer, intent(inout) :: stat
    if (allocated(self%path)) then
      self%message = self%path//': '//cause
    else
      self%message = 'HDF5 output: '//cause
    end if
    stat = VCI_ERR_IO
  end subroutine fail

  !> Why the OS refuses to create PATH, as Fortran's runtime reports it.
  function os_reason(path) result(reason)
    character(len=*), intent(in) :: path
    character(len=:), allocatable :: reason
    character(len=256) :: iomsg
    integer :: u, ios
    open (newunit=u, file=path, status='new', action='write', iostat=ios, iomsg=iomsg)
    if (ios == 0) then
      close (u, status='delete')
      reason = 'HDF5 refused it'
    else
      reason = trim(iomsg)
    end if
  end function os_reason

  function iso_now() result(s)
    character(len=:), allocatable :: s
    character(len=8) :: d
    character(len=10) :: t
    character(len=5) :: z
    call date_and_time(d, t, z)
    s = d(1:4)//'-'//d(5:6)//'-'//d(7:8)//'T'//t(1:2)//':'//t(3:4)//':'//t(5:6)//z(1:3)//':'//z(4:5)
  end function iso_now

end module vci_hdf5_output
