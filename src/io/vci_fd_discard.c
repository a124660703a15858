/* Used by the HDF5 output layer (vci_h5_io.f90, h5io_discard_writes) when a file can no longer be
 * written (a full disk): its descriptor is pointed at a sink, so that what HDF5 still holds goes
 * nowhere and its closes complete. The sink must accept writes *and* ftruncate, which HDF5's sec2
 * driver calls at close when its end of allocation differs from the file's end: /dev/null refuses
 * ftruncate (EINVAL), H5Fclose then fails half-way and HDF5 crashed at exit closing the file again.
 * An anonymous in-memory file (memfd, Linux) takes both and holds only what HDF5 writes at close
 * (its metadata); elsewhere /dev/null stays the sink. */
#define _GNU_SOURCE
#include <fcntl.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>
#if defined(__linux__)
#include <dirent.h>
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

/* Every descriptor of this process open on the file at path (same device and inode) pointed at a
 * sink: for files whose descriptor HDF5 does not hand out (the MPI-IO driver opens its own, and
 * asking HDF5 for it is collective). The number redirected, or -1 when the descriptors cannot be
 * listed (no /proc/self/fd) or path is gone. */
int vci_discard_path(const char *path) {
#if defined(__linux__)
  struct stat target, st;
  struct dirent *e;
  DIR *dir;
  int n = 0;
  if (stat(path, &target) != 0) return -1;
  dir = opendir("/proc/self/fd");
  if (!dir) return -1;
  while ((e = readdir(dir)) != NULL) {
    char *end;
    long fd = strtol(e->d_name, &end, 10);
    if (end == e->d_name || *end != '\0' || fd == dirfd(dir)) continue;
    if (fstat((int)fd, &st) != 0 || !S_ISREG(st.st_mode)) continue;
    if (st.st_dev == target.st_dev && st.st_ino == target.st_ino && vci_discard_fd((int)fd) == 0) n++;
  }
  closedir(dir);
  return n;
#else
  (void)path;
  return -1;
#endif
}
