/* The paper's bouncing ellipse and nonholonomic pendulum as vci callbacks (docs/DESIGN.md section 8),
 * the same Lagrangians as the Fortran scene modules in examples/scenes. Header-only, shared by the C examples and the C
 * API tests. */
#ifndef VCI_C_SCENES_H
#define VCI_C_SCENES_H

#include <math.h>
#include "vci.h"

/* ---- ellipse: q = (theta, x, y), midpoint L_d with gravity, floor g = y - phi(theta) ---- */
typedef struct { double mass, grav, a, b; } ellipse_params;

static const ellipse_params ellipse_default = {1.0, 9.8, 1.0, 0.5};

static double ellipse_inertia(const ellipse_params *e) { return e->mass * (e->a * e->a + e->b * e->b) / 4.0; }

static int ellipse_d1(int n, const double *q, const double *v, double h, double *out, void *user) {
  const ellipse_params *e = (const ellipse_params *)user;
  (void)n;
  out[0] = -ellipse_inertia(e) * (v[0] - q[0]) / h;
  out[1] = -e->mass * (v[1] - q[1]) / h;
  out[2] = -e->mass * (v[2] - q[2]) / h - 0.5 * h * e->mass * e->grav;
  return 0;
}

static int ellipse_d2(int n, const double *q, const double *v, double h, double *out, void *user) {
  const ellipse_params *e = (const ellipse_params *)user;
  (void)n;
  out[0] = ellipse_inertia(e) * (v[0] - q[0]) / h;
  out[1] = e->mass * (v[1] - q[1]) / h;
  out[2] = e->mass * (v[2] - q[2]) / h - 0.5 * h * e->mass * e->grav;
  return 0;
}

static int ellipse_d3(int n, const double *q, const double *v, double h, double *out, void *user) {
  const ellipse_params *e = (const ellipse_params *)user;
  double d0 = v[0] - q[0], d1 = v[1] - q[1], d2 = v[2] - q[2];
  (void)n;
  out[0] = -0.5 * (ellipse_inertia(e) * d0 * d0 + e->mass * (d1 * d1 + d2 * d2)) / (h * h)
           - 0.5 * e->mass * e->grav * (q[2] + v[2]);
  return 0;
}

static int ellipse_hessian(int n, const double *q, const double *v, double h, double *hess, void *user) {
  const ellipse_params *e = (const ellipse_params *)user;
  int i;
  (void)q; (void)v;
  for (i = 0; i < n * n; ++i) hess[i] = 0.0;
  hess[0 + 3 * 0] = -ellipse_inertia(e) / h;
  hess[1 + 3 * 1] = -e->mass / h;
  hess[2 + 3 * 2] = -e->mass / h;
  return 0;
}

static int ellipse_gaps(int n, int ngaps, const double *q, double *g, void *user) {
  const ellipse_params *e = (const ellipse_params *)user;
  double s = sin(q[0]), c = cos(q[0]);
  (void)n; (void)ngaps;
  g[0] = q[2] - sqrt(e->a * e->a * s * s + e->b * e->b * c * c);
  return 0;
}

static int ellipse_gap_grads(int n, int ngaps, const double *q, double *dg, void *user) {
  const ellipse_params *e = (const ellipse_params *)user;
  double s = sin(q[0]), c = cos(q[0]), phi = sqrt(e->a * e->a * s * s + e->b * e->b * c * c);
  (void)n; (void)ngaps;
  dg[0] = -(e->a * e->a - e->b * e->b) * s * c / phi;
  dg[1] = 0.0;
  dg[2] = 1.0;
  return 0;
}

static int ellipse_energy(int n, const double *q, const double *p, double *en, void *user) {
  const ellipse_params *e = (const ellipse_params *)user;
  (void)n;
  en[0] = 0.5 * p[0] * p[0] / ellipse_inertia(e) + 0.5 * (p[1] * p[1] + p[2] * p[2]) / e->mass + e->mass * e->grav * q[2];
  return 0;
}

/* D1, D2, D3 and the Hessian in one call (vci_callbacks.ld_fused), the arithmetic of the four above. */
static inline int ellipse_fused(int n, const double *q, const double *v, double h, double *d1, double *d2, double *d3,
                                double *hess, void *user) {
  const ellipse_params *e = (const ellipse_params *)user;
  double in = ellipse_inertia(e), w0 = v[0] - q[0], w1 = v[1] - q[1], w2 = v[2] - q[2];
  int i;
  d1[0] = -in * w0 / h;
  d1[1] = -e->mass * w1 / h;
  d1[2] = -e->mass * w2 / h - 0.5 * h * e->mass * e->grav;
  d2[0] = in * w0 / h;
  d2[1] = e->mass * w1 / h;
  d2[2] = e->mass * w2 / h - 0.5 * h * e->mass * e->grav;
  d3[0] = -0.5 * (in * w0 * w0 + e->mass * (w1 * w1 + w2 * w2)) / (h * h) - 0.5 * e->mass * e->grav * (q[2] + v[2]);
  for (i = 0; i < n * n; ++i) hess[i] = 0.0;
  hess[0 + 3 * 0] = -in / h;
  hess[1 + 3 * 1] = -e->mass / h;
  hess[2 + 3 * 2] = -e->mass / h;
  return 0;
}

/* All of the ellipse's callbacks (the optional ones included; not ld_fused, which the examples add:
 * tests replace single callbacks of this set). */
static vci_callbacks ellipse_callbacks(void) {
  vci_callbacks cb = VCI_CALLBACKS_INIT;
  cb.d1_ld = ellipse_d1; cb.d2_ld = ellipse_d2; cb.d3_ld = ellipse_d3;
  cb.mixed_hessian = ellipse_hessian;
  cb.gaps = ellipse_gaps; cb.gap_gradients = ellipse_gap_grads;
  cb.energy = ellipse_energy;
  return cb;
}

/* The paper's initial data: q(0) = (pi/2, 0, 3.5), qdot(0) = (-3, 2, 0); the pair q(0) -/+ (h/2) qdot(0)
 * at t0 = -h/2 brackets t = 0 by half a step. */
static void ellipse_initial_pair(double h, double *t0, double *q0, double *q1) {
  const double q[3] = {acos(-1.0) / 2.0, 0.0, 3.5}, qd[3] = {-3.0, 2.0, 0.0};
  int i;
  *t0 = -0.5 * h;
  for (i = 0; i < 3; ++i) {
    q0[i] = q[i] - 0.5 * h * qd[i];
    q1[i] = q[i] + 0.5 * h * qd[i];
  }
}

/* ---- pendulum: q = (theta, phi), constraint f(theta) dtheta - dphi = 0, cylinder wall ---- */
typedef struct { double mass, grav, length, radius; } pendulum_params;

static const pendulum_params pendulum_default = {1.0, 9.8, 2.0, 1.5};

static double pendulum_f(double theta) { return acos(-1.0) + cos(theta) * cos(theta); }

static int pendulum_d1(int n, const double *q, const double *v, double h, double *out, void *user) {
  const pendulum_params *P = (const pendulum_params *)user;
  double ml2 = P->mass * P->length * P->length, s = sin(q[0]), c = cos(q[0]);
  (void)n;
  out[0] = -ml2 * (v[0] - q[0]) / h + ml2 * (v[1] - q[1]) * (v[1] - q[1]) * s * c / h
           + h * P->mass * P->grav * P->length * s;
  out[1] = -ml2 * (v[1] - q[1]) * s * s / h;
  return 0;
}

static int pendulum_d2(int n, const double *q, const double *v, double h, double *out, void *user) {
  const pendulum_params *P = (const pendulum_params *)user;
  double ml2 = P->mass * P->length * P->length, s = sin(q[0]);
  (void)n;
  out[0] = ml2 * (v[0] - q[0]) / h;
  out[1] = ml2 * (v[1] - q[1]) * s * s / h;
  return 0;
}

static int pendulum_d3(int n, const double *q, const double *v, double h, double *out, void *user) {
  const pendulum_params *P = (const pendulum_params *)user;
  double s = sin(q[0]), d0 = v[0] - q[0], d1 = v[1] - q[1];
  (void)n;
  out[0] = -0.5 * P->mass * P->length * P->length * (d0 * d0 + d1 * d1 * s * s) / (h * h)
           - P->mass * P->grav * P->length * cos(q[0]);
  return 0;
}

static int pendulum_hessian(int n, const double *q, const double *v, double h, double *hess, void *user) {
  const pendulum_params *P = (const pendulum_params *)user;
  double ml2 = P->mass * P->length * P->length, s = sin(q[0]), c = cos(q[0]);
  (void)n;
  hess[0 + 2 * 0] = -ml2 / h;
  hess[0 + 2 * 1] = 2.0 * ml2 * (v[1] - q[1]) * s * c / h;
  hess[1 + 2 * 0] = 0.0;
  hess[1 + 2 * 1] = -ml2 * s * s / h;
  return 0;
}

/* D1, D2, D3 and the Hessian in one call, one sine and cosine (vci_callbacks.ld_fused). */
static inline int pendulum_fused(int n, const double *q, const double *v, double h, double *d1, double *d2, double *d3,
                                 double *hess, void *user) {
  const pendulum_params *P = (const pendulum_params *)user;
  double ml2 = P->mass * P->length * P->length, s = sin(q[0]), c = cos(q[0]), w0 = v[0] - q[0], w1 = v[1] - q[1];
  (void)n;
  d1[0] = -ml2 * w0 / h + ml2 * w1 * w1 * s * c / h + h * P->mass * P->grav * P->length * s;
  d1[1] = -ml2 * w1 * s * s / h;
  d2[0] = ml2 * w0 / h;
  d2[1] = ml2 * w1 * s * s / h;
  d3[0] = -0.5 * P->mass * P->length * P->length * (w0 * w0 + w1 * w1 * s * s) / (h * h) - P->mass * P->grav * P->length * c;
  hess[0 + 2 * 0] = -ml2 / h;
  hess[0 + 2 * 1] = 2.0 * ml2 * w1 * s * c / h;
  hess[1 + 2 * 0] = 0.0;
  hess[1 + 2 * 1] = -ml2 * s * s / h;
  return 0;
}

static int pendulum_forms(int n, int m, const double *q, double *omega, void *user) {
  (void)n; (void)m; (void)user;
  omega[0] = pendulum_f(q[0]);
  omega[1] = -1.0;
  return 0;
}

static int pendulum_dconstraint(int n, int m, const double *base, const double *other, double h, double *out,
                                void *user) {
  (void)n; (void)m; (void)user;
  out[0] = (pendulum_f(base[0]) * (other[0] - base[0]) - (other[1] - base[1])) / h;
  return 0;
}

/* jac[mu + m*i] = d omega_d^mu / d other_i (optional: without it the library differences omega_d) */
static int pendulum_dconstraint_jacobian(int n, int m, const double *base, const double *other, double h,
                                         double *jac, void *user) {
  (void)n; (void)m; (void)other; (void)user;
  jac[0] = pendulum_f(base[0]) / h;
  jac[1] = -1.0 / h;
  return 0;
}

static int pendulum_gaps(int n, int ngaps, const double *q, double *g, void *user) {
  const pendulum_params *P = (const pendulum_params *)user;
  double s = sin(q[0]);
  (void)n; (void)ngaps;
  g[0] = P->radius * P->radius - P->length * P->length * s * s;
  return 0;
}

static int pendulum_gap_grads(int n, int ngaps, const double *q, double *dg, void *user) {
  const pendulum_params *P = (const pendulum_params *)user;
  (void)n; (void)ngaps;
  dg[0] = -2.0 * P->length * P->length * sin(q[0]) * cos(q[0]);
  dg[1] = 0.0;
  return 0;
}

static vci_callbacks pendulum_callbacks(void) {
  vci_callbacks cb = VCI_CALLBACKS_INIT;
  cb.d1_ld = pendulum_d1; cb.d2_ld = pendulum_d2; cb.d3_ld = pendulum_d3;
  cb.mixed_hessian = pendulum_hessian;
  cb.constraint_forms = pendulum_forms; cb.discrete_constraint = pendulum_dconstraint;
  cb.discrete_constraint_jacobian = pendulum_dconstraint_jacobian;
  cb.gaps = pendulum_gaps; cb.gap_gradients = pendulum_gap_grads;
  return cb;
}

/* The paper's initial data: q(0) = (0.75 pi, 0), qdot(0) = (pi/4, (pi + 0.5) pi/4), q1 = q0 + h qdot(0). */
static void pendulum_initial_pair(double h, double *q0, double *q1) {
  const double pi = acos(-1.0);
  q0[0] = 0.75 * pi; q0[1] = 0.0;
  q1[0] = q0[0] + h * pi / 4.0;
  q1[1] = q0[1] + h * (pi + 0.5) * pi / 4.0;
}

#endif
