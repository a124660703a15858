/* Continuous-Lagrangian models through the C ABI (vci_model_create_lagrangian, vci_set_scheme).
 * Usage: vci_lagrangian_test run REF_FILE | bad.
 *  run: the walled pendulum (theta'' = -9.8 sin theta, walls at +-1 rad, theta(0) = 0,
 *       theta'(0) = 4, 10 s) with lobatto s = 4 from C, against REF_FILE written by vci_lagrangian_ref
 *       (the same run through the Fortran API with the scene's Fortran model, and the exact state).
 *  bad: missing required callbacks, unknown scheme, s out of range, a scheme for a discrete model,
 *       and the return contract (a negative code from dl_dq fails the step and is named).
 *  restart: that run split at step 83 through an HDF5 file (vci_restore_from_file,
 *       vci_append_output) ends bit for bit where the uninterrupted run ends. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include "vci.h"
#include "walls_lagrangian.h"

static int failures = 0;
#define CHECK(c) do { if (!(c)) { printf("  line %d: CHECK(%s) failed\n", __LINE__, #c); failures++; } } while (0)

static int fail_dl_dq_after = -1; /* dl_dq returns fail_code from this call on (-1: never) */
static int fail_code = 0;
static int dl_dq_calls = 0;

static int l_dq(int n, const double *q, const double *v, double *out, void *user) {
  (void)n; (void)v; (void)user;
  out[0] = -9.8 * sin(q[0]);
  dl_dq_calls++;
  if (fail_dl_dq_after >= 0 && dl_dq_calls > fail_dl_dq_after) return fail_code;
  return 0;
}

static int wrong_wall_grads(int n, int ng, const double *q, double *dg, void *user) {
  (void)n; (void)ng; (void)q; (void)user;
  dg[0] = 1.0; dg[1] = 1.0; /* the first wall's gradient with the wrong sign */
  return 0;
}
static int swapped_hess(int n, const double *q, const double *v, double *lqq, double *lqv, double *lvv, void *user) {
  return l_hess(n, q, v, lvv, lqv, lqq, user); /* lqq and lvv swapped */
}

static int progress_calls = 0;
static int64_t progress_last_done = -1;
static int stop_at_third(const vci_progress *info, void *user) {
  (void)user;
  progress_calls++;
  progress_last_done = info->steps_done;
  return progress_calls == 3;
}

static vci_lagrangian_callbacks pendulum_callbacks(int hessians) {
  vci_lagrangian_callbacks cb = VCI_LAGRANGIAN_CALLBACKS_INIT;
  cb.lagrangian = l_value; cb.dl_dq = l_dq; cb.dl_dv = l_dv;
  if (hessians) cb.hessians = l_hess;
  cb.gaps = walls; cb.gap_gradients = wall_grads;
  return cb;
}

/* 200 steps of h = 0.05 with lobatto s = 4, rtol 1e-15 (examples/pendulum_walls.f90's defaults). */
static int run(const vci_lagrangian_callbacks *cb, double *t, double *q, double *p, int64_t *impacts) {
  vci_model model = NULL;
  vci_integrator it = NULL;
  double q0 = 0.0, p0 = 4.0;
  int st = vci_model_create_lagrangian(&model, 1, 0, 2, cb, NULL);
  if (st == VCI_OK) st = vci_integrator_create(&it, model, 0.05);
  vci_model_destroy(&model);
  if (st == VCI_OK) st = vci_set_scheme(it, VCI_SCHEME_LOBATTO, 4);
  if (st == VCI_OK) st = vci_set_tolerances(it, 0.0, 1e-15, 30);
  if (st == VCI_OK) st = vci_init_from_momentum(it, 0.0, &q0, &p0);
  if (st == VCI_OK) st = vci_integrate(it, 200, 1);
  if (st == VCI_OK) st = vci_get_state(it, t, q, p);
  if (st == VCI_OK) st = vci_get_stats(it, NULL, impacts, NULL);
  if (st != VCI_OK) {
    char msg[512];
    vci_last_error(it, msg, sizeof msg);
    printf("  run failed: %s: %s\n", vci_status_string(st), msg);
  }
  vci_integrator_destroy(&it);
  return st;
}

static void suite_run(const char *ref_path) {
  double t_ref, q_ref, p_ref, theta_exact, omega_exact, t, q, p;
  long long imp_ref, imp_exact;
  int64_t impacts = -1;
  FILE *f = fopen(ref_path, "r");
  CHECK(f != NULL);
  if (!f) return;
  CHECK(fscanf(f, "%lf %lf %lf %lf %lf %lld %lld", &t_ref, &q_ref, &p_ref, &theta_exact, &omega_exact, &imp_ref,
               &imp_exact) == 7);
  fclose(f);
  vci_lagrangian_callbacks cb = pendulum_callbacks(1);
  CHECK(run(&cb, &t, &q, &p, &impacts) == VCI_OK);
  printf("  C: t = %.17g theta = %.17g p = %.17g impacts = %lld\n", t, q, p, (long long)impacts);
  printf("  C - Fortran: %.3e %.3e   C - exact: %.3e %.3e\n", q - q_ref, p - p_ref, q - theta_exact,
         p - omega_exact);
  /* the same scheme on the same L through the two interfaces: equal to round-off */
  CHECK(t == t_ref);
  CHECK(fabs(q - q_ref) <= 1e-12);
  CHECK(fabs(p - p_ref) <= 1e-12);
  CHECK(impacts == imp_ref && impacts == imp_exact && imp_exact == 18);
  /* and the exact solution: build/bin/pendulum_walls measures errors 2.5e-11 (theta) and 6.4e-11
   * (theta') for this order-8 run; 1e-9 leaves room for round-off, not for a lower order (h^6 at
   * h = 0.05 is 1.6e-8) */
  CHECK(fabs(q - theta_exact) <= 1e-9);
  CHECK(fabs(p - omega_exact) <= 1e-9);
  /* without the Hessian callback the blocks are differenced: the same solution to the solver's
   * tolerance, the same impacts */
  cb = pendulum_callbacks(0);
  CHECK(run(&cb, &t, &q, &p, &impacts) == VCI_OK);
  printf("  differenced Hessians - exact: %.3e %.3e\n", q - theta_exact, p - omega_exact);
  CHECK(impacts == 18);
  CHECK(fabs(q - theta_exact) <= 1e-9);
  CHECK(fabs(p - omega_exact) <= 1e-9);
}

/* a free particle, L_d = (v - q)^2 / (2 h) */
static int free_d1(int n, const double *q, const double *v, double h, double *out, void *user) {
  (void)n; (void)user; out[0] = -(v[0] - q[0]) / h; return 0;
}
static int free_d2(int n, const double *q, const double *v, double h, double *out, void *user) {
  (void)n; (void)user; out[0] = (v[0] - q[0]) / h; return 0;
}
static int free_d3(int n, const double *q, const double *v, double h, double *out, void *user) {
  (void)n; (void)user; out[0] = -0.5 * (v[0] - q[0]) * (v[0] - q[0]) / (h * h); return 0;
}

static int contains(const char *s, const char *part) { return strstr(s, part) != NULL; }

static void suite_bad(void) {
  vci_model model = NULL, discrete = NULL;
  vci_integrator it = NULL;
  char msg[512];
  double t, q, p, q0 = 0.0, p0 = 4.0;
  int64_t impacts;
  vci_lagrangian_callbacks cb = pendulum_callbacks(1);
  /* a required callback missing: a clear status and a message naming it */
  cb.dl_dv = NULL;
  CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(model == NULL);
  vci_last_error(NULL, msg, sizeof msg);
  printf("  %s\n", msg);
  CHECK(contains(msg, "dl_dv"));
  cb = pendulum_callbacks(1);
  cb.lagrangian = NULL;
  CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_ERR_ARGUMENT);
  cb = pendulum_callbacks(1);
  cb.size = 3; /* not initialised with VCI_LAGRANGIAN_CALLBACKS_INIT */
  CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_ERR_ARGUMENT);
  /* issue 31: the model checker passes the right model, catches a wrong gap gradient and swapped
     Hessian blocks, and says which */
  {
    double qc = 0.3, vc = 1.7, worst = -1.0;
    int passed = -1;
    char rep[2048];
    cb = pendulum_callbacks(1);
    CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_OK);
    CHECK(vci_check_model(model, &qc, &vc, 0.05, 0.0, &passed, &worst, rep, sizeof rep) == VCI_OK);
    printf("%s", rep);
    CHECK(passed == 1 && worst >= 0.0 && worst < 1e-6);
    CHECK(contains(rep, "dl_dq") && contains(rep, "hessians: lvv") && contains(rep, "gap_gradients"));
    CHECK(vci_check_model(model, &qc, &vc, 0.0, 0.0, &passed, &worst, NULL, 0) == VCI_ERR_ARGUMENT);
    CHECK(vci_check_model(model, NULL, &vc, 0.05, 0.0, &passed, &worst, NULL, 0) == VCI_ERR_ARGUMENT);
    vci_model_destroy(&model);
    cb.gap_gradients = wrong_wall_grads;
    CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_OK);
    CHECK(vci_check_model(model, &qc, &vc, 0.05, 0.0, &passed, &worst, rep, sizeof rep) == VCI_OK);
    CHECK(passed == 0 && worst > 0.1 && contains(rep, "MISMATCH"));
    vci_model_destroy(&model);
    cb = pendulum_callbacks(1);
    cb.hessians = swapped_hess;
    CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_OK);
    CHECK(vci_check_model(model, &qc, &vc, 0.05, 0.0, &passed, &worst, rep, sizeof rep) == VCI_OK);
    printf("%s", rep);
    CHECK(passed == 0 && worst > 0.1);
    vci_model_destroy(&model);
  }
  cb = pendulum_callbacks(1); /* issue 31: walls given but ngaps = 0 (was: no impacts, status 0) */
  CHECK(vci_model_create_lagrangian(&model, 1, 0, 0, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(model == NULL);
  vci_last_error(NULL, msg, sizeof msg);
  CHECK(contains(msg, "ngaps = 0"));
  /* a size between two members is no header's struct: every such size is refused (as by
   * vci_model_create), not rounded down to the members it covers */
  {
    size_t sz, whole = 0;
    for (sz = offsetof(vci_lagrangian_callbacks, gaps) + 1; sz < sizeof(vci_lagrangian_callbacks); ++sz) {
      cb = pendulum_callbacks(1);
      cb.size = sz;
      if ((sz - sizeof(size_t)) % sizeof(void (*)(void)) == 0) {
        ++whole; /* an older header's size: accepted */
        CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_OK);
        vci_model_destroy(&model);
        continue;
      }
      CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_ERR_ARGUMENT);
      CHECK(model == NULL);
      vci_last_error(NULL, msg, sizeof msg);
      CHECK(contains(msg, "VCI_LAGRANGIAN_CALLBACKS_INIT"));
    }
    CHECK(whole == 4); /* gap_gradients, energy, hessians_band, hessians_sparse: the whole sizes after gaps */
  }
  /* SIZE_MAX is printed as C prints a size_t, not as -1 */
  cb = pendulum_callbacks(1);
  cb.size = SIZE_MAX;
  CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_ERR_ARGUMENT);
  vci_last_error(NULL, msg, sizeof msg);
  printf("  %s\n", msg);
  {
    char expect[64];
    snprintf(expect, sizeof expect, "cb->size = %zu ", (size_t)SIZE_MAX);
    CHECK(contains(msg, expect));
    CHECK(!contains(msg, "= -1"));
  }
  cb = pendulum_callbacks(1);
  cb.gaps = NULL; /* ngaps > 0 needs gaps */
  CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(vci_model_create_lagrangian(NULL, 1, 0, 2, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, NULL, NULL) == VCI_ERR_ARGUMENT);
  /* every message names the entry point that was called, not vci_model_create */
  cb = pendulum_callbacks(1);
  CHECK(vci_model_create_lagrangian(&model, 0, 0, 2, &cb, NULL) == VCI_ERR_ARGUMENT);
  vci_last_error(NULL, msg, sizeof msg);
  printf("  %s\n", msg);
  CHECK(strncmp(msg, "vci_model_create_lagrangian: sizes n = 0", 40) == 0);

  cb = pendulum_callbacks(1);
  CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_OK);
  CHECK(vci_integrator_create(&it, model, 0.05) == VCI_OK);
  /* unknown scheme, stages out of range: refused, the integrator keeps its scheme and works */
  CHECK(vci_set_scheme(it, 7, 1) == VCI_ERR_ARGUMENT);
  vci_last_error(it, msg, sizeof msg);
  printf("  %s\n", msg);
  CHECK(contains(msg, "unknown scheme"));
  CHECK(vci_set_scheme(it, VCI_SCHEME_DISCRETE, 1) == VCI_ERR_ARGUMENT);
  /* the explicit compositions need a separable Fortran model (issue 32): refused with the reason */
  CHECK(vci_set_scheme(it, VCI_SCHEME_COMPOSITION, 4) == VCI_ERR_ARGUMENT);
  vci_last_error(it, msg, sizeof msg);
  CHECK(contains(msg, "separable"));
  CHECK(vci_set_scheme(it, VCI_SCHEME_LOBATTO, 0) == VCI_ERR_ARGUMENT);
  CHECK(vci_set_scheme(it, VCI_SCHEME_LOBATTO, VCI_LOBATTO_MAX_STAGES + 1) == VCI_ERR_ARGUMENT);
  vci_last_error(it, msg, sizeof msg);
  printf("  %s\n", msg);
  CHECK(contains(msg, "stages"));
  CHECK(vci_set_scheme(it, VCI_SCHEME_LOBATTO, VCI_LOBATTO_MAX_STAGES) == VCI_OK);
  CHECK(vci_set_scheme(it, VCI_SCHEME_LEFT, 0) == VCI_OK); /* stages ignored */
  CHECK(vci_set_scheme(it, VCI_SCHEME_MIDPOINT, 0) == VCI_OK);
  CHECK(vci_init_from_momentum(it, 0.0, &q0, &p0) == VCI_OK);
  CHECK(vci_integrate(it, 10, 1) == VCI_OK);
  /* issue 31: set_scheme after initialisation is refused (was OK and a silent reset of the state);
     the run goes on from where it was */
  CHECK(vci_get_state(it, &t, &q, &p) == VCI_OK);
  CHECK(vci_set_scheme(it, VCI_SCHEME_LEFT, 0) == VCI_ERR_STATE);
  vci_last_error(it, msg, sizeof msg);
  CHECK(contains(msg, "already initialised"));
  CHECK(vci_integrate(it, 10, 1) == VCI_OK);
  {
    double t2, q2, p2;
    CHECK(vci_get_state(it, &t2, &q2, &p2) == VCI_OK && fabs(t2 - (t + 10 * 0.05)) < 1e-12);
  }
  /* issue 31: a progress callback reports after each step (interval 0) and stops the run cleanly */
  CHECK(vci_set_progress(it, stop_at_third, -1.0, NULL) == VCI_ERR_ARGUMENT);
  CHECK(vci_set_progress(it, stop_at_third, 0.0, NULL) == VCI_OK);
  CHECK(vci_integrate(it, 100, 1) == VCI_STOPPED);
  CHECK(progress_calls == 3 && progress_last_done == 3);
  vci_last_error(it, msg, sizeof msg);
  CHECK(contains(msg, "stopped by the progress report after 3 of 100 steps"));
  CHECK(strcmp(vci_status_string(VCI_STOPPED), "stopped by the caller") == 0);
  CHECK(vci_set_progress(it, NULL, 0.0, NULL) == VCI_OK);
  CHECK(vci_integrate(it, 10, 1) == VCI_OK && progress_calls == 3);
  CHECK(vci_set_scheme(NULL, VCI_SCHEME_MIDPOINT, 1) == VCI_ERR_ARGUMENT);
  vci_integrator_destroy(&it);

  /* a discrete model has no schemes to choose */
  {
    vci_callbacks dcb = VCI_CALLBACKS_INIT;
    dcb.d1_ld = free_d1; dcb.d2_ld = free_d2; dcb.d3_ld = free_d3;
    CHECK(vci_model_create(&discrete, 1, 0, 0, &dcb, NULL) == VCI_OK);
    CHECK(vci_integrator_create(&it, discrete, 0.05) == VCI_OK);
    CHECK(vci_set_scheme(it, VCI_SCHEME_MIDPOINT, 1) == VCI_ERR_ARGUMENT);
    vci_integrator_destroy(&it);
    vci_model_destroy(&discrete);
  }

  /* the contract: dl_dq returning a negative code fails the step at once, named with its code;
   * the state stays at the last accepted step */
  fail_dl_dq_after = 2000; fail_code = -3; dl_dq_calls = 0;
  CHECK(run(&cb, &t, &q, &p, &impacts) == VCI_ERR_CALLBACK);
  {
    vci_integrator it2 = NULL;
    CHECK(vci_integrator_create(&it2, model, 0.05) == VCI_OK);
    CHECK(vci_set_scheme(it2, VCI_SCHEME_LOBATTO, 4) == VCI_OK);
    CHECK(vci_init_from_momentum(it2, 0.0, &q0, &p0) == VCI_OK);
    dl_dq_calls = 0;
    CHECK(vci_integrate(it2, 200, 1) == VCI_ERR_CALLBACK);
    vci_last_error(it2, msg, sizeof msg);
    printf("  %s\n", msg);
    CHECK(contains(msg, "dl_dq returned -3"));
    CHECK(contains(msg, "unrecoverable"));
    vci_integrator_destroy(&it2);
  }
  fail_dl_dq_after = -1;
  vci_model_destroy(&model);
}

/* The run of run() in two halves: 83 steps into a file, then a new integrator restored from it
 * that appends the other 117. Lobatto's Newton starts from the checkpoint's velocity: a restart
 * that lost it ends ~1e-13 away, which memcmp sees. */
static void suite_restart(void) {
#ifdef VCI_TEST_HDF5
  vci_lagrangian_callbacks cb = pendulum_callbacks(1);
  vci_model model = NULL;
  vci_integrator it[2] = {NULL, NULL};
  const char *path = "capi_lagrangian_restart.h5";
  double q0 = 0.0, p0 = 4.0, t_a = 0, q_a = 0, p_a = 0, t_b = 1, q_b = 1, p_b = 1;
  int64_t impacts = 0, k = 0;
  int i;
  CHECK(run(&cb, &t_a, &q_a, &p_a, &impacts) == VCI_OK);
  remove(path);
  CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_OK);
  for (i = 0; i < 2; ++i) {
    CHECK(vci_integrator_create(&it[i], model, 0.05) == VCI_OK);
    CHECK(vci_set_scheme(it[i], VCI_SCHEME_LOBATTO, 4) == VCI_OK);
    CHECK(vci_set_tolerances(it[i], 0.0, 1e-15, 30) == VCI_OK);
  }
  CHECK(vci_init_from_momentum(it[0], 0.0, &q0, &p0) == VCI_OK);
  CHECK(vci_open_output(it[0], path) == VCI_OK);
  CHECK(vci_integrate(it[0], 83, 1) == VCI_OK);
  CHECK(vci_close_output(it[0]) == VCI_OK);
  CHECK(vci_restore_from_file(it[1], path) == VCI_OK);
  CHECK(vci_get_index(it[1], &k) == VCI_OK && k == 83);
  CHECK(vci_append_output(it[1], path) == VCI_OK);
  CHECK(vci_integrate(it[1], 117, 1) == VCI_OK);
  CHECK(vci_get_state(it[1], &t_b, &q_b, &p_b) == VCI_OK);
  CHECK(vci_close_output(it[1]) == VCI_OK);
  printf("  whole run q = %.17g, split run q = %.17g\n", q_a, q_b);
  CHECK(memcmp(&t_a, &t_b, sizeof t_a) == 0);
  CHECK(memcmp(&q_a, &q_b, sizeof q_a) == 0);
  CHECK(memcmp(&p_a, &p_b, sizeof p_a) == 0);
  for (i = 0; i < 2; ++i) vci_integrator_destroy(&it[i]);
  vci_model_destroy(&model);
  remove(path);
#else
  printf("  built without HDF5: nothing to restart from\n");
#endif
}

int main(int argc, char **argv) {
  if (argc >= 3 && strcmp(argv[1], "run") == 0) {
    suite_run(argv[2]);
  } else if (argc >= 2 && strcmp(argv[1], "bad") == 0) {
    suite_bad();
  } else if (argc >= 2 && strcmp(argv[1], "restart") == 0) {
    suite_restart();
  } else {
    printf("usage: vci_lagrangian_test run REF_FILE | bad | restart\n");
    return 2;
  }
  printf("%s: %d failure(s)\n", argv[1], failures);
  return failures == 0 ? 0 : 1;
}
