/* A disk that fills up: preloaded (LD_PRELOAD), it lets write()/pwrite() to files whose name ends
 * in VCI_ENOSPC_SUFFIX (default ".h5") put VCI_ENOSPC_BYTES bytes in all, then fails them with
 * ENOSPC, as a full file system does. Other files (stdout, logs) are not touched. Test use only.
 *
 * To put the failure at one chosen write (test/ensemble/totals_flush.sh): VCI_ENOSPC_OPEN=K and
 * VCI_ENOSPC_WRITES=W let the process's K-th open() of such a file be followed by W writes to
 * them, and fail every later one. VCI_ENOSPC_LOG=PREFIX appends a line per open ("open") and per
 * write ("write BYTES") of such files to PREFIX.PID, so that a first run can count them.
 *
 * VCI_ENOSPC_KILL=1: the process is killed (SIGKILL) at the write that would fail, instead: a kill
 * at a chosen byte of the file's writes, e.g. inside a flush (test/hdf5/kill_in_flush.sh). */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

static long long written = 0;
static int full = 0;           /* once full, it stays full */
static long long opens = 0;    /* opens of target files */
static long long after = 0;    /* writes to target files since the VCI_ENOSPC_OPEN-th open */

static int is_target_path(const char *path, size_t n) {
  const char *suffix = getenv("VCI_ENOSPC_SUFFIX");
  size_t ls;
  if (!suffix) suffix = ".h5";
  ls = strlen(suffix);
  return n >= ls && strcmp(path + n - ls, suffix) == 0;
}

static int is_target(int fd) {
  char link[64], path[PATH_MAX];
  ssize_t n;
  if (fd <= 2) return 0;
  snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
  n = readlink(link, path, sizeof path - 1);
  if (n <= 0) return 0;
  path[n] = '\0';
  return is_target_path(path, (size_t)n);
}

/* One line to PREFIX.PID (the log is not a target: its name does not end in the suffix). */
static void log_line(const char *what, long long bytes) {
  const char *prefix = getenv("VCI_ENOSPC_LOG");
  char name[PATH_MAX];
  FILE *f;
  if (!prefix) return;
  snprintf(name, sizeof name, "%s.%ld", prefix, (long)getpid());
  f = fopen(name, "a");
  if (!f) return;
  if (bytes >= 0)
    fprintf(f, "%s %lld\n", what, bytes);
  else
    fprintf(f, "%s\n", what);
  fclose(f);
}

/* 1: the write may go ahead (and is counted); 0: the disk is full. */
static int room_for(int fd, size_t count) {
  const char *limit = getenv("VCI_ENOSPC_BYTES");
  const char *at_open = getenv("VCI_ENOSPC_OPEN"), *writes = getenv("VCI_ENOSPC_WRITES");
  if (!is_target(fd)) return 1;
  if (!full && at_open && writes && opens >= atoll(at_open)) {
    if (after >= atoll(writes)) full = 1;
    else after++;
  }
  if (!full && limit && written + (long long)count > atoll(limit)) full = 1;
  if (full && getenv("VCI_ENOSPC_KILL")) raise(SIGKILL);
  if (full) return 0;
  written += (long long)count;
  log_line("write", (long long)count);
  return 1;
}

static void opened(const char *path, int fd) {
  if (fd < 0 || !path || !is_target_path(path, strlen(path))) return;
  opens++;
  log_line("open", -1);
}

int open(const char *path, int flags, ...) {
  static int (*real)(const char *, int, ...) = NULL;
  mode_t mode = 0;
  int fd;
  if (!real) real = (int (*)(const char *, int, ...))dlsym(RTLD_NEXT, "open");
  if (flags & (O_CREAT | O_TMPFILE)) {
    va_list ap;
    va_start(ap, flags);
    mode = va_arg(ap, mode_t);
    va_end(ap);
  }
  fd = real(path, flags, mode);
  opened(path, fd);
  return fd;
}

int open64(const char *path, int flags, ...) {
  static int (*real)(const char *, int, ...) = NULL;
  mode_t mode = 0;
  int fd;
  if (!real) real = (int (*)(const char *, int, ...))dlsym(RTLD_NEXT, "open64");
  if (flags & (O_CREAT | O_TMPFILE)) {
    va_list ap;
    va_start(ap, flags);
    mode = va_arg(ap, mode_t);
    va_end(ap);
  }
  fd = real(path, flags, mode);
  opened(path, fd);
  return fd;
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
