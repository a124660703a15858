/* The walled pendulum as a continuous Lagrangian for the C tests (theta'' = -9.8 sin theta, walls at
 * theta = +-1 rad): L = v^2/2 + 9.8 cos q, its derivatives and the two walls. No shared state, so
 * they may run on several threads at once. dl_dq is each test's own (lagrangian_test.c counts its calls). */
#ifndef VCI_TEST_WALLS_LAGRANGIAN_H
#define VCI_TEST_WALLS_LAGRANGIAN_H
#include <math.h>

static int l_value(int n, const double *q, const double *v, double *l, void *user) {
  (void)n; (void)user;
  l[0] = 0.5 * v[0] * v[0] + 9.8 * cos(q[0]);
  return 0;
}
static int l_dv(int n, const double *q, const double *v, double *out, void *user) {
  (void)n; (void)q; (void)user;
  out[0] = v[0];
  return 0;
}
static int l_hess(int n, const double *q, const double *v, double *lqq, double *lqv, double *lvv, void *user) {
  (void)n; (void)v; (void)user;
  lqq[0] = -9.8 * cos(q[0]); lqv[0] = 0.0; lvv[0] = 1.0;
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
#endif
