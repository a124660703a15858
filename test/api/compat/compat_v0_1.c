/* A client of vci 0.1 compiled against the 0.1.0 header (vci.h next to this file: nine callback
 * pointers and no size field; long counts), linked to this library: programs built against the
 * older header keep working. The symbol vci_model_create keeps the 0.1 layout; newer headers map
 * vci_model_create to vci_model_create_v2. Checks the ellipse's two impacts against the Fortran
 * API's times (as test/api/api_test.c does), the counters and the error path. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "vci.h" /* test/api/compat/vci.h, the 0.1.0 header */

#if VCI_VERSION_NUMBER != 100
#error "compat_v0_1.c must be compiled against the 0.1.0 header"
#endif

typedef struct { double mass, grav, a, b; } params;
static double inertia(const params *e) { return e->mass * (e->a * e->a + e->b * e->b) / 4.0; }

static int d1(int n, const double *q, const double *v, double h, double *out, void *user) {
  const params *e = (const params *)user;
  (void)n;
  out[0] = -inertia(e) * (v[0] - q[0]) / h;
  out[1] = -e->mass * (v[1] - q[1]) / h;
  out[2] = -e->mass * (v[2] - q[2]) / h - 0.5 * h * e->mass * e->grav;
  return 0;
}
static int d2(int n, const double *q, const double *v, double h, double *out, void *user) {
  const params *e = (const params *)user;
  (void)n;
  out[0] = inertia(e) * (v[0] - q[0]) / h;
  out[1] = e->mass * (v[1] - q[1]) / h;
  out[2] = e->mass * (v[2] - q[2]) / h - 0.5 * h * e->mass * e->grav;
  return 0;
}
static int d3(int n, const double *q, const double *v, double h, double *out, void *user) {
  const params *e = (const params *)user;
  double a = v[0] - q[0], b = v[1] - q[1], c = v[2] - q[2];
  (void)n;
  out[0] = -0.5 * (inertia(e) * a * a + e->mass * (b * b + c * c)) / (h * h) - 0.5 * e->mass * e->grav * (q[2] + v[2]);
  return 0;
}
static int gaps(int n, int ng, const double *q, double *g, void *user) {
  const params *e = (const params *)user;
  double s = sin(q[0]), c = cos(q[0]);
  (void)n; (void)ng;
  g[0] = q[2] - sqrt(e->a * e->a * s * s + e->b * e->b * c * c);
  return 0;
}
static int energy(int n, const double *q, const double *p, double *en, void *user) {
  const params *e = (const params *)user;
  (void)n;
  en[0] = 0.5 * p[0] * p[0] / inertia(e) + 0.5 * (p[1] * p[1] + p[2] * p[2]) / e->mass + e->mass * e->grav * q[2];
  return 0;
}
static double first_impact = -1.0;
static int on_impact(double t, double alpha, int gap, const double *q, double impulse, void *user) {
  (void)alpha; (void)gap; (void)q; (void)impulse; (void)user;
  if (first_impact < 0.0) first_impact = t;
  return 0;
}

int main(void) {
  static const double expected_first = 7.50564104356950312e-01; /* as in api_test.c */
  params par = {1.0, 9.8, 1.0, 0.5};
  vci_callbacks cb = {0};
  vci_model model = NULL;
  vci_integrator integ = NULL;
  const double h = 1e-2, pi = acos(-1.0);
  double q0[3], q1[3], qd[3] = {-3.0, 2.0, 0.0}, t;
  long k = -1, steps = -1, impacts = -1, iters = -1;
  int i, s, failures = 0;
  char msg[256];
  q0[0] = pi / 2.0; q0[1] = 0.0; q0[2] = 3.5;
  for (i = 0; i < 3; ++i) {
    q1[i] = q0[i] + 0.5 * h * qd[i];
    q0[i] = q0[i] - 0.5 * h * qd[i];
  }
  cb.d1_ld = d1; cb.d2_ld = d2; cb.d3_ld = d3; cb.gaps = gaps; cb.energy = energy;
  s = vci_model_create(&model, 3, 0, 1, &cb, &par);
  if (!s) s = vci_integrator_create(&integ, model, h);
  if (!s) s = vci_set_tolerances(integ, 0.0, 1e-12, 30);
  if (!s) s = vci_set_impact_callback(integ, on_impact, NULL);
  if (!s) s = vci_set_impact_energy(integ, VCI_IMPACT_HAMILTONIAN); /* the ninth member is read */
  if (!s) s = vci_set_impact_energy(integ, VCI_IMPACT_DISCRETE);
  if (!s) s = vci_init_from_pair(integ, -0.5 * h, q0, q1);
  if (!s) s = vci_integrate(integ, 200L, 1);
  if (!s) s = vci_get_state(integ, &t, NULL, NULL);
  if (!s) s = vci_get_index(integ, &k);
  if (!s) s = vci_get_stats(integ, &steps, &impacts, &iters);
  vci_last_error(integ, msg, sizeof msg);
  printf("0.1 client on library %d: status %d (%s) t = %.15f k = %ld steps %ld impacts %ld first impact %.15f\n",
         vci_version(), s, msg, t, k, steps, impacts, first_impact);
  if (s != VCI_OK || k != 201 || steps != 200 || impacts != 2 || !(fabs(t - 2.005) <= 1e-13) ||
      !(fabs(first_impact - expected_first) <= 1e-12)) {
    printf("FAIL: run\n");
    ++failures;
  }
  /* errors still come back as statuses with messages */
  if (vci_step(integ, 3) != VCI_ERR_ARGUMENT) ++failures, printf("FAIL: bad direction\n");
  vci_last_error(integ, msg, sizeof msg);
  if (!strstr(msg, "direction 3")) ++failures, printf("FAIL: message \"%s\"\n", msg);
  cb.gaps = NULL;
  if (vci_model_create(&model, 3, 0, 1, &cb, &par) != VCI_ERR_ARGUMENT || model != NULL) ++failures, printf("FAIL: gaps\n");
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
  printf("%s\n", failures ? "FAILED" : "passed");
  return failures ? 1 : 0;
}
