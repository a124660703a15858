/* A disk that fills up: preloaded (LD_PRELOAD), it lets write()/pwrite() to files whose name ends
 * in VCI_ENOSPC_SUFFIX (default ".h5") put VCI_ENOSPC_BYTES bytes in all, then fails them with
 * ENOSPC, as a full file system does. Other files (stdout, logs) are not touched. Test use only. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

static long long written = 0;
static int full = 0; /* once full, it stays full */

static int is_target(int fd) {
  char link[64], path[PATH_MAX];
  const char *suffix = getenv("VCI_ENOSPC_SUFFIX");
  ssize_t n;
  size_t ls;
  if (fd <= 2) return 0;
  if (!suffix) suffix = ".h5";
  snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
  n = readlink(link, path, sizeof path - 1);
  if (n <= 0) return 0;
  path[n] = '\0';
  ls = strlen(suffix);
  return (size_t)n >= ls && strcmp(path + n - ls, suffix) == 0;
}

/* 1: the write may go ahead (and is counted); 0: the disk is full. */
static int room_for(int fd, size_t count) {
  const char *limit = getenv("VCI_ENOSPC_BYTES");
  if (!limit || !is_target(fd)) return 1;
  if (full || written + (long long)count > atoll(limit)) {
    full = 1;
    return 0;
  }
  written += (long long)count;
  return 1;
}

ssize_t write(int fd, const void *buf, size_t count) {
  static ssize_t (*real)(int, const void *, size_t) = NULL;
  if (!real) real = (ssize_t(*)(int, const void *, size_t))dlsym(RTLD_NEXT, "write");
  if (!room_for(fd, count)) {
    errno = ENOSPC;
    return -1;
  }
  return real(fd, buf, count);
}

ssize_t pwrite(int fd, const void *buf, size_t count, off_t offset) {
  static ssize_t (*real)(int, const void *, size_t, off_t) = NULL;
  if (!real) real = (ssize_t(*)(int, const void *, size_t, off_t))dlsym(RTLD_NEXT, "pwrite");
  if (!room_for(fd, count)) {
    errno = ENOSPC;
    return -1;
  }
  return real(fd, buf, count, offset);
}

ssize_t pwrite64(int fd, const void *buf, size_t count, off_t offset) {
  static ssize_t (*real)(int, const void *, size_t, off_t) = NULL;
  if (!real) real = (ssize_t(*)(int, const void *, size_t, off_t))dlsym(RTLD_NEXT, "pwrite64");
  if (!room_for(fd, count)) {
    errno = ENOSPC;
    return -1;
  }
  return real(fd, buf, count, offset);
}
