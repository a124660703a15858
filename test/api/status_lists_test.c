/* vci.h lists every status each function can return (issue 24, item 2): this test drives the
 * failures that the lists gained when they were checked against the code, and asserts the status
 * each one returns. Usage: vci_status_lists_test; the exit status is the number of failed checks.
 *  - vci_set_scheme once initialised: VCI_ERR_STATE and the run stays (the header said "the state
 *    is reset"); a composition for a model that is not separable, or of an order that is none:
 *    VCI_ERR_ARGUMENT;
 *  - vci_init_from_pair with VCI_SCHEME_COMPOSITION: VCI_ERR_ARGUMENT (from a momentum it runs);
 *  - vci_integrate stopped by its progress callback: VCI_STOPPED;
 *  - vci_set_progress with an interval above 1e9 or NaN: VCI_ERR_ARGUMENT;
 *  - vci_ensemble_run with a separable model: VCI_ERR_ARGUMENT; with results it cannot allocate
 *    (impact_cap = INT_MAX): VCI_ERR_MEMORY (was VCI_ERR_ARGUMENT);
 *  - vci_check_model whose n x n work arrays cannot be allocated: VCI_ERR_MEMORY (the Fortran
 *    runtime ended the process before).
 * The allocation failures are made certain by RLIMIT_AS (skipped with VCI_TEST_NO_RLIMIT, which the
 * sanitizer presets set: ASan reserves its shadow memory in the address space). */
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include "vci.h"
#include "walls_lagrangian.h"

static int failures = 0;
static int finished = 0;

/* library code never ends the process: an exit before main returns is a failure */
static void exit_guard(void) {
  if (finished) return;
  printf("FAIL: the process exited inside a test (exit or STOP in library code)\n");
  fflush(stdout);
  _Exit(70);
}

static void check_status(int actual, int expected, const char *what, int line) {
  if (actual != expected) {
    ++failures;
    printf("FAIL line %d: %s returned %d (%s), expected %d (%s)\n", line, what, actual, vci_status_string(actual),
           expected, vci_status_string(expected));
  } else {
    printf("  ok: %s -> %s\n", what, vci_status_string(actual));
  }
}
#define CHECK_STATUS(call, expected) check_status((call), (expected), #call, __LINE__)
#define CHECK(c) do { if (!(c)) { printf("FAIL line %d: %s\n", __LINE__, #c); ++failures; } } while (0)

static int l_dq(int n, const double *q, const double *v, double *out, void *user) {
  (void)n; (void)v; (void)user;
  out[0] = -9.8 * sin(q[0]);
  return 0;
}

static vci_model pendulum(void) {
  vci_lagrangian_callbacks cb = VCI_LAGRANGIAN_CALLBACKS_INIT;
  vci_model model = NULL;
  cb.lagrangian = l_value; cb.dl_dq = l_dq; cb.dl_dv = l_dv; cb.hessians = l_hess;
  cb.gaps = walls; cb.gap_gradients = wall_grads;
  CHECK_STATUS(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL), VCI_OK);
  return model;
}

/* V = q^2 / 2 (a spring), M = 1 */
static int spring_v(int n, const double *q, double *out, void *u) { (void)n; (void)u; out[0] = 0.5 * q[0] * q[0]; return 0; }
static int spring_dv(int n, const double *q, double *out, void *u) { (void)n; (void)u; out[0] = q[0]; return 0; }

static vci_model spring(void) {
  vci_separable_callbacks cb = VCI_SEPARABLE_CALLBACKS_INIT;
  vci_model model = NULL;
  double mass = 1.0;
  cb.potential = spring_v; cb.potential_gradient = spring_dv;
  CHECK_STATUS(vci_model_create_separable(&model, 1, 0, 0, VCI_MASS_DIAGONAL, &mass, &cb, NULL), VCI_OK);
  return model;
}

/* a free particle as a discrete L_d = |v - q|^2 / (2h) of any n */
static int free_d1(int n, const double *q, const double *v, double h, double *out, void *u) {
  (void)u; for (int i = 0; i < n; i++) out[i] = -(v[i] - q[i]) / h; return 0;
}
static int free_d2(int n, const double *q, const double *v, double h, double *out, void *u) {
  (void)u; for (int i = 0; i < n; i++) out[i] = (v[i] - q[i]) / h; return 0;
}
static int free_d3(int n, const double *q, const double *v, double h, double *out, void *u) {
  double s = 0.0;
  (void)u; for (int i = 0; i < n; i++) s += (v[i] - q[i]) * (v[i] - q[i]);
  out[0] = -s / (2.0 * h * h);
  return 0;
}

static int stop_at_once(const vci_progress *info, void *user) { (void)info; (void)user; return 1; }

/* run body() with the address space limited to 4 GB, or say that it is skipped */
static void with_rlimit(void (*body)(void), const char *what) {
  struct rlimit old, tight;
  if (getenv("VCI_TEST_NO_RLIMIT") != NULL || getrlimit(RLIMIT_AS, &old) != 0) {
    printf("  (RLIMIT_AS not set: %s not exercised)\n", what);
    return;
  }
  tight = old;
  tight.rlim_cur = 4UL * 1024UL * 1024UL * 1024UL;
  if (old.rlim_cur != RLIM_INFINITY && old.rlim_cur < tight.rlim_cur) tight.rlim_cur = old.rlim_cur;
  if (setrlimit(RLIMIT_AS, &tight) != 0) {
    printf("  (RLIMIT_AS could not be set: %s not exercised)\n", what);
    return;
  }
  body();
  setrlimit(RLIMIT_AS, &old);
}

static void set_scheme_lists(void) {
  vci_model model = pendulum(), sep = spring();
  vci_integrator integ = NULL;
  double q0[1] = {0.0}, p0[1] = {1.0}, t1, t2;
  printf("vci_set_scheme, vci_init_from_pair:\n");
  CHECK_STATUS(vci_integrator_create(&integ, model, 1e-2), VCI_OK);
  CHECK_STATUS(vci_set_scheme(integ, VCI_SCHEME_COMPOSITION, 4), VCI_ERR_ARGUMENT); /* not separable */
  CHECK_STATUS(vci_init_from_momentum(integ, 0.0, q0, p0), VCI_OK);
  CHECK_STATUS(vci_integrate(integ, 3, 1), VCI_OK);
  CHECK_STATUS(vci_get_state(integ, &t1, NULL, NULL), VCI_OK);
  CHECK_STATUS(vci_set_scheme(integ, VCI_SCHEME_LOBATTO, 2), VCI_ERR_STATE);       /* initialised */
  CHECK_STATUS(vci_get_state(integ, &t2, NULL, NULL), VCI_OK);                     /* the run stays */
  CHECK(t1 == t2);
  CHECK_STATUS(vci_integrate(integ, 1, 1), VCI_OK);
  vci_integrator_destroy(&integ);

  CHECK_STATUS(vci_integrator_create(&integ, sep, 1e-2), VCI_OK);
  CHECK_STATUS(vci_set_scheme(integ, VCI_SCHEME_COMPOSITION, 3), VCI_ERR_ARGUMENT); /* no such order */
  CHECK_STATUS(vci_set_scheme(integ, VCI_SCHEME_COMPOSITION, 4), VCI_OK);
  CHECK_STATUS(vci_init_from_pair(integ, 0.0, q0, p0), VCI_ERR_ARGUMENT);          /* starts from p0 */
  CHECK_STATUS(vci_init_from_momentum(integ, 0.0, q0, p0), VCI_OK);
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
  vci_model_destroy(&sep);
}

static void progress_lists(void) {
  vci_model model = pendulum();
  vci_integrator integ = NULL;
  double q0[1] = {0.0}, p0[1] = {1.0};
  int64_t k = -1;
  printf("vci_set_progress, vci_integrate:\n");
  CHECK_STATUS(vci_integrator_create(&integ, model, 1e-2), VCI_OK);
  CHECK_STATUS(vci_init_from_momentum(integ, 0.0, q0, p0), VCI_OK);
  CHECK_STATUS(vci_set_progress(integ, stop_at_once, 2e9, NULL), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_set_progress(integ, stop_at_once, NAN, NULL), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_set_progress(integ, stop_at_once, 0.0, NULL), VCI_OK);
  CHECK_STATUS(vci_integrate(integ, 100, 1), VCI_STOPPED);
  CHECK_STATUS(vci_get_index(integ, &k), VCI_OK);
  CHECK(k == 1); /* stopped after the step the callback was told of */
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
}

#define NM 1000
static double et0[NM], eq0[NM], ep0[NM];
static vci_model ens_model;

static void ensemble_memory(void) {
  vci_ensemble_config c = VCI_ENSEMBLE_CONFIG_INIT;
  vci_ensemble_results r = VCI_ENSEMBLE_RESULTS_INIT;
  int status[NM];
  c.h = 1e-2; c.nsteps = 1; c.start_kind = VCI_START_MOMENTUM; c.threads = 1;
  c.impact_cap = INT_MAX; /* 8 * 2^31 * 1000 bytes of impact times */
  r.status = status;
  CHECK_STATUS(vci_ensemble_run(ens_model, &c, NM, et0, eq0, ep0, &r), VCI_ERR_MEMORY);
}

static void ensemble_lists(void) {
  vci_model sep = spring();
  vci_ensemble_config c = VCI_ENSEMBLE_CONFIG_INIT;
  vci_ensemble_results r = VCI_ENSEMBLE_RESULTS_INIT;
  int status[NM];
  printf("vci_ensemble_run:\n");
  for (int k = 0; k < NM; k++) et0[k] = 0.0, eq0[k] = 0.0, ep0[k] = 1.0;
  c.h = 1e-2; c.nsteps = 1; c.start_kind = VCI_START_MOMENTUM; c.threads = 1;
  r.status = status;
  CHECK_STATUS(vci_ensemble_run(sep, &c, NM, et0, eq0, ep0, &r), VCI_ERR_ARGUMENT); /* separable */
  ens_model = pendulum();
  CHECK_STATUS(vci_ensemble_run(ens_model, &c, NM, et0, eq0, ep0, &r), VCI_OK);
  with_rlimit(ensemble_memory, "the results' allocation failure");
  vci_model_destroy(&ens_model);
  vci_model_destroy(&sep);
}

#define NBIG 46000 /* n + 1 <= 46340, n x n doubles = 17 GB */
static vci_model big_model;
static double *bq, *bv;

static void check_model_memory(void) {
  int passed = -1;
  double worst = -1.0;
  CHECK_STATUS(vci_check_model(big_model, bq, bv, 1e-2, 0.0, &passed, &worst, NULL, 0), VCI_ERR_MEMORY);
}

static void check_model_lists(void) {
  vci_callbacks cb = VCI_CALLBACKS_INIT;
  int passed = -1;
  double worst = -1.0, q[2] = {0.0, 0.0}, v[2] = {0.1, 0.2};
  vci_model small = NULL;
  printf("vci_check_model:\n");
  cb.d1_ld = free_d1; cb.d2_ld = free_d2; cb.d3_ld = free_d3;
  CHECK_STATUS(vci_model_create(&small, 2, 0, 0, &cb, NULL), VCI_OK);
  CHECK_STATUS(vci_check_model(small, q, v, 1e-2, 0.0, &passed, &worst, NULL, 0), VCI_OK);
  CHECK(passed == 1);
  v[1] = NAN;
  CHECK_STATUS(vci_check_model(small, q, v, 1e-2, 0.0, &passed, &worst, NULL, 0), VCI_ERR_ARGUMENT);
  vci_model_destroy(&small);
  CHECK_STATUS(vci_model_create(&big_model, NBIG, 0, 0, &cb, NULL), VCI_OK);
  bq = calloc(NBIG, sizeof *bq);
  bv = calloc(NBIG, sizeof *bv);
  if (bq && bv) with_rlimit(check_model_memory, "the check's allocation failure");
  free(bq);
  free(bv);
  vci_model_destroy(&big_model);
}

int main(void) {
  atexit(exit_guard);
  set_scheme_lists();
  progress_lists();
  ensemble_lists();
  check_model_lists();
  finished = 1;
  printf("%s (%d failed checks)\n", failures ? "FAILED" : "passed", failures);
  return failures ? 1 : 0;
}
