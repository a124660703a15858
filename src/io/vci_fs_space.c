/* What the file system says before a file is written or read (vci_h5_io.f90: h5io_free_bytes,
 * h5io_path_kind). Free space: the ensemble file allocates all its datasets at creation, so its size
 * is known before anything is written and a file larger than the disk's room is refused up front
 * instead of filling the disk with fill values. */
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/statvfs.h>

/* Bytes available to this user on the file system that would hold `path` (its directory: the file
 * need not exist), or -1 when that cannot be told. */
long long vci_free_bytes(const char *path) {
  struct statvfs st;
  size_t n = strlen(path);
  char *dir = malloc(n + 2);
  char *slash;
  int r;
  if (!dir) return -1;
  memcpy(dir, path, n + 1);
  slash = strrchr(dir, '/');
  if (!slash) strcpy(dir, ".");
  else if (slash == dir) dir[1] = '\0';   /* a file in / */
  else *slash = '\0';
  r = statvfs(dir, &st);
  free(dir);
  if (r != 0) return -1;
  return (long long)st.f_bavail * (long long)st.f_frsize;
}

/* What `path` names, without opening it (opening a FIFO for reading blocks until a writer comes):
 * 0 nothing (or it cannot be told), 1 a regular file, 2 anything else (FIFO, device, directory). */
int vci_path_kind(const char *path) {
  struct stat st;
  if (stat(path, &st) != 0) return 0;
  return S_ISREG(st.st_mode) ? 1 : 2;
}
