/* A random-input harness for the C ABI (vci.h): random programs of 1 to 40 calls on random models,
 * with random, often invalid, arguments (NULL, stale and garbage handles, NaN, Inf, huge or
 * negative sizes and counts) and callbacks that fail at random calls with positive or negative
 * codes, or return NaN, Inf or +-1e308. Each program runs in a child process under alarm(): the
 * parent reports a crash (signal), a hang (SIGALRM), an exit from library code (status 70), NaN or
 * Inf handed to LAPACK (status 71, lapack_guard.c), a broken promise of the API (status 72), or
 * a sanitizer report (the sanitizer's exit status). The seeds are fixed, so a failure replays:
 *
 *   vci_fuzz SEED_FIRST SEED_COUNT [SECONDS]     run the seeds, stop early after SECONDS (default 60)
 *   vci_fuzz -1 SEED                             run one seed in this process (for a debugger)
 */
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include "vci.h"
#include "../api/lapack_guard.h"

/* ---- a small deterministic generator (xorshift64*) ---- */
static uint64_t rng_state;
static uint64_t rnd(void) {
  rng_state ^= rng_state >> 12;
  rng_state ^= rng_state << 25;
  rng_state ^= rng_state >> 27;
  return rng_state * 2685821657736338717ULL;
}
static int below(int n) { return n <= 0 ? 0 : (int)(rnd() % (uint64_t)n); }
static double uniform(double a, double b) { return a + (b - a) * (double)(rnd() >> 11) / 9007199254740992.0; }
static int chance(int percent) { return below(100) < percent; }

/* a double that is often ordinary and sometimes hostile */
static double wild(double typical) {
  static const double hostile[] = {0.0, -0.0, 1e308, -1e308, 1e-308, 5e-324, 1e20, -1e20};
  switch (below(12)) {
  case 0: return NAN;
  case 1: return chance(50) ? INFINITY : -INFINITY;
  case 2: return hostile[below(8)];
  default: return typical * uniform(-2.0, 2.0);
  }
}
static int wild_int(int typical) {
  static const int hostile[] = {0, -1, 1, 2147483647, -2147483647 - 1, 46341, 100000, 1000000000};
  return chance(20) ? hostile[below(8)] : below(typical + 1);
}

/* ---- the model: L_d(q, v, h) = h [ sum_i mass_i (v_i - q_i)^2 / (2 h^2) - V((q + v)/2) ],
 * V(x) = sum_i (grav_i x_i + stiff_i x_i^2 / 2); constraints a_mu . qdot = 0 (omega_d = a_mu .
 * (other - base) / h); walls g_j = normal_j . q - offset_j >= 0. Faults: a callback fails from
 * a random call on, now and then, with a random code or output. ---- */
enum { MAXN = 4, MAXM = 2, MAXG = 6, NCALLBACKS = 9 };
typedef struct {
  int n, m, ng;
  double mass[MAXN], grav[MAXN], stiff[MAXN], a[MAXM][MAXN], normal[MAXG][MAXN], offset[MAXG];
  int fault_which, fault_from, fault_every, fault_kind, fault_code;
  long calls[NCALLBACKS];
} model_t;

static int fault(model_t *md, int which, double *out, int nout) {
  long c = ++md->calls[which];
  if (md->fault_which != which || c < md->fault_from || (c - md->fault_from) % md->fault_every != 0) return 0;
  switch (md->fault_kind) {
  case 0: return md->fault_code;                              /* failure code, either sign */
  case 1: if (nout > 0) out[c % nout] = NAN; return 0;
  case 2: if (nout > 0) out[c % nout] = (c & 1) ? INFINITY : -INFINITY; return 0;
  case 3: if (nout > 0) out[c % nout] = (c & 1) ? 1e308 : -1e308; return 0;
  default: return 0;
  }
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

static int impact_calls = 0, impact_fail_at = -1;
static int cb_impact(double t, double alpha, int gap, const double *q, double impulse, void *user) {
  (void)t; (void)alpha; (void)gap; (void)q; (void)impulse; (void)user;
  return ++impact_calls == impact_fail_at ? (chance(50) ? 9 : -9) : 0;
}

/* the walls leave the reference point `ref` (where programs start) inside the admissible set */
static double ref[MAXN];

static void random_model(model_t *md) {
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
  md->fault_which = chance(60) ? below(NCALLBACKS) : -1;
  md->fault_from = 1 + below(400);
  md->fault_every = 1 + below(chance(50) ? 3 : 50);
  md->fault_kind = below(4);
  md->fault_code = chance(50) ? 1 + below(100) : -1 - below(100);
  if (chance(3)) md->fault_code = chance(50) ? 2147483647 : -2147483647 - 1;
}

/* ---- the promises checked on the way (exit status 72 when one is broken) ---- */
static void promise(int ok, const char *what) {
  if (!ok) {
    printf("broken promise: %s\n", what);
    fflush(stdout);
    _exit(72);
  }
}

static void check_status(int s) { promise(s >= VCI_OK && s <= VCI_ERR_MEMORY, "status within the enum"); }

static int finished = 0, trace = 0;
static void exit_guard(void) {
  if (!finished) {
    printf("exit() during the program (library code ended the process)\n");
    fflush(stdout);
    _exit(70);
  }
}

/* One random program. */
static void program(uint64_t seed) {
  enum { NM = 3, NI = 4 };
  model_t models[NM];
  vci_model mh[NM] = {NULL};
  vci_integrator ih[NI] = {NULL}, stale = NULL;
  char msg[600], path[64];
  int ncalls, c, histogram[VCI_ERR_MEMORY + 1] = {0};
  rng_state = seed * 0x9E3779B97F4A7C15ULL + 1;
  impact_calls = 0;
  impact_fail_at = chance(30) ? 1 + below(5) : -1;
  snprintf(path, sizeof path, "fuzz_%ld.h5", (long)getpid());
  for (c = 0; c < MAXN; ++c) ref[c] = uniform(-1.0, 1.0);
  ncalls = 1 + below(40);
  if (chance(85)) { /* most programs start with a working integrator, so that steps get taken */
    vci_callbacks cb = VCI_CALLBACKS_INIT;
    double q0[MAXN], q1[MAXN];
    random_model(&models[0]);
    cb.d1_ld = cb_d1; cb.d2_ld = cb_d2; cb.d3_ld = cb_d3; cb.constraint_forms = cb_forms;
    cb.discrete_constraint = cb_dconstraint; cb.gaps = cb_gaps;
    if (chance(50)) cb.mixed_hessian = cb_hessian;
    if (chance(50)) cb.gap_gradients = cb_gap_grads;
    if (chance(70)) cb.energy = cb_energy;
    check_status(vci_model_create(&mh[0], models[0].n, models[0].m, models[0].ng, &cb, &models[0]));
    check_status(vci_integrator_create(&ih[0], mh[0], uniform(2e-3, 3e-2)));
    for (c = 0; c < MAXN; ++c) {
      q0[c] = ref[c];
      q1[c] = ref[c] + uniform(-0.02, 0.02);
    }
    /* a pair that moves off the constraint gets a multiplier; one across a wall is refused */
    check_status(vci_init_from_pair(ih[0], 0.0, q0, q1));
  }
  for (c = 0; c < ncalls; ++c) {
    int k = chance(70) ? 0 : below(NI), j = chance(50) ? 0 : below(NM), s = VCI_OK, i;
    vci_integrator it = chance(3) ? stale : (chance(2) ? (vci_integrator)(uintptr_t)rnd() : ih[k]);
    double q0[MAXN], q1[MAXN], t, e, lambda[MAXM];
    int64_t kk, st, im, ni;
    int what = below(22);
    if (what >= 16) what = 5;   /* integrate most often */
    if (trace) printf("call %d: case %d on integrator %d\n", c, what, k), fflush(stdout);
    switch (what) {
    case 0: { /* a model */
      vci_callbacks cb = VCI_CALLBACKS_INIT;
      int n, m, ng;
      random_model(&models[j]);
      n = models[j].n; m = models[j].m; ng = models[j].ng;
      cb.d1_ld = cb_d1; cb.d2_ld = cb_d2; cb.d3_ld = cb_d3;
      if (chance(50)) cb.mixed_hessian = cb_hessian;
      cb.constraint_forms = cb_forms; cb.discrete_constraint = cb_dconstraint;
      cb.gaps = cb_gaps;
      if (chance(50)) cb.gap_gradients = cb_gap_grads;
      if (chance(70)) cb.energy = cb_energy;
      if (chance(5)) cb.d2_ld = NULL;
      if (chance(5)) cb.size = (size_t)below((int)sizeof cb + 1); /* an older or broken header; never beyond
                                                                   the struct (a caller's lie the library cannot see) */
      if (chance(10)) { n = wild_int(4); m = wild_int(2); ng = wild_int(6); }
      if (n > MAXN || m > MAXM || ng > MAXG) { /* sizes the callbacks cannot serve: must be refused or unused */
        if (n > 0 && n <= 46339 && m >= 0 && m <= n && ng >= 0) n = MAXN + 1 + below(3);
      }
      vci_model_destroy(&mh[j]);
      if (n <= MAXN && m <= MAXM && ng <= MAXG) {
        s = vci_model_create(&mh[j], n, m, ng, &cb, &models[j]);
        promise((s == VCI_OK) == (mh[j] != NULL), "model handle set iff VCI_OK");
      } else {
        /* sizes beyond what these callbacks can serve: only the refused ones are created */
        vci_model tmp = NULL;
        s = vci_model_create(&tmp, n, m, ng, &cb, &models[j]);
        if (s == VCI_OK) vci_model_destroy(&tmp);
      }
      break;
    }
    case 1: /* an integrator */
      vci_integrator_destroy(&ih[k]);
      s = vci_integrator_create(&ih[k], chance(5) ? (vci_model)ih[0] : mh[j], chance(80) ? uniform(1e-3, 5e-2) : wild(1e-2));
      promise((s == VCI_OK) == (ih[k] != NULL), "integrator handle set iff VCI_OK");
      break;
    case 2:
      if (chance(30)) stale = ih[k];
      vci_integrator_destroy(chance(5) ? NULL : &ih[k]);
      break;
    case 3: case 4: { /* a start */
      for (i = 0; i < MAXN; ++i) {
        q0[i] = chance(95) ? ref[i] + uniform(-0.05, 0.05) : wild(1.0);
        q1[i] = q0[i] + (chance(90) ? uniform(-0.05, 0.05) : wild(0.05));
      }
      if (chance(50))
        s = vci_init_from_pair(it, chance(90) ? uniform(-5.0, 5.0) : wild(1.0), chance(3) ? NULL : q0, q1);
      else
        s = vci_init_from_momentum(it, uniform(-5.0, 5.0), q0, chance(3) ? NULL : q1);
      break;
    }
    case 5: case 6: case 7:
      /* hostile counts are negative: a huge positive one is a long run, not a fault */
      s = vci_integrate(it, chance(95) ? below(200) : (chance(50) ? -1 - below(3) : INT64_MIN),
                        chance(90) ? (chance(70) ? 1 : -1) : wild_int(3));
      break;
    case 8:
      s = vci_step(it, chance(90) ? (chance(70) ? 1 : -1) : wild_int(3));
      break;
    case 9:
      s = vci_get_state(it, chance(80) ? &t : NULL, chance(80) ? q0 : NULL, chance(80) ? q1 : NULL);
      if (s == VCI_OK && it == ih[k]) s = vci_get_multipliers(it, lambda);
      break;
    case 10:
      s = vci_get_energy(it, chance(90) ? &e : NULL);
      if (s == VCI_OK) s = vci_get_index(it, &kk);
      if (s == VCI_OK) s = vci_get_stats(it, &st, chance(80) ? &im : NULL, &ni);
      if (s == VCI_OK) promise(st >= 0 && ni >= 0, "counters are not negative");
      break;
    case 11: {
      double atol = chance(70) ? 0.0 : wild(1e-10), rtol = chance(70) ? uniform(1e-13, 1e-6) : wild(1e-10);
      int maxit = chance(80) ? 1 + below(40) : wild_int(50);
      if (trace) printf("  set_tolerances(%g, %g, %d)\n", atol, rtol, maxit);
      s = vci_set_tolerances(it, atol, rtol, maxit);
      break;
    }
    case 12:
      s = chance(50) ? vci_set_impact_energy(it, chance(90) ? below(2) : wild_int(3))
                     : vci_set_max_impacts(it, chance(80) ? 1 + below(20) : wild_int(30));
      break;
    case 13:
      s = vci_set_impact_callback(it, chance(80) ? cb_impact : NULL, NULL);
      break;
    case 14:
      s = chance(70) ? vci_open_output(it, chance(95) ? path : (chance(50) ? "" : "/nonexistent-dir/f.h5"))
                     : vci_close_output(it);
      break;
    default:
      s = vci_last_error(chance(90) ? it : NULL, chance(95) ? msg : NULL, chance(95) ? (int)sizeof msg : wild_int(3));
      if (s == VCI_OK) promise(memchr(msg, '\0', sizeof msg) != NULL, "message NUL-terminated");
      break;
    }
    check_status(s);
    ++histogram[s];
    if (s != VCI_OK && it != NULL) {
      /* a failure always says why (through the integrator, or the thread's message) */
      msg[0] = '\0';
      if (vci_last_error(it, msg, sizeof msg) != VCI_OK) vci_last_error(NULL, msg, sizeof msg);
    }
    (void)vci_status_string(s);
  }
  if (getenv("VCI_FUZZ_VERBOSE")) { /* what the program got done, for judging the harness */
    int64_t steps = 0, total = 0;
    for (c = 0; c < NI; ++c)
      if (vci_get_stats(ih[c], &steps, NULL, NULL) == VCI_OK) total += steps;
    printf("seed %llu: %d calls, %lld steps on live integrators, statuses", (unsigned long long)seed, ncalls,
           (long long)total);
    for (c = 0; c <= VCI_ERR_MEMORY; ++c) printf(" %d", histogram[c]);
    printf("\n");
  }
  for (c = 0; c < NI; ++c) vci_integrator_destroy(&ih[c]);
  for (c = 0; c < NM; ++c) vci_model_destroy(&mh[c]);
  remove(path);
  if (vci_test_lapack_nonfinite_calls() != 0) _exit(71); /* (the guard exits at once anyway) */
}

static void run_child(uint64_t seed) {
  atexit(exit_guard);
  /* a hang: SIGALRM ends the child; 20 s, or VCI_FUZZ_CHILD_SECONDS (the sanitizer build runs
   * 4-5x slower: a program of 5 s in release is no hang there) */
  const char *env = getenv("VCI_FUZZ_CHILD_SECONDS");
  unsigned limit = env != NULL && atoi(env) > 0 ? (unsigned)atoi(env) : 20u;
  alarm(limit);
  program(seed);
  finished = 1;
  exit(0); /* normal exit: sanitizers report leaks here */
}

int main(int argc, char **argv) {
  long first, count, i, ran = 0, bad = 0;
  double budget;
  time_t start = time(NULL);
  trace = getenv("VCI_FUZZ_TRACE") != NULL;
  setenv("VCI_LAPACK_GUARD_EXIT", "1", 1); /* NaN/Inf to LAPACK ends the child at once: status 71 */
  if (argc == 3 && atol(argv[1]) == -1) { /* one seed in this process */
    run_child((uint64_t)atoll(argv[2]));
    return 0;
  }
  if (argc < 3) {
    fprintf(stderr, "usage: vci_fuzz SEED_FIRST SEED_COUNT [SECONDS] | vci_fuzz -1 SEED\n");
    return 2;
  }
  first = atol(argv[1]);
  count = atol(argv[2]);
  budget = argc > 3 ? atof(argv[3]) : 60.0;
  for (i = 0; i < count; ++i) {
    pid_t pid;
    int status;
    if (difftime(time(NULL), start) > budget) break;
    fflush(stdout);
    pid = fork();
    if (pid < 0) {
      perror("fork");
      return 2;
    }
    if (pid == 0) run_child((uint64_t)(first + i));
    waitpid(pid, &status, 0);
    ++ran;
    if (bad >= 5) { /* enough to act on; the rest would repeat the reports */
      printf("stopping after 5 failures\n");
      break;
    }
    if (WIFSIGNALED(status)) {
      ++bad;
      printf("FAIL seed %ld: %s (signal %d)\n", first + i, WTERMSIG(status) == SIGALRM ? "hang" : "crash", WTERMSIG(status));
    } else if (WEXITSTATUS(status) != 0) {
      static const char *why[] = {"exit from library code", "NaN/Inf given to LAPACK", "broken promise"};
      int code = WEXITSTATUS(status);
      ++bad;
      printf("FAIL seed %ld: exit status %d (%s)\n", first + i, code,
             code >= 70 && code <= 72 ? why[code - 70] : "sanitizer report or runtime error");
    }
  }
  printf("%ld random programs (seeds %ld..%ld) in %.0f s: %ld failed%s\n", ran, first, first + ran - 1,
         difftime(time(NULL), start), bad, ran < count ? " (time budget reached)" : "");
  return bad ? 1 : 0;
}
