/* The FPU-beta chain's continuous Lagrangian for the C tests (banded_test.c, sparse_test.c): n unit
 * masses with fixed ends, L = |v|^2/2 - sum_j (r_j^2/2 + beta r_j^4/4) over the stretches, and its
 * dense Hessian blocks. The including file defines N (largest n) and `beta`, and includes
 * <math.h> and <string.h>. */
#ifndef VCI_TEST_FPU_CHAIN_H
#define VCI_TEST_FPU_CHAIN_H
/* stretches r_0..r_n (fixed ends) */
static void stretches(int n, const double *x, double *r) {
  r[0] = x[0];
  for (int i = 1; i < n; i++) r[i] = x[i] - x[i - 1];
  r[n] = -x[n - 1];
}
static int l_value(int n, const double *q, const double *v, double *l, void *u) {
  (void)u; double r[N + 1], s = 0.0;
  stretches(n, q, r);
  for (int i = 0; i < n; i++) s += 0.5 * v[i] * v[i];
  for (int i = 0; i <= n; i++) s -= 0.5 * r[i] * r[i] + 0.25 * beta * pow(r[i], 4);
  *l = s; return 0;
}
static int l_dq(int n, const double *q, const double *v, double *out, void *u) {
  (void)v; (void)u; double r[N + 1], f[N + 1];
  stretches(n, q, r);
  for (int i = 0; i <= n; i++) f[i] = r[i] + beta * r[i] * r[i] * r[i];
  for (int i = 0; i < n; i++) out[i] = -(f[i] - f[i + 1]);
  return 0;
}
static int l_dv(int n, const double *q, const double *v, double *out, void *u) {
  (void)q; (void)u;
  for (int i = 0; i < n; i++) out[i] = v[i];
  return 0;
}
static int l_hess(int n, const double *q, const double *v, double *lqq, double *lqv, double *lvv, void *u) {
  (void)v; (void)u; double r[N + 1];
  stretches(n, q, r);
  memset(lqq, 0, sizeof(double) * n * n); memset(lqv, 0, sizeof(double) * n * n); memset(lvv, 0, sizeof(double) * n * n);
  for (int i = 0; i < n; i++) {
    lqq[i + n * i] = -(2.0 + 3.0 * beta * (r[i] * r[i] + r[i + 1] * r[i + 1]));
    if (i + 1 < n) lqq[i + n * (i + 1)] = lqq[(i + 1) + n * i] = 1.0 + 3.0 * beta * r[i + 1] * r[i + 1];
    lvv[i + n * i] = 1.0;
  }
  return 0;
}
#endif
