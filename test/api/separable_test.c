/* Separable models through the C ABI (vci_model_create_separable, VCI_SCHEME_COMPOSITION).
 * Usage: vci_separable_test run REF_FILE | bad.
 *  run: the walled pendulum (V = -9.8 cos theta, M = 1, walls at +-1 rad, theta(0) = 0,
 *       theta'(0) = 4, 10 s, 18 impacts) with the order-6 composition from C at h = 0.1, 0.05,
 *       0.025, against REF_FILE written by vci_separable_ref (the same runs through the Fortran
 *       API with the Fortran separable scene, and the exact state): the same bits, and order 6
 *       against the exact state; M given densely gives the same bits; lobatto s = 4 runs the same
 *       model to its own accuracy; the model checker passes it.
 *  bad: every refusal of vci_model_create_separable (m > 0 among them), composition on a
 *       non-separable C model, and a failing potential_gradient named in the message. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include "vci.h"

static int failures = 0;
#define CHECK(c) do { if (!(c)) { printf("  line %d: CHECK(%s) failed\n", __LINE__, #c); failures++; } } while (0)

static int fail_grad_above = 0; /* potential_gradient returns -3 when theta > 0.5 (0: never) */

static int pot(int n, const double *q, double *out, void *user) {
  (void)n; (void)user;
  out[0] = -9.8 * cos(q[0]);
  return 0;
}
static int pot_grad(int n, const double *q, double *out, void *user) {
  (void)n; (void)user;
  out[0] = 9.8 * sin(q[0]);
  if (fail_grad_above && q[0] > 0.5) return -3;
  return 0;
}
static int pot_hess(int n, const double *q, double *out, void *user) {
  (void)n; (void)user;
  out[0] = 9.8 * cos(q[0]);
  return 0;
}
static int walls(int n, int ng, const double *q, double *g, void *user) {
  (void)n; (void)ng; (void)user;
  g[0] = 1.0 - q[0]; g[1] = q[0] + 1.0;
  return 0;
}
static int wall_grads(int n, int ng, const double *q, double *dg, void *user) {
  (void)n; (void)ng; (void)q; (void)user;
  dg[0] = -1.0; dg[1] = 1.0;
  return 0;
}

/* the same pendulum as a general continuous L (not separable to the library) */
static int l_value(int n, const double *q, const double *v, double *l, void *user) {
  (void)n; (void)user;
  l[0] = 0.5 * v[0] * v[0] + 9.8 * cos(q[0]);
  return 0;
}
static int l_dq(int n, const double *q, const double *v, double *out, void *user) {
  (void)n; (void)v; (void)user;
  out[0] = -9.8 * sin(q[0]);
  return 0;
}
static int l_dv(int n, const double *q, const double *v, double *out, void *user) {
  (void)n; (void)q; (void)user;
  out[0] = v[0];
  return 0;
}

static vci_separable_callbacks pendulum_callbacks(void) {
  vci_separable_callbacks cb = VCI_SEPARABLE_CALLBACKS_INIT;
  cb.potential = pot; cb.potential_gradient = pot_grad; cb.potential_hessian = pot_hess;
  cb.gaps = walls; cb.gap_gradients = wall_grads;
  return cb;
}

/* 10 s of the walled pendulum with `scheme` (stages) at step h from (0, 4). */
static int run(int mass_kind, int scheme, int stages, double h, double *q, double *p, int64_t *impacts) {
  vci_model model = NULL;
  vci_integrator it = NULL;
  vci_separable_callbacks cb = pendulum_callbacks();
  double q0 = 0.0, p0 = 4.0, mass = 1.0, t;
  int st = vci_model_create_separable(&model, 1, 0, 2, mass_kind, &mass, &cb, NULL);
  if (st == VCI_OK) st = vci_integrator_create(&it, model, h);
  vci_model_destroy(&model);
  if (st == VCI_OK) st = vci_set_scheme(it, scheme, stages);
  if (st == VCI_OK && scheme == VCI_SCHEME_LOBATTO) st = vci_set_tolerances(it, 0.0, 1e-15, 30);
  if (st == VCI_OK) st = vci_init_from_momentum(it, 0.0, &q0, &p0);
  if (st == VCI_OK) st = vci_integrate(it, (int64_t)lround(10.0 / h), 1);
  if (st == VCI_OK) st = vci_get_state(it, &t, q, p);
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
  double h_ref[3], q_ref[3], p_ref[3], theta, omega, q, p, err[3];
  long long imp_ref[3], imp_exact;
  int64_t impacts = -1;
  int j;
  FILE *f = fopen(ref_path, "r");
  CHECK(f != NULL);
  if (!f) return;
  for (j = 0; j < 3; j++) CHECK(fscanf(f, "%lf %lf %lf %lld", &h_ref[j], &q_ref[j], &p_ref[j], &imp_ref[j]) == 4);
  CHECK(fscanf(f, "%lf %lf %lld", &theta, &omega, &imp_exact) == 3);
  fclose(f);
  for (j = 0; j < 3; j++) {
    CHECK(run(VCI_MASS_DIAGONAL, VCI_SCHEME_COMPOSITION, 6, h_ref[j], &q, &p, &impacts) == VCI_OK);
    printf("  h = %.3f: C - Fortran %.3e %.3e   C - exact %.3e %.3e  impacts %lld\n", h_ref[j], q - q_ref[j],
           p - p_ref[j], q - theta, p - omega, (long long)impacts);
    /* the same map on the same callbacks' values through the two interfaces: the same bits */
    CHECK(q == q_ref[j] && p == p_ref[j]);
    CHECK(impacts == imp_ref[j] && impacts == imp_exact && imp_exact == 18);
    err[j] = fmax(fabs(q - theta), fabs(p - omega));
    /* M given densely (1 x 1): M^-1 is 1 exactly, the same bits */
    double qd, pd;
    CHECK(run(VCI_MASS_DENSE, VCI_SCHEME_COMPOSITION, 6, h_ref[j], &qd, &pd, &impacts) == VCI_OK);
    CHECK(qd == q && pd == p);
  }
  /* order 6 against the exact state over the two octaves h = 0.1 .. 0.025 (errors 1.2e-4 ..
   * 2.2e-8, far above the round-off floor ~3e-14): 6 +- 0.5. One octave alone scatters (7.15 and
   * 5.28 measured: where each of the 18 impacts falls in its step changes the error constant) */
  {
    double slope = log(err[0] / err[2]) / log(h_ref[0] / h_ref[2]);
    printf("  observed order over h = %.3f .. %.3f: %.2f\n", h_ref[0], h_ref[2], slope);
    CHECK(fabs(slope - 6.0) <= 0.5);
  }
  /* the same C model through an implicit scheme (lobatto s = 4, order 8, Newton with the derived
   * L): at h = 0.05 its error against the exact state is ~3e-11 (capi_lagrangian measures
   * 2.5e-11 / 6.4e-11 for this run with a hand-written L); 1e-9 leaves room for round-off only */
  CHECK(run(VCI_MASS_DIAGONAL, VCI_SCHEME_LOBATTO, 4, 0.05, &q, &p, &impacts) == VCI_OK);
  printf("  lobatto 4, h = 0.05: C - exact %.3e %.3e  impacts %lld\n", q - theta, p - omega, (long long)impacts);
  CHECK(impacts == 18);
  CHECK(fabs(q - theta) <= 1e-9 && fabs(p - omega) <= 1e-9);
  /* the model checker on the separable model (dl_dq, dl_dv against L, Hessians, H, gap gradients) */
  {
    vci_model model = NULL;
    vci_separable_callbacks cb = pendulum_callbacks();
    double mass = 1.0, qc = 0.3, vc = 1.7, worst = -1.0;
    int passed = 0;
    CHECK(vci_model_create_separable(&model, 1, 0, 2, VCI_MASS_DIAGONAL, &mass, &cb, NULL) == VCI_OK);
    CHECK(vci_check_model(model, &qc, &vc, 0.05, 0.0, &passed, &worst, NULL, 0) == VCI_OK);
    printf("  model checker: passed %d, worst %.2e\n", passed, worst);
    CHECK(passed == 1);
    vci_model_destroy(&model);
  }
}

/* vci_last_error(NULL, ...) contains `what` */
static int thread_message_has(const char *what) {
  char msg[512];
  vci_last_error(NULL, msg, sizeof msg);
  if (!strstr(msg, what)) printf("  message without '%s': %s\n", what, msg);
  return strstr(msg, what) != NULL;
}

static void suite_bad(void) {
  vci_model model = NULL;
  vci_integrator it = NULL;
  vci_separable_callbacks cb = pendulum_callbacks();
  double one = 1.0, neg[2] = {1.0, -1.0}, nonsym[4] = {2.0, 0.5, 0.0, 2.0}, indef[4] = {1.0, 2.0, 2.0, 1.0};
  double q0 = 0.0, p0 = 4.0;
  /* constraints are not part of the kind: a clear status and message */
  CHECK(vci_model_create_separable(&model, 1, 1, 2, VCI_MASS_DIAGONAL, &one, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(model == NULL && thread_message_has("nonholonomic"));
  cb.potential_gradient = NULL;
  CHECK(vci_model_create_separable(&model, 1, 0, 2, VCI_MASS_DIAGONAL, &one, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(thread_message_has("potential_gradient"));
  cb = pendulum_callbacks(); cb.gap_gradients = NULL;
  CHECK(vci_model_create_separable(&model, 1, 0, 2, VCI_MASS_DIAGONAL, &one, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(thread_message_has("gap_gradients"));
  cb = pendulum_callbacks(); /* walls given but ngaps = 0: refused as for the other model kinds */
  CHECK(vci_model_create_separable(&model, 1, 0, 0, VCI_MASS_DIAGONAL, &one, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(model == NULL && thread_message_has("ngaps = 0"));
  cb = pendulum_callbacks();
  CHECK(vci_model_create_separable(&model, 1, 0, 2, 2, &one, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(thread_message_has("mass_kind"));
  CHECK(vci_model_create_separable(&model, 1, 0, 2, VCI_MASS_DIAGONAL, NULL, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(vci_model_create_separable(&model, 2, 0, 2, VCI_MASS_DIAGONAL, neg, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(thread_message_has("positive"));
  CHECK(vci_model_create_separable(&model, 2, 0, 2, VCI_MASS_DENSE, nonsym, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(thread_message_has("symmetric positive definite"));
  CHECK(vci_model_create_separable(&model, 2, 0, 2, VCI_MASS_DENSE, indef, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(vci_model_create_separable(&model, 0, 0, 2, VCI_MASS_DIAGONAL, &one, &cb, NULL) == VCI_ERR_ARGUMENT);
  cb.size = sizeof cb - 1;   /* not a whole number of members */
  CHECK(vci_model_create_separable(&model, 1, 0, 2, VCI_MASS_DIAGONAL, &one, &cb, NULL) == VCI_ERR_ARGUMENT);
  CHECK(thread_message_has("VCI_SEPARABLE_CALLBACKS_INIT"));
  CHECK(model == NULL);
  /* composition on a continuous model that is not separable: refused, and says why */
  {
    vci_lagrangian_callbacks lcb = VCI_LAGRANGIAN_CALLBACKS_INIT;
    char msg[512];
    lcb.lagrangian = l_value; lcb.dl_dq = l_dq; lcb.dl_dv = l_dv;
    CHECK(vci_model_create_lagrangian(&model, 1, 0, 0, &lcb, NULL) == VCI_OK);
    CHECK(vci_integrator_create(&it, model, 0.05) == VCI_OK);
    vci_model_destroy(&model);
    CHECK(vci_set_scheme(it, VCI_SCHEME_COMPOSITION, 4) == VCI_ERR_ARGUMENT);
    vci_last_error(it, msg, sizeof msg);
    CHECK(strstr(msg, "separable") != NULL);
    vci_integrator_destroy(&it);
  }
  /* a failing potential_gradient (code -3 once theta > 0.5) ends the step with VCI_ERR_CALLBACK
   * and names the callback and its code; the state stays the last accepted one */
  cb = pendulum_callbacks();
  CHECK(vci_model_create_separable(&model, 1, 0, 2, VCI_MASS_DIAGONAL, &one, &cb, NULL) == VCI_OK);
  CHECK(vci_integrator_create(&it, model, 0.05) == VCI_OK);
  vci_model_destroy(&model);
  CHECK(vci_set_scheme(it, VCI_SCHEME_COMPOSITION, 7) == VCI_ERR_ARGUMENT);
  CHECK(vci_set_scheme(it, VCI_SCHEME_COMPOSITION, 4) == VCI_OK);
  CHECK(vci_init_from_momentum(it, 0.0, &q0, &p0) == VCI_OK);
  fail_grad_above = 1;
  int st = vci_integrate(it, 100, 1);
  fail_grad_above = 0;
  CHECK(st == VCI_ERR_CALLBACK);
  {
    char msg[512];
    double t, q, p;
    vci_last_error(it, msg, sizeof msg);
    printf("  failing gradient: %s\n", msg);
    CHECK(strstr(msg, "potential_gradient") != NULL && strstr(msg, "-3") != NULL);
    CHECK(vci_get_state(it, &t, &q, &p) == VCI_OK);
    CHECK(q <= 0.5 && t > 0.0);
  }
  vci_integrator_destroy(&it);
}

int main(int argc, char **argv) {
  if (argc >= 3 && strcmp(argv[1], "run") == 0) {
    suite_run(argv[2]);
  } else if (argc >= 2 && strcmp(argv[1], "bad") == 0) {
    suite_bad();
  } else {
    printf("usage: vci_separable_test run REF_FILE | bad\n");
    return 2;
  }
  printf("%s: %d failure(s)\n", argv[1], failures);
  return failures ? 1 : 0;
}
