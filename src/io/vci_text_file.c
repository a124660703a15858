/* Text files written through C stdio, for the CSV writer (vci_csv_output.f90): gfortran 12's
 * formatted and stream writes drop a failed write(2) without an iostat (a full disk, even
 * /dev/full: the run reported success beside a truncated file), while fwrite, fflush and fclose
 * report it. Each call gives 0 or errno's value (EIO when the C library set none). */
#include <errno.h>
#include <stdio.h>
#include <string.h>

static int vci_text_errno(void) { return errno ? errno : EIO; }

/* path opened for writing (replaced); NULL and *err = errno when it cannot be. */
void *vci_text_open(const char *path, int *err) {
  FILE *f;
  errno = 0;
  f = fopen(path, "w");
  *err = f ? 0 : vci_text_errno();
  return f;
}

/* len characters of line and a newline. */
int vci_text_put(void *file, const char *line, int len) {
  FILE *f = (FILE *)file;
  errno = 0;
  if (len > 0 && fwrite(line, 1, (size_t)len, f) != (size_t)len) return vci_text_errno();
  if (fputc('\n', f) == EOF) return vci_text_errno();
  return 0;
}

/* Everything buffered to the file, then closed (always: the FILE is gone either way). */
int vci_text_close(void *file) {
  FILE *f = (FILE *)file;
  int e = 0;
  errno = 0;
  if (fflush(f) != 0 || ferror(f)) e = vci_text_errno();
  errno = 0;
  if (fclose(f) != 0 && e == 0) e = vci_text_errno();
  return e;
}

/* The text of an errno value into buf (size bytes, NUL-terminated). */
void vci_text_reason(int code, char *buf, int size) {
  if (size < 1) return;
  snprintf(buf, (size_t)size, "%s", strerror(code));
}
