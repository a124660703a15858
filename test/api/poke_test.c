/* vci_set_poke_samples (docs/BACKWARD.md, "A wall poked within one sub-step"): a parabola under a
 * ceiling y <= 1 (gravity 9.8, h = 1e-2) whose apex, at t = 0.205 half-way between two grid points,
 * is 6.1e-5 above the ceiling: half of g h^2 / 8, so both grid points next to it are below the
 * ceiling (by 6.1e-5) and only the screen inside the step meets the touch. The midpoint rule is
 * exact on a parabola, so the discrete motion pokes through exactly as the exact one does.
 *  - default (on): one impact in 60 steps; off (0): none; on again (1): one;
 *  - on = 2 or -1, or a NULL handle: VCI_ERR_ARGUMENT.
 * Usage: vci_poke_test; the exit status is the number of failed checks. */
#include <stdint.h>
#include <stdio.h>
#include "vci.h"

static int failures = 0;

#define CHECK(c) do { if (!(c)) { printf("FAIL line %d: %s\n", __LINE__, #c); ++failures; } } while (0)

static const double grav = 9.8;

static int l_value(int n, const double *q, const double *v, double *l, void *user) {
  (void)n; (void)user;
  l[0] = 0.5 * v[0] * v[0] - grav * q[0];
  return 0;
}
static int l_dq(int n, const double *q, const double *v, double *out, void *user) {
  (void)n; (void)q; (void)v; (void)user;
  out[0] = -grav;
  return 0;
}
static int l_dv(int n, const double *q, const double *v, double *out, void *user) {
  (void)n; (void)q; (void)user;
  out[0] = v[0];
  return 0;
}
static int l_hess(int n, const double *q, const double *v, double *lqq, double *lqv, double *lvv, void *user) {
  (void)n; (void)q; (void)v; (void)user;
  lqq[0] = 0.0; lqv[0] = 0.0; lvv[0] = 1.0;
  return 0;
}
static int ceiling(int n, int ng, const double *q, double *g, void *user) {
  (void)n; (void)ng; (void)user;
  g[0] = 1.0 - q[0];
  return 0;
}
static int ceiling_grad(int n, int ng, const double *q, double *dg, void *user) {
  (void)n; (void)ng; (void)q; (void)user;
  dg[0] = -1.0;
  return 0;
}

/* Impacts in 60 steps; poke < 0: the default, else vci_set_poke_samples(poke) first. */
static int64_t impacts_of_run(vci_model model, int poke) {
  const double h = 1.0e-2, t_apex = 0.205, depth = 0.5 * grav * h * h / 8.0;
  double q0 = 1.0 + depth - 0.5 * grav * t_apex * t_apex, p0 = grav * t_apex;
  vci_integrator it = NULL;
  int64_t impacts = -1;
  CHECK(vci_integrator_create(&it, model, h) == VCI_OK);
  if (poke >= 0) CHECK(vci_set_poke_samples(it, poke) == VCI_OK);
  CHECK(vci_init_from_momentum(it, 0.0, &q0, &p0) == VCI_OK);
  CHECK(vci_integrate(it, 60, 1) == VCI_OK);
  CHECK(vci_get_stats(it, NULL, &impacts, NULL) == VCI_OK);
  vci_integrator_destroy(&it);
  return impacts;
}

int main(void) {
  vci_lagrangian_callbacks cb = VCI_LAGRANGIAN_CALLBACKS_INIT;
  vci_model model = NULL;
  vci_integrator it = NULL;
  int64_t on, off, on_again;
  cb.lagrangian = l_value; cb.dl_dq = l_dq; cb.dl_dv = l_dv; cb.hessians = l_hess;
  cb.gaps = ceiling; cb.gap_gradients = ceiling_grad;
  CHECK(vci_model_create_lagrangian(&model, 1, 0, 1, &cb, NULL) == VCI_OK);
  on = impacts_of_run(model, -1);
  off = impacts_of_run(model, 0);
  on_again = impacts_of_run(model, 1);
  printf("impacts: default %lld, off %lld, on %lld\n", (long long)on, (long long)off, (long long)on_again);
  CHECK(on == 1);
  CHECK(off == 0);
  CHECK(on_again == 1);
  CHECK(vci_set_poke_samples(NULL, 1) == VCI_ERR_ARGUMENT);
  CHECK(vci_integrator_create(&it, model, 1.0e-2) == VCI_OK);
  CHECK(vci_set_poke_samples(it, 2) == VCI_ERR_ARGUMENT);
  CHECK(vci_set_poke_samples(it, -1) == VCI_ERR_ARGUMENT);
  CHECK(vci_set_poke_samples(it, 0) == VCI_OK);
  vci_integrator_destroy(&it);
  vci_model_destroy(&model);
  printf("%s: %d failed\n", failures ? "FAIL" : "ok", failures);
  return failures;
}
