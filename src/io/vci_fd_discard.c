/* Used by the HDF5 output layer (vci_h5_io.f90, h5io_discard_writes) when a file can no longer be
 * written (a full disk): its descriptor is pointed at a sink, so that what HDF5 still holds goes
 * nowhere and its closes complete. The sink must accept writes *and* ftruncate, which HDF5's sec2
 * driver calls at close when its end of allocation differs from the file's end: /dev/null refuses
 * ftruncate (EINVAL), H5Fclose then fails half-way and HDF5 crashed at exit closing the file again.
 * An anonymous in-memory file (memfd, Linux) takes both and holds only what HDF5 writes at close
 * (its metadata); elsewhere /dev/null stays the sink. */
#define _GNU_SOURCE
#include <fcntl.h>
#include <unistd.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif

/* 0 when fd now refers to the sink; -1 when it could not be redirected (fd unchanged). */
int vci_discard_fd(int fd) {
  int sink = -1, r;
#if defined(__linux__) && defined(MFD_CLOEXEC)
  sink = memfd_create("vci-discarded-writes", MFD_CLOEXEC);
#endif
  if (sink < 0) sink = open("/dev/null", O_RDWR | O_CLOEXEC);
  if (sink < 0) return -1;
  r = dup2(sink, fd);
  close(sink);
  return r < 0 ? -1 : 0;
}
