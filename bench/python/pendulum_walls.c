/* The C client of bench/python/bench_python.py: the walled pendulum (theta'' = -9.8 sin theta,
 * walls at +-1 rad, theta(0) = 0, theta'(0) = 4) as a continuous L through vci.h, lobatto s = 4,
 * h = 0.05, Newton rtol 1e-15 (the run of test/api/lagrangian_test.c), NSTEPS steps, best of
 * REPEATS timings of vci_integrate alone.
 * Usage: pendulum_walls_c NSTEPS REPEATS. Prints: seconds (best), then t theta p impacts. */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "vci.h"

static int l_value(int n, const double *q, const double *v, double *l, void *u) {
  (void)n; (void)u; l[0] = 0.5 * v[0] * v[0] + 9.8 * cos(q[0]); return 0; }
static int l_dq(int n, const double *q, const double *v, double *o, void *u) {
  (void)n; (void)v; (void)u; o[0] = -9.8 * sin(q[0]); return 0; }
static int l_dv(int n, const double *q, const double *v, double *o, void *u) {
  (void)n; (void)q; (void)u; o[0] = v[0]; return 0; }
static int l_hess(int n, const double *q, const double *v, double *a, double *b, double *c, void *u) {
  (void)n; (void)v; (void)u; a[0] = -9.8 * cos(q[0]); b[0] = 0.0; c[0] = 1.0; return 0; }
static int walls(int n, int ng, const double *q, double *g, void *u) {
  (void)n; (void)ng; (void)u; g[0] = 1.0 - q[0]; g[1] = q[0] + 1.0; return 0; }
static int wall_grads(int n, int ng, const double *q, double *dg, void *u) {
  (void)n; (void)ng; (void)q; (void)u; dg[0] = -1.0; dg[1] = 1.0; return 0; }

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv) {
  long long nsteps = argc > 1 ? atoll(argv[1]) : 20000;
  int repeats = argc > 2 ? atoi(argv[2]) : 5, r, st = VCI_OK;
  double best = INFINITY, t = 0, q = 0, p = 0;
  int64_t impacts = 0;
  vci_lagrangian_callbacks cb = VCI_LAGRANGIAN_CALLBACKS_INIT;
  vci_model model = NULL;
  cb.lagrangian = l_value; cb.dl_dq = l_dq; cb.dl_dv = l_dv; cb.hessians = l_hess;
  cb.gaps = walls; cb.gap_gradients = wall_grads;
  st = vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL);
  for (r = 0; r < repeats && st == VCI_OK; ++r) {
    vci_integrator it = NULL;
    double q0 = 0.0, p0 = 4.0, t0;
    st = vci_integrator_create(&it, model, 0.05);
    if (st == VCI_OK) st = vci_set_scheme(it, VCI_SCHEME_LOBATTO, 4);
    if (st == VCI_OK) st = vci_set_tolerances(it, 0.0, 1e-15, 30);
    if (st == VCI_OK) st = vci_init_from_momentum(it, 0.0, &q0, &p0);
    t0 = now();
    if (st == VCI_OK) st = vci_integrate(it, nsteps, 1);
    t0 = now() - t0;
    if (t0 < best) best = t0;
    if (st == VCI_OK) st = vci_get_state(it, &t, &q, &p);
    if (st == VCI_OK) st = vci_get_stats(it, NULL, &impacts, NULL);
    if (st != VCI_OK) {
      char msg[512];
      vci_last_error(it, msg, sizeof msg);
      fprintf(stderr, "pendulum_walls_c: %s: %s\n", vci_status_string(st), msg);
    }
    vci_integrator_destroy(&it);
  }
  vci_model_destroy(&model);
  if (st != VCI_OK) return 1;
  printf("%.9e\n%.17g %.17g %.17g %lld\n", best, t, q, p, (long long)impacts);
  return 0;
}
