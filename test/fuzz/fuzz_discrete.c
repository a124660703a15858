/* fuzz_discrete.c: the discrete model of the fuzz harness:
 * L_d(q, v, h) = h [ sum_i mass_i (v_i - q_i)^2 / (2 h^2) - V((q + v)/2) ],
 * V(x) = sum_i (grav_i x_i + stiff_i x_i^2 / 2); constraints a_mu . qdot = 0 (omega_d = a_mu .
 * (other - base) / h); walls g_j = normal_j . q - offset_j >= 0. Faults: a callback fails from
 * a random call on, now and then, with a random code or output (fuzz_util.h). */
#include "fuzz_discrete.h"
#include <string.h>

static int fault(model_t *md, int which, double *out, int nout) {
  return apply_fault(&md->fault, md->calls, which, out, nout);
}

static double force(const model_t *md, int i, double x) { return md->grav[i] + md->stiff[i] * x; }

static int cb_d1(int n, const double *q, const double *v, double h, double *out, void *u) {
  model_t *md = (model_t *)u;
  int i;
  for (i = 0; i < n; ++i) out[i] = -md->mass[i] * (v[i] - q[i]) / h - 0.5 * h * force(md, i, 0.5 * (q[i] + v[i]));
  return fault(md, 0, out, n);
}
static int cb_d2(int n, const double *q, const double *v, double h, double *out, void *u) {
  model_t *md = (model_t *)u;
  int i;
  for (i = 0; i < n; ++i) out[i] = md->mass[i] * (v[i] - q[i]) / h - 0.5 * h * force(md, i, 0.5 * (q[i] + v[i]));
  return fault(md, 1, out, n);
}
static int cb_d3(int n, const double *q, const double *v, double h, double *out, void *u) {
  model_t *md = (model_t *)u;
  int i;
  out[0] = 0.0;
  for (i = 0; i < n; ++i) {
    double x = 0.5 * (q[i] + v[i]);
    out[0] += -0.5 * md->mass[i] * (v[i] - q[i]) * (v[i] - q[i]) / (h * h) - (md->grav[i] * x + 0.5 * md->stiff[i] * x * x);
  }
  return fault(md, 2, out, 1);
}
static int cb_hessian(int n, const double *q, const double *v, double h, double *hess, void *u) {
  model_t *md = (model_t *)u;
  int i;
  (void)q; (void)v;
  for (i = 0; i < n * n; ++i) hess[i] = 0.0;
  for (i = 0; i < n; ++i) hess[i + n * i] = -md->mass[i] / h - 0.25 * h * md->stiff[i];
  return fault(md, 3, hess, n * n);
}
static int cb_forms(int n, int m, const double *q, double *omega, void *u) {
  model_t *md = (model_t *)u;
  int i, mu;
  (void)q;
  for (mu = 0; mu < m; ++mu)
    for (i = 0; i < n; ++i) omega[i + n * mu] = md->a[mu][i];
  return fault(md, 4, omega, n * m);
}
static int cb_dconstraint(int n, int m, const double *base, const double *other, double h, double *out, void *u) {
  model_t *md = (model_t *)u;
  int i, mu;
  for (mu = 0; mu < m; ++mu) {
    out[mu] = 0.0;
    for (i = 0; i < n; ++i) out[mu] += md->a[mu][i] * (other[i] - base[i]) / h;
  }
  return fault(md, 5, out, m);
}
static int cb_gaps(int n, int ng, const double *q, double *g, void *u) {
  model_t *md = (model_t *)u;
  int i, j;
  for (j = 0; j < ng; ++j) {
    g[j] = -md->offset[j];
    for (i = 0; i < n; ++i) g[j] += md->normal[j][i] * q[i];
  }
  return fault(md, 6, g, ng);
}
static int cb_gap_grads(int n, int ng, const double *q, double *dg, void *u) {
  model_t *md = (model_t *)u;
  int i, j;
  (void)q;
  for (j = 0; j < ng; ++j)
    for (i = 0; i < n; ++i) dg[i + n * j] = md->normal[j][i];
  return fault(md, 7, dg, n * ng);
}
static int cb_energy(int n, const double *q, const double *p, double *e, void *u) {
  model_t *md = (model_t *)u;
  int i;
  e[0] = 0.0;
  for (i = 0; i < n; ++i) e[0] += 0.5 * p[i] * p[i] / md->mass[i] + md->grav[i] * q[i] + 0.5 * md->stiff[i] * q[i] * q[i];
  return fault(md, 8, e, 1);
}

void random_model(model_t *md, const double *ref) {
  int i, j, mu;
  memset(md, 0, sizeof *md);
  md->n = 1 + below(MAXN);
  md->m = below((md->n < MAXM ? md->n : MAXM) + 1);
  md->ng = below(MAXG + 1);
  for (i = 0; i < md->n; ++i) {
    md->mass[i] = chance(5) ? wild(1.0) : uniform(0.2, 3.0);
    md->grav[i] = chance(50) ? uniform(-10.0, 10.0) : 0.0;
    md->stiff[i] = chance(30) ? uniform(0.0, chance(20) ? 1e6 : 50.0) : 0.0;
  }
  for (mu = 0; mu < md->m; ++mu)
    for (i = 0; i < md->n; ++i) md->a[mu][i] = uniform(-1.0, 1.0);
  for (j = 0; j < md->ng; ++j) {
    md->offset[j] = -uniform(0.01, chance(50) ? 0.3 : 2.0);
    for (i = 0; i < md->n; ++i) {
      md->normal[j][i] = uniform(-1.0, 1.0);
      md->offset[j] += md->normal[j][i] * ref[i];
    }
  }
  random_fault(&md->fault, NCALLBACKS);
}

void discrete_callbacks(vci_callbacks *cb, int ngaps) {
  vci_callbacks c = VCI_CALLBACKS_INIT;
  c.d1_ld = cb_d1; c.d2_ld = cb_d2; c.d3_ld = cb_d3; c.constraint_forms = cb_forms;
  c.discrete_constraint = cb_dconstraint;
  if (ngaps > 0 || chance(5)) c.gaps = cb_gaps;
  if (chance(50)) c.mixed_hessian = cb_hessian;
  if (chance(50)) c.gap_gradients = cb_gap_grads;
  if (chance(70)) c.energy = cb_energy;
  *cb = c;
}
