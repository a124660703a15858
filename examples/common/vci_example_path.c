/* What a command-line path names, for the examples' parser (vci_example_cli): Fortran's inquire
 * cannot tell a regular file from a device or a directory. */
#include <sys/stat.h>

/* 0: nothing there, 1: a regular file, 2: something else (a directory, a device, a FIFO). */
int vci_example_path_kind(const char *path) {
  struct stat st;
  if (stat(path, &st) != 0) return 0;
  return S_ISREG(st.st_mode) ? 1 : 2;
}
