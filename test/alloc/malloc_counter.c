/* Counts the heap allocations of the whole process, for test_alloc_free.pf. Built as a shared
 * library linked into the test executable, it comes before libc in the symbol search order, so
 * its malloc family replaces glibc's for the program, libgfortran and libvci.so alike (the suite
 * checks this with allocations it makes on purpose). Each call is counted and forwarded to
 * glibc's own allocator; free is left to glibc, which owns every block. Test use only: not for
 * sanitizer builds, whose runtimes replace malloc themselves. */
#include <errno.h>
#include <stddef.h>

extern void *__libc_malloc(size_t size);
extern void *__libc_calloc(size_t count, size_t size);
extern void *__libc_realloc(void *ptr, size_t size);
extern void *__libc_memalign(size_t alignment, size_t size);

static long long allocations = 0;

static void count_one(void) { __atomic_fetch_add(&allocations, 1, __ATOMIC_RELAXED); }

void *malloc(size_t size) {
  count_one();
  return __libc_malloc(size);
}

void *calloc(size_t count, size_t size) {
  count_one();
  return __libc_calloc(count, size);
}

void *realloc(void *ptr, size_t size) {
  count_one();
  return __libc_realloc(ptr, size);
}

void *memalign(size_t alignment, size_t size) {
  count_one();
  return __libc_memalign(alignment, size);
}

void *aligned_alloc(size_t alignment, size_t size) {
  count_one();
  return __libc_memalign(alignment, size);
}

int posix_memalign(void **out, size_t alignment, size_t size) {
  void *p;
  /* a power of two and a multiple of sizeof(void *), as POSIX requires */
  if (alignment == 0 || (alignment & (alignment - 1)) != 0 || alignment % sizeof(void *) != 0) return EINVAL;
  count_one();
  p = __libc_memalign(alignment, size);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}

/* Allocations so far (malloc, calloc, realloc and the aligned ones), for Fortran through bind(C). */
long long vci_test_malloc_count(void) { return __atomic_load_n(&allocations, __ATOMIC_RELAXED); }
