!> The HDF5 file of a run as the entry points that restart (the legacy VCIOUT/VCIRST) see it:
!> an output opened new or for appending, and the checkpoint of a file's last state, or
!> VCI_ERR_IO saying that this library was built without HDF5. The one place of the legacy entry
!> that depends on the build's HDF5 (vci_legacy itself is compiled the same either way).
module vci_bindings_h5
  use vci_status, only: VCI_OK, VCI_ERR_IO, VCI_ERR_MEMORY
  use vci_observer, only: vci_observer_t
  use vci_checkpoint, only: vci_checkpoint_t
#ifdef VCI_HAVE_HDF5
  use vci_hdf5_output, only: vci_hdf5_writer_t, vci_hdf5_read_checkpoint
#endif
  implicit none
  private
  public :: bindings_open_h5, bindings_read_h5

  character(len=*), parameter :: no_hdf5 = ': this vci library was built without HDF5 (configure with -DVCI_WITH_HDF5=ON)'

contains

  !> An HDF5 writer on PATH as `output`: a new file (replaced if it exists), or with append the
  !> file continued. stat VCI_OK, VCI_ERR_IO (message: the file and the cause) or VCI_ERR_MEMORY.
  subroutine bindings_open_h5(path, append, output, stat, message)
    character(len=*), intent(in) :: path
    logical, intent(in) :: append
    class(vci_observer_t), allocatable, intent(out) :: output
    integer, intent(out) :: stat
    character(len=*), intent(out) :: message
#ifdef VCI_HAVE_HDF5
    type(vci_hdf5_writer_t), allocatable :: w
    message = ''
    allocate (w, stat=stat)
    if (stat /= 0) then
      message = 'out of memory'; stat = VCI_ERR_MEMORY; return
    end if
    if (append) then
      call w%open(path, stat, append=.true.)
    else
      call w%open(path, stat, overwrite=.true.)
    end if
    if (stat /= VCI_OK) then
      message = w%message; stat = VCI_ERR_IO; return
    end if
    call move_alloc(w, output)
#else
    message = 'cannot write '//path//no_hdf5
    stat = VCI_ERR_IO
    if (append) continue   ! (the argument is used with HDF5 only)
#endif
  end subroutine bindings_open_h5

  !> The checkpoint of the last state of the HDF5 file PATH (vci_hdf5_read_checkpoint).
  subroutine bindings_read_h5(path, cp, stat, message)
    character(len=*), intent(in) :: path
    type(vci_checkpoint_t), intent(out) :: cp
    integer, intent(out) :: stat
    character(len=*), intent(out) :: message
#ifdef VCI_HAVE_HDF5
    call vci_hdf5_read_checkpoint(path, cp, stat, message)
    if (stat /= VCI_OK) stat = VCI_ERR_IO
#else
    message = 'cannot read '//path//no_hdf5
    stat = VCI_ERR_IO
    cp%step = 0
#endif
  end subroutine bindings_read_h5
end module vci_bindings_h5
