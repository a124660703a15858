/* vci_close_output when memory runs out for the last state's checkpoint (issue 24, ckpt24j): the
 * file is finished without it and the call returns VCI_ERR_MEMORY; the integrator goes on, bit for
 * bit as a twin that never failed. malloc_counter.c fails the k-th allocation of at least 8 bytes
 * (the pendulum's n = 1 vectors) from the moment it is asked to, k = 1 ..: the driver's 5 copies of
 * the state come first (the runtime's own buffers before them would end this program). Before the
 * fix the first copy ended the process ("Error allocating 8 bytes", vci_state.f90). Usage:
 * vci_alloc_close_output; the exit status is the number of failed checks. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include "vci.h"
#include "../api/walls_lagrangian.h"

void vci_test_malloc_fail(long long k, long long min_bytes);
long long vci_test_malloc_fail_pending(void);

static int failures = 0;
#define CHECK(c, ...) do { if (!(c)) { printf("FAIL line %d: %s: ", __LINE__, #c); printf(__VA_ARGS__); printf("\n"); ++failures; } } while (0)

static int l_dq(int n, const double *q, const double *v, double *out, void *user) {
  (void)n; (void)v; (void)user;
  out[0] = -9.8 * sin(q[0]);
  return 0;
}

static vci_integrator started(vci_model model, const char *path) {
  vci_integrator integ = NULL;
  double q0 = 0.9, p0 = 1.5;   /* swings into the walls at +-1 */
  CHECK(vci_integrator_create(&integ, model, 1e-2) == VCI_OK, "create");
  CHECK(vci_init_from_momentum(integ, 0.0, &q0, &p0) == VCI_OK, "init");
  if (path) CHECK(vci_open_output(integ, path) == VCI_OK, "open %s", path);
  CHECK(vci_integrate(integ, 50, 1) == VCI_OK, "50 steps");
  return integ;
}

int main(void) {
  vci_lagrangian_callbacks cb = VCI_LAGRANGIAN_CALLBACKS_INIT;
  vci_model model = NULL;
  int k, failed = 0;
  cb.lagrangian = l_value; cb.dl_dq = l_dq; cb.dl_dv = l_dv; cb.hessians = l_hess;
  cb.gaps = walls; cb.gap_gradients = wall_grads;
  if (vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) != VCI_OK) return 1;
  for (k = 1; k <= 5; ++k) {
    char path[64], msg[512];
    vci_integrator integ, twin;
    double q, p, tq, tp, t;
    long long pending;
    int st;
    snprintf(path, sizeof path, "alloc_close_output_%d.h5", k);
    integ = started(model, path);
    twin = started(model, NULL);
    vci_test_malloc_fail(k, 8);
    st = vci_close_output(integ);
    pending = vci_test_malloc_fail_pending();
    vci_test_malloc_fail(0, 0);
    vci_last_error(integ, msg, sizeof msg);
    CHECK(pending == 0, "k = %d: the failure was met", k);
    CHECK(st == VCI_ERR_MEMORY, "k = %d: vci_close_output returned %d: %s", k, st, msg);
    CHECK(strstr(msg, "no memory for the last state's checkpoint") != NULL, "k = %d: %s", k, msg);
    if (st == VCI_ERR_MEMORY) ++failed;
    /* the integrator goes on as its twin */
    CHECK(vci_integrate(integ, 20, 1) == VCI_OK && vci_integrate(twin, 20, 1) == VCI_OK, "k = %d: 20 more steps", k);
    vci_get_state(integ, &t, &q, &p);
    vci_get_state(twin, &t, &tq, &tp);
    CHECK(q == tq && p == tp, "k = %d: q %.17g p %.17g, twin %.17g %.17g", k, q, p, tq, tp);
    vci_integrator_destroy(&integ);
    vci_integrator_destroy(&twin);
    remove(path);
  }
  printf("vci_close_output: %d failed allocations a status\n", failed);
  vci_model_destroy(&model);
  return failures;
}
