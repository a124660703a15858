/* fuzz_continuous.c: closed-form continuous models for the fuzz harness.
 *   L(q, qdot) = sum_i (mass_i qdot_i^2 / 2 + quart qdot_i^4 / 4) - V(q),
 *   V(q) = sum_i (grav_i q_i + stiff_i q_i^2 / 2 - pend cos q_i)
 *        + sum_{i < n-1} (kchain d_i^2 / 2 + beta d_i^4 / 4),  d_i = q_{i+1} - q_i,
 * with constant constraint forms a_mu and linear walls g_j = normal_j . q - offset_j >= 0 (as the
 * discrete model). The kinds set some of the parameters: a particle in gravity, pendulums,
 * L quartic in qdot (quart > 0), an FPU-like chain (tridiagonal Hessians: bandwidth 1). */
#include "fuzz_continuous.h"
#include <math.h>
#include <string.h>

static int fault(cmodel_t *md, int which, double *out, int nout) {
  return apply_fault(&md->fault, md->calls, which, out, nout);
}

static double potential(const cmodel_t *md, int n, const double *q) {
  double v = 0.0;
  int i;
  for (i = 0; i < n; ++i) v += md->grav[i] * q[i] + 0.5 * md->stiff[i] * q[i] * q[i] - md->pend * cos(q[i]);
  for (i = 0; i + 1 < n; ++i) {
    double d = q[i + 1] - q[i];
    v += 0.5 * md->kchain * d * d + 0.25 * md->beta * d * d * d * d;
  }
  return v;
}
static void potential_gradient(const cmodel_t *md, int n, const double *q, double *g) {
  int i;
  for (i = 0; i < n; ++i) g[i] = md->grav[i] + md->stiff[i] * q[i] + md->pend * sin(q[i]);
  for (i = 0; i + 1 < n; ++i) {
    double d = q[i + 1] - q[i], f = md->kchain * d + md->beta * d * d * d;
    g[i + 1] += f;
    g[i] -= f;
  }
}
/* the Hessian of V entry (i, j) (tridiagonal) */
static double potential_hessian(const cmodel_t *md, int n, const double *q, int i, int j) {
  double hv = 0.0;
  if (i == j) hv = md->stiff[i] + md->pend * cos(q[i]);
  if (i == j || j == i + 1 || j == i - 1) {
    int k;
    for (k = 0; k + 1 < n; ++k) { /* spring k joins k and k + 1 */
      double d = q[k + 1] - q[k], c = md->kchain + 3.0 * md->beta * d * d;
      if ((i == k || i == k + 1) && (j == k || j == k + 1)) hv += i == j ? c : -c;
    }
  }
  return hv;
}
static double kinetic(const cmodel_t *md, int n, const double *v) {
  double t = 0.0;
  int i;
  for (i = 0; i < n; ++i) t += 0.5 * md->mass[i] * v[i] * v[i] + 0.25 * md->quart * v[i] * v[i] * v[i] * v[i];
  return t;
}

static int cb_lagrangian(int n, const double *q, const double *v, double *l, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  l[0] = kinetic(md, n, v) - potential(md, n, q);
  return fault(md, 0, l, 1);
}
static int cb_dl_dq(int n, const double *q, const double *v, double *out, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  int i;
  (void)v;
  potential_gradient(md, n, q, out);
  for (i = 0; i < n; ++i) out[i] = -out[i];
  return fault(md, 1, out, n);
}
static int cb_dl_dv(int n, const double *q, const double *v, double *out, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  int i;
  (void)q;
  for (i = 0; i < n; ++i) out[i] = md->mass[i] * v[i] + md->quart * v[i] * v[i] * v[i];
  return fault(md, 2, out, n);
}
static int cb_hessians(int n, const double *q, const double *v, double *lqq, double *lqv, double *lvv, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  int i, j, r;
  for (j = 0; j < n; ++j)
    for (i = 0; i < n; ++i) {
      lqq[i + n * j] = -potential_hessian(md, n, q, i, j);
      lqv[i + n * j] = 0.0;
      lvv[i + n * j] = i == j ? md->mass[i] + 3.0 * md->quart * v[i] * v[i] : 0.0;
    }
  r = fault(md, 3, lqq, n * n);
  return r != 0 ? r : fault(md, 3, lvv, n * n);
}
static int cb_hessians_band(int n, int bw, const double *q, const double *v, double *lqq, double *lqv,
                            double *lvv, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  int i, j, ld = 2 * bw + 1;
  for (j = 0; j < n; ++j)
    for (i = j - bw; i <= j + bw; ++i) {
      int slot = (bw + i - j) + ld * j;
      if (i < 0 || i >= n) continue;
      lqq[slot] = -potential_hessian(md, n, q, i, j);
      lqv[slot] = 0.0;
      lvv[slot] = i == j ? md->mass[i] + 3.0 * md->quart * v[i] * v[i] : 0.0;
    }
  return fault(md, 8, lqq, ld * n);
}
static int cb_forms(int n, int m, const double *q, double *omega, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  int i, mu;
  (void)q;
  for (mu = 0; mu < m; ++mu)
    for (i = 0; i < n; ++i) omega[i + n * mu] = md->a[mu][i];
  return fault(md, 4, omega, n * m);
}
static int cb_gaps(int n, int ng, const double *q, double *g, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  int i, j;
  for (j = 0; j < ng; ++j) {
    g[j] = -md->offset[j];
    for (i = 0; i < n; ++i) g[j] += md->normal[j][i] * q[i];
  }
  return fault(md, 5, g, ng);
}
static int cb_gap_grads(int n, int ng, const double *q, double *dg, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  int i, j;
  (void)q;
  for (j = 0; j < ng; ++j)
    for (i = 0; i < n; ++i) dg[i + n * j] = md->normal[j][i];
  return fault(md, 6, dg, n * ng);
}
/* H(q, p) = sum p v - T(v) + V(q) with v from p = mass v + quart v^3 (Newton; monotone in v) */
static int cb_energy(int n, const double *q, const double *p, double *e, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  double v[MAXC];
  int i, it;
  e[0] = potential(md, n, q);
  for (i = 0; i < n; ++i) {
    v[i] = p[i] / md->mass[i];
    for (it = 0; it < 60 && md->quart != 0.0; ++it) {
      double r = md->mass[i] * v[i] + md->quart * v[i] * v[i] * v[i] - p[i];
      v[i] -= r / (md->mass[i] + 3.0 * md->quart * v[i] * v[i]);
    }
    e[0] += p[i] * v[i];
  }
  e[0] -= kinetic(md, n, v);
  return fault(md, 7, e, 1);
}
static int cb_potential(int n, const double *q, double *out, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  out[0] = potential(md, n, q);
  return fault(md, 9, out, 1);
}
static int cb_potential_gradient(int n, const double *q, double *out, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  potential_gradient(md, n, q, out);
  return fault(md, 10, out, n);
}
static int cb_potential_hessian(int n, const double *q, double *out, void *u) {
  cmodel_t *md = (cmodel_t *)u;
  int i, j;
  for (j = 0; j < n; ++j)
    for (i = 0; i < n; ++i) out[i + n * j] = potential_hessian(md, n, q, i, j);
  return fault(md, 11, out, n * n);
}

void random_cmodel(cmodel_t *md, const double *ref, int benign, int separable) {
  int i, j, mu;
  memset(md, 0, sizeof *md);
  md->kind = below(NKINDS);
  if (separable && md->kind == KIND_QUARTIC) md->kind = KIND_GRAVITY;
  md->n = md->kind == KIND_CHAIN ? 3 + below(MAXC - 2) : md->kind == KIND_PENDULUM ? 1 + below(2) : 1 + below(3);
  md->m = benign || separable ? 0 : below((md->n < MAXCM ? md->n : MAXCM) + 1);
  md->ng = below(MAXCG + 1);
  for (i = 0; i < md->n; ++i) {
    md->mass[i] = !benign && chance(5) ? wild(1.0) : uniform(0.5, 2.0);
    md->stiff[i] = chance(20) ? uniform(0.0, !benign && chance(20) ? 1e6 : 20.0) : 0.0;
  }
  switch (md->kind) {
  case KIND_GRAVITY: md->grav[md->n - 1] = uniform(1.0, 10.0); break;
  case KIND_PENDULUM: md->pend = uniform(1.0, 10.0); break;
  case KIND_QUARTIC: md->quart = uniform(0.2, 3.0); break;
  default: md->kchain = uniform(1.0, 50.0); md->beta = chance(50) ? uniform(0.0, 5.0) : 0.0; break;
  }
  if (!benign && chance(10)) md->quart = wild(1.0);
  for (i = 0; i < MAXC * MAXC; ++i) md->dense_mass[i] = 0.0;
  for (i = 0; i < md->n; ++i) { /* diagonally dominant (SPD) unless hostile */
    md->dense_mass[i + md->n * i] = md->mass[i] + 1.0;
    if (i + 1 < md->n) {
      double c = uniform(-0.4, 0.4);
      md->dense_mass[i + 1 + md->n * i] = md->dense_mass[i + md->n * (i + 1)] = c;
    }
  }
  if (!benign && chance(10)) md->dense_mass[below(md->n * md->n)] = wild(1.0);
  for (mu = 0; mu < md->m; ++mu)
    for (i = 0; i < md->n; ++i) md->a[mu][i] = uniform(-1.0, 1.0);
  for (j = 0; j < md->ng; ++j) {
    md->offset[j] = -uniform(benign ? 0.05 : 0.01, chance(50) ? 0.3 : 2.0);
    for (i = 0; i < md->n; ++i) {
      md->normal[j][i] = uniform(-1.0, 1.0);
      md->offset[j] += md->normal[j][i] * ref[i];
    }
  }
  if (benign) md->fault.which = -1;
  else random_fault(&md->fault, NCCALLBACKS);
}

int cmodel_bandwidth(const cmodel_t *md) { return md->kind == KIND_CHAIN ? 1 : 0; }

void lagrangian_callbacks(vci_lagrangian_callbacks *cb, int ngaps, int hostile) {
  vci_lagrangian_callbacks c = VCI_LAGRANGIAN_CALLBACKS_INIT;
  c.lagrangian = cb_lagrangian; c.dl_dq = cb_dl_dq; c.dl_dv = cb_dl_dv;
  c.constraint_forms = cb_forms;
  if (ngaps > 0 || (hostile && chance(5))) c.gaps = cb_gaps;
  if (!hostile || chance(60)) c.hessians = cb_hessians;
  if (!hostile || chance(60)) c.gap_gradients = cb_gap_grads;
  if (!hostile || chance(60)) c.energy = cb_energy;
  if (!hostile || chance(50)) c.hessians_band = cb_hessians_band;
  *cb = c;
}

void separable_callbacks(vci_separable_callbacks *cb, int ngaps, int hostile) {
  vci_separable_callbacks c = VCI_SEPARABLE_CALLBACKS_INIT;
  c.potential = cb_potential; c.potential_gradient = cb_potential_gradient;
  if (ngaps > 0 || (hostile && chance(5))) {
    c.gaps = cb_gaps;
    c.gap_gradients = cb_gap_grads;
  }
  if (!hostile || chance(60)) c.potential_hessian = cb_potential_hessian;
  *cb = c;
}
