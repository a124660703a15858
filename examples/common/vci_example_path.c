/* What kind of file a command-line path names, for the examples' --output check: writing a
 * trajectory into a device or a directory (say /dev/full) must be refused, not turned into
 * "/dev/full.h5" or a disk-full error halfway through a run. */
#include <sys/stat.h>

/* 0: nothing there; 1: a regular file; 2: something else (device, directory, fifo, socket). */
int vci_example_path_kind(const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0) return 0;
    return S_ISREG(st.st_mode) ? 1 : 2;
}
