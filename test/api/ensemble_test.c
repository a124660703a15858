/* Ensembles through the C ABI (vci_ensemble_run, vci_ensemble_run_file).
 * Usage: vci_ensemble_test run | bad | file PATH.
 *  run:  the walled pendulum (theta'' = -9.8 sin theta, walls at +-1 rad) as a continuous model with
 *        lobatto s = 4, 24 members theta'(0) = 0.5 .. 6 (some never reach a wall, some bounce) and one
 *        that starts outside the walls, on 2 threads; and the paper's ellipse (a discrete model) from
 *        examples/c/scenes.h. Every member equals the same run made alone through vci_integrator
 *        (state, steps, impacts, impact times, energy), bit for bit; only the bad start fails.
 *  bad:  NULL pointers, dead handles, struct sizes of no header, settings out of range: statuses
 *        and messages.
 *  file: the same pendulum ensemble to the ensemble HDF5 file PATH: status, members_failed, an
 *        existing file kept unless overwrite (the Python suite reads the file back). Built with
 *        MPI (VCI_TEST_MPI) it runs under mpirun, collective over MPI_COMM_WORLD given as its
 *        Fortran handle; ensemble_mpi_c.sh compares the files of 1 and 2 ranks. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "vci.h"
#include "walls_lagrangian.h"
#include "scenes.h"
#ifdef VCI_TEST_MPI
#include <mpi.h>
#endif

static int failures = 0;
#define CHECK(c) do { if (!(c)) { printf("  line %d: CHECK(%s) failed\n", __LINE__, #c); failures++; } } while (0)

/* dL/dq of the walled pendulum (the rest: walls_lagrangian.h); no shared state */
static int l_dq(int n, const double *q, const double *v, double *out, void *user) {
  (void)n; (void)v; (void)user;
  out[0] = -9.8 * sin(q[0]);
  return 0;
}

static vci_model pendulum_model(void) {
  vci_lagrangian_callbacks cb = VCI_LAGRANGIAN_CALLBACKS_INIT;
  vci_model model = NULL;
  cb.lagrangian = l_value; cb.dl_dq = l_dq; cb.dl_dv = l_dv; cb.hessians = l_hess;
  cb.gaps = walls; cb.gap_gradients = wall_grads;
  CHECK(vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) == VCI_OK);
  return model;
}

#define NP 25      /* pendulum members: 24 good ones and member BAD */
#define BAD 7      /* starts at theta = 1.5, outside the wall at 1 */
#define CAP 8      /* impact times kept per member */

static void pendulum_starts(double *t0, double *q0, double *p0) {
  for (int k = 0; k < NP; k++) {
    t0[k] = 0.1 * k;
    q0[k] = 0.0;
    p0[k] = 0.5 + 5.5 * k / (NP - 1);
  }
  q0[BAD] = 1.5;
}

static vci_ensemble_config pendulum_config(void) {
  vci_ensemble_config c = VCI_ENSEMBLE_CONFIG_INIT;
  c.h = 0.05; c.nsteps = 200; c.start_kind = VCI_START_MOMENTUM;
  c.scheme = VCI_SCHEME_LOBATTO; c.stages = 4; c.rtol = 1e-15; c.impact_cap = CAP; c.threads = 2;
  return c;
}

/* One member alone: what the ensemble must reproduce. */
typedef struct {
  int status;
  double t, q[3], p[3], energy, impact_t[CAP];
  int64_t steps, impacts, newton;
  int impact_gap[CAP], kept;
} single_run;

static int on_impact(double t, double alpha, int gap, const double *q, double impulse, void *user) {
  single_run *r = user;
  (void)alpha; (void)q; (void)impulse;
  if (r->kept < CAP) { r->impact_t[r->kept] = t; r->impact_gap[r->kept] = gap; r->kept++; }
  return 0;
}

static single_run run_alone(vci_model model, int n, const vci_ensemble_config *c, double t0, const double *q0,
                            const double *v0) {
  single_run r;
  vci_integrator it = NULL;
  memset(&r, 0, sizeof r);
  int st = vci_integrator_create(&it, model, c->h);
  if (st == VCI_OK && c->scheme >= 0) st = vci_set_scheme(it, (int)c->scheme, (int)c->stages);
  if (st == VCI_OK && c->rtol >= 0) st = vci_set_tolerances(it, 0.0, c->rtol, 30);
  if (st == VCI_OK) st = vci_set_impact_callback(it, on_impact, &r);
  if (st == VCI_OK)
    st = c->start_kind == VCI_START_MOMENTUM ? vci_init_from_momentum(it, t0, q0, v0) : vci_init_from_pair(it, t0, q0, v0);
  if (st == VCI_OK) st = vci_integrate(it, c->nsteps, (int)c->direction);
  r.status = st;
  if (vci_get_state(it, &r.t, r.q, r.p) != VCI_OK) r.t = NAN;
  vci_get_energy(it, &r.energy);
  vci_get_stats(it, &r.steps, &r.impacts, &r.newton);
  (void)n;
  vci_integrator_destroy(&it);
  return r;
}

static int same(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

/* Member k of the results against its run alone (n coordinates). */
static void compare_member(int k, int n, const single_run *r, const int *status, const double *t, const double *q,
                           const double *p, const int64_t *steps, const int64_t *impacts, const double *energy_end,
                           const double *impact_t, const int *impact_gap) {
  if (isnan(r->t)) {   /* refused at its start: no state alone, none in the ensemble */
    CHECK(status[k] == r->status && r->status != VCI_OK && isnan(t[k]) && isnan(q[n * k]) && steps[k] == 0);
    return;
  }
  int ok = status[k] == r->status && same(t[k], r->t) && steps[k] == r->steps && impacts[k] == r->impacts;
  for (int i = 0; i < n; i++) ok = ok && same(q[i + n * k], r->q[i]) && same(p[i + n * k], r->p[i]);
  ok = ok && same(energy_end[k], r->energy);
  for (int j = 0; j < CAP; j++) {
    if (j < r->kept) ok = ok && same(impact_t[j + CAP * k], r->impact_t[j]) && impact_gap[j + CAP * k] == r->impact_gap[j];
    else ok = ok && isnan(impact_t[j + CAP * k]) && impact_gap[j + CAP * k] == -1;
  }
  if (!ok) {
    printf("  member %d: ensemble status %d t %a q0 %a p0 %a steps %lld impacts %lld E %a\n", k, status[k], t[k], q[n * k],
           p[n * k], (long long)steps[k], (long long)impacts[k], energy_end[k]);
    printf("  member %d: alone    status %d t %a q0 %a p0 %a steps %lld impacts %lld E %a\n", k, r->status, r->t,
           r->q[0], r->p[0], (long long)r->steps, (long long)r->impacts, r->energy);
  }
  CHECK(ok);
}

static void suite_run(void) {
  /* the continuous pendulum */
  double t0[NP], q0[NP], p0[NP], t[NP], q[NP], p[NP], e0[NP], e1[NP], it_[CAP * NP];
  int status[NP], gap[CAP * NP];
  int64_t steps[NP], impacts[NP], newton[NP];
  char msg[NP][160];
  vci_model model = pendulum_model();
  vci_ensemble_config c = pendulum_config();
  vci_ensemble_results r = VCI_ENSEMBLE_RESULTS_INIT;
  pendulum_starts(t0, q0, p0);
  r.status = status; r.t = t; r.q = q; r.p = p; r.steps = steps; r.impacts = impacts; r.newton_iterations = newton;
  r.energy_start = e0; r.energy_end = e1; r.impact_t = it_; r.impact_gap = gap;
  r.messages = &msg[0][0]; r.message_size = sizeof msg[0];
  CHECK(vci_ensemble_run(model, &c, NP, t0, q0, p0, &r) == VCI_OK);
  int bouncing = 0, failed = 0;
  for (int k = 0; k < NP; k++) {
    single_run one = run_alone(model, 1, &c, t0[k], &q0[k], &p0[k]);
    compare_member(k, 1, &one, status, t, q, p, steps, impacts, e1, it_, gap);
    if (status[k] != VCI_OK) { failed++; printf("  member %d: %s\n", k, msg[k]); }
    else CHECK(msg[k][0] == '\0');
    if (impacts[k] > 0) bouncing++;
  }
  printf("  pendulum: %d members, %d with impacts, %d failed\n", NP, bouncing, failed);
  CHECK(failed == 1 && status[BAD] == VCI_ERR_INADMISSIBLE && strstr(msg[BAD], "admissible") != NULL);
  CHECK(bouncing >= NP / 2 && bouncing < NP - 1);   /* both kinds of member are there */
  CHECK(impacts[NP - 1] > CAP);                      /* the cap keeps the first CAP times, counts all */

  /* the same on one thread, results NULL but status and q: the same bits */
  {
    double q1t[NP];
    int st1[NP];
    vci_ensemble_results r1 = VCI_ENSEMBLE_RESULTS_INIT;
    r1.status = st1; r1.q = q1t;
    c.threads = 1;
    CHECK(vci_ensemble_run(model, &c, NP, t0, q0, p0, &r1) == VCI_OK);
    for (int k = 0; k < NP; k++) CHECK(st1[k] == status[k] && (k == BAD || same(q1t[k], q[k])));
  }
  vci_model_destroy(&model);

  /* the paper's ellipse, a discrete model, from its initial pair turned by 1e-3 k */
  {
    enum { NE = 9, N = 3 };
    double et0[NE], eq0[N * NE], eq1[N * NE], et[NE], eq[N * NE], ep[N * NE], ee0[NE], ee1[NE], eit[CAP * NE];
    int est[NE], egap[CAP * NE];
    int64_t esteps[NE], eimp[NE];
    ellipse_params par = ellipse_default;
    vci_callbacks cb = ellipse_callbacks();
    vci_model em = NULL;
    vci_ensemble_config ec = VCI_ENSEMBLE_CONFIG_INIT;
    vci_ensemble_results er = VCI_ENSEMBLE_RESULTS_INIT;
    CHECK(vci_model_create(&em, N, 0, 1, &cb, &par) == VCI_OK);
    ec.h = 1e-2; ec.nsteps = 300; ec.impact_cap = CAP; ec.threads = 2;
    for (int k = 0; k < NE; k++) {
      ellipse_initial_pair(ec.h, &et0[k], &eq0[N * k], &eq1[N * k]);
      eq0[N * k] += 1e-3 * k; eq1[N * k] += 1e-3 * k;
    }
    er.status = est; er.t = et; er.q = eq; er.p = ep; er.steps = esteps; er.impacts = eimp;
    er.energy_start = ee0; er.energy_end = ee1; er.impact_t = eit; er.impact_gap = egap;
    CHECK(vci_ensemble_run(em, &ec, NE, et0, eq0, eq1, &er) == VCI_OK);
    int with_impacts = 0;
    for (int k = 0; k < NE; k++) {
      single_run one = run_alone(em, N, &ec, et0[k], &eq0[N * k], &eq1[N * k]);
      ellipse_energy(N, one.q, one.p, &one.energy, &par);   /* the ellipse has H: energy_end is H(q, p) */
      compare_member(k, N, &one, est, et, eq, ep, esteps, eimp, ee1, eit, egap);
      CHECK(est[k] == VCI_OK);
      if (eimp[k] > 0) with_impacts++;
    }
    /* the ellipse has energy: energy_start/end are H, conserved to the method's O(h^2) = 1e-4 */
    for (int k = 0; k < NE; k++) CHECK(fabs(ee1[k] - ee0[k]) <= 1e-3 * fabs(ee0[k]));
    printf("  ellipse: %d members, %d with impacts\n", NE, with_impacts);
    CHECK(with_impacts == NE);
    vci_model_destroy(&em);
  }
}

static void last_error_has(const char *part) {
  char buf[512];
  vci_last_error(NULL, buf, sizeof buf);
  if (!strstr(buf, part)) printf("  message \"%s\" lacks \"%s\"\n", buf, part);
  CHECK(strstr(buf, part) != NULL);
}

static void suite_bad(void) {
  double t0[NP], q0[NP], p0[NP], q[NP];
  int status[NP];
  char small[NP][4];
  vci_model model = pendulum_model(), dead = pendulum_model();
  vci_model kept_dead = dead;
  vci_ensemble_config c = pendulum_config();
  vci_ensemble_results r = VCI_ENSEMBLE_RESULTS_INIT;
  pendulum_starts(t0, q0, p0);
  r.status = status; r.q = q;
  vci_model_destroy(&dead);

  CHECK(vci_ensemble_run(NULL, &c, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
  last_error_has("model handle is NULL");
  CHECK(vci_ensemble_run(kept_dead, &c, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
  last_error_has("not a live model handle");
  CHECK(vci_ensemble_run(model, NULL, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
  last_error_has("config argument is NULL");
  CHECK(vci_ensemble_run(model, &c, NP, NULL, q0, p0, &r) == VCI_ERR_ARGUMENT);
  last_error_has("t0, q0 or v0 is NULL");
  CHECK(vci_ensemble_run(model, &c, NP, t0, q0, NULL, &r) == VCI_ERR_ARGUMENT);
  CHECK(vci_ensemble_run(model, &c, NP, t0, q0, p0, NULL) == VCI_ERR_ARGUMENT);
  last_error_has("results argument is NULL");
  CHECK(vci_ensemble_run(model, &c, 0, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
  last_error_has("members = 0");
  CHECK(vci_ensemble_run(model, &c, (int64_t)1 << 40, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);

  /* struct sizes: not a whole number of members, too small, a newer header's with a member set */
  {
    vci_ensemble_config b = c;
    b.size = sizeof b - 4;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    last_error_has("config->size");
    b.size = 16;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    b.size = 0;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    struct { vci_ensemble_config c; int64_t extra; } newer = {c, 7};
    newer.c.size = sizeof newer;
    CHECK(vci_ensemble_run(model, &newer.c, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    last_error_has("newer vci.h");
    newer.extra = 0;     /* a newer header's struct with its new member left 0: fine */
    CHECK(vci_ensemble_run(model, &newer.c, NP, t0, q0, p0, &r) == VCI_OK);
    /* an older header's struct (up to nsteps): the rest defaults, i.e. midpoint, pair start, 1 member ok */
    vci_ensemble_config old = VCI_ENSEMBLE_CONFIG_INIT;
    double a = 0.0, b1 = 0.05;
    int st1 = -5;
    vci_ensemble_results r1 = VCI_ENSEMBLE_RESULTS_INIT;
    old.h = 0.05; old.nsteps = 10; old.size = offsetof(vci_ensemble_config, direction);
    old.start_kind = VCI_START_MOMENTUM; old.threads = -1;   /* beyond its size: not read (-1 would be refused) */
    r1.status = &st1;
    CHECK(vci_ensemble_run(model, &old, 1, &a, &a, &b1, &r1) == VCI_OK && st1 == VCI_OK);
    vci_ensemble_results rb = r;
    rb.size = 12;
    CHECK(vci_ensemble_run(model, &c, NP, t0, q0, p0, &rb) == VCI_ERR_ARGUMENT);
    last_error_has("results->size");
    rb = r; rb.messages = &small[0][0]; rb.message_size = 0;
    CHECK(vci_ensemble_run(model, &c, NP, t0, q0, p0, &rb) == VCI_ERR_ARGUMENT);
    last_error_has("message_size");
    /* a short message slot: truncated and NUL-terminated */
    rb.message_size = sizeof small[0];
    CHECK(vci_ensemble_run(model, &c, NP, t0, q0, p0, &rb) == VCI_OK);
    CHECK(small[BAD][3] == '\0' && strlen(small[BAD]) == 3 && small[0][0] == '\0');
  }

  /* settings */
  {
    vci_ensemble_config b = c;
    b.h = 0.0;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    last_error_has("step length");
    b = c; b.h = NAN;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    b = c; b.nsteps = -1;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    b = c; b.direction = 0;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    b = c; b.start_kind = 2;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    b = c; b.stages = 9;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    last_error_has("stages = 9");
    b = c; b.scheme = VCI_SCHEME_COMPOSITION;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    last_error_has("scheme = 4");
    b = c; b.impact_energy = 2;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    b = c; b.threads = -1;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    b = c; b.atol = 0.0; b.rtol = 0.0;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    b = c; b.threads = (int64_t)1 << 40;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_ERR_ARGUMENT);
    /* hamiltonian impacts (H by Legendre inversion of dl_dv): every member but the bad start runs */
    b = c; b.impact_energy = VCI_IMPACT_HAMILTONIAN;
    CHECK(vci_ensemble_run(model, &b, NP, t0, q0, p0, &r) == VCI_OK);
    for (int k = 0; k < NP; k++) CHECK(status[k] == (k == BAD ? VCI_ERR_INADMISSIBLE : VCI_OK));
  }
  /* a scheme for a discrete model */
  {
    ellipse_params par = ellipse_default;
    vci_callbacks cb = ellipse_callbacks();
    vci_model em = NULL;
    vci_ensemble_config ec = VCI_ENSEMBLE_CONFIG_INIT;
    double et0, eq0[3], eq1[3];
    ec.h = 1e-2; ec.nsteps = 3; ec.scheme = VCI_SCHEME_MIDPOINT;
    ellipse_initial_pair(ec.h, &et0, eq0, eq1);
    CHECK(vci_model_create(&em, 3, 0, 1, &cb, &par) == VCI_OK);
    CHECK(vci_ensemble_run(em, &ec, 1, &et0, eq0, eq1, &r) == VCI_ERR_ARGUMENT);
    last_error_has("discrete model");
    vci_model_destroy(&em);
  }
  /* the file entry's own arguments */
  {
    int64_t nf = -3;
    CHECK(vci_ensemble_run_file(model, &c, NP, t0, q0, p0, NULL, 0, -1, &nf) == VCI_ERR_ARGUMENT && nf == 0);
    last_error_has("path is NULL or empty");
    CHECK(vci_ensemble_run_file(model, &c, NP, t0, q0, p0, "", 0, -1, NULL) == VCI_ERR_ARGUMENT);
  }
  vci_model_destroy(&model);
}

static void suite_file(const char *path) {
#ifdef VCI_TEST_HDF5
  double t0[NP], q0[NP], p0[NP];
  int64_t failed = -1;
  vci_model model = pendulum_model();
  vci_ensemble_config c = pendulum_config();
  pendulum_starts(t0, q0, p0);
  int comm = -1, rank = 0;
  c.stride = 50;
#ifdef VCI_TEST_MPI
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  comm = (int)MPI_Comm_c2f(MPI_COMM_WORLD);
#endif
  if (rank == 0) remove(path);
#ifdef VCI_TEST_MPI
  MPI_Barrier(MPI_COMM_WORLD);
#endif
  CHECK(vci_ensemble_run_file(model, &c, NP, t0, q0, p0, path, 0, comm, &failed) == VCI_OK);
  CHECK(failed == 1);
  /* an existing file is kept unless overwrite */
  CHECK(vci_ensemble_run_file(model, &c, NP, t0, q0, p0, path, 0, comm, &failed) == VCI_ERR_IO);
  last_error_has(path);
  CHECK(vci_ensemble_run_file(model, &c, NP, t0, q0, p0, path, 1, -1, &failed) == VCI_OK && failed == 1);
  vci_model_destroy(&model);
#else
  double x = 0.0;
  vci_model model = pendulum_model();
  vci_ensemble_config c = pendulum_config();
  CHECK(vci_ensemble_run_file(model, &c, 1, &x, &x, &x, path, 0, -1, NULL) == VCI_ERR_IO);
  last_error_has("without HDF5");
  vci_model_destroy(&model);
#endif
}

int main(int argc, char **argv) {
  if (argc < 2) {
    printf("usage: %s run | bad | file PATH\n", argv[0]);
    return 2;
  }
#ifdef VCI_TEST_MPI
  int provided;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
#endif
  if (!strcmp(argv[1], "run")) suite_run();
  else if (!strcmp(argv[1], "bad")) suite_bad();
  else if (!strcmp(argv[1], "file") && argc > 2) suite_file(argv[2]);
  else {
    printf("unknown suite %s\n", argv[1]);
    return 2;
  }
  printf("%s: %d failure(s)\n", argv[1], failures);
#ifdef VCI_TEST_MPI
  MPI_Finalize();
#endif
  return failures ? 1 : 0;
}
