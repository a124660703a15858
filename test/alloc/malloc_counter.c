/* Counts the heap allocations of the whole process, for test_alloc_free.pf. Built as a shared
 * library linked into the test executable, it comes before libc in the symbol search order, so
 * its malloc family replaces glibc's for the program, libgfortran and libvci.so alike (the suite
 * checks this with allocations it makes on purpose). Each call is counted and forwarded to
 * glibc's own allocator; free is left to glibc, which owns every block. Test use only: not for
 * sanitizer builds, whose runtimes replace malloc themselves.
 * It also injects one allocation failure on request (vci_test_malloc_fail, for
 * test_alloc_failure.pf): the k-th allocation of at least min_bytes from then on returns NULL
 * (errno ENOMEM), as an allocator out of address space would; vci_test_malloc_fail_in counts only
 * the allocations one shared object makes. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stddef.h>
#include <string.h>

extern void *__libc_malloc(size_t size);
extern void *__libc_calloc(size_t count, size_t size);
extern void *__libc_realloc(void *ptr, size_t size);
extern void *__libc_memalign(size_t alignment, size_t size);

static long long allocations = 0;

static void count_one(void) { __atomic_fetch_add(&allocations, 1, __ATOMIC_RELAXED); }

/* > 0: allocations of at least fail_min bytes still to come before the one that fails */
static long long fail_countdown = 0;
static size_t fail_min = 0;

/* non-empty: only allocations called from a shared object whose path contains this count */
static char fail_from[64] = "";

/* The caller (return address) lies in an object whose path contains fail_from (or no filter). */
static int from_chosen_object(const void *caller) {
  Dl_info info;
  if (fail_from[0] == '\0') return 1;
  return dladdr(caller, &info) != 0 && info.dli_fname != NULL && strstr(info.dli_fname, fail_from) != NULL;
}

static int injected_failure(size_t size, const void *caller) {
  if (__atomic_load_n(&fail_countdown, __ATOMIC_RELAXED) <= 0 || size < fail_min) return 0;
  if (!from_chosen_object(caller)) return 0;
  if (__atomic_sub_fetch(&fail_countdown, 1, __ATOMIC_RELAXED) != 0) return 0;
  errno = ENOMEM;
  return 1;
}

#define CALLER __builtin_return_address(0)

void *malloc(size_t size) {
  count_one();
  if (injected_failure(size, CALLER)) return NULL;
  return __libc_malloc(size);
}

void *calloc(size_t count, size_t size) {
  count_one();
  if (count != 0 && size <= (size_t)-1 / count && injected_failure(count * size, CALLER)) return NULL;
  return __libc_calloc(count, size);
}

void *realloc(void *ptr, size_t size) {
  count_one();
  if (injected_failure(size, CALLER)) return NULL; /* ptr stays valid, as after a real failure */
  return __libc_realloc(ptr, size);
}

void *memalign(size_t alignment, size_t size) {
  count_one();
  if (injected_failure(size, CALLER)) return NULL;
  return __libc_memalign(alignment, size);
}

void *aligned_alloc(size_t alignment, size_t size) {
  count_one();
  if (injected_failure(size, CALLER)) return NULL;
  return __libc_memalign(alignment, size);
}

int posix_memalign(void **out, size_t alignment, size_t size) {
  void *p;
  /* a power of two and a multiple of sizeof(void *), as POSIX requires */
  if (alignment == 0 || (alignment & (alignment - 1)) != 0 || alignment % sizeof(void *) != 0) return EINVAL;
  count_one();
  if (injected_failure(size, CALLER)) return ENOMEM;
  p = __libc_memalign(alignment, size);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}

/* Allocations so far (malloc, calloc, realloc and the aligned ones), for Fortran through bind(C). */
long long vci_test_malloc_count(void) { return __atomic_load_n(&allocations, __ATOMIC_RELAXED); }

/* Disarm, set what counts (allocations of at least min_bytes from `object`, "" for any), arm k. */
static void arm(long long k, long long min_bytes, const char *object) {
  __atomic_store_n(&fail_countdown, 0, __ATOMIC_RELAXED);
  strncpy(fail_from, object, sizeof fail_from - 1);
  fail_from[sizeof fail_from - 1] = '\0';
  fail_min = min_bytes > 0 ? (size_t)min_bytes : 0;
  __atomic_store_n(&fail_countdown, k > 0 ? k : 0, __ATOMIC_RELAXED);
}

/* From now on the k-th allocation of at least min_bytes fails (once); k <= 0: no failure. */
void vci_test_malloc_fail(long long k, long long min_bytes) { arm(k, min_bytes, ""); }

/* The same, counting only allocations called from a shared object whose path contains `object`
 * (say "libvci.": gfortran compiles allocate and array temporaries into calls of malloc from the
 * object itself), so that a library whose own failed allocations crash it (OpenMPI's MPI-IO) is
 * left out. */
void vci_test_malloc_fail_in(long long k, long long min_bytes, const char *object) { arm(k, min_bytes, object); }

/* Allocations still to come before the injected failure (0: it happened, or none was asked). */
long long vci_test_malloc_fail_pending(void) { return __atomic_load_n(&fail_countdown, __ATOMIC_RELAXED); }
