/* A declared sparse Hessian pattern through the C ABI (vci_model_declare_pattern, issue 28): the
 * FPU-beta chain of n = 20 between walls |x_i| <= 0.6 (test/api/banded_test.c's run), h = 0.01,
 * 100 steps, Hamiltonian impacts.
 *  1. the tridiagonal pattern (both triangles given; and the lower one alone, which the library
 *     closes under transposition), midpoint and left schemes, debug check off and on: the same
 *     impacts and end state as the dense run to 1e-9 (each Newton solve meets rtol 1e-12; KLU's
 *     and LAPACK's rounding differ by ~1e-15 a step);
 *     With the hessians_sparse member alone (no dense hessians; the tridiagonal pattern, Newton's
 *     matrix assembled in it, issue 28): the same, and the callback called;
 *  2. the pattern withdrawn (n = 0): the dense run bit for bit;
 *  3. the diagonal alone with the check on (midpoint): the first Newton matrix has (2, 1) outside
 *     it and the step fails with VCI_ERR_ARGUMENT naming that entry;
 *  4. bad patterns refused at the declaration with VCI_ERR_ARGUMENT and a message naming the
 *     cause (colptr[0], a decreasing colptr, a row out of range, rows unsorted or repeated, NULL
 *     arrays, n not the model's, a dead handle, a separable model); a pattern together with a
 *     bandwidth refused by vci_integrator_create;
 *  5. in a build without the sparse solver (VCI_SPARSE=OFF, vci_sparse_available() == 0): a valid
 *     pattern refused with VCI_ERR_ARGUMENT naming the option, withdrawing it accepted. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include "vci.h"

#define N 20
static int failures = 0;
#define CHECK(c) do { if (!(c)) { printf("  line %d: CHECK(%s) failed\n", __LINE__, #c); failures++; } } while (0)

static const double beta = 1.0, wall = 0.6;

#include "fpu_chain_model.h"
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

/* 0-based compressed columns of the n x n pattern with rows j + d, d in offs[0..noff) (|d| <= 1 here),
 * in increasing order; returns nnz. */
static int offsets_pattern(int n, const int *offs, int noff, int *colptr, int *rowind) {
  int q = 0;
  for (int j = 0; j < n; j++) {
    colptr[j] = q;
    for (int k = 0; k < noff; k++)
      if (j + offs[k] >= 0 && j + offs[k] < n) rowind[q++] = j + offs[k];
  }
  colptr[n] = q;
  return q;
}

/* The declared pattern hessians_sparse fills (the tridiagonal one, both triangles) and its calls. */
static int sp_colptr[N + 1], sp_rowind[3 * N], sp_calls = 0;

/* The chain's blocks in the declared pattern's order: lqq[k] = d2L/dq_i dq_j, i = sp_rowind[k]. */
static int l_hess_sparse(int n, int nnz, const double *q, const double *v, double *lqq, double *lqv, double *lvv,
                         void *u) {
  (void)v; (void)u; double r[N + 1];
  if (nnz != sp_colptr[n]) return -1;
  stretches(n, q, r);
  for (int j = 0; j < n; j++)
    for (int k = sp_colptr[j]; k < sp_colptr[j + 1]; k++) {
      int i = sp_rowind[k];
      lqv[k] = 0.0;
      lvv[k] = i == j ? 1.0 : 0.0;
      if (i == j) lqq[k] = -(2.0 + 3.0 * beta * (r[i] * r[i] + r[i + 1] * r[i + 1]));
      else { int lo = i < j ? i : j; lqq[k] = 1.0 + 3.0 * beta * r[lo + 1] * r[lo + 1]; }
    }
  sp_calls++;
  return 0;
}

static vci_model chain_model_cb(int sparse) {
  vci_lagrangian_callbacks cb = VCI_LAGRANGIAN_CALLBACKS_INIT;
  vci_model model = NULL;
  cb.lagrangian = l_value; cb.dl_dq = l_dq; cb.dl_dv = l_dv;
  if (sparse) cb.hessians_sparse = l_hess_sparse; else cb.hessians = l_hess;
  cb.gaps = gaps; cb.gap_gradients = gap_grads;
  if (vci_model_create_lagrangian(&model, N, 0, 2 * N, &cb, NULL) != VCI_OK) return NULL;
  return model;
}

static vci_model chain_model(void) { return chain_model_cb(0); }

/* pattern: 0 dense; 1 tridiagonal (both triangles); 2 its lower triangle; 3 the diagonal alone;
 * 4 declared, then withdrawn (n = 0); 5 tridiagonal with hessians_sparse alone. */
static int run(int scheme, int pattern, int check, double *q, double *p, int64_t *impacts, char *msg, size_t len) {
  static const int tri[] = {-1, 0, 1}, lower[] = {0, 1}, diag[] = {0};
  int colptr[N + 1], rowind[3 * N];
  vci_model model = chain_model_cb(pattern == 5);
  vci_integrator it = NULL;
  double q0[N], p0[N], t, pi = acos(-1.0);
  for (int i = 1; i <= N; i++) {
    q0[i - 1] = 0.24 * sin(2 * pi * i / 21.0);
    p0[i - 1] = 1.2 * sin(3 * pi * i / 21.0) + 0.8 * sin(pi * i / 21.0);
  }
  msg[0] = '\0';
  int st = model ? VCI_OK : VCI_ERR_MEMORY;
  if (pattern == 1 || pattern == 4) offsets_pattern(N, tri, 3, colptr, rowind);
  if (pattern == 5) {
    offsets_pattern(N, tri, 3, sp_colptr, sp_rowind);
    memcpy(colptr, sp_colptr, sizeof colptr); memcpy(rowind, sp_rowind, sizeof rowind);
  }
  if (pattern == 2) offsets_pattern(N, lower, 2, colptr, rowind);
  if (pattern == 3) offsets_pattern(N, diag, 1, colptr, rowind);
  if (st == VCI_OK && pattern > 0) st = vci_model_declare_pattern(model, N, colptr, rowind, check);
  if (st == VCI_OK && pattern == 4) st = vci_model_declare_pattern(model, 0, NULL, NULL, 0);
  if (st == VCI_OK) st = vci_integrator_create(&it, model, 0.01);
  vci_model_destroy(&model);
  if (st == VCI_OK) st = vci_set_scheme(it, scheme, 1);
  if (st == VCI_OK) st = vci_set_impact_energy(it, VCI_IMPACT_HAMILTONIAN);
  if (st == VCI_OK) st = vci_init_from_momentum(it, 0.0, q0, p0);
  if (st == VCI_OK) st = vci_integrate(it, 100, 1);
  if (st == VCI_OK) st = vci_get_state(it, &t, q, p);
  if (st == VCI_OK) st = vci_get_stats(it, NULL, impacts, NULL);
  if (st != VCI_OK) vci_last_error(it, msg, len);
  vci_integrator_destroy(&it);
  return st;
}

static double maxdiff(const double *a, const double *b) {
  double d = 0.0;
  for (int i = 0; i < N; i++) d = fmax(d, fabs(a[i] - b[i]));
  return d;
}

/* vci_model_declare_pattern(model, n, colptr, rowind, 0) is refused with VCI_ERR_ARGUMENT and a
 * message containing want. */
static void refused(vci_model model, int n, const int *colptr, const int *rowind, const char *want) {
  char msg[512];
  int st = vci_model_declare_pattern(model, n, colptr, rowind, 0);
  vci_last_error(NULL, msg, sizeof msg);
  printf("refused: %s: %s\n", vci_status_string(st), msg);
  CHECK(st == VCI_ERR_ARGUMENT);
  if (!strstr(msg, want)) printf("  (wanted \"%s\")\n", want);
  CHECK(strstr(msg, want) != NULL);
}

static void bad_patterns(void) {
  vci_model model = chain_model();
  /* the tridiagonal pattern, then one thing wrong with it at a time */
  int cp[N + 1], ri[3 * N];
  static const int tri[] = {-1, 0, 1};
  CHECK(model != NULL);
  offsets_pattern(N, tri, 3, cp, ri);
  cp[0] = 1; refused(model, N, cp, ri, "colptr[0] = 1, not 0");
  cp[0] = 0; cp[5] = cp[4] - 1; refused(model, N, cp, ri, "colptr decreases: colptr[5]");
  offsets_pattern(N, tri, 3, cp, ri);
  ri[cp[N] - 1] = N; refused(model, N, cp, ri, "is outside 0..19");
  ri[cp[N] - 1] = -1; refused(model, N, cp, ri, "is outside 0..19");
  offsets_pattern(N, tri, 3, cp, ri);
  { int s = ri[cp[3]]; ri[cp[3]] = ri[cp[3] + 1]; ri[cp[3] + 1] = s; }
  refused(model, N, cp, ri, "rows of column 3 are not strictly increasing");
  offsets_pattern(N, tri, 3, cp, ri);
  ri[cp[3] + 1] = ri[cp[3]]; refused(model, N, cp, ri, "rows of column 3 are not strictly increasing");
  offsets_pattern(N, tri, 3, cp, ri);
  refused(model, N, NULL, ri, "colptr is NULL");
  refused(model, N, cp, NULL, "rowind is NULL");
  refused(model, -1, cp, ri, "n = -1");
  offsets_pattern(10, tri, 3, cp, ri);
  refused(model, 10, cp, ri, "the model has n = 20");
  /* the pattern and a bandwidth: vci_integrator_create says to declare one */
  {
    vci_integrator it = NULL;
    char msg[512];
    offsets_pattern(N, tri, 3, cp, ri);
    CHECK(vci_model_declare_pattern(model, N, cp, ri, 0) == VCI_OK);
    CHECK(vci_model_declare_bandwidth(model, 1, 0) == VCI_OK);
    int st = vci_integrator_create(&it, model, 0.01);
    vci_last_error(NULL, msg, sizeof msg);
    printf("pattern and band: %s: %s\n", vci_status_string(st), msg);
    CHECK(st == VCI_ERR_ARGUMENT && it == NULL);
    CHECK(strstr(msg, "both a Hessian bandwidth and a sparse pattern") != NULL);
  }
  {
    vci_model keep = model;
    vci_model_destroy(&model);
    offsets_pattern(N, tri, 3, cp, ri);
    refused(keep, N, cp, ri, "not a live model handle");
  }
}

static int potential(int n, const double *q, double *out, void *u) {
  (void)u; out[0] = 0.0;
  for (int i = 0; i < n; i++) out[0] += 0.5 * q[i] * q[i];
  return 0;
}
static int potential_grad(int n, const double *q, double *out, void *u) {
  (void)u;
  for (int i = 0; i < n; i++) out[i] = q[i];
  return 0;
}

int main(void) {
  double qd[N], pd[N], qs[N], ps[N];
  int64_t id = 0, is = 0;
  char msg[512];
  static const int tri[] = {-1, 0, 1};
  int cp[N + 1], ri[3 * N];
  if (!vci_sparse_available()) {
    vci_model model = chain_model();
    offsets_pattern(N, tri, 3, cp, ri);
    refused(model, N, cp, ri, "built without the sparse solver (CMake VCI_SPARSE=OFF");
    CHECK(vci_model_declare_pattern(model, 0, NULL, NULL, 0) == VCI_OK);
    vci_model_destroy(&model);
    printf("no sparse solver in this build: %s (%d failures)\n", failures ? "FAILED" : "passed", failures);
    return failures ? 1 : 0;
  }
  static const int schemes[2] = {VCI_SCHEME_MIDPOINT, VCI_SCHEME_LEFT};
  for (int s = 0; s < 2; s++) {
    int st = run(schemes[s], 0, 0, qd, pd, &id, msg, sizeof msg);
    if (st != VCI_OK) printf("  dense run failed: %s\n", msg);
    CHECK(st == VCI_OK);
    for (int pattern = 1; pattern <= 2; pattern++)
      for (int check = 0; check <= 1; check++) {
        st = run(schemes[s], pattern, check, qs, ps, &is, msg, sizeof msg);
        if (st != VCI_OK) printf("  sparse run failed: %s\n", msg);
        CHECK(st == VCI_OK);
        printf("scheme %d, pattern %s, check %d: %lld impacts (dense %lld); |dq| = %.2e, |dp| = %.2e\n", schemes[s],
               pattern == 1 ? "tridiagonal" : "lower", check, (long long)is, (long long)id, maxdiff(qs, qd),
               maxdiff(ps, pd));
        CHECK(id >= 10 && is == id);
        CHECK(maxdiff(qs, qd) <= 1e-9 && maxdiff(ps, pd) <= 1e-9);
      }
    sp_calls = 0;
    st = run(schemes[s], 5, 0, qs, ps, &is, msg, sizeof msg);
    if (st != VCI_OK) printf("  sparse-callback run failed: %s\n", msg);
    printf("scheme %d, hessians_sparse alone: %lld impacts (dense %lld); |dq| = %.2e, |dp| = %.2e; %d calls\n",
           schemes[s], (long long)is, (long long)id, maxdiff(qs, qd), maxdiff(ps, pd), sp_calls);
    CHECK(st == VCI_OK && sp_calls > 0 && is == id);
    CHECK(maxdiff(qs, qd) <= 1e-9 && maxdiff(ps, pd) <= 1e-9);
    st = run(schemes[s], 4, 0, qs, ps, &is, msg, sizeof msg);
    CHECK(st == VCI_OK && is == id && maxdiff(qs, qd) == 0.0 && maxdiff(ps, pd) == 0.0);
    /* (left's Newton matrix is h D1 D2 L_d = -L_vv/h + L_qv terms, diagonal for the chain: only
     * midpoint's, with L_qq at the midpoint, has (2, 1)) */
    if (schemes[s] != VCI_SCHEME_MIDPOINT) continue;
    st = run(schemes[s], 3, 1, qs, ps, &is, msg, sizeof msg);
    printf("diagonal pattern, check 1: %s: %s\n", vci_status_string(st), msg);
    CHECK(st == VCI_ERR_ARGUMENT);
    CHECK(strstr(msg, "nonzero at (2, 1) outside the Hessian bandwidth the model declared, or its sparse pattern") != NULL);
  }
  bad_patterns();
  {
    vci_separable_callbacks scb = VCI_SEPARABLE_CALLBACKS_INIT;
    vci_model sep = NULL;
    double mass[N];
    for (int i = 0; i < N; i++) mass[i] = 1.0;
    scb.potential = potential; scb.potential_gradient = potential_grad;
    CHECK(vci_model_create_separable(&sep, N, 0, 0, VCI_MASS_DIAGONAL, mass, &scb, NULL) == VCI_OK);
    offsets_pattern(N, tri, 3, cp, ri);
    refused(sep, N, cp, ri, "a separable model has no declared pattern");
    vci_model_destroy(&sep);
  }
  printf("%s (%d failures)\n", failures ? "FAILED" : "passed", failures);
  return failures ? 1 : 0;
}
