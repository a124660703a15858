/* The C ABI from several threads at once (vci.h, "Threads"): run in the default build, and under
 * ThreadSanitizer by tools/test.sh (preset tsan), where any data race is a failure.
 *  - shared model: two threads integrate from one model, each with a callback failing with 7 at its
 *    own 60th call; each message names the callback and its code (the model used to hold the last
 *    callback failure, written by both threads);
 *  - handles: threads create, use and destroy models and integrators concurrently; no spurious
 *    "not a live handle" (the registry used to be unguarded);
 *  - handle-less failures are per thread: each thread reads back its own message;
 *  - vci_status_string from every thread at once;
 *  - output: threads write HDF5 files at the same time (HDF5 itself is not thread-safe).
 * Usage: vci_threads_test [rounds]; exit status = number of failed checks (capped). */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "vci.h"
#include "scenes.h"

enum { NTHREADS = 4 };
static int rounds = 50;
static int failures = 0; /* written under failures_lock */
static pthread_mutex_t failures_lock = PTHREAD_MUTEX_INITIALIZER;

static void fail(const char *what, const char *detail) {
  pthread_mutex_lock(&failures_lock);
  ++failures;
  printf("FAIL: %s: %s\n", what, detail);
  pthread_mutex_unlock(&failures_lock);
}

/* ---- shared model, per-thread callback failure ---- */
static _Thread_local int d1_calls = 0;
static _Thread_local int d1_fail_at = 0;
static ellipse_params shared_par; /* read-only while threads run */

static int flaky_d1(int n, const double *q, const double *v, double h, double *out, void *user) {
  int rc = ellipse_d1(n, q, v, h, out, user);
  if (++d1_calls == d1_fail_at) return 7;
  return rc;
}

static vci_model shared_model = NULL;

static void *shared_model_worker(void *arg) {
  int r, id = (int)(size_t)arg;
  for (r = 0; r < rounds; ++r) {
    vci_integrator integ = NULL;
    double t0, q0[3], q1[3];
    char msg[512];
    int s;
    d1_calls = 0;
    d1_fail_at = 1; /* the first D1 of the first step: fails whatever the line search does */
    if (vci_integrator_create(&integ, shared_model, 1e-2) != VCI_OK) {
      vci_last_error(NULL, msg, sizeof msg);
      fail("create from the shared model", msg);
      continue;
    }
    ellipse_initial_pair(1e-2, &t0, q0, q1);
    s = vci_init_from_pair(integ, t0, q0, q1);
    if (s == VCI_OK) s = vci_integrate(integ, 20 + id, 1);
    vci_last_error(integ, msg, sizeof msg);
    if (s != VCI_ERR_CALLBACK || strstr(msg, "(the C callback d1_ld returned 7)") == NULL) fail("shared model", msg);
    vci_integrator_destroy(&integ);
  }
  return NULL;
}

/* ---- handles created and destroyed concurrently ---- */
static void *handles_worker(void *arg) {
  int r;
  vci_callbacks cb = ellipse_callbacks();
  (void)arg;
  for (r = 0; r < 40 * rounds; ++r) {
    vci_model model = NULL;
    vci_integrator a = NULL, b = NULL;
    char msg[512];
    if (vci_model_create(&model, 3, 0, 1, &cb, &shared_par) != VCI_OK ||
        vci_integrator_create(&a, model, 1e-2) != VCI_OK || vci_integrator_create(&b, model, 1e-2) != VCI_OK) {
      vci_last_error(NULL, msg, sizeof msg);
      fail("create", msg);
    }
    vci_model_destroy(&model);
    if (vci_set_max_impacts(a, 8) != VCI_OK || vci_set_max_impacts(b, 8) != VCI_OK) {
      vci_last_error(NULL, msg, sizeof msg);
      fail("use", msg);
    }
    vci_integrator_destroy(&a);
    if (vci_set_max_impacts(b, 9) != VCI_OK) fail("use after another destroy", "");
    vci_integrator_destroy(&b);
    if (a != NULL || b != NULL || model != NULL) fail("destroy", "handle not nulled");
  }
  return NULL;
}

/* ---- per-thread messages ---- */
static void *messages_worker(void *arg) {
  int r, id = (int)(size_t)arg;
  vci_callbacks cb = ellipse_callbacks();
  char want[64], msg[512];
  for (r = 0; r < 20 * rounds; ++r) {
    vci_model model = NULL;
    int n = -(1000 * id + r % 1000) - 1;
    snprintf(want, sizeof want, "sizes n = %d,", n);
    if (vci_model_create(&model, n, 0, 0, &cb, NULL) != VCI_ERR_ARGUMENT) fail("bad size accepted", "");
    vci_last_error(NULL, msg, sizeof msg);
    if (strstr(msg, want) == NULL) fail("per-thread message", msg);
    if (strcmp(vci_status_string(r % 13), r % 13 <= VCI_STOPPED ? vci_status_string(r % 13) : "unknown status") != 0)
      fail("status string", "");
    if (strcmp(vci_status_string(VCI_ERR_MEMORY), "out of memory") != 0) fail("status string", "");
  }
  return NULL;
}

/* ---- output files from several threads ---- */
static void *output_worker(void *arg) {
  int id = (int)(size_t)arg, r;
  vci_callbacks cb = ellipse_callbacks();
  for (r = 0; r < 2; ++r) {
    vci_model model = NULL;
    vci_integrator integ = NULL;
    double t0, q0[3], q1[3];
    char path[64], msg[512];
    int s;
    snprintf(path, sizeof path, "threads_test_%d_%d.h5", id, r);
    s = vci_model_create(&model, 3, 0, 1, &cb, &shared_par);
    if (!s) s = vci_integrator_create(&integ, model, 1e-2);
    ellipse_initial_pair(1e-2, &t0, q0, q1);
    if (!s) s = vci_init_from_pair(integ, t0, q0, q1);
    if (!s) s = vci_open_output(integ, path);
    if (!s) s = vci_integrate(integ, 300, 1);
    if (!s) s = vci_close_output(integ);
    if (s != VCI_OK) {
      vci_last_error(integ, msg, sizeof msg);
      fail("output", msg);
    }
    vci_integrator_destroy(&integ);
    vci_model_destroy(&model);
    remove(path);
  }
  return NULL;
}

static void run(const char *name, void *(*worker)(void *), int nthreads) {
  pthread_t th[NTHREADS];
  int i, before = failures;
  for (i = 0; i < nthreads; ++i) pthread_create(&th[i], NULL, worker, (void *)(size_t)i);
  for (i = 0; i < nthreads; ++i) pthread_join(th[i], NULL);
  printf("%s: %s\n", name, failures == before ? "passed" : "FAILED");
}

int main(int argc, char **argv) {
  vci_callbacks cb = ellipse_callbacks();
  if (argc > 1) rounds = atoi(argv[1]);
  shared_par = ellipse_default;
  cb.d1_ld = flaky_d1;
  cb.mixed_hessian = NULL;
  if (vci_model_create(&shared_model, 3, 0, 1, &cb, &shared_par) != VCI_OK) return 1;
  run("shared model", shared_model_worker, 2);
  vci_model_destroy(&shared_model);
  run("handles", handles_worker, NTHREADS);
  run("messages", messages_worker, NTHREADS);
#ifdef VCI_TEST_HDF5
  run("output", output_worker, NTHREADS);
#else
  (void)output_worker;
#endif
  printf("%d failed checks\n", failures);
  return failures > 100 ? 100 : failures;
}
