/* Downstream check: the bouncing ellipse at h = 1e-2 through the installed vci.h; exit 1 unless
 * there are 2 impacts in 2 s and the first is at the Fortran API's time to 1e-12. */
#include <math.h>
#include <stdio.h>
#include "vci.h"

static const double M = 1.0, G = 9.8, A = 1.0, B = 0.5;
#define I3 (M * (A * A + B * B) / 4.0)

static int d1(int n, const double *q, const double *v, double h, double *out, void *u) {
  (void)n; (void)u;
  out[0] = -I3 * (v[0] - q[0]) / h;
  out[1] = -M * (v[1] - q[1]) / h;
  out[2] = -M * (v[2] - q[2]) / h - 0.5 * h * M * G;
  return 0;
}
static int d2(int n, const double *q, const double *v, double h, double *out, void *u) {
  (void)n; (void)u;
  out[0] = I3 * (v[0] - q[0]) / h;
  out[1] = M * (v[1] - q[1]) / h;
  out[2] = M * (v[2] - q[2]) / h - 0.5 * h * M * G;
  return 0;
}
static int d3(int n, const double *q, const double *v, double h, double *out, void *u) {
  double a = v[0] - q[0], b = v[1] - q[1], c = v[2] - q[2];
  (void)n; (void)u;
  out[0] = -0.5 * (I3 * a * a + M * (b * b + c * c)) / (h * h) - 0.5 * M * G * (q[2] + v[2]);
  return 0;
}
static int gaps(int n, int ng, const double *q, double *g, void *u) {
  (void)n; (void)ng; (void)u;
  g[0] = q[2] - sqrt(A * A * sin(q[0]) * sin(q[0]) + B * B * cos(q[0]) * cos(q[0]));
  return 0;
}
static int on_impact(double t, double alpha, int j, const double *q, double impulse, void *u) {
  double *first = (double *)u;
  (void)alpha; (void)j; (void)q; (void)impulse;
  if (*first != *first) *first = t;
  return 0;
}

int main(void) {
  const double h = 1e-2, t_ref = 7.50564104356950312e-01, pi = acos(-1.0);
  double q0[3] = {pi / 2 + 0.5 * h * 3.0, -0.5 * h * 2.0, 3.5}, q1[3] = {pi / 2 - 0.5 * h * 3.0, 0.5 * h * 2.0, 3.5};
  double first = NAN, t;
  int64_t impacts = -1;
  vci_callbacks cb = VCI_CALLBACKS_INIT;
  vci_model model = NULL;
  vci_integrator integ = NULL;
  int s;
  char msg[256] = "";
  cb.d1_ld = d1; cb.d2_ld = d2; cb.d3_ld = d3; cb.gaps = gaps;
  s = vci_model_create(&model, 3, 0, 1, &cb, NULL);
  if (!s) s = vci_integrator_create(&integ, model, h);
  if (!s) s = vci_set_tolerances(integ, 0.0, 1e-12, 30);
  if (!s) s = vci_set_impact_callback(integ, on_impact, &first);
  if (!s) s = vci_init_from_pair(integ, -0.5 * h, q0, q1);
  if (!s) s = vci_integrate(integ, 200, 1);
  if (!s) s = vci_get_stats(integ, NULL, &impacts, NULL);
  if (!s) s = vci_get_state(integ, &t, NULL, NULL);
  vci_last_error(integ, msg, sizeof msg);
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
  printf("vci %d: status %d %s, %lld impacts, first at t = %.15f (expected %.15f, off by %.1e)\n", vci_version(), s,
         msg, (long long)impacts, first, t_ref, fabs(first - t_ref));
  if (s != VCI_OK || impacts != 2 || !(fabs(first - t_ref) <= 1e-12) || !(fabs(t - 2.005) <= 1e-13) ||
      vci_version() != VCI_VERSION_NUMBER || model != NULL || integ != NULL) {
    printf("FAILED\n");
    return 1;
  }
  printf("passed\n");
  return 0;
}
