/* What Fortran 2008 cannot express portably, for the C ABI (src/bindings/vci_capi_registry.f90): the locks that make
 * the handle registry and the HDF5 output thread-safe, and the per-thread message of failures that
 * have no live integrator to hold them (read with vci_last_error(NULL, ...)). Statically
 * initialised, so there is no initialisation race; hidden from the library's users. */
#include <string.h>

#if defined(_WIN32)
#include <windows.h>
static SRWLOCK registry_lock = SRWLOCK_INIT, io_lock = SRWLOCK_INIT;
#define LOCK(l) AcquireSRWLockExclusive(&(l))
#define UNLOCK(l) ReleaseSRWLockExclusive(&(l))
#define THREAD_LOCAL __declspec(thread)
#define HIDDEN
#else
#include <pthread.h>
static pthread_mutex_t registry_lock = PTHREAD_MUTEX_INITIALIZER, io_lock = PTHREAD_MUTEX_INITIALIZER;
#define LOCK(l) pthread_mutex_lock(&(l))
#define UNLOCK(l) pthread_mutex_unlock(&(l))
#define THREAD_LOCAL _Thread_local
#define HIDDEN __attribute__((visibility("hidden")))
#endif

enum { MESSAGE_LEN = 512 }; /* VCI_MSG_LEN of vci_status */
static THREAD_LOCAL char thread_message[MESSAGE_LEN + 1];

HIDDEN void vci_lock_registry(void) { LOCK(registry_lock); }
HIDDEN void vci_unlock_registry(void) { UNLOCK(registry_lock); }
HIDDEN void vci_lock_io(void) { LOCK(io_lock); }
HIDDEN void vci_unlock_io(void) { UNLOCK(io_lock); }

/* Keep msg[0..len) (not NUL-terminated, from Fortran) as this thread's message. */
HIDDEN void vci_set_thread_message(const char *msg, int len) {
  if (len < 0) len = 0;
  if (len > MESSAGE_LEN) len = MESSAGE_LEN;
  memcpy(thread_message, msg, (size_t)len);
  thread_message[len] = '\0';
}

/* Copy this thread's message into buf[0..size) blank-padded (Fortran style); its length. */
HIDDEN int vci_get_thread_message(char *buf, int size) {
  int n = (int)strlen(thread_message);
  if (n > size) n = size;
  memcpy(buf, thread_message, (size_t)n);
  if (size > n) memset(buf + n, ' ', (size_t)(size - n));
  return n;
}
