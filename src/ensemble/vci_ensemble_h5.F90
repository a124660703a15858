!> The ensemble file: one HDF5 file for all members, in a fixed layout (docs/ENSEMBLES.md), written
!> by one process or, built with MPI (VCI_HAVE_MPI), by all ranks at once through parallel HDF5.
!>
!> Every dataset is indexed by member (the slowest index; h5py shape (N, ...)) and allocated in full
!> when the file is created, with fill values that mean "not run" (status -1, NaN, 0). Afterwards only
!> raw data are written, one block of consecutive members at a time, each rank its own blocks
!> (independent I/O): the file's metadata never change until it is closed, and the members'
!> status is written last, so a killed run leaves a file that opens and holds every member whose
!> status is not -1.
!>
!> create, write_table (with each rank's share), close and abandon are collective under MPI;
!> write_results is independent. Nothing here stops or prints (HDF5's own error printing is switched
!> off); failures give VCI_ERR_IO (VCI_ERR_MEMORY: a buffer of this module's) and a message naming
!> the file.
!>
!> A write that fails (a full disk) ends the file's writing: its descriptor is pointed at a sink
!> (vci_h5_io's h5io_discard_writes, as the run writer does), so that HDF5 closes it without touching
!> the disk again, and the disk keeps the metadata flushed at creation and every block written
!> before. Under MPI no metadata are written in parallel: rank 0 alone lays the file out (groups,
!> datasets, attributes) through the serial driver and closes it, then every rank opens it through
!> MPI-IO and writes raw data only (parallel HDF5 1.10 cannot flush or close a file again after a
!> metadata write failed, and crashed in MPI_Finalize). A failure inside create is made every
!> rank's before the next collective call; abandoning, every rank discards its own writes before
!> the collective flush and close; a successful close leaves the totals to rank 0 alone, through
!> the serial driver after the collective close.
module vci_ensemble_h5
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_null_ptr
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use hdf5
#ifdef VCI_HAVE_MPI
  use mpi_f08, only: MPI_Comm, MPI_INFO_NULL, MPI_Allreduce, MPI_Bcast, MPI_Comm_rank, MPI_IN_PLACE, &
                     MPI_INTEGER, MPI_CHARACTER, MPI_MAX, MPI_MIN
#endif
  use vci_kinds, only: dp, i8
  use vci_status, only: VCI_OK, VCI_ERR_IO, VCI_ERR_ARGUMENT, VCI_ERR_MEMORY, VCI_MSG_LEN
  use vci_message, only: vci_int_text
  use vci_h5_io, only: h5io_put_attr, h5io_get_attr, h5io_string_type, h5io_check_dims, h5io_discard_writes, &
                       h5io_discard_path, &
                       h5io_os_cause, h5io_free_bytes
  use vci_ensemble, only: vci_ensemble_config_t, vci_ensemble_table_t, vci_ensemble_results_t, &
                          vci_ensemble_samples, vci_ensemble_results_alloc, vci_ensemble_size, &
                          VCI_MEMBER_NOT_RUN, VCI_START_PAIR, VCI_START_MOMENTUM
  implicit none
  private

  !> Root attribute `format_version` of the layout written here.
  integer, parameter, public :: VCI_ENSEMBLE_FORMAT_VERSION = 1
  !> Characters kept of a failed member's message (`/members/message`).
  integer, parameter, public :: VCI_ENSEMBLE_MESSAGE_LEN = 256

  ! the leading dimensions of a dataset with one value per member: none
  integer, parameter :: per_member(0) = [integer ::]

  ! datasets, in the order of docs/ENSEMBLES.md
  integer, parameter :: D_STATUS = 1, D_MESSAGE = 2, D_T0 = 3, D_Q0 = 4, D_V0 = 5, D_PARAMS = 6, &
                        D_T = 7, D_Q = 8, D_P = 9, D_STEPS = 10, D_IMPACTS = 11, D_NEWTON = 12, &
                        D_IMPT = 13, D_IMPGAP = 14, D_EKIND = 15, D_E0 = 16, D_E1 = 17, D_DE = 18, &
                        D_TRCOUNT = 19, D_TRT = 20, D_TRQ = 21, D_TRP = 22, D_RANK = 23, D_THREAD = 24, &
                        D_SECONDS = 25, N_DSETS = 25
  character(len=*), parameter :: names(N_DSETS) = [character(len=32) :: &
    'members/status', 'members/message', 'members/t0', 'members/q0', 'members/v0', 'members/params', &
    'members/t', 'members/q', 'members/p', 'members/steps', 'members/impacts', 'members/newton_iterations', &
    'members/impact_t', 'members/impact_gap', 'members/energy_kind', 'members/energy_start', &
    'members/energy_end', 'members/energy_change', 'members/trajectory/count', 'members/trajectory/t', &
    'members/trajectory/q', 'members/trajectory/p', 'run/rank', 'run/thread', 'run/seconds']

  !> An ensemble file being written.
  type, public :: vci_ensemble_file_t
    character(len=VCI_MSG_LEN) :: message = ''   !< what went wrong, naming the file
    character(len=:), allocatable :: path         !< the file
    logical :: is_open = .false.                  !< a file is open
    integer :: n_members = 0                      !< members of the ensemble
    integer :: n = 0                              !< configuration size
    integer :: n_params = 0                       !< parameters per member
    integer :: impact_cap = 0                     !< impact times kept per member
    integer :: samples = 0                        !< states kept per member
    integer(hid_t), private :: file = -1
    integer(hid_t), private :: d(N_DSETS) = -1
    logical, private :: discarded = .false.   !< a write failed: nothing more reaches the file
    logical, private :: parallel = .false.    !< opened collectively through the MPI-IO driver
    logical, private :: alone = .false.       !< under MPI, rank 0 laying the file out by itself
#ifdef VCI_HAVE_MPI
    type(MPI_Comm), private :: comm
#endif
  contains
    !> Create PATH for the ensemble (every dataset allocated, "not run"); under MPI collectively over comm.
    procedure :: create => f_create
    !> Write the starts and parameters of a range of members.
    procedure :: write_table => f_write_table
    !> Write a block of results (members results%first onwards).
    procedure :: write_results => f_write_results
    !> Record how many members ran and failed, mark the file complete when all ran, and close it.
    procedure :: close => f_close
    !> Stop writing and close, keeping every block of members written before (collective under MPI).
    procedure :: abandon => f_abandon
  end type vci_ensemble_file_t

  public :: vci_ensemble_read

contains

  !> Create PATH for the ensemble of `config` and `table` (every dataset allocated, "not run").
  !> An existing file is kept (VCI_ERR_IO) unless `overwrite`. `ranks` and `threads` are recorded as
  !> attributes. Under MPI, pass the communicator: collective over it.
#ifdef VCI_HAVE_MPI
  subroutine f_create(self, path, config, table, ranks, threads, chunk, stat, overwrite, comm)
#else
  subroutine f_create(self, path, config, table, ranks, threads, chunk, stat, overwrite)
#endif
    class(vci_ensemble_file_t), intent(inout) :: self
    character(len=*), intent(in) :: path
    type(vci_ensemble_config_t), intent(in) :: config
    type(vci_ensemble_table_t), intent(in) :: table
    integer, intent(in) :: ranks, threads, chunk
    integer, intent(out) :: stat
    logical, intent(in), optional :: overwrite
#ifdef VCI_HAVE_MPI
    type(MPI_Comm), intent(in) :: comm
#endif
    integer :: err, e2, nm
#ifdef VCI_HAVE_MPI
    integer :: rank
#endif
    logical :: replace

    stat = VCI_OK
    self%message = ''
    self%path = path
    if (self%is_open) call f_close(self, 0, 0, e2)
    nm = vci_ensemble_size(table)
    self%n_members = nm; self%n = size(table%q0, 1)
    self%n_params = 0
    if (allocated(table%params)) self%n_params = size(table%params, 1)
    self%impact_cap = config%impact_cap
    self%samples = vci_ensemble_samples(config)
    self%d = -1
    self%discarded = .false.
    self%parallel = .false.
#ifdef VCI_HAVE_MPI
    self%comm = comm
    self%parallel = .true.
#endif
    replace = .false.
    if (present(overwrite)) replace = overwrite

    call h5open_f(err)
    if (err == 0) call h5eset_auto_f(0, err)   ! the library never prints
    if (err /= 0) then
      call fail(self, 'the HDF5 library could not be initialised', stat); return
    end if
    ! every dataset is written in full (fill values) at creation: a file the disk cannot hold is
    ! refused before a byte is written (ranks agree: each asks the file system itself)
    call check_room(self, stat)
    call sync(self, stat)
    if (stat /= VCI_OK) return
#ifdef VCI_HAVE_MPI
    ! The layout (groups, datasets, attributes: every metadata write) is made by rank 0 alone through
    ! the serial driver, flushed and closed; then every rank opens the file through MPI-IO and
    ! writes only raw data. A metadata flush that fails in parallel HDF5 (1.10: a full disk) leaves
    ! its metadata cache unable to flush or close the file ever again ("slist already enabled"): the
    ! file stayed open, and HDF5's own close at MPI_Finalize crashed every rank. In one process a
    ! failed flush is completed into the discard sink (f_abandon), as in a serial run.
    call MPI_Comm_rank(comm, rank, err)
    if (rank == 0) then
      self%parallel = .false.; self%alone = .true.
      call create_layout(self, path, replace, config, ranks, threads, chunk, stat)
      call close_layout(self, stat)
      self%parallel = .true.; self%alone = .false.
    end if
    call sync(self, stat)
    if (stat /= VCI_OK) return
    call open_parallel(self, stat)
    call sync(self, stat)
    if (stat == VCI_OK) then
      call fill_share(self, int(int(nm, i8) * rank / ranks) + 1, int(int(nm, i8) * (rank + 1) / ranks), stat)
      call sync(self, stat)
    end if
    if (stat == VCI_OK) then
      call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
      if (err /= 0) call fail(self, 'cannot flush the new file'//os_cause(), stat)
      call sync(self, stat)
    end if
    if (stat /= VCI_OK .and. self%is_open) call drop_new_file(self)
#else
    call create_layout(self, path, replace, config, ranks, threads, chunk, stat)
#endif
  end subroutine f_create

  !> The file's layout: PATH created (replacing it when `replace`), every group and dataset (all
  !> space allocated) and the root attributes, flushed to disk. On a failure the file is abandoned
  !> and removed (drop_new_file). Serial: one process (under MPI rank 0 alone, `alone` set).
  subroutine create_layout(self, path, replace, config, ranks, threads, chunk, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    character(len=*), intent(in) :: path
    logical, intent(in) :: replace
    type(vci_ensemble_config_t), intent(in) :: config
    integer, intent(in) :: ranks, threads, chunk
    integer, intent(inout) :: stat
    integer(hid_t) :: fapl, g
    integer :: err, e2, nm
    character(len=16) :: start_kind
    if (stat /= VCI_OK) return
    nm = self%n_members
    call h5pcreate_f(H5P_FILE_ACCESS_F, fapl, err)
    ! no data sieving: each block of members goes to the file when written, not when a buffer fills
    if (err == 0) call h5pset_sieve_buf_size_f(fapl, 0_size_t, err)
    if (err == 0) then
      if (replace) then
        call h5fcreate_f(path, H5F_ACC_TRUNC_F, self%file, err, access_prp=fapl)
      else
        call h5fcreate_f(path, H5F_ACC_EXCL_F, self%file, err, access_prp=fapl)
      end if
    end if
    call h5pclose_f(fapl, e2)
    if (err /= 0) then
      if (replace) then
        call fail(self, 'cannot create the file'//os_cause(), stat)
      else
        call fail(self, 'cannot create the file (an existing file is kept; ask to overwrite it)', stat)
      end if
    end if
    self%is_open = err == 0
    call sync(self, stat)
    if (stat /= VCI_OK) then
      if (self%is_open) call drop_new_file(self)
      return
    end if

    call h5gcreate_f(self%file, 'members', g, err)
    call h5gclose_f(g, e2)
    if (err == 0 .and. self%samples > 0) then
      call h5gcreate_f(self%file, 'members/trajectory', g, err)
      call h5gclose_f(g, e2)
    end if
    if (err == 0) call h5gcreate_f(self%file, 'run', g, err)
    call h5gclose_f(g, e2)
    if (err /= 0) call fail(self, 'cannot create the groups', stat)
    call sync(self, stat)
    if (stat /= VCI_OK) then
      call drop_new_file(self); return
    end if

    call new_dset(self, D_STATUS, H5T_STD_I32LE, [nm], stat, fill_int=VCI_MEMBER_NOT_RUN)
    call new_string_dset(self, D_MESSAGE, nm, stat)
    call new_dset(self, D_T0, H5T_IEEE_F64LE, [nm], stat)
    call new_dset(self, D_Q0, H5T_IEEE_F64LE, [self%n, nm], stat)
    call new_dset(self, D_V0, H5T_IEEE_F64LE, [self%n, nm], stat)
    if (self%n_params > 0) call new_dset(self, D_PARAMS, H5T_IEEE_F64LE, [self%n_params, nm], stat)
    call new_dset(self, D_T, H5T_IEEE_F64LE, [nm], stat, fill_nan=.true.)
    call new_dset(self, D_Q, H5T_IEEE_F64LE, [self%n, nm], stat, fill_nan=.true.)
    call new_dset(self, D_P, H5T_IEEE_F64LE, [self%n, nm], stat, fill_nan=.true.)
    call new_dset(self, D_STEPS, H5T_STD_I64LE, [nm], stat)
    call new_dset(self, D_IMPACTS, H5T_STD_I64LE, [nm], stat)
    call new_dset(self, D_NEWTON, H5T_STD_I64LE, [nm], stat)
    if (self%impact_cap > 0) then
      call new_dset(self, D_IMPT, H5T_IEEE_F64LE, [self%impact_cap, nm], stat, fill_nan=.true.)
      call new_dset(self, D_IMPGAP, H5T_STD_I32LE, [self%impact_cap, nm], stat)
    end if
    call new_dset(self, D_EKIND, H5T_STD_I32LE, [nm], stat)
    call new_dset(self, D_E0, H5T_IEEE_F64LE, [nm], stat, fill_nan=.true.)
    call new_dset(self, D_E1, H5T_IEEE_F64LE, [nm], stat, fill_nan=.true.)
    call new_dset(self, D_DE, H5T_IEEE_F64LE, [nm], stat, fill_nan=.true.)
    if (self%samples > 0) then
      call new_dset(self, D_TRCOUNT, H5T_STD_I32LE, [nm], stat)
      call new_dset(self, D_TRT, H5T_IEEE_F64LE, [self%samples, nm], stat, fill_nan=.true.)
      call new_dset(self, D_TRQ, H5T_IEEE_F64LE, [self%n, self%samples, nm], stat, fill_nan=.true.)
      call new_dset(self, D_TRP, H5T_IEEE_F64LE, [self%n, self%samples, nm], stat, fill_nan=.true.)
    end if
    call new_dset(self, D_RANK, H5T_STD_I32LE, [nm], stat, fill_int=-1)
    call new_dset(self, D_THREAD, H5T_STD_I32LE, [nm], stat, fill_int=-1)
    call new_dset(self, D_SECONDS, H5T_IEEE_F64LE, [nm], stat, fill_nan=.true.)
    if (stat /= VCI_OK) then
      call drop_new_file(self); return
    end if

    start_kind = 'pair'
    if (config%start_kind /= VCI_START_PAIR) start_kind = 'momentum'
    call h5io_put_attr(self%file, 'format', 'vci-ensemble', stat, self%message, who(self))
    call h5io_put_attr(self%file, 'format_version', VCI_ENSEMBLE_FORMAT_VERSION, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'vci_version', VCI_VERSION_STRING, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'name', trim(config%name), stat, self%message, who(self))
    call h5io_put_attr(self%file, 'n_members', nm, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'n', self%n, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'n_params', self%n_params, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'h', config%h, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'nsteps', config%nsteps, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'direction', config%direction, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'start_kind', trim(start_kind), stat, self%message, who(self))
    call h5io_put_attr(self%file, 'impact_energy', config%impact_energy, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'impact_cap', config%impact_cap, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'stride', config%stride, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'samples', self%samples, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'message_length', VCI_ENSEMBLE_MESSAGE_LEN, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'ranks', ranks, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'threads', threads, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'chunk', chunk, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'complete', 0, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'members_run', 0, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'members_failed', 0, stat, self%message, who(self))
    ! metadata on disk now: from here on only raw data are written until close
    if (stat == VCI_OK) then
      call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
      if (err /= 0) call fail(self, 'cannot flush the new file'//os_cause(), stat)
    end if
    call sync(self, stat)
    if (stat /= VCI_OK .and. self%is_open) call drop_new_file(self)
  end subroutine create_layout

#ifdef VCI_HAVE_MPI
  !> Rank 0's layout closed again (its metadata are on disk: nothing is left to write), so that
  !> every rank can open the file through MPI-IO.
  subroutine close_layout(self, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(inout) :: stat
    integer :: i, err
    if (.not. self%is_open) return
    do i = 1, N_DSETS
      if (self%d(i) >= 0) call h5dclose_f(self%d(i), err)
      self%d(i) = -1
    end do
    call h5fclose_f(self%file, err)
    if (err /= 0) then
      call fail(self, 'cannot close the new file'//os_cause(), stat)
      call drop_new_file(self); return
    end if
    self%is_open = .false.
  end subroutine close_layout

  !> Every rank opens the file rank 0 laid out, through the MPI-IO driver (collective), and its
  !> datasets; nothing is written.
  subroutine open_parallel(self, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(inout) :: stat
    integer(hid_t) :: fapl
    integer :: err, e2, j
    call h5pcreate_f(H5P_FILE_ACCESS_F, fapl, err)
    if (err == 0) call h5pset_fapl_mpio_f(fapl, self%comm%MPI_VAL, MPI_INFO_NULL%MPI_VAL, err)
    if (err == 0) call h5fopen_f(self%path, H5F_ACC_RDWR_F, self%file, err, access_prp=fapl)
    call h5pclose_f(fapl, e2)
    if (err /= 0) then
      call fail(self, 'cannot open the new file on every rank'//os_cause(), stat); return
    end if
    self%is_open = .true.
    do j = 1, N_DSETS
      if (j == D_PARAMS .and. self%n_params == 0) cycle
      if ((j == D_IMPT .or. j == D_IMPGAP) .and. self%impact_cap == 0) cycle
      if (j >= D_TRCOUNT .and. j <= D_TRP .and. self%samples == 0) cycle
      call h5dopen_f(self%file, trim(names(j)), self%d(j), err)
      if (err /= 0) then
        call fail(self, 'cannot open dataset /'//trim(names(j))//' of the new file', stat); return
      end if
    end do
  end subroutine open_parallel
#endif

#ifdef VCI_HAVE_MPI
  !> The fill values ("not run") of members first .. last in every dataset, written by this rank
  !> alone (independent I/O), in blocks of at most 2 MiB (or one member's values, when larger).
  subroutine fill_share(self, first, last, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: first, last
    integer, intent(inout) :: stat
    integer, allocatable :: dims(:)
    integer :: j, r
    do j = 1, N_DSETS
      if (self%d(j) < 0 .or. stat /= VCI_OK .or. last < first) cycle
      dims = dims_of(self, j)   ! (at most 3 values: tiny)
      r = size(dims)
      call fill_members(self, j, dims(1:r - 1), first, last, stat)
    end do
  end subroutine fill_share

  !> Dataset `which`'s fill value into members first .. last (leading dimensions `lead`), a block of
  !> members a write, from one buffer of a block's values allocated with stat= (2 MiB: the 2^18
  !> messages a block once took were 64 MB): running out of memory is a status, VCI_ERR_MEMORY,
  !> that f_create's sync makes every rank's.
  subroutine fill_members(self, which, lead, first, last, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which, lead(:), first, last
    integer, intent(inout) :: stat
    integer, parameter :: max_bytes = 2**21
    real(dp), allocatable, target :: r(:)
    integer, allocatable, target :: k(:)
    integer(i8), allocatable, target :: l(:)
    character(len=VCI_ENSEMBLE_MESSAGE_LEN), allocatable, target :: c(:)
    integer(hid_t) :: mtype
    type(c_ptr) :: buf
    integer :: per_member, value_bytes, block, values, at, err, e2
    select case (which)
    case (D_STATUS, D_RANK, D_THREAD, D_IMPGAP, D_EKIND, D_TRCOUNT)
      value_bytes = 4
    case (D_MESSAGE)
      value_bytes = VCI_ENSEMBLE_MESSAGE_LEN
    case default
      value_bytes = 8
    end select
    per_member = max(1, product(lead))
    block = min(max(1, max_bytes / value_bytes / per_member), last - first + 1)
    values = per_member * block
    select case (which)
    case (D_STATUS, D_RANK, D_THREAD, D_IMPGAP, D_EKIND, D_TRCOUNT)
      allocate (k(values), stat=err)
      if (err == 0) then
        k = merge(-1, 0, which == D_STATUS .or. which == D_RANK .or. which == D_THREAD)
        buf = c_loc(k); mtype = H5T_NATIVE_INTEGER
      end if
    case (D_STEPS, D_IMPACTS, D_NEWTON)
      allocate (l(values), stat=err)
      if (err == 0) then
        l = 0_i8
        buf = c_loc(l); mtype = h5kind_to_type(i8, H5_INTEGER_KIND)
      end if
    case (D_MESSAGE)
      allocate (c(values), stat=err)
      if (err == 0) then
        c = repeat(achar(0), VCI_ENSEMBLE_MESSAGE_LEN)
        buf = c_loc(c)
      end if
    case default
      allocate (r(values), stat=err)
      if (err == 0) then
        r = ieee_value(1.0_dp, ieee_quiet_nan)
        if (which == D_T0 .or. which == D_Q0 .or. which == D_V0 .or. which == D_PARAMS) r = 0.0_dp
        buf = c_loc(r); mtype = H5T_NATIVE_DOUBLE
      end if
    end select
    if (err /= 0) then
      call fail(self, 'no memory to fill /'//trim(names(which))//' ('//trim(vci_int_text(values))// &
                ' values a block) for members '//trim(vci_int_text(first))//' to '//trim(vci_int_text(last)), &
                stat, VCI_ERR_MEMORY)
      return
    end if
    if (which == D_MESSAGE) then
      call h5io_string_type(VCI_ENSEMBLE_MESSAGE_LEN, mtype, err)
      if (err /= 0) then
        call fail(self, 'cannot make a string type to fill /'//trim(names(which)), stat); return
      end if
    end if
    do at = first, last, block
      call put_raw(self, which, mtype, buf, lead, at, min(block, last - at + 1), stat)
      if (stat /= VCI_OK) exit
    end do
    if (which == D_MESSAGE) call h5tclose_f(mtype, e2)
  end subroutine fill_members
#endif

  !> Write the starts and parameters of members first .. first + count - 1 (each rank its share).
  subroutine f_write_table(self, table, first, count, stat)
    class(vci_ensemble_file_t), intent(inout) :: self
    type(vci_ensemble_table_t), intent(in), target :: table
    integer, intent(in) :: first, count
    integer, intent(out) :: stat
    stat = VCI_OK
    if (count < 1) return
    call put_f64(self, D_T0, table%t0(first:first + count - 1), per_member, first, count, stat)
    call put_f64(self, D_Q0, table%q0(:, first:first + count - 1), [self%n], first, count, stat)
    call put_f64(self, D_V0, table%v0(:, first:first + count - 1), [self%n], first, count, stat)
    if (self%n_params > 0) &
      call put_f64(self, D_PARAMS, table%params(:, first:first + count - 1), [self%n_params], first, count, stat)
  end subroutine f_write_table

  !> Write a block of results (members results%first .. results%first + count - 1), run by `rank`.
  !> Statuses last: a member is in the file once its status is.
  subroutine f_write_results(self, results, rank, stat)
    class(vci_ensemble_file_t), intent(inout) :: self
    type(vci_ensemble_results_t), intent(in) :: results
    integer, intent(in) :: rank
    integer, intent(out) :: stat
    integer :: f, c, j, n
    stat = VCI_OK
    f = results%first; c = results%count; n = self%n
    if (c < 1) return
    if (f < 1 .or. f + c - 1 > self%n_members .or. results%n /= n .or. results%impact_cap /= self%impact_cap &
        .or. results%samples /= self%samples) then
      call fail(self, 'results do not match the file''s ensemble', stat, VCI_ERR_ARGUMENT); return
    end if
    do j = 1, c
      if (results%status(j) /= VCI_OK .and. results%status(j) /= VCI_MEMBER_NOT_RUN) &
        call put_message(self, f + j - 1, results%message(j), stat)
    end do
    call put_f64(self, D_T, results%t, per_member, f, c, stat)
    call put_f64(self, D_Q, results%q, [n], f, c, stat)
    call put_f64(self, D_P, results%p, [n], f, c, stat)
    call put_i64(self, D_STEPS, results%steps, f, c, stat)
    call put_i64(self, D_IMPACTS, results%impacts, f, c, stat)
    call put_i64(self, D_NEWTON, results%newton_iterations, f, c, stat)
    if (self%impact_cap > 0) then
      call put_f64(self, D_IMPT, results%impact_t, [self%impact_cap], f, c, stat)
      call put_i32(self, D_IMPGAP, results%impact_gap, [self%impact_cap], f, c, stat)
    end if
    call put_i32(self, D_EKIND, results%energy_kind, per_member, f, c, stat)
    call put_f64(self, D_E0, results%energy_start, per_member, f, c, stat)
    call put_f64(self, D_E1, results%energy_end, per_member, f, c, stat)
    call put_f64(self, D_DE, results%energy_change, per_member, f, c, stat)
    if (self%samples > 0) then
      call put_i32(self, D_TRCOUNT, results%traj_count, per_member, f, c, stat)
      call put_f64(self, D_TRT, results%traj_t, [self%samples], f, c, stat)
      call put_f64(self, D_TRQ, results%traj_q, [n, self%samples], f, c, stat)
      call put_f64(self, D_TRP, results%traj_p, [n, self%samples], f, c, stat)
    end if
    call put_ranks(self, rank, f, c, stat)
    call put_i32(self, D_THREAD, results%thread, per_member, f, c, stat)
    call put_f64(self, D_SECONDS, results%seconds, per_member, f, c, stat)
    call put_i32(self, D_STATUS, results%status, per_member, f, c, stat)
  end subroutine f_write_results

  !> `rank` as the rank of members first .. first + count - 1, from a buffer of count values
  !> allocated with stat= (a block may hold many members): no memory is VCI_ERR_MEMORY, and the
  !> members' statuses are then not written (write_results writes them last), so the file holds none
  !> of them.
  subroutine put_ranks(self, rank, first, count, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: rank, first, count
    integer, intent(inout) :: stat
    integer, allocatable :: ranks(:)
    integer :: err
    if (stat /= VCI_OK) return
    allocate (ranks(count), stat=err)
    if (err /= 0) then
      call fail(self, 'no memory for the ranks of members '//trim(vci_int_text(first))//' to '// &
                trim(vci_int_text(first + count - 1))//' ('//trim(vci_int_text(count))// &
                ' values): they are not in the file', stat, VCI_ERR_MEMORY)
      return
    end if
    ranks = rank
    call put_i32(self, D_RANK, ranks, per_member, first, count, stat)
  end subroutine put_ranks

  !> Record how many members ran and failed, mark the file complete when all ran, and close it.
  !> Collective under MPI (every rank passes the same totals).
  subroutine f_close(self, members_run, members_failed, stat)
    class(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: members_run, members_failed
    integer, intent(out) :: stat
#ifdef VCI_HAVE_MPI
    integer :: i, err, rank
#endif
    stat = VCI_OK
    if (.not. self%is_open) return
#ifdef VCI_HAVE_MPI
    ! a rank whose writes failed abandons; every rank must take that branch with it (collective)
    if (self%discarded) stat = VCI_ERR_IO
    call sync(self, stat)
#endif
    if (self%discarded .or. stat /= VCI_OK) then   ! the message says why; the disk keeps every block written before
      call f_abandon(self)
      stat = VCI_ERR_IO; return
    end if
#ifdef VCI_HAVE_MPI
    ! The parallel file is closed as it was flushed at creation: its metadata are unchanged, so the
    ! collective close has nothing to write that a full disk could fail half-way (parallel HDF5's
    ! metadata flush leaves rank 0 at a failed write while the others wait for it). Rank 0 then
    ! records the totals alone through the serial driver, where a failure is discarded as in one
    ! process, and every rank learns the outcome.
    do i = 1, N_DSETS
      if (self%d(i) >= 0) call h5dclose_f(self%d(i), err)
      self%d(i) = -1
    end do
    call h5fclose_f(self%file, err)
    self%is_open = .false.
    if (err /= 0) call fail(self, 'cannot close the file', stat)
    call sync(self, stat)
    if (stat /= VCI_OK) return
    call MPI_Comm_rank(self%comm, rank, err)
    if (rank == 0) then
      call h5fopen_f(self%path, H5F_ACC_RDWR_F, self%file, err)
      if (err /= 0) then
        call fail(self, 'cannot reopen the file to record the totals'//os_cause(), stat)
      else
        self%is_open = .true.
        self%parallel = .false.
        call write_totals(self, members_run, members_failed, stat)
      end if
    end if
    call sync(self, stat)
#else
    call write_totals(self, members_run, members_failed, stat)
#endif
  end subroutine f_close

  !> The totals and then `complete` written into the open file (one process), each flushed, and the
  !> file closed; on a failure the file is abandoned (its descriptor discarded) and closed all the
  !> same, and `complete` stays 0 on disk.
  subroutine write_totals(self, members_run, members_failed, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: members_run, members_failed
    integer, intent(inout) :: stat
    integer :: i, err
    call h5io_put_attr(self%file, 'members_run', members_run, stat, self%message, who(self))
    call h5io_put_attr(self%file, 'members_failed', members_failed, stat, self%message, who(self))
    ! flushed before closing: a full disk here must not leave HDF5 a metadata flush it cannot finish
    if (stat == VCI_OK) then
      call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
      if (err /= 0) call fail(self, 'cannot record the totals'//os_cause(), stat)
    end if
    ! `complete` last and alone, once everything else is on disk: a flush that fails part-way may
    ! have written some of its blocks, so the totals' flush must not carry it
    call h5io_put_attr(self%file, 'complete', merge(1, 0, members_run == self%n_members), stat, self%message, who(self))
    if (stat == VCI_OK) then
      call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
      if (err /= 0) call fail(self, 'cannot mark the file complete'//os_cause(), stat)
    end if
    if (stat /= VCI_OK) then
      call f_abandon(self); return
    end if
    ! Everything is on disk. The close would still rewrite the superblock (HDF5 gives back the
    ! unused end of its metadata block): that goes to the sink, so that a full disk cannot fail
    ! the close after `complete` = 1 reached the disk (a status contradicting the file), nor leave
    ! HDF5 a half-closed file that crashed the process at exit (the on-disk superblock keeps the
    ! end of allocation flushed above, which the file's size covers)
    call discard(self)
    do i = 1, N_DSETS
      if (self%d(i) >= 0) call h5dclose_f(self%d(i), err)
      self%d(i) = -1
    end do
    call h5fclose_f(self%file, err)
    if (err /= 0 .and. stat == VCI_OK) call fail(self, 'cannot close the file', stat)
    self%is_open = .false.
  end subroutine write_totals

  !> Stop writing: what HDF5 still holds goes to a sink (see the module's head), then close, leaving
  !> no HDF5 object of the file open. The file keeps its metadata as flushed at creation and every
  !> block of members written before: it opens, and holds every member whose status is not -1.
  !> Collective under MPI: every rank makes the same calls in the same order.
  subroutine f_abandon(self)
    class(vci_ensemble_file_t), intent(inout) :: self
    integer :: i, err
    if (.not. self%is_open) return
    ! in parallel every rank points its own descriptor at the sink, failed or not: the collective
    ! flush and close then cannot fail on one rank and hang the others
    if (.not. self%discarded .or. self%parallel) call discard(self)
    self%discarded = .true.
    ! a metadata flush that failed half-way (a full disk) is completed into the sink: HDF5 1.10
    ! can neither close a file with such a flush pending nor leave it (it crashed at exit). (In
    ! parallel the metadata were written by one process at creation: nothing is pending.)
    call h5fflush_f(self%file, H5F_SCOPE_GLOBAL_F, err)
    do i = 1, N_DSETS
      if (self%d(i) >= 0) call h5dclose_f(self%d(i), err)
      self%d(i) = -1
    end do
    call close_leftovers(self)
    call h5fclose_f(self%file, err)
    self%is_open = .false.
  end subroutine f_abandon

  !> Objects of the file still open besides the file itself (groups, datasets, named types,
  !> attributes that a failed call left behind: H5Fget_obj_count) are closed, so that the file's
  !> close really closes it: an HDF5 file left open is closed by HDF5 at exit (under MPI inside
  !> MPI_Finalize, where its collective calls crashed).
  subroutine close_leftovers(self)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer(size_t) :: count, got
    integer(hid_t), allocatable :: ids(:)
    integer :: err, i, which, kind
    which = ieor(H5F_OBJ_ALL_F, H5F_OBJ_FILE_F)     ! datasets, groups, named types, attributes
    call h5fget_obj_count_f(self%file, which, count, err)
    if (err /= 0 .or. count < 1) return
    allocate (ids(count), stat=err)
    if (err /= 0) return
    call h5fget_obj_ids_f(self%file, which, count, ids, err, got)
    if (err /= 0) return
    do i = 1, int(min(got, count))
      call h5iget_type_f(ids(i), kind, err)
      if (err /= 0) cycle
      if (kind == H5I_ATTR_F) then
        call h5aclose_f(ids(i), err)
      else
        call h5oclose_f(ids(i), err)
      end if
    end do
  end subroutine close_leftovers

  !> Creation failed (on some rank): close without writing more and remove the file, which holds no
  !> member and whose metadata never reached the disk. Collective under MPI.
  subroutine drop_new_file(self)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer :: u, ios, rank
    call f_abandon(self)
    rank = 0
#ifdef VCI_HAVE_MPI
    call MPI_Comm_rank(self%comm, rank, ios)
#endif
    if (rank /= 0) return
    open (newunit=u, file=self%path, status='old', iostat=ios)
    if (ios == 0) close (u, status='delete', iostat=ios)
    if (ios == 0) self%message = trim(self%message)//' (the file was removed: it held no member yet)'
  end subroutine drop_new_file

  !> The file's size (every dataset of this ensemble, as f_create makes them) against the room on its
  !> file system; a failure (VCI_ERR_IO) saying both when it does not fit.
  subroutine check_room(self, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(inout) :: stat
    real(dp) :: per_member, bytes
    integer(i8) :: free
    character(len=300) :: why
    ! in real(dp): the product of sizes read from a command line may not fit an integer
    per_member = 4 + VCI_ENSEMBLE_MESSAGE_LEN + 8 * (1 + 4 * real(self%n, dp) + self%n_params) + 8 + 24 + 4 + 24 &
                 + 12 * real(self%impact_cap, dp) + 4 + 8 + 4 + 8
    if (self%samples > 0) per_member = per_member + 4 + real(self%samples, dp) * (8 + 16 * real(self%n, dp))
    bytes = per_member * real(self%n_members, dp)
    free = h5io_free_bytes(self%path)
    if (free < 0 .or. bytes <= real(free, dp)) return
    write (why, '(a,es10.3,a,i0,a,i0,a,i0,a,es10.3,a)') 'the file would take ', bytes, ' bytes (', self%n_members, &
      ' members, ', self%samples, ' trajectory samples and ', self%impact_cap, ' impact times each), the file '// &
      'system has ', real(free, dp), ' free; nothing was written'
    call fail(self, trim(why), stat)
  end subroutine check_room

  !> Under MPI, a failure on any rank becomes every rank's (the lowest failing rank's status and
  !> message), so that all ranks take the same branch before the next collective call.
  subroutine sync(self, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(inout) :: stat
#ifdef VCI_HAVE_MPI
    integer :: owner, rank, ierr
    if (self%alone) return          ! rank 0 laying the file out: the others wait at the next sync
    call MPI_Comm_rank(self%comm, rank, ierr)
    owner = huge(1)
    if (stat /= VCI_OK) owner = rank
    call MPI_Allreduce(MPI_IN_PLACE, owner, 1, MPI_INTEGER, MPI_MIN, self%comm, ierr)
    if (owner == huge(1)) return
    call MPI_Bcast(stat, 1, MPI_INTEGER, owner, self%comm, ierr)
    call MPI_Bcast(self%message, len(self%message), MPI_CHARACTER, owner, self%comm, ierr)
#else
    if (stat /= VCI_OK .and. len_trim(self%message) == 0) self%message = 'ensemble file: failed'
#endif
  end subroutine sync

  !> Point the file's descriptor at a sink (vci_h5_io), this process's only (not collective). A
  !> parallel file's descriptors are found by the file's path: HDF5 does not hand out the MPI-IO
  !> driver's, and asking it for the driver of such a file is itself collective (H5Fget_access_plist
  !> duplicates the communicator), which one failed rank cannot call alone.
  subroutine discard(self)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer :: redirected
    if (self%parallel) then
      redirected = h5io_discard_path(self%path)
    else
      call h5io_discard_writes(self%file)
    end if
    self%discarded = .true.
  end subroutine discard

  !> ': ' and the operating system's reason for HDF5's last failure (say "No space left on device"),
  !> or nothing; right after the failing call.
  function os_cause() result(s)
    character(len=:), allocatable :: s
    character(len=256) :: cause
    cause = h5io_os_cause()
    s = ''
    if (len_trim(cause) > 0) s = ': '//trim(cause)
  end function os_cause

  !> Read a whole ensemble file (any number of ranks wrote it) into `results` (all members) and,
  !> optionally, its table and the configuration it was run with (threads and chunk as recorded).
  !> Serial: call it from one process.
  subroutine vci_ensemble_read(path, results, stat, message, table, config)
    character(len=*), intent(in) :: path
    type(vci_ensemble_results_t), intent(out), target :: results
    integer, intent(out) :: stat
    character(len=*), intent(out), optional :: message
    type(vci_ensemble_table_t), intent(out), optional, target :: table
    type(vci_ensemble_config_t), intent(out), optional :: config
    type(vci_ensemble_file_t) :: f
    type(vci_ensemble_config_t) :: cfg
    character(len=:), allocatable :: text
    integer(hid_t) :: fapl
    integer :: err, e2, nm, j
    integer(i8) :: stride, nsteps
    character(len=VCI_MSG_LEN) :: msg

    stat = VCI_OK
    f%path = path
    if (present(message)) message = ''
    call h5open_f(err)
    if (err == 0) call h5eset_auto_f(0, err)
    call h5pcreate_f(H5P_FILE_ACCESS_F, fapl, err)
    if (err == 0) call h5fopen_f(path, H5F_ACC_RDONLY_F, f%file, err, access_prp=fapl)
    call h5pclose_f(fapl, e2)
    if (err /= 0) then
      call fail(f, 'cannot open the file', stat)
      if (present(message)) message = f%message
      return
    end if
    f%is_open = .true.
    call h5io_get_attr(f%file, 'n_members', nm, stat, f%message, who(f))
    call h5io_get_attr(f%file, 'n', f%n, stat, f%message, who(f))
    call h5io_get_attr(f%file, 'n_params', f%n_params, stat, f%message, who(f))
    call h5io_get_attr(f%file, 'impact_cap', cfg%impact_cap, stat, f%message, who(f))
    call h5io_get_attr(f%file, 'stride', stride, stat, f%message, who(f))
    call h5io_get_attr(f%file, 'nsteps', nsteps, stat, f%message, who(f))
    call h5io_get_attr(f%file, 'h', cfg%h, stat, f%message, who(f))
    call h5io_get_attr(f%file, 'direction', cfg%direction, stat, f%message, who(f))
    call h5io_get_attr(f%file, 'impact_energy', cfg%impact_energy, stat, f%message, who(f))
    call h5io_get_attr(f%file, 'threads', cfg%threads, stat, f%message, who(f))
    call h5io_get_attr(f%file, 'chunk', cfg%chunk, stat, f%message, who(f))
    call h5io_get_attr(f%file, 'start_kind', text, stat, f%message, who(f))
    if (text /= 'pair') cfg%start_kind = VCI_START_MOMENTUM
    call h5io_get_attr(f%file, 'name', text, stat, f%message, who(f))
    cfg%name = text
    f%n_members = nm
    cfg%stride = stride; cfg%nsteps = nsteps
    if (present(config)) config = cfg
    f%impact_cap = cfg%impact_cap
    f%samples = vci_ensemble_samples(cfg)
    ! every dataset has the shape the attributes give, within the file's bytes, before anything is
    ! allocated from them (a damaged impact_cap of 2^31 - 1 asked for 51 GB of results first)
    do j = 1, N_DSETS
      if (stat /= VCI_OK) exit
      if (j == D_PARAMS .and. f%n_params == 0) cycle
      if ((j == D_IMPT .or. j == D_IMPGAP) .and. f%impact_cap == 0) cycle
      if (j >= D_TRCOUNT .and. j <= D_TRP .and. f%samples == 0) cycle
      call h5dopen_f(f%file, trim(names(j)), f%d(j), err)
      if (err /= 0) call fail(f, 'dataset /'//trim(names(j))//' missing', stat)
      ! read whole into buffers sized from the attributes: the shape must be theirs
      if (err == 0) call h5io_check_dims(f%d(j), '/'//trim(names(j)), dims_of(f, j), stat, f%message, who(f))
    end do
    if (stat == VCI_OK) then
      call vci_ensemble_results_alloc(results, cfg, f%n, 1, nm, stat, msg)
      if (stat /= VCI_OK .and. f%message == '') call fail(f, msg, stat)
    end if
    if (stat == VCI_OK) then
      call get_i32(f, D_STATUS, results%status, stat)
      call get_messages(f, results%message, stat)
      call get_f64(f, D_T, c_loc(results%t), stat)
      call get_f64(f, D_Q, c_loc(results%q), stat)
      call get_f64(f, D_P, c_loc(results%p), stat)
      call get_i64(f, D_STEPS, results%steps, stat)
      call get_i64(f, D_IMPACTS, results%impacts, stat)
      call get_i64(f, D_NEWTON, results%newton_iterations, stat)
      if (f%impact_cap > 0) then
        call get_f64(f, D_IMPT, c_loc(results%impact_t), stat)
        call get_i32(f, D_IMPGAP, results%impact_gap, stat)
      end if
      call get_i32(f, D_EKIND, results%energy_kind, stat)
      call get_f64(f, D_E0, c_loc(results%energy_start), stat)
      call get_f64(f, D_E1, c_loc(results%energy_end), stat)
      call get_f64(f, D_DE, c_loc(results%energy_change), stat)
      if (f%samples > 0) then
        call get_i32(f, D_TRCOUNT, results%traj_count, stat)
        call get_f64(f, D_TRT, c_loc(results%traj_t), stat)
        call get_f64(f, D_TRQ, c_loc(results%traj_q), stat)
        call get_f64(f, D_TRP, c_loc(results%traj_p), stat)
      end if
      call get_i32(f, D_THREAD, results%thread, stat)
      call get_f64(f, D_SECONDS, c_loc(results%seconds), stat)
    end if
    if (stat == VCI_OK .and. present(table)) then
      allocate (table%t0(nm), table%q0(f%n, nm), table%v0(f%n, nm), stat=err)
      if (err == 0 .and. f%n_params > 0) allocate (table%params(f%n_params, nm), stat=err)
      if (err /= 0) then
        call fail(f, 'out of memory for the table', stat)
      else
        call get_f64(f, D_T0, c_loc(table%t0), stat)
        call get_f64(f, D_Q0, c_loc(table%q0), stat)
        call get_f64(f, D_V0, c_loc(table%v0), stat)
        if (f%n_params > 0) call get_f64(f, D_PARAMS, c_loc(table%params), stat)
      end if
    end if
    do j = 1, N_DSETS
      if (f%d(j) >= 0) call h5dclose_f(f%d(j), e2)
    end do
    call h5fclose_f(f%file, e2)
    if (present(message)) message = f%message
  end subroutine vci_ensemble_read

  ! --- helpers ---

  subroutine fail(self, cause, stat, status)
    type(vci_ensemble_file_t), intent(inout) :: self
    character(len=*), intent(in) :: cause
    integer, intent(inout) :: stat
    integer, intent(in), optional :: status
    if (stat /= VCI_OK) return     ! keep the first cause
    stat = VCI_ERR_IO
    if (present(status)) stat = status
    self%message = 'ensemble file '//self%path//': '//cause
  end subroutine fail

  !> A dataset of Fortran shape `dims` (the member index last), allocated now; fill NaN or an integer.
  subroutine new_dset(self, which, ftype, dims, stat, fill_nan, fill_int)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which
    integer(hid_t), intent(in) :: ftype
    integer, intent(in) :: dims(:)
    integer, intent(inout) :: stat
    logical, intent(in), optional :: fill_nan
    integer, intent(in), optional :: fill_int
    integer(hid_t) :: space, dcpl
    integer :: err, e2
    real(dp), target :: fnan
    integer, target :: fint
    if (stat /= VCI_OK) return
    call h5screate_simple_f(size(dims), int(dims, hsize_t), space, err)
    if (err == 0) call h5pcreate_f(H5P_DATASET_CREATE_F, dcpl, err)
    ! space allocated now (parallel HDF5 requires it): later writes never touch metadata
    if (err == 0) call h5pset_alloc_time_f(dcpl, H5D_ALLOC_TIME_EARLY_F, err)
#ifdef VCI_HAVE_MPI
    ! not by rank 0 alone at creation: every rank writes its share of the fill once the file is open
    ! on all of them (fill_share; parallel HDF5 wrote it inside the collective H5Dcreate and waited
    ! at a barrier after, where a rank whose write failed left the others for ever)
    if (err == 0) call h5pset_fill_time_f(dcpl, H5D_FILL_TIME_NEVER_F, err)
#endif
    if (err == 0 .and. present(fill_nan)) then
      fnan = ieee_value(1.0_dp, ieee_quiet_nan)
      call h5pset_fill_value_f(dcpl, H5T_NATIVE_DOUBLE, c_loc(fnan), err)
    end if
    if (err == 0 .and. present(fill_int)) then
      fint = fill_int
      call h5pset_fill_value_f(dcpl, H5T_NATIVE_INTEGER, c_loc(fint), err)
    end if
    if (err == 0) call h5dcreate_f(self%file, trim(names(which)), ftype, space, self%d(which), err, dcpl_id=dcpl)
    if (err /= 0) call fail(self, 'cannot create dataset /'//trim(names(which))//os_cause(), stat)
    call h5pclose_f(dcpl, e2)
    call h5sclose_f(space, e2)
    call sync(self, stat)
  end subroutine new_dset

  subroutine new_string_dset(self, which, nm, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which, nm
    integer, intent(inout) :: stat
    integer(hid_t) :: stype
    integer :: err, e2
    if (stat /= VCI_OK) return
    call h5io_string_type(VCI_ENSEMBLE_MESSAGE_LEN, stype, err)
    if (err /= 0) then
      call fail(self, 'cannot make a string type', stat); return
    end if
    ! no fill value written: members that did not fail keep the file's zero bytes (an empty string)
    call new_dset(self, which, stype, [nm], stat)
    call h5tclose_f(stype, e2)
  end subroutine new_string_dset

  !> Select members first .. first + count - 1 of dataset `which` (leading dimensions `lead`, whole;
  !> none for a dataset of one value per member).
  subroutine select_members(self, which, lead, first, count, fspace, mspace, err)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which, lead(:), first, count
    integer(hid_t), intent(out) :: fspace, mspace
    integer, intent(out) :: err
    integer(hsize_t) :: offset(size(lead) + 1), cnt(size(lead) + 1)
    integer :: r
    r = size(lead) + 1
    offset(1:r - 1) = 0; cnt(1:r - 1) = int(lead, hsize_t)
    offset(r) = int(first - 1, hsize_t); cnt(r) = int(count, hsize_t)
    mspace = -1
    call h5dget_space_f(self%d(which), fspace, err)
    if (err == 0) call h5sselect_hyperslab_f(fspace, H5S_SELECT_SET_F, offset(1:r), cnt(1:r), err)
    if (err == 0) call h5screate_simple_f(r, cnt(1:r), mspace, err)
  end subroutine select_members

  subroutine put_raw(self, which, mtype, buf, lead, first, count, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which
    integer(hid_t), intent(in) :: mtype
    type(c_ptr), intent(in) :: buf
    integer, intent(in) :: lead(:), first, count
    integer, intent(inout) :: stat
    integer(hid_t) :: fspace, mspace
    integer :: err, e2
    if (stat /= VCI_OK) return
    if (self%discarded) then
      call fail(self, 'writes stopped after an earlier failure', stat); return
    end if
    call select_members(self, which, lead, first, count, fspace, mspace, err)
    if (err == 0) call h5dwrite_f(self%d(which), mtype, buf, err, mspace, fspace)
    if (err /= 0) call fail(self, 'cannot write /'//trim(names(which))//os_cause(), stat)
    if (mspace >= 0) call h5sclose_f(mspace, e2)
    call h5sclose_f(fspace, e2)
    if (err /= 0) then           ! (a full disk): nothing more may reach the file
      call discard(self)
      self%discarded = .true.
    end if
  end subroutine put_raw

  subroutine put_f64(self, which, buf, lead, first, count, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which
    real(dp), intent(in), target, contiguous :: buf(..)
    integer, intent(in) :: lead(:), first, count
    integer, intent(inout) :: stat
    call put_raw(self, which, H5T_NATIVE_DOUBLE, c_loc(buf), lead, first, count, stat)
  end subroutine put_f64

  subroutine put_i32(self, which, buf, lead, first, count, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which
    integer, intent(in), target, contiguous :: buf(..)
    integer, intent(in) :: lead(:), first, count
    integer, intent(inout) :: stat
    call put_raw(self, which, H5T_NATIVE_INTEGER, c_loc(buf), lead, first, count, stat)
  end subroutine put_i32

  subroutine put_i64(self, which, buf, first, count, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which
    integer(i8), intent(in), target :: buf(:)
    integer, intent(in) :: first, count
    integer, intent(inout) :: stat
    call put_raw(self, which, h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(buf), per_member, first, count, stat)
  end subroutine put_i64

  subroutine put_message(self, member, text, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: member
    character(len=*), intent(in) :: text
    integer, intent(inout) :: stat
    character(len=VCI_ENSEMBLE_MESSAGE_LEN), target :: buf
    integer(hid_t) :: stype
    integer :: err, e2
    if (stat /= VCI_OK) return
    ! null-padded like the dataset's type: readers see the message without trailing blanks
    buf = repeat(achar(0), VCI_ENSEMBLE_MESSAGE_LEN)
    buf(1:min(len_trim(text), VCI_ENSEMBLE_MESSAGE_LEN)) = text
    call h5io_string_type(VCI_ENSEMBLE_MESSAGE_LEN, stype, err)
    if (err == 0) call put_raw(self, D_MESSAGE, stype, c_loc(buf), per_member, member, 1, stat)
    call h5tclose_f(stype, e2)
  end subroutine put_message

  subroutine get_raw(self, which, mtype, buf, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which
    integer(hid_t), intent(in) :: mtype
    type(c_ptr), intent(in) :: buf
    integer, intent(inout) :: stat
    type(c_ptr) :: p
    integer :: err
    if (stat /= VCI_OK) return
    p = buf      ! HDF5's pointer interface takes the pointer intent(inout)
    call h5dread_f(self%d(which), mtype, p, err)
    if (err /= 0) call fail(self, 'cannot read /'//trim(names(which)), stat)
  end subroutine get_raw

  subroutine get_f64(self, which, buf, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which
    type(c_ptr), intent(in) :: buf
    integer, intent(inout) :: stat
    call get_raw(self, which, H5T_NATIVE_DOUBLE, buf, stat)
  end subroutine get_f64

  subroutine get_i32(self, which, buf, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which
    integer, intent(inout), target, contiguous :: buf(..)
    integer, intent(inout) :: stat
    call get_raw(self, which, H5T_NATIVE_INTEGER, c_loc(buf), stat)
  end subroutine get_i32

  subroutine get_i64(self, which, buf, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    integer, intent(in) :: which
    integer(i8), intent(inout), target :: buf(:)
    integer, intent(inout) :: stat
    call get_raw(self, which, h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(buf), stat)
  end subroutine get_i64

  subroutine get_messages(self, msgs, stat)
    type(vci_ensemble_file_t), intent(inout) :: self
    character(len=*), intent(inout) :: msgs(:)
    integer, intent(inout) :: stat
    character(len=VCI_ENSEMBLE_MESSAGE_LEN), allocatable, target :: buf(:)
    integer(hid_t) :: stype
    integer :: err, e2, j, k
    if (stat /= VCI_OK) return
    allocate (buf(size(msgs)), stat=err)
    if (err == 0) call h5io_string_type(VCI_ENSEMBLE_MESSAGE_LEN, stype, err)
    if (err /= 0) then
      call fail(self, 'cannot read /'//trim(names(D_MESSAGE)), stat); return
    end if
    call get_raw(self, D_MESSAGE, stype, c_loc(buf), stat)
    call h5tclose_f(stype, e2)
    do j = 1, size(msgs)
      k = index(buf(j), achar(0))
      if (k > 0) buf(j)(k:) = ' '
      msgs(j) = buf(j)
    end do
  end subroutine get_messages

  ! --- root attributes: vci_h5_io's (collective under MPI: every rank writes the same value) ---

  !> The Fortran shape of dataset `which` in a file of this ensemble's sizes (as f_create makes it).
  pure function dims_of(self, which) result(dims)
    type(vci_ensemble_file_t), intent(in) :: self
    integer, intent(in) :: which
    integer, allocatable :: dims(:)
    select case (which)
    case (D_Q0, D_V0, D_Q, D_P)
      dims = [self%n, self%n_members]
    case (D_PARAMS)
      dims = [self%n_params, self%n_members]
    case (D_IMPT, D_IMPGAP)
      dims = [self%impact_cap, self%n_members]
    case (D_TRT)
      dims = [self%samples, self%n_members]
    case (D_TRQ, D_TRP)
      dims = [self%n, self%samples, self%n_members]
    case default
      dims = [self%n_members]
    end select
  end function dims_of

  !> How failures name this file (vci_h5_io's messages: who: cause).
  pure function who(self)
    type(vci_ensemble_file_t), intent(in) :: self
    character(len=len(self%path) + 14) :: who
    who = 'ensemble file '//self%path
  end function who
end module vci_ensemble_h5
