!> HDF5 helpers shared by the run file (vci_hdf5_output) and the ensemble file (vci_ensemble_h5):
!> scalar attributes (real, integer, 64-bit integer, string), extendible row datasets (create, open,
!> check the shape, append rows, read one row), small fixed vectors, and the reason of a failure.
!>
!> One body serves every numeric type: the typed entry points are thin wrappers of a generic
!> interface that pass the HDF5 file and memory types and a C pointer to the data (the HDF5
!> Fortran 2003 interface). Every helper takes `stat` (inout): it does nothing if stat is already
!> nonzero, and on failure sets stat = VCI_ERR_IO and message = who//': '//cause. Reading checks
!> before use: an attribute holds one value of the right class, a string at most 4096 bytes, a
!> dataset has the rank and row width asked for. Dims are in Fortran order (the row index last).
module vci_h5_io
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_char, c_int, c_size_t, c_f_pointer, &
                                          c_associated, c_funptr, c_funloc, c_int64_t, c_long_long, c_null_char
  use hdf5
  use vci_kinds, only: dp, i8
  use vci_status, only: VCI_OK, VCI_ERR_IO
  implicit none
  private

  public :: h5io_fail, h5io_os_cause, h5io_discard_writes, h5io_discard_path, h5io_free_bytes, h5io_path_kind
  public :: h5io_allocate_to_file_end
  public :: h5io_put_attr, h5io_get_attr
  public :: h5io_make_rows, h5io_open_dset, h5io_rows, h5io_append_rows, h5io_read_row, h5io_read_i8, h5io_check_dims
  public :: h5io_put_vector, h5io_get_vector, h5io_close_dset, h5io_string_type

  !> A scalar attribute: real(dp), integer, integer(i8) or a string (fixed length, null-padded).
  interface h5io_put_attr
    module procedure put_attr_real, put_attr_int, put_attr_i8, put_attr_str
  end interface h5io_put_attr

  !> Read a scalar attribute after checking it holds one value of the right class.
  interface h5io_get_attr
    module procedure get_attr_real, get_attr_int, get_attr_i8, get_attr_str
  end interface h5io_get_attr

  !> Append `count` rows at row `first` (0-based) of a dataset of rows of `width` values.
  interface h5io_append_rows
    module procedure append_real, append_i8, append_int
  end interface h5io_append_rows

  ! HDF5's error record (H5E_error2_t), read by the walk over the error stack
  type, bind(C) :: h5e_error_t
    integer(c_int64_t) :: cls_id, maj_num, min_num   ! hid_t: int64_t since HDF5 1.10
    integer(c_int) :: line
    type(c_ptr) :: func_name, file_name, desc
  end type h5e_error_t

  interface
    integer(c_int) function h5ewalk2(stack, direction, func, client) bind(C, name='H5Ewalk2')
      import :: c_int64_t, c_int, c_funptr, c_ptr
      integer(c_int64_t), value :: stack
      integer(c_int), value :: direction
      type(c_funptr), value :: func
      type(c_ptr), value :: client
    end function h5ewalk2
    integer(c_int) function h5fget_vfd_handle(file, fapl, handle) bind(C, name='H5Fget_vfd_handle')
      import :: c_int64_t, c_int, c_ptr
      integer(c_int64_t), value :: file, fapl
      type(c_ptr), intent(out) :: handle
    end function h5fget_vfd_handle
    !> src/io/vci_fd_discard.c: point fd at a sink that takes writes and ftruncate; 0 on success
    integer(c_int) function vci_discard_fd(fd) bind(C, name='vci_discard_fd')
      import :: c_int
      integer(c_int), value :: fd
    end function vci_discard_fd
    !> src/io/vci_fd_discard.c: every descriptor on the file at path pointed at a sink; how many, or -1
    integer(c_int) function vci_discard_path(path) bind(C, name='vci_discard_path')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
    end function vci_discard_path
    !> src/io/vci_fs_space.c: bytes free where path would be written, -1 when unknown
    integer(c_long_long) function vci_free_bytes(path) bind(C, name='vci_free_bytes')
      import :: c_long_long, c_char
      character(kind=c_char), intent(in) :: path(*)
    end function vci_free_bytes
    !> src/io/vci_fs_space.c: 0 nothing there, 1 a regular file, 2 anything else (FIFO, device, ...)
    integer(c_int) function vci_path_kind(path) bind(C, name='vci_path_kind')
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
    end function vci_path_kind
    !> the file's end of allocation to max(EOA, end of the file on disk) + increment (HDF5 >= 1.10.2)
    integer(c_int) function h5fincrement_filesize(file, increment) bind(C, name='H5Fincrement_filesize')
      import :: c_int64_t, c_long_long, c_int
      integer(c_int64_t), value :: file
      integer(c_long_long), value :: increment   ! hsize_t
    end function h5fincrement_filesize
    integer(c_size_t) function c_strlen(s) bind(C, name='strlen')
      import :: c_ptr, c_size_t
      type(c_ptr), value :: s
    end function c_strlen
  end interface

contains

  !> stat = VCI_ERR_IO and message = who: cause, unless stat is set already (the first cause stays).
  subroutine h5io_fail(cause, stat, message, who)
    character(len=*), intent(in) :: cause, who
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    if (stat /= VCI_OK) return
    stat = VCI_ERR_IO
    message = who//': '//cause
  end subroutine h5io_fail

  !> The operating system's reason for HDF5's last failure, as its file driver recorded it (e.g. "No
  !> space left on device"), or blank. Call it right after the failing HDF5 call: the next call
  !> clears HDF5's error stack.
  function h5io_os_cause() result(cause)
    character(len=256) :: cause
    character(len=256), target :: found
    integer(c_int) :: r
    found = ''
    r = h5ewalk2(0_c_int64_t, 0_c_int, c_funloc(take_os_cause), c_loc(found))
    cause = found
  end function h5io_os_cause

  !> One record of the walk: keep the driver's "error message = '...'" (errno's text) if it has one.
  integer(c_int) function take_os_cause(n, err, client) bind(C, name='vci_h5io_take_os_cause') result(r)
    integer(c_int), value :: n
    type(h5e_error_t), intent(in) :: err
    type(c_ptr), value :: client
    character(len=256), pointer :: found
    character(kind=c_char), pointer :: chars(:)
    character(len=1024) :: desc
    integer :: i, k, l
    r = 0
    if (.not. c_associated(err%desc) .or. .not. c_associated(client)) return
    call c_f_pointer(client, found)
    if (len_trim(found) > 0) return
    l = int(min(c_strlen(err%desc), int(len(desc), c_size_t)))
    call c_f_pointer(err%desc, chars, [l])
    desc = ''
    do i = 1, l
      desc(i:i) = chars(i)
    end do
    k = index(desc, "error message = '")
    if (k == 0) return
    desc = desc(k + 17:)
    k = index(desc, "'")
    if (k > 1) found = desc(1:k - 1)
  end function take_os_cause

  !> A file that cannot be written any more (a full disk; a row dataset's failed write, caught before
  !> any H5Fflush: see h5io_make_rows): point its descriptor (sec2 driver) at a sink (an in-memory
  !> file, else /dev/null), so that what HDF5 still holds goes nowhere and its closes complete and
  !> free everything. The file keeps what reached the disk before (up to the last complete flush).
  subroutine h5io_discard_writes(file)
    integer(hid_t), intent(in) :: file
    integer(hid_t) :: fapl, driver
    integer :: e2
    integer(c_int) :: r
    type(c_ptr) :: handle
    integer(c_int), pointer :: fd
    call h5fget_access_plist_f(file, fapl, e2)
    if (e2 == 0) call h5pget_driver_f(fapl, driver, e2)
    if (e2 == 0) call h5pclose_f(fapl, e2)
    if (e2 /= 0 .or. driver /= H5FD_SEC2_F) return
    r = h5fget_vfd_handle(int(file, c_int64_t), 0_c_int64_t, handle)
    if (r >= 0 .and. c_associated(handle)) then
      call c_f_pointer(handle, fd)
      r = vci_discard_fd(fd)   ! (src/io/vci_fd_discard.c: a sink that also takes HDF5's ftruncate at close)
    end if
  end subroutine h5io_discard_writes

  !> Extend the end of allocation (EOA) of a file opened for writing to the end of the file on disk,
  !> when it is below it. H5Fflush writes new extents, chunk indexes and object headers, which may
  !> point at blocks it allocated past the old EOA, before the superblock that records the new EOA:
  !> a run killed between them leaves a file whose datasets point past its EOA, where HDF5 neither
  !> reads nor writes (cutting such a dataset back and appending to it failed with an I/O error).
  !> Every block the file points at was written before the pointer to it, so it lies below the end
  !> on disk; taking that end as the EOA makes them addressable, and new blocks go after them.
  subroutine h5io_allocate_to_file_end(file, stat, message, who)
    integer(hid_t), intent(in) :: file
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    character(len=*), intent(in) :: who
    if (stat /= VCI_OK) return
    if (h5fincrement_filesize(int(file, c_int64_t), 0_c_long_long) < 0) &
      call h5io_fail('cannot extend the end of allocation to the end of the file', stat, message, who)
  end subroutine h5io_allocate_to_file_end

  !> Point this process's descriptors of the file at PATH at a sink (vci_fd_discard.c), for drivers
  !> whose descriptor HDF5 does not hand out (MPI-IO); local, not collective. How many were redirected,
  !> or -1 when this system cannot tell.
  integer function h5io_discard_path(path)
    character(len=*), intent(in) :: path
    h5io_discard_path = int(vci_discard_path(path//c_null_char))
  end function h5io_discard_path

  !> Bytes free on the file system that would hold PATH (the file need not exist); -1 when unknown.
  integer(i8) function h5io_free_bytes(path)
    character(len=*), intent(in) :: path
    h5io_free_bytes = int(vci_free_bytes(path//c_null_char), i8)
  end function h5io_free_bytes

  !> What PATH names, told without opening it: 0 nothing, 1 a regular file, 2 anything else (a FIFO,
  !> whose opening for reading blocks until a writer comes; a device; a directory).
  integer function h5io_path_kind(path)
    character(len=*), intent(in) :: path
    h5io_path_kind = int(vci_path_kind(path//c_null_char))
  end function h5io_path_kind

  ! --- attributes --------------------------------------------------------------------------------

  !> A scalar attribute of type ftype, returned open: an existing one is reused (numbers are
  !> rewritten in place) or, with `replace` (strings, whose size changes), deleted and made anew.
  subroutine new_attr(loc, name, ftype, attr, stat, message, who, replace)
    integer(hid_t), intent(in) :: loc, ftype
    character(len=*), intent(in) :: name, who
    integer(hid_t), intent(out) :: attr
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    logical, intent(in) :: replace
    integer(hid_t) :: space
    integer :: err, e2
    logical :: ex
    attr = -1
    if (stat /= VCI_OK) return
    call h5aexists_f(loc, name, ex, err)
    if (err == 0 .and. ex .and. .not. replace) then
      call h5aopen_f(loc, name, attr, err)
      if (err /= 0) call h5io_fail('cannot open attribute '//name, stat, message, who)
      return
    end if
    if (err == 0 .and. ex) call h5adelete_f(loc, name, err)
    space = -1
    if (err == 0) call h5screate_f(H5S_SCALAR_F, space, err)
    if (err == 0) call h5acreate_f(loc, name, ftype, space, attr, err)
    if (space >= 0) call h5sclose_f(space, e2)
    if (err /= 0) call h5io_fail('cannot write attribute '//name, stat, message, who)
  end subroutine new_attr

  !> The one body of every attribute write: value at `buf` of memory type mtype, file type ftype.
  subroutine write_attr(loc, name, ftype, mtype, buf, stat, message, who, replace)
    integer(hid_t), intent(in) :: loc, ftype, mtype
    character(len=*), intent(in) :: name, who
    type(c_ptr), intent(in) :: buf
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    logical, intent(in) :: replace
    integer(hid_t) :: attr
    integer :: err, e2
    call new_attr(loc, name, ftype, attr, stat, message, who, replace)
    if (stat /= VCI_OK) return
    call h5awrite_f(attr, mtype, buf, err)
    call h5aclose_f(attr, e2)
    if (err /= 0) call h5io_fail('cannot write attribute '//name, stat, message, who)
  end subroutine write_attr

  subroutine put_attr_real(loc, name, v, stat, message, who)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name, who
    real(dp), intent(in), target :: v
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    call write_attr(loc, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, c_loc(v), stat, message, who, .false.)
  end subroutine put_attr_real

  subroutine put_attr_int(loc, name, v, stat, message, who)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name, who
    integer, intent(in), target :: v
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    call write_attr(loc, name, H5T_STD_I32LE, H5T_NATIVE_INTEGER, c_loc(v), stat, message, who, .false.)
  end subroutine put_attr_int

  subroutine put_attr_i8(loc, name, v, stat, message, who)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name, who
    integer(i8), intent(in), target :: v
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    call write_attr(loc, name, H5T_STD_I64LE, h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(v), stat, message, who, &
                    .false.)
  end subroutine put_attr_i8

  !> A fixed-length, null-padded string of exactly len(v) characters (h5py: numpy.bytes_).
  subroutine put_attr_str(loc, name, v, stat, message, who)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name, v, who
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    integer(hid_t) :: stype
    integer :: err, e2
    character(len=max(1, len(v))), target :: buf
    type(c_ptr) :: p
    if (stat /= VCI_OK) return
    buf = v
    if (len(v) == 0) buf = achar(0)
    call h5io_string_type(len(buf), stype, err)
    if (err /= 0) then
      call h5io_fail('cannot make a string type', stat, message, who); return
    end if
    ! c_loc(buf) of a character buffer given straight as an argument makes gfortran 12 pass len(buf)
    ! as an extra hidden length, which shifted write_attr's: on a failure its message had len(v)
    ! and `who` the message's length, read past the path (the garbled messages of issue 24)
    p = c_loc(buf)
    call write_attr(loc, name, stype, stype, p, stat, message, who, .true.)
    call h5tclose_f(stype, e2)
  end subroutine put_attr_str

  !> A fixed-length, null-padded string type of `length` bytes (close it with h5tclose_f).
  subroutine h5io_string_type(length, stype, err)
    integer, intent(in) :: length
    integer(hid_t), intent(out) :: stype
    integer, intent(out) :: err
    call h5tcopy_f(H5T_FORTRAN_S1, stype, err)
    if (err == 0) call h5tset_size_f(stype, int(length, size_t), err)
    if (err == 0) call h5tset_strpad_f(stype, H5T_STR_NULLPAD_F, err)
  end subroutine h5io_string_type

  !> Open attribute `name` and check it holds exactly one value of type class `class`; attr = -1
  !> and err /= 0 otherwise.
  subroutine open_attr(loc, name, class, attr, err)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name
    integer, intent(in) :: class
    integer(hid_t), intent(out) :: attr
    integer, intent(out) :: err
    integer(hid_t) :: space, ftype
    integer(hsize_t) :: npoints
    integer :: c, e2
    call h5aopen_f(loc, name, attr, err)
    if (err /= 0) then
      attr = -1; return
    end if
    call h5aget_space_f(attr, space, err)
    if (err == 0) call h5sget_simple_extent_npoints_f(space, npoints, err)
    if (err == 0 .and. npoints /= 1) err = -1
    call h5sclose_f(space, e2)
    if (err == 0) call h5aget_type_f(attr, ftype, err)
    if (err == 0) then
      call h5tget_class_f(ftype, c, err)
      if (err == 0 .and. c /= class) err = -1
      call h5tclose_f(ftype, e2)
    end if
    if (err /= 0) err = -1
  end subroutine open_attr

  !> The one body of every numeric attribute read.
  subroutine read_attr(loc, name, class, mtype, buf, what, stat, message, who)
    integer(hid_t), intent(in) :: loc, mtype
    character(len=*), intent(in) :: name, what, who
    integer, intent(in) :: class
    type(c_ptr), intent(in) :: buf
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    integer(hid_t) :: attr
    integer :: err, e2
    type(c_ptr) :: p
    if (stat /= VCI_OK) return
    p = buf      ! HDF5's pointer interface takes the pointer intent(inout)
    call open_attr(loc, name, class, attr, err)
    if (err == 0) call h5aread_f(attr, mtype, p, err)
    if (attr >= 0) call h5aclose_f(attr, e2)
    if (err /= 0) call h5io_fail('attribute '//name//' missing, unreadable, or not '//what, stat, message, who)
  end subroutine read_attr

  subroutine get_attr_real(loc, name, v, stat, message, who)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name, who
    real(dp), intent(out), target :: v
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    v = 0.0_dp
    call read_attr(loc, name, H5T_FLOAT_F, H5T_NATIVE_DOUBLE, c_loc(v), 'one real number', stat, message, who)
  end subroutine get_attr_real

  subroutine get_attr_int(loc, name, v, stat, message, who)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name, who
    integer, intent(out), target :: v
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    v = 0
    call read_attr(loc, name, H5T_INTEGER_F, H5T_NATIVE_INTEGER, c_loc(v), 'one integer', stat, message, who)
  end subroutine get_attr_int

  subroutine get_attr_i8(loc, name, v, stat, message, who)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name, who
    integer(i8), intent(out), target :: v
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    v = 0
    call read_attr(loc, name, H5T_INTEGER_F, h5kind_to_type(i8, H5_INTEGER_KIND), c_loc(v), 'one integer', &
                   stat, message, who)
  end subroutine get_attr_i8

  !> A string attribute of 1 to 4096 bytes (no allocation the file dictates), without its padding.
  subroutine get_attr_str(loc, name, v, stat, message, who)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name, who
    character(len=:), allocatable, intent(out) :: v
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    integer(hid_t) :: attr, ftype
    integer(size_t) :: sz
    integer :: err, e2, k
    v = ''
    if (stat /= VCI_OK) return
    ftype = -1
    call open_attr(loc, name, H5T_STRING_F, attr, err)
    if (err == 0) call h5aget_type_f(attr, ftype, err)
    if (err == 0) call h5tget_size_f(ftype, sz, err)
    if (err == 0 .and. (sz < 1 .or. sz > 4096)) err = -1
    if (err == 0) then
      deallocate (v)
      allocate (character(len=sz) :: v)   ! (sz <= 4096 checked above: tiny, no stat=)
      call h5aread_f(attr, ftype, v, [1_hsize_t], err)
    end if
    if (ftype >= 0) call h5tclose_f(ftype, e2)
    if (attr >= 0) call h5aclose_f(attr, e2)
    if (err /= 0) then
      call h5io_fail('attribute '//name//' missing or unreadable', stat, message, who); return
    end if
    k = index(v, achar(0))
    if (k > 0) v = v(1:k - 1)
  end subroutine get_attr_str

  ! --- datasets of rows ------------------------------------------------------------------------

  subroutine h5io_close_dset(d)
    integer(hid_t), intent(inout) :: d
    integer :: err
    if (d >= 0) call h5dclose_f(d, err)
    d = -1
  end subroutine h5io_close_dset

  !> Dataset access without a chunk cache: appended rows go to the disk in H5Dwrite, so a full disk
  !> is seen there, before H5Fflush. HDF5 1.10 can neither flush nor close a file whose metadata
  !> flush failed (its cache stays in flushing mode, "slist already enabled?") and then crashes at
  !> exit in its shutdown (H5F__close_cb); a failed raw write leaves it sound.
  subroutine uncached_access(dapl, err)
    integer(hid_t), intent(out) :: dapl
    integer, intent(out) :: err
    call h5pcreate_f(H5P_DATASET_ACCESS_F, dapl, err)
    if (err == 0) call h5pset_chunk_cache_f(dapl, 0_size_t, 0_size_t, 1.0, err)
  end subroutine uncached_access

  !> An extendible dataset of 0 rows, each row `width` values (width 0: a 1-D dataset).
  subroutine h5io_make_rows(loc, name, width, rows_per_chunk, ftype, dset, stat, message, who, deflate)
    integer(hid_t), intent(in) :: loc, ftype
    character(len=*), intent(in) :: name, who
    integer, intent(in) :: width, rows_per_chunk
    integer(hid_t), intent(out) :: dset
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    !> gzip level 1..9 with the shuffle filter before it (bytes of equal significance together: the
    !> exponents of a smooth trajectory compress); 0 or absent: no filter
    integer, intent(in), optional :: deflate
    integer(hid_t) :: space, plist, dapl
    integer(hsize_t) :: dims(2), maxdims(2), chunk(2)
    integer :: rank, err, e2
    character(len=256) :: os
    dset = -1
    if (stat /= VCI_OK) return
    dapl = -1
    if (width > 0) then
      rank = 2; dims = [int(width, hsize_t), 0_hsize_t]; maxdims = [int(width, hsize_t), H5S_UNLIMITED_F]
      chunk = [int(width, hsize_t), int(rows_per_chunk, hsize_t)]
    else
      rank = 1; dims = 0; maxdims = [H5S_UNLIMITED_F, 0_hsize_t]; chunk = [int(rows_per_chunk, hsize_t), 0_hsize_t]
    end if
    call h5screate_simple_f(rank, dims(1:rank), space, err, maxdims(1:rank))
    if (err == 0) call h5pcreate_f(H5P_DATASET_CREATE_F, plist, err)
    if (err == 0) call h5pset_chunk_f(plist, rank, chunk(1:rank), err)
    if (present(deflate)) then
      if (deflate > 0 .and. err == 0) call h5pset_shuffle_f(plist, err)
      if (deflate > 0 .and. err == 0) call h5pset_deflate_f(plist, deflate, err)
    end if
    if (err == 0) call uncached_access(dapl, err)
    if (err == 0) call h5dcreate_f(loc, name, ftype, space, dset, err, plist, dapl_id=dapl)
    os = ''
    if (err /= 0) os = h5io_os_cause()
    call h5pclose_f(plist, e2); call h5sclose_f(space, e2)
    if (dapl >= 0) call h5pclose_f(dapl, e2)
    ! HDF5 1.10 creates no chunked dataset again, without a reason, once an allocation of its own
    ! failed inside a write (docs/OUTPUT.md, "HDF5 out of memory")
    if (len_trim(os) == 0) os = 'HDF5 gives no reason (as after an allocation of its own failed earlier in '// &
                               'this process: HDF5 1.10 then creates no chunked dataset until the process restarts)'
    if (err /= 0) call h5io_fail('cannot create dataset '//name//': '//trim(os), stat, message, who)
  end subroutine h5io_make_rows

  subroutine h5io_open_dset(loc, name, dset, stat, message, who)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name, who
    integer(hid_t), intent(out) :: dset
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    integer(hid_t) :: dapl
    integer :: err, e2
    dset = -1
    if (stat /= VCI_OK) return
    dapl = -1
    call uncached_access(dapl, err)
    if (err == 0) call h5dopen_f(loc, name, dset, err, dapl)
    if (dapl >= 0) call h5pclose_f(dapl, e2)
    if (err /= 0) call h5io_fail('dataset '//name//' missing', stat, message, who)
  end subroutine h5io_open_dset

  !> Number of rows of a dataset of rows of `width` values (width 0: a 1-D dataset), after checking
  !> its shape: rank 1 (width 0) or rank 2 with `width` values in the first (Fortran) dimension.
  !> 0 and a failure (stat) when the shape is another one.
  integer(i8) function h5io_rows(dset, name, width, stat, message, who) result(rows)
    integer(hid_t), intent(in) :: dset
    character(len=*), intent(in) :: name, who
    integer, intent(in) :: width
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    integer(hid_t) :: space
    integer(hsize_t) :: dims(2), maxdims(2)
    integer :: rank, want, err, e2
    rows = 0
    if (stat /= VCI_OK) return
    want = merge(2, 1, width > 0)
    call h5dget_space_f(dset, space, err)
    if (err == 0) call h5sget_simple_extent_ndims_f(space, rank, err)
    if (err == 0 .and. rank /= want) err = -1
    if (err == 0) call h5sget_simple_extent_dims_f(space, dims(1:want), maxdims(1:want), err)
    call h5sclose_f(space, e2)
    if (err >= 0 .and. width > 0) then
      if (dims(1) /= int(width, hsize_t)) err = -1
    end if
    if (err < 0) then
      call h5io_fail('dataset '//name//' is not a list of rows of the expected width', stat, message, who); return
    end if
    if (dims(want) > int(huge(1_i8), hsize_t)) then
      call h5io_fail('dataset '//name//' has too many rows', stat, message, who); return
    end if
    call check_extent_fits(dset, name, real(dims(want), dp) * max(width, 1), stat, message, who)
    if (stat /= VCI_OK) return
    rows = int(dims(want), i8)
  end function h5io_rows

  !> A dataset of `elements` values must fit in its file's bytes: an extent a damaged file claims
  !> (2^40 rows in 100 kB) is refused before anything is read, cut or allocated by it (cutting it
  !> with H5Dset_extent visits every chunk of the extent: hours). A filtered (compressed) dataset
  !> may hold up to deflate's largest ratio, 1032:1, more: a run's constant columns compress that
  !> far, and a legitimate file was refused as damaged.
  subroutine check_extent_fits(dset, name, elements, stat, message, who)
    integer(hid_t), intent(in) :: dset
    character(len=*), intent(in) :: name, who
    real(dp), intent(in) :: elements     ! (real: a damaged extent times the width may pass 2^63)
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    real(dp), parameter :: deflate_max_ratio = 1032.0_dp
    integer(hid_t) :: file, dtype, dcpl
    integer(hsize_t) :: file_bytes
    integer(size_t) :: type_bytes
    integer :: err, e2, nfilters
    real(dp) :: room
    character(len=200) :: why
    if (stat /= VCI_OK) return
    call h5iget_file_id_f(dset, file, err)
    if (err == 0) call h5fget_filesize_f(file, file_bytes, err)
    if (err == 0) call h5fclose_f(file, e2)      ! (closes the identifier only; the file stays open)
    type_bytes = 1
    call h5dget_type_f(dset, dtype, e2)
    if (e2 == 0) then
      call h5tget_size_f(dtype, type_bytes, e2)
      call h5tclose_f(dtype, e2)
    end if
    if (err /= 0) then
      call h5io_fail('cannot tell the size of the file holding dataset '//name, stat, message, who); return
    end if
    nfilters = 0
    call h5dget_create_plist_f(dset, dcpl, e2)
    if (e2 == 0) then
      call h5pget_nfilters_f(dcpl, nfilters, e2)
      if (e2 /= 0) nfilters = 0
      call h5pclose_f(dcpl, e2)
    end if
    room = real(file_bytes, dp)
    if (nfilters > 0) room = deflate_max_ratio * room
    if (elements * real(max(type_bytes, 1_size_t), dp) <= room) return
    write (why, '(a,es10.3,a,i0,a)') 'dataset '//name//' claims ', elements, &
      ' values, more than the file''s ', file_bytes, ' bytes can hold'//trim(merge(' compressed', '           ', &
      nfilters > 0))//' (a damaged extent)'
    call h5io_fail(trim(why), stat, message, who)
  end subroutine check_extent_fits

  !> Check that a dataset has exactly the Fortran shape `dims` (rank and every extent), and that
  !> so many values fit in the file's bytes (check_extent_fits), before it is read whole into a
  !> buffer of that shape.
  subroutine h5io_check_dims(dset, name, dims, stat, message, who)
    integer(hid_t), intent(in) :: dset
    character(len=*), intent(in) :: name, who
    integer, intent(in) :: dims(:)
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    integer(hid_t) :: space
    integer(hsize_t) :: got(7), maxdims(7)
    integer :: rank, err, e2
    if (stat /= VCI_OK) return
    if (size(dims) > 7) then
      call h5io_fail('dataset '//name//': more than 7 dimensions asked for', stat, message, who); return
    end if
    call h5dget_space_f(dset, space, err)
    if (err == 0) call h5sget_simple_extent_ndims_f(space, rank, err)
    if (err == 0 .and. rank /= size(dims)) err = -1
    if (err == 0) call h5sget_simple_extent_dims_f(space, got(1:rank), maxdims(1:rank), err)
    if (err >= 0) then
      if (any(got(1:rank) /= int(dims, hsize_t))) err = -1
    end if
    call h5sclose_f(space, e2)
    if (err < 0) call h5io_fail('dataset '//name//' does not have the shape the file''s attributes give', &
                                stat, message, who)
    call check_extent_fits(dset, name, product(real(dims, dp)), stat, message, who)
  end subroutine h5io_check_dims

  !> Spaces selecting rows first .. first + count - 1 (file) and count rows (memory); with `extend`
  !> the dataset is first extended to first + count rows.
  subroutine select_rows(dset, width, first, count, extend, fspace, mspace, err)
    integer(hid_t), intent(in) :: dset
    integer, intent(in) :: width, count
    integer(i8), intent(in) :: first
    logical, intent(in) :: extend
    integer(hid_t), intent(out) :: fspace, mspace
    integer, intent(out) :: err
    integer(hsize_t) :: newdims(2), offset(2), cnt(2)
    integer :: rank
    fspace = -1; mspace = -1
    if (width > 0) then
      rank = 2; newdims = [int(width, hsize_t), int(first + count, hsize_t)]
      offset = [0_hsize_t, int(first, hsize_t)]; cnt = [int(width, hsize_t), int(count, hsize_t)]
    else
      rank = 1; newdims = [int(first + count, hsize_t), 0_hsize_t]
      offset = [int(first, hsize_t), 0_hsize_t]; cnt = [int(count, hsize_t), 0_hsize_t]
    end if
    err = 0
    if (extend) call h5dset_extent_f(dset, newdims(1:rank), err)
    if (err == 0) call h5dget_space_f(dset, fspace, err)
    if (err == 0) call h5sselect_hyperslab_f(fspace, H5S_SELECT_SET_F, offset(1:rank), cnt(1:rank), err)
    if (err == 0) call h5screate_simple_f(rank, cnt(1:rank), mspace, err)
  end subroutine select_rows

  !> The one body of every append: rows at `buf` of memory type mtype.
  subroutine append_raw(dset, mtype, width, first, count, buf, stat, message, who)
    integer(hid_t), intent(in) :: dset, mtype
    integer, intent(in) :: width, count
    integer(i8), intent(in) :: first
    type(c_ptr), intent(in) :: buf
    integer, intent(inout) :: stat
    character(len=*), intent(in) :: who
    character(len=*), intent(inout) :: message
    integer(hid_t) :: fspace, mspace
    integer :: err, e2
    character(len=256) :: os
    if (stat /= VCI_OK .or. count < 1) return
    call select_rows(dset, width, first, count, .true., fspace, mspace, err)
    if (err /= 0) then
      os = h5io_os_cause()
    else
      call h5dwrite_f(dset, mtype, buf, err, mspace, fspace)
      if (err /= 0) os = h5io_os_cause()
    end if
    if (mspace >= 0) call h5sclose_f(mspace, e2)
    if (fspace >= 0) call h5sclose_f(fspace, e2)
    if (err /= 0) then
      if (len_trim(os) == 0) os = 'HDF5 gives no reason'
      call h5io_fail('writing rows failed: '//trim(os), stat, message, who)
    end if
  end subroutine append_raw

  subroutine append_real(dset, width, first, buf, count, stat, message, who)
    integer(hid_t), intent(in) :: dset
    integer, intent(in) :: width, count
    integer(i8), intent(in) :: first
    real(dp), intent(in), target, contiguous :: buf(..)
    integer, intent(inout) :: stat
    character(len=*), intent(in) :: who
    character(len=*), intent(inout) :: message
    call append_raw(dset, H5T_NATIVE_DOUBLE, width, first, count, c_loc(buf), stat, message, who)
  end subroutine append_real

  subroutine append_i8(dset, width, first, buf, count, stat, message, who)
    integer(hid_t), intent(in) :: dset
    integer, intent(in) :: width, count
    integer(i8), intent(in) :: first
    integer(i8), intent(in), target, contiguous :: buf(..)
    integer, intent(inout) :: stat
    character(len=*), intent(in) :: who
    character(len=*), intent(inout) :: message
    call append_raw(dset, h5kind_to_type(i8, H5_INTEGER_KIND), width, first, count, c_loc(buf), stat, message, who)
  end subroutine append_i8

  subroutine append_int(dset, width, first, buf, count, stat, message, who)
    integer(hid_t), intent(in) :: dset
    integer, intent(in) :: width, count
    integer(i8), intent(in) :: first
    integer, intent(in), target, contiguous :: buf(..)
    integer, intent(inout) :: stat
    character(len=*), intent(in) :: who
    character(len=*), intent(inout) :: message
    call append_raw(dset, H5T_NATIVE_INTEGER, width, first, count, c_loc(buf), stat, message, who)
  end subroutine append_int

  !> Read row `row` (0-based) of a dataset of rows of `width` real values into buf(1:max(width, 1)).
  subroutine h5io_read_row(dset, width, row, buf, stat, message, who)
    integer(hid_t), intent(in) :: dset
    integer, intent(in) :: width
    integer(i8), intent(in) :: row
    real(dp), intent(inout), target, contiguous :: buf(..)
    integer, intent(inout) :: stat
    character(len=*), intent(in) :: who
    character(len=*), intent(inout) :: message
    integer(hid_t) :: fspace, mspace
    integer :: err, e2
    type(c_ptr) :: p
    if (stat /= VCI_OK) return
    err = 0; fspace = -1; mspace = -1
    p = c_loc(buf)
    if (size(buf) < max(width, 1)) err = -1
    if (err == 0) call select_rows(dset, width, row, 1, .false., fspace, mspace, err)
    if (err == 0) call h5dread_f(dset, H5T_NATIVE_DOUBLE, p, err, mspace, fspace)
    if (mspace >= 0) call h5sclose_f(mspace, e2)
    if (fspace >= 0) call h5sclose_f(fspace, e2)
    if (err /= 0) call h5io_fail('cannot read the last row', stat, message, who)
  end subroutine h5io_read_row

  !> Value `row` (0-based) of a 1-D int64 dataset.
  subroutine h5io_read_i8(dset, row, v, stat, message, who)
    integer(hid_t), intent(in) :: dset
    integer(i8), intent(in) :: row
    integer(i8), intent(out), target :: v
    integer, intent(inout) :: stat
    character(len=*), intent(in) :: who
    character(len=*), intent(inout) :: message
    integer(hid_t) :: fspace, mspace
    integer :: err, e2
    type(c_ptr) :: pv
    v = 0
    if (stat /= VCI_OK) return
    pv = c_loc(v)
    call select_rows(dset, 0, row, 1, .false., fspace, mspace, err)
    if (err == 0) call h5dread_f(dset, h5kind_to_type(i8, H5_INTEGER_KIND), pv, err, mspace, fspace)
    if (mspace >= 0) call h5sclose_f(mspace, e2)
    if (fspace >= 0) call h5sclose_f(fspace, e2)
    if (err /= 0) call h5io_fail('cannot read a row', stat, message, who)
  end subroutine h5io_read_i8

  ! --- small fixed vectors -----------------------------------------------------------------------

  !> A fixed dataset of size(v) reals, created on first use, overwritten afterwards; one of another
  !> shape (a damaged or foreign file being appended to) is replaced.
  subroutine h5io_put_vector(loc, name, v, stat, message, who)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name, who
    real(dp), intent(in), target, contiguous :: v(:)
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    integer(hid_t) :: space, dset
    integer :: err, e2, s
    logical :: ex
    character(len=256) :: os, scratch
    if (stat /= VCI_OK) return
    dset = -1; os = ''
    call h5lexists_f(loc, name, ex, err)
    if (err == 0 .and. ex) then
      call h5dopen_f(loc, name, dset, err)
      s = VCI_OK
      if (err == 0) then
        if (h5io_rows(dset, name, 0, s, scratch, who) /= size(v) .or. s /= VCI_OK) then
          call h5dclose_f(dset, e2)
          dset = -1
          call h5ldelete_f(loc, name, err)
          ex = .false.
        end if
      end if
    end if
    if (err == 0 .and. .not. ex) then
      call h5screate_simple_f(1, [int(size(v), hsize_t)], space, err)
      if (err == 0) call h5dcreate_f(loc, name, H5T_IEEE_F64LE, space, dset, err)
      call h5sclose_f(space, e2)
    end if
    if (err == 0) call h5dwrite_f(dset, H5T_NATIVE_DOUBLE, c_loc(v), err)
    if (err /= 0) os = h5io_os_cause()
    if (dset >= 0) call h5dclose_f(dset, e2)
    if (err /= 0 .and. len_trim(os) == 0) os = 'HDF5 gives no reason'
    if (err /= 0) call h5io_fail('cannot write '//name//': '//trim(os), stat, message, who)
  end subroutine h5io_put_vector

  !> Read a fixed dataset that must hold exactly size(v) reals.
  subroutine h5io_get_vector(loc, name, v, stat, message, who)
    integer(hid_t), intent(in) :: loc
    character(len=*), intent(in) :: name, who
    real(dp), intent(out), target, contiguous :: v(:)
    integer, intent(inout) :: stat
    character(len=*), intent(inout) :: message
    integer(hid_t) :: dset
    integer :: err, e2, s
    character(len=256) :: scratch
    type(c_ptr) :: p
    if (stat /= VCI_OK) return
    p = c_loc(v)
    call h5dopen_f(loc, name, dset, err)
    if (err == 0) then
      s = VCI_OK
      if (h5io_rows(dset, name, 0, s, scratch, who) /= size(v) .or. s /= VCI_OK) err = -1
      if (err == 0) call h5dread_f(dset, H5T_NATIVE_DOUBLE, p, err)
      call h5dclose_f(dset, e2)
    end if
    if (err /= 0) call h5io_fail('cannot read '//name//' (missing, or not a vector of the expected length)', &
                                 stat, message, who)
  end subroutine h5io_get_vector
end module vci_h5_io
