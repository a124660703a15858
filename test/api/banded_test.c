/* A declared Hessian bandwidth through the C ABI (vci_model_declare_bandwidth and the
 * hessians_band member of vci_lagrangian_callbacks): the FPU-beta chain of n = 20 between walls
 * |x_i| <= 0.6 (docs/RESULTS.md's start), midpoint, h = 0.01, 100 steps.
 *  1. band 1 with hessians_band only (no dense hessians): same impacts and end state as the dense
 *     run with dense hessians to 1e-9 (each solve meets rtol 1e-12; observed ~1e-15);
 *  2. the same with the debug check on (the band against central differences at the start);
 *  3. band 0 declared with the check on: the start is refused with VCI_ERR_ARGUMENT and a message
 *     naming L_qq(2, 1) outside the band;
 *  4. a separable model or a dead handle is refused;
 *  5. vci_set_bordered_impacts: the banded run with the whole stage matrices (0) agrees with the
 *     dense run to 1e-9 as the bordered one does, and solves no direction by bordering
 *     (vci_get_bordered_directions 0; > 0 by default); on = 2, min_unknowns 1 or -1 are refused. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include "vci.h"

#define N 20
static int failures = 0;
#define CHECK(c) do { if (!(c)) { printf("  line %d: CHECK(%s) failed\n", __LINE__, #c); failures++; } } while (0)

static const double beta = 1.0, wall = 0.6;
static int band_calls = 0;

#include "fpu_chain_model.h"
/* band storage (2 bw + 1) x n: entry (i, j) at [(bw + i - j) + (2 bw + 1) j]; a band of 0 gets the diagonal */
static int l_hess_band(int n, int bw, const double *q, const double *v, double *lqq, double *lqv, double *lvv,
                       void *u) {
  (void)v; (void)u; double r[N + 1]; int ld = 2 * bw + 1;
  band_calls++;
  stretches(n, q, r);
  memset(lqq, 0, sizeof(double) * ld * n); memset(lqv, 0, sizeof(double) * ld * n); memset(lvv, 0, sizeof(double) * ld * n);
  for (int j = 0; j < n; j++) {
    lqq[bw + ld * j] = -(2.0 + 3.0 * beta * (r[j] * r[j] + r[j + 1] * r[j + 1]));
    lvv[bw + ld * j] = 1.0;
    if (bw >= 1 && j + 1 < n) {
      double k = 1.0 + 3.0 * beta * r[j + 1] * r[j + 1];
      lqq[(bw + 1) + ld * j] = k;         /* (j + 1, j) */
      lqq[(bw - 1) + ld * (j + 1)] = k;   /* (j, j + 1) */
    }
  }
  return 0;
}
static int gaps(int n, int ng, const double *q, double *g, void *u) {
  (void)ng; (void)u;
  for (int i = 0; i < n; i++) { g[i] = wall - q[i]; g[n + i] = wall + q[i]; }
  return 0;
}
static int gap_grads(int n, int ng, const double *q, double *dg, void *u) {
  (void)q; (void)u;
  memset(dg, 0, sizeof(double) * n * ng);
  for (int i = 0; i < n; i++) { dg[i + n * i] = -1.0; dg[i + n * (n + i)] = 1.0; }
  return 0;
}

/* bw < 0: dense hessians, no band; else band bw, hessians_band only, check as given. bordered >= 0:
 * vci_set_bordered_impacts(bordered, 0) (after its bad arguments are seen refused); *bdir: directions
 * solved by bordering. */
static int run_b(int bw, int check, int bordered, double *q, double *p, int64_t *impacts, int64_t *bdir,
                 char *msg, size_t len) {
  vci_lagrangian_callbacks cb = VCI_LAGRANGIAN_CALLBACKS_INIT;
  vci_model model = NULL;
  vci_integrator it = NULL;
  double q0[N], p0[N], t, pi = acos(-1.0);
  cb.lagrangian = l_value; cb.dl_dq = l_dq; cb.dl_dv = l_dv; cb.gaps = gaps; cb.gap_gradients = gap_grads;
  if (bw < 0) cb.hessians = l_hess; else cb.hessians_band = l_hess_band;
  for (int i = 1; i <= N; i++) {
    q0[i - 1] = 0.24 * sin(2 * pi * i / 21.0);
    p0[i - 1] = 1.2 * sin(3 * pi * i / 21.0) + 0.8 * sin(pi * i / 21.0);
  }
  msg[0] = '\0';
  int st = vci_model_create_lagrangian(&model, N, 0, 2 * N, &cb, NULL);
  if (st == VCI_OK && bw >= 0) st = vci_model_declare_bandwidth(model, bw, check);
  if (st == VCI_OK) st = vci_integrator_create(&it, model, 0.01);
  vci_model_destroy(&model);
  if (st == VCI_OK) st = vci_set_impact_energy(it, VCI_IMPACT_HAMILTONIAN);
  if (st == VCI_OK && bordered >= 0) {
    CHECK(vci_set_bordered_impacts(it, 2, 0) == VCI_ERR_ARGUMENT);
    CHECK(vci_set_bordered_impacts(it, 1, 1) == VCI_ERR_ARGUMENT);
    CHECK(vci_set_bordered_impacts(it, 1, -1) == VCI_ERR_ARGUMENT);
    CHECK(vci_get_bordered_directions(it, NULL) == VCI_ERR_ARGUMENT);
    st = vci_set_bordered_impacts(it, bordered, 0);
  }
  if (st == VCI_OK) st = vci_init_from_momentum(it, 0.0, q0, p0);
  if (st == VCI_OK) st = vci_integrate(it, 100, 1);
  if (st == VCI_OK) st = vci_get_state(it, &t, q, p);
  if (st == VCI_OK) st = vci_get_stats(it, NULL, impacts, NULL);
  if (st == VCI_OK && bdir) st = vci_get_bordered_directions(it, bdir);
  if (st != VCI_OK) vci_last_error(it, msg, len);
  vci_integrator_destroy(&it);
  return st;
}

static int run(int bw, int check, double *q, double *p, int64_t *impacts, char *msg, size_t len) {
  return run_b(bw, check, -1, q, p, impacts, NULL, msg, len);
}

static double maxdiff(const double *a, const double *b) {
  double d = 0.0;
  for (int i = 0; i < N; i++) d = fmax(d, fabs(a[i] - b[i]));
  return d;
}

int main(void) {
  double qd[N], pd[N], qb[N], pb[N];
  int64_t id = 0, ib = 0;
  char msg[512];
  int st = run(-1, 0, qd, pd, &id, msg, sizeof msg);
  CHECK(st == VCI_OK);
  for (int check = 0; check <= 1; check++) {
    band_calls = 0;
    st = run(1, check, qb, pb, &ib, msg, sizeof msg);
    if (st != VCI_OK) printf("  banded run failed: %s\n", msg);
    CHECK(st == VCI_OK);
    printf("band 1, check %d: %lld impacts (dense %lld); |dq| = %.2e, |dp| = %.2e; %d hessians_band calls\n",
           check, (long long)ib, (long long)id, maxdiff(qb, qd), maxdiff(pb, pd), band_calls);
    CHECK(id >= 10 && ib == id);
    CHECK(maxdiff(qb, qd) <= 1e-9 && maxdiff(pb, pd) <= 1e-9);
    CHECK(band_calls > 100);
  }
  {
    int64_t bon = -1, boff = -1;
    st = run_b(1, 0, -1, qb, pb, &ib, &bon, msg, sizeof msg);
    CHECK(st == VCI_OK);
    st = run_b(1, 0, 0, qb, pb, &ib, &boff, msg, sizeof msg);
    if (st != VCI_OK) printf("  whole-stage run failed: %s\n", msg);
    CHECK(st == VCI_OK);
    printf("band 1, whole stage matrices: %lld impacts; |dq| = %.2e, |dp| = %.2e; bordered directions %lld "
           "(default run %lld)\n", (long long)ib, maxdiff(qb, qd), maxdiff(pb, pd), (long long)boff, (long long)bon);
    CHECK(ib == id && maxdiff(qb, qd) <= 1e-9 && maxdiff(pb, pd) <= 1e-9);
    CHECK(boff == 0 && bon > 0);
  }
  st = run(0, 1, qb, pb, &ib, msg, sizeof msg);
  printf("band 0, check 1: %s: %s\n", vci_status_string(st), msg);
  CHECK(st == VCI_ERR_ARGUMENT);
  CHECK(strstr(msg, "L_qq(2, 1) =") != NULL);
  CHECK(strstr(msg, "outside the declared Hessian bandwidth 0") != NULL);
  {
    vci_model dead = NULL;
    vci_lagrangian_callbacks cb = VCI_LAGRANGIAN_CALLBACKS_INIT;
    cb.lagrangian = l_value; cb.dl_dq = l_dq; cb.dl_dv = l_dv;
    CHECK(vci_model_create_lagrangian(&dead, N, 0, 0, &cb, NULL) == VCI_OK);
    vci_model keep = dead;
    vci_model_destroy(&dead);
    CHECK(vci_model_declare_bandwidth(keep, 1, 0) == VCI_ERR_ARGUMENT);
  }
  printf("%s (%d failures)\n", failures ? "FAILED" : "passed", failures);
  return failures ? 1 : 0;
}
