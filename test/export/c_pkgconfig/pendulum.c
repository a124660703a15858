/* Downstream check built with plain `cc pendulum.c $(pkg-config --cflags --libs vci)`: the
 * nonholonomic pendulum at h = 1e-3 to t = 5 through the installed vci.h; exit 1 unless there are
 * 3 impacts at the Fortran example's times (build/bin/pendulum) to 5e-11 and the discrete
 * constraint holds at the last step. */
#include <math.h>
#include <stdio.h>
#include "vci.h"

static const double M = 1.0, G = 9.8, L = 2.0, R = 1.5;

static double f(double th) { return acos(-1.0) + cos(th) * cos(th); }
static int d1(int n, const double *q, const double *v, double h, double *o, void *u) {
  double s = sin(q[0]), c = cos(q[0]), a = v[0] - q[0], b = v[1] - q[1];
  (void)n; (void)u;
  o[0] = -M * L * L * a / h + M * L * L * b * b * s * c / h + h * M * G * L * s;
  o[1] = -M * L * L * b * s * s / h;
  return 0;
}
static int d2(int n, const double *q, const double *v, double h, double *o, void *u) {
  double s = sin(q[0]);
  (void)n; (void)u;
  o[0] = M * L * L * (v[0] - q[0]) / h;
  o[1] = M * L * L * (v[1] - q[1]) * s * s / h;
  return 0;
}
static int d3(int n, const double *q, const double *v, double h, double *o, void *u) {
  double s = sin(q[0]), a = v[0] - q[0], b = v[1] - q[1];
  (void)n; (void)u;
  o[0] = -0.5 * M * L * L * (a * a + b * b * s * s) / (h * h) - M * G * L * cos(q[0]);
  return 0;
}
static int forms(int n, int m, const double *q, double *w, void *u) {
  (void)n; (void)m; (void)u;
  w[0] = f(q[0]); w[1] = -1.0;
  return 0;
}
static int dcon(int n, int m, const double *a, const double *b, double h, double *o, void *u) {
  (void)n; (void)m; (void)u;
  o[0] = (f(a[0]) * (b[0] - a[0]) - (b[1] - a[1])) / h;
  return 0;
}
static int gaps(int n, int ng, const double *q, double *g, void *u) {
  (void)n; (void)ng; (void)u;
  g[0] = R * R - L * L * sin(q[0]) * sin(q[0]);
  return 0;
}
static int on_impact(double t, double alpha, int j, const double *q, double impulse, void *u) {
  double *times = (double *)u;
  int k = (int)times[0];
  (void)alpha; (void)j; (void)q; (void)impulse;
  if (k < 8) times[1 + k] = t;
  times[0] = k + 1;
  return 0;
}

int main(void) {
  static const double expected[3] = {1.232288308117, 2.547498996101, 3.862275285217};
  const double h = 1e-3, pi = acos(-1.0);
  double q0[2] = {0.75 * pi, 0.0}, q1[2], times[9] = {0}, qa[2], qb[2], w, lambda;
  vci_callbacks cb = VCI_CALLBACKS_INIT;
  vci_model model = NULL;
  vci_integrator integ = NULL;
  int s, k, bad = 0;
  q1[0] = q0[0] + h * pi / 4; q1[1] = q0[1] + h * (pi + 0.5) * pi / 4;
  cb.d1_ld = d1; cb.d2_ld = d2; cb.d3_ld = d3; cb.constraint_forms = forms; cb.discrete_constraint = dcon;
  cb.gaps = gaps;
  s = vci_model_create(&model, 2, 1, 1, &cb, NULL);
  if (!s) s = vci_integrator_create(&integ, model, h);
  vci_model_destroy(&model); /* the integrator keeps it */
  if (!s) s = vci_set_tolerances(integ, 0.0, 1e-12, 30);
  if (!s) s = vci_set_impact_callback(integ, on_impact, times);
  if (!s) s = vci_init_from_pair(integ, 0.0, q0, q1);
  if (!s) s = vci_integrate(integ, 4998, 1);
  if (!s) s = vci_get_state(integ, NULL, qa, NULL);
  if (!s) s = vci_step(integ, 1);
  if (!s) s = vci_get_state(integ, NULL, qb, NULL);
  if (!s) s = vci_get_multipliers(integ, &lambda);
  vci_integrator_destroy(&integ);
  dcon(2, 1, qa, qb, h, &w, NULL);
  printf("status %d, %d impacts, omega_d at the last step %.1e, lambda %.6e\n", s, (int)times[0], w, lambda);
  bad = s != VCI_OK || (int)times[0] != 3 || !(fabs(w) <= 1e-9);
  for (k = 0; k < 3; ++k) {
    printf("impact %d t=%.15f expected %.12f off by %.1e\n", k + 1, times[1 + k], expected[k],
           fabs(times[1 + k] - expected[k]));
    if (!(fabs(times[1 + k] - expected[k]) <= 5e-11)) bad = 1;
  }
  printf(bad ? "FAILED\n" : "passed\n");
  return bad;
}
