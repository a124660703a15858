/* A random-input harness for the C ABI (vci.h): random programs of 1 to 40 calls on random models
 * of every kind (discrete L_d: fuzz_discrete.c; continuous L and separable: fuzz_continuous.c),
 * with random, often invalid, arguments (NULL, stale and garbage handles, NaN, Inf, huge or
 * negative sizes and counts, schemes and stages out of range, wrong bandwidths and patterns) and
 * callbacks that fail at random calls with positive or negative codes, or return NaN, Inf or
 * +-1e308. Each program runs in a child process under a CPU-time limit and an alarm(): the parent
 * reports a crash (signal), a hang (SIGXCPU, or SIGALRM when blocked), an exit from library code (status 70), NaN or Inf handed to LAPACK (status 71,
 * lapack_guard.c), a broken promise of the API (status 72: a status not in the function's list in
 * vci.h, a failure without a message, a non-finite state, a handle set on failure), or a sanitizer
 * report (the sanitizer's exit status).
 *
 * --reversal: the reversal property instead (issue 24): a random continuous model without faults
 * (fuzz_continuous.c's four kinds, walls at random), a random scheme (left, midpoint, Lobatto s = 1..4,
 * compositions of order 2, 4, 6 for a separable model) and solver tolerance rtol; N steps forward
 * and N back must return (q0, p0) to REVERSAL_C * 2N * rtol (relative to 1 + |q0|, 1 + |p0|), at
 * index 0, with as many impacts back as forward; runs where the safety net split a step, an energy
 * fallback was taken or the library reported an irreversible impact (vci_get_split_steps,
 * vci_get_energy_fallbacks, vci_get_irreversible_impacts) are counted but not judged; those where
 * the directions differ in splits or fallbacks ("one-sided") are printed with where the two impact
 * lists first part (walked from the run's end), and counted apart for the left rule, which is not
 * symmetric; a one-sided run of a symmetric scheme fails unless the library reported an
 * irreversible impact in the step where the two directions part (parting_step: the steps are taken
 * one by one and each one's counters recorded; docs/BACKWARD.md). VCI_FUZZ_IMPACTS=1 prints both
 * lists. A run off only in its distance is judged against the scene's measured forward growth
 * (chaos_bound) and by whether reruns with rtol/10 and tiny start moves reproduce its error
 * (error_spread): within the bound and not reproduced, "chaotic"; beyond it and not reproduced,
 * "amplified round-off" (each counted apart); reproduced, broken whatever the bound says;
 * VCI_FUZZ_RTOL_SCALE, VCI_FUZZ_MOVE_START and VCI_FUZZ_ASYMMETRY change a seed's rtol, start or
 * backward walls to measure why (below).
 * The seeds are fixed, so a failure replays:
 *
 *   vci_fuzz [--reversal] SEED_FIRST SEED_COUNT [SECONDS]   run the seeds, stop after SECONDS (default 60)
 *   vci_fuzz [--reversal] -1 SEED                           run one seed in this process (for a debugger)
 */
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include "vci.h"
#include "fuzz_util.h"
#include "fuzz_discrete.h"
#include "fuzz_continuous.h"
#include "../api/lapack_guard.h"

/* Reversal tolerance: REVERSAL_C * 2N * rtol. Each of the 2N solves stops with a residual of at
 * most rtol relative to its terms; the constant covers the Newton matrices' condition (O(1) at
 * these h) and the impact solves' own tolerance. Measured over seeds 1-3000: at most 7.1 (a chain
 * with 43 impacts each way), above 1 in 3 of 2911 judged runs (docs/TESTING.md). */
#define REVERSAL_C 100.0
/* exit statuses of a reversal child beside 0 (held): judged broken, not judged (a step failed, the
 * net split steps or energy fallbacks were taken alike both ways, or the library reported an impact
 * it could not make reversible), not judged and one-sided with a symmetric scheme (the two
 * directions differ in splits or fallbacks) where the library reported the cause (an irreversible
 * impact: vci_get_irreversible_impacts), the same with the left rule (not symmetric: counted apart),
 * and one-sided with a symmetric scheme and no cause reported: a failure (issue 24 item 1 wants a
 * fallback never taken in one direction only; docs/BACKWARD.md) */
enum { EXIT_REVERSAL_BROKEN = 73, EXIT_REVERSAL_UNJUDGED = 74, EXIT_REVERSAL_ONE_SIDED = 75,
       EXIT_REVERSAL_ONE_SIDED_LEFT = 76, EXIT_REVERSAL_ONE_SIDED_UNEXPLAINED = 77,
       EXIT_REVERSAL_ONE_SIDED_ELSEWHERE = 78, EXIT_REVERSAL_CHAOTIC = 79, EXIT_REVERSAL_AMPLIFIED = 80 };
/* ... and 78: one-sided with a symmetric scheme where the library reported an irreversible impact,
 * but not in the step where the two directions part (parting_step below): the reported impact is
 * not what made the run one-sided, so it explains nothing (a failure); 79 and 80: off only in its
 * distance, with an error that reruns do not reproduce (error_spread: the solves' errors amplified),
 * within the scene's measured chaos (chaos_bound) or beyond it (both counted apart) */

/* The impacts of a reversal run, in the order met (forward: time increasing; backward: decreasing),
 * to find where the two directions first part (one-sided runs, sorted by cause: docs/BACKWARD.md) */
enum { MAX_LISTED_IMPACTS = 4096 };
typedef struct {
  int count;
  double t[MAX_LISTED_IMPACTS], impulse[MAX_LISTED_IMPACTS];
  int gap[MAX_LISTED_IMPACTS];
  /* the step each impact was met in, as the forward step of the same interval (step_counts) */
  int step[MAX_LISTED_IMPACTS], current_step;
  /* every impact point must be admissible: the most negative gap there, relative to its terms
   * (seed 14739 reflected at a point 1.4e-2 beyond another wall, crossed unseen) */
  const cmodel_t *md;
  double worst_gap;
} impact_list;
static int list_impact(double t, double alpha, int gap, const double *q, double impulse, void *user) {
  impact_list *l = (impact_list *)user;
  int i, j;
  (void)alpha;
  for (j = 0; j < l->md->ng; ++j) {
    double g = -l->md->offset[j], terms = fabs(l->md->offset[j]);
    for (i = 0; i < l->md->n; ++i) {
      g += l->md->normal[j][i] * q[i];
      terms += fabs(l->md->normal[j][i] * q[i]);
    }
    if (g / (1.0 + terms) < l->worst_gap) l->worst_gap = g / (1.0 + terms);
  }
  if (l->count < MAX_LISTED_IMPACTS) {
    l->t[l->count] = t; l->gap[l->count] = gap; l->impulse[l->count] = impulse;
    l->step[l->count] = l->current_step;
  }
  ++l->count;
  return 0;
}
/* Forward impact i and backward impact k are not the same impact: another wall or time (1e-6
 * relative), or another |impulse| (1e-6 relative). */
static int other_wall_or_time(const impact_list *f, int i, const impact_list *b, int k) {
  return f->gap[i] != b->gap[k] || fabs(f->t[i] - b->t[k]) > 1e-6 * (1.0 + fabs(f->t[i]));
}
static int other_impulse(const impact_list *f, int i, const impact_list *b, int k) {
  double mf = fabs(f->impulse[i]), mb = fabs(b->impulse[k]);
  return fabs(mf - mb) > 1e-6 * (1.0 + mf);
}
/* Walk the forward impacts from the run's end and the backward ones from their start (the same
 * end): the first pair that is not the same impact. Writes what differs; "none" when the lists
 * agree. */
static void first_difference(const impact_list *f, const impact_list *b, char *out, size_t size) {
  int k, nf = f->count < MAX_LISTED_IMPACTS ? f->count : MAX_LISTED_IMPACTS;
  int nb = b->count < MAX_LISTED_IMPACTS ? b->count : MAX_LISTED_IMPACTS;
  for (k = 0; k < nf && k < nb; ++k) {
    int i = nf - 1 - k;
    double tf = f->t[i], tb = b->t[k], mf = fabs(f->impulse[i]), mb = fabs(b->impulse[k]);
    if (other_wall_or_time(f, i, b, k)) {
      snprintf(out, size, "other-impact: forward #%d t %.6f wall %d, backward t %.6f wall %d", i, tf, f->gap[i], tb,
               b->gap[k]);
      return;
    }
    if (other_impulse(f, i, b, k)) {
      snprintf(out, size, "other-impulse: t %.6f wall %d, |impulse| forward %.6g backward %.6g", tf, f->gap[i], mf, mb);
      return;
    }
  }
  if (nf != nb) snprintf(out, size, "extra-impact: %d forward, %d backward, alike up to the shorter", nf, nb);
  else snprintf(out, size, "none");
}

/* What each step of a reversal run did, filed under the forward step that covers the same time
 * interval: forward step i runs from index i - 1 to i, and the backward run's j-th step (from index
 * N + 1 - j to N - j) is filed under interval N + 1 - j. Entries 1..N; the counters' increments
 * over the step (vci_get_stats' impacts, vci_get_split_steps, vci_get_energy_fallbacks,
 * vci_get_irreversible_impacts). */
enum { MAX_REVERSAL_STEPS = 100 };
typedef struct {
  int64_t impacts[MAX_REVERSAL_STEPS + 2], splits[MAX_REVERSAL_STEPS + 2], fallbacks[MAX_REVERSAL_STEPS + 2],
      irreversible[MAX_REVERSAL_STEPS + 2];
} step_counts;
enum { COUNTER_IMPACTS, COUNTER_SPLITS, COUNTER_FALLBACKS, COUNTER_IRREVERSIBLE, NCOUNTERS };
static void read_counters(vci_integrator it, int64_t c[NCOUNTERS]) {
  c[0] = c[1] = c[2] = c[3] = 0;
  vci_get_stats(it, NULL, &c[COUNTER_IMPACTS], NULL);
  vci_get_split_steps(it, &c[COUNTER_SPLITS], NULL);
  vci_get_energy_fallbacks(it, &c[COUNTER_FALLBACKS]);
  vci_get_irreversible_impacts(it, &c[COUNTER_IRREVERSIBLE]);
}
/* VCI_FUZZ_MOVE_IRREVERSIBLE=k files each step's irreversible impacts k intervals later (dropped
 * beyond the run): only to see the check below fail where the reported impact is elsewhere
 * (ctest fuzz_capi_reversal_irreversible_elsewhere_13, _8934) */
static int irreversible_offset(void) {
  const char *env = getenv("VCI_FUZZ_MOVE_IRREVERSIBLE");
  return env != NULL ? atoi(env) : 0;
}
/* nsteps single steps (vci_step, as vci_integrate takes them) in direction dir, each step's
 * counter increments filed in *r and its impacts in l (via l->current_step). Returns the first
 * status that is not VCI_OK (the run stops there, as vci_integrate), else VCI_OK. */
static int recorded_steps(vci_integrator it, int nsteps, int dir, impact_list *l, step_counts *r) {
  int64_t before[NCOUNTERS], after[NCOUNTERS];
  int j, s, moved = irreversible_offset();
  memset(r, 0, sizeof *r);
  read_counters(it, before);
  for (j = 1; j <= nsteps; ++j) {
    int interval = dir > 0 ? j : nsteps + 1 - j;
    l->current_step = interval;
    s = vci_step(it, dir);
    if (s != VCI_OK) return s;
    read_counters(it, after);
    r->impacts[interval] = after[COUNTER_IMPACTS] - before[COUNTER_IMPACTS];
    r->splits[interval] = after[COUNTER_SPLITS] - before[COUNTER_SPLITS];
    r->fallbacks[interval] = after[COUNTER_FALLBACKS] - before[COUNTER_FALLBACKS];
    if (interval + moved >= 1 && interval + moved <= nsteps)
      r->irreversible[interval + moved] += after[COUNTER_IRREVERSIBLE] - before[COUNTER_IRREVERSIBLE];
    memcpy(before, after, sizeof before);
  }
  return VCI_OK;
}
/* Interval i of the two runs differs: another number of impacts, splits or energy fallbacks, or
 * (where both lists hold every impact) an impact that is not the same, paired from the interval's
 * end (the forward impacts from the last, the backward ones from the first met). */
static int interval_differs(int i, const impact_list *f, const step_counts *rf, const impact_list *b,
                           const step_counts *rb) {
  int kf[MAX_LISTED_IMPACTS], kb[MAX_LISTED_IMPACTS], nf = 0, nb = 0, k;
  if (rf->impacts[i] != rb->impacts[i] || rf->splits[i] != rb->splits[i] || rf->fallbacks[i] != rb->fallbacks[i])
    return 1;
  if (f->count > MAX_LISTED_IMPACTS || b->count > MAX_LISTED_IMPACTS) return 0; /* counts only */
  for (k = 0; k < f->count; ++k)
    if (f->step[k] == i) kf[nf++] = k;
  for (k = 0; k < b->count; ++k)
    if (b->step[k] == i) kb[nb++] = k;
  if (nf != nb) return 1; /* (the counters agreed; an impact callback that was not called) */
  for (k = 0; k < nf; ++k)
    if (other_wall_or_time(f, kf[nf - 1 - k], b, kb[k]) || other_impulse(f, kf[nf - 1 - k], b, kb[k])) return 1;
  return 0;
}
/* The step where the two directions part: walking from the run's end (where the backward run
 * starts from the forward run's last state), the first interval whose steps differ; 0 when none
 * does. Before it the backward run retraced the forward one (the same impacts, splits and
 * fallbacks), so it started this interval from the forward run's state at the interval's end; a
 * symmetric scheme's backward step then inverts the forward step unless one of the two made a
 * decision in this interval that the other direction cannot pose (an impact whose condition could
 * not be tied: vci_get_irreversible_impacts). An irreversible impact earlier in time cannot have
 * caused it (the backward run had not reached it), one later in time left the steps after it alike
 * (so it changed nothing the comparison sees): only this interval explains the parting. */
static int parting_step(int nsteps, const impact_list *f, const step_counts *rf, const impact_list *b,
                        const step_counts *rb) {
  int i;
  for (i = nsteps; i >= 1; --i)
    if (interval_differs(i, f, rf, b, rb)) return i;
  return 0;
}
/* An irreversible impact was reported (either direction) in the step where the directions part */
static int irreversible_where_parted(int parted, int nsteps, const step_counts *rf, const step_counts *rb) {
  return parted >= 1 && parted <= nsteps && rf->irreversible[parted] + rb->irreversible[parted] > 0;
}
/* the intervals with an irreversible impact, forward then backward, e.g. "12/-" or "3,7/12" */
static void irreversible_steps(int nsteps, const step_counts *rf, const step_counts *rb, char *out, size_t size) {
  const step_counts *r[2] = {rf, rb};
  size_t used = 0;
  int d, i;
  out[0] = '\0';
  for (d = 0; d < 2; ++d) {
    int any = 0;
    for (i = 1; i <= nsteps; ++i)
      if (r[d]->irreversible[i] > 0 && used + 16 < size) {
        used += (size_t)snprintf(out + used, size - used, "%s%d", any ? "," : "", i);
        any = 1;
      }
    if (!any && used + 2 < size) used += (size_t)snprintf(out + used, size - used, "-");
    if (d == 0 && used + 2 < size) used += (size_t)snprintf(out + used, size - used, "/");
  }
}

static int impact_calls = 0, impact_fail_at = -1;
static int cb_impact(double t, double alpha, int gap, const double *q, double impulse, void *user) {
  (void)t; (void)alpha; (void)gap; (void)q; (void)impulse; (void)user;
  return ++impact_calls == impact_fail_at ? (chance(50) ? 9 : -9) : 0;
}
static int progress_calls = 0, progress_stop_at = -1;
static int cb_progress(const vci_progress *info, void *user) {
  (void)user;
  promise(info != NULL && info->steps_done >= 0 && info->steps_done <= info->steps_total, "progress counts");
  return ++progress_calls == progress_stop_at;
}

/* the reference point (programs start near it; every wall leaves it inside) */
static double ref[MAXC];
static int finished = 0;

enum { KIND_DISCRETE_MODEL, KIND_LAGRANGIAN_MODEL, KIND_SEPARABLE_MODEL };

static const char *scheme_name(int scheme) {
  static const char *names[] = {"discrete", "left", "midpoint", "lobatto", "composition"};
  return scheme >= 0 && scheme <= 4 ? names[scheme] : "?";
}

/* Create a model of a random kind in slot j (hostile sizes and struct sizes now and then).
 * Returns the status; *n_out = the model's n when created. */
static int create_model(vci_model *mh, int *kind, int *n_out, model_t *dm, cmodel_t *cm, int hostile) {
  int s, n, m, ng, k = below(100) < 35 ? KIND_DISCRETE_MODEL : (chance(60) ? KIND_LAGRANGIAN_MODEL : KIND_SEPARABLE_MODEL);
  int maxn = k == KIND_DISCRETE_MODEL ? MAXN : MAXC, maxm = k == KIND_DISCRETE_MODEL ? MAXM : MAXCM;
  int maxg = k == KIND_DISCRETE_MODEL ? MAXG : MAXCG;
  vci_callbacks dcb;
  vci_lagrangian_callbacks lcb;
  vci_separable_callbacks scb;
  const char *fn;
  vci_model tmp = NULL, *target;
  int mass_kind = chance(60) ? VCI_MASS_DIAGONAL : VCI_MASS_DENSE;
  if (k == KIND_DISCRETE_MODEL) {
    random_model(dm, ref);
    discrete_callbacks(&dcb, dm->ng);
    n = dm->n; m = dm->m; ng = dm->ng;
    if (hostile && chance(5)) dcb.d2_ld = NULL;
    if (hostile && chance(5)) dcb.size = (size_t)below((int)sizeof dcb + 1); /* an older or broken header; never beyond
                                                                              the struct (a lie the library cannot see) */
  } else {
    random_cmodel(cm, ref, 0, k == KIND_SEPARABLE_MODEL);
    n = cm->n; m = cm->m; ng = cm->ng;
    if (k == KIND_LAGRANGIAN_MODEL) {
      lagrangian_callbacks(&lcb, cm->ng, 1);
      if (hostile && chance(5)) lcb.dl_dv = NULL;
      if (hostile && chance(5)) lcb.size = (size_t)below((int)sizeof lcb + 1);
    } else {
      separable_callbacks(&scb, cm->ng, 1);
      if (hostile && chance(5)) scb.gap_gradients = NULL;
      if (hostile && chance(5)) scb.size = (size_t)below((int)sizeof scb + 1);
      if (hostile && chance(5)) m = 1;  /* refused: a separable model has no constraints */
      if (hostile && chance(5)) mass_kind = wild_int(2);
    }
  }
  if (hostile && chance(10)) { n = wild_int(maxn); m = wild_int(maxm); ng = wild_int(maxg); }
  if (n > maxn || m > maxm || ng > maxg) { /* sizes the callbacks cannot serve: must be refused or unused */
    if (n > 0 && n <= 46339 && m >= 0 && m <= n && ng >= 0) n = maxn + 1 + below(3);
  }
  /* sizes beyond what these callbacks can serve: only the refused ones are created (and dropped) */
  target = n <= maxn && m <= maxm && ng <= maxg ? mh : &tmp;
  if (k == KIND_DISCRETE_MODEL) {
    fn = "vci_model_create";
    s = vci_model_create(target, n, m, ng, &dcb, dm);
  } else if (k == KIND_LAGRANGIAN_MODEL) {
    fn = "vci_model_create_lagrangian";
    s = vci_model_create_lagrangian(target, n, m, ng, &lcb, cm);
  } else {
    fn = "vci_model_create_separable";
    s = vci_model_create_separable(target, n, m, ng, mass_kind,
                                   chance(3) ? NULL : (mass_kind == VCI_MASS_DENSE ? cm->dense_mass : cm->mass), &scb, cm);
  }
  if (fuzz_trace) printf("  %s(n %d, m %d, ng %d, kind %d) = %d\n", fn, n, m, ng, cm->kind, s);
  check_listed(s, ST_CREATE, fn);
  promise((s == VCI_OK) == (*target != NULL), "model handle set iff VCI_OK");
  check_message(s, NULL, fn);
  if (target == &tmp) vci_model_destroy(&tmp);
  *kind = k;
  *n_out = n;
  return s;
}

/* a random scheme: mostly valid for a continuous model, now and then out of range */
static void random_scheme(int *scheme, int *stages) {
  *scheme = chance(90) ? 1 + below(4) : wild_int(6);
  *stages = *scheme == VCI_SCHEME_COMPOSITION ? 2 * (1 + below(5)) : 1 + below(VCI_LOBATTO_MAX_STAGES);
  if (chance(10)) *stages = wild_int(12);
}

/* a sparsity pattern for n: the tridiagonal one (right for a chain), the diagonal (wrong for a chain),
 * full, or hostile (colptr[0] != 0, decreasing, rows out of range or repeated); the rows never run
 * past rowind's end (that lie the library cannot see) */
static int random_pattern(int n, int *colptr, int *rowind, int cap) {
  int j, i, nnz = 0, kind = below(5);
  colptr[0] = 0;
  for (j = 0; j < n; ++j) {
    for (i = 0; i < n && nnz < cap; ++i) {
      int in = kind == 0 ? abs(i - j) <= 1 : kind == 1 ? i == j : kind == 2 ? 1 : chance(40);
      if (in) rowind[nnz++] = i;
    }
    colptr[j + 1] = nnz;
  }
  if (kind >= 3 && nnz > 0) { /* break it */
    switch (below(4)) {
    case 0: colptr[0] = 1; break;
    case 1: if (n > 1) colptr[1 + below(n - 1)] = chance(50) ? -1 : colptr[n]; break;
    case 2: rowind[below(nnz)] = chance(50) ? n + below(3) : -1 - below(3); break;
    default: rowind[below(nnz)] = rowind[0]; break;
    }
  }
  return kind;
}

static void check_finite_state(vci_integrator it, int n) {
  double t, q[MAXC], p[MAXC];
  int i;
  if (vci_get_state(it, &t, q, p) != VCI_OK) return;
  promise(isfinite(t), "state finite (t)");
  for (i = 0; i < n; ++i) promise(isfinite(q[i]) && isfinite(p[i]), "state finite (q, p)");
}

/* One random program. */
static void program(uint64_t seed) {
  enum { NM = 3, NI = 4 };
  static model_t dmodels[NM];
  static cmodel_t cmodels[NM];
  vci_model mh[NM] = {NULL};
  int mkind[NM] = {0}, mn[NM] = {0}, in[NI] = {0}, ik[NI] = {0};
  int64_t steps_by_kind[3] = {0, 0, 0}, steps_before = 0;
  vci_integrator ih[NI] = {NULL}, stale = NULL;
  char msg[600], path[64];
  int ncalls, c, progress_set = 0, histogram[VCI_STOPPED + 1] = {0};
  fuzz_seed(seed);
  impact_calls = 0;
  impact_fail_at = chance(30) ? 1 + below(5) : -1;
  progress_calls = 0;
  progress_stop_at = chance(50) ? 1 + below(20) : -1;
  snprintf(path, sizeof path, "fuzz_%ld.h5", (long)getpid());
  for (c = 0; c < MAXC; ++c) ref[c] = uniform(-1.0, 1.0);
  ncalls = 1 + below(40);
  if (chance(85)) { /* most programs start with a working integrator, so that steps get taken */
    double q0[MAXC], q1[MAXC];
    int s;
    if (create_model(&mh[0], &mkind[0], &mn[0], &dmodels[0], &cmodels[0], 0) == VCI_OK) {
      if (mkind[0] != KIND_DISCRETE_MODEL && chance(30))
        check_listed(vci_model_declare_bandwidth(mh[0], cmodel_bandwidth(&cmodels[0]), chance(20)), ST_BUSY_ARG,
                     "vci_model_declare_bandwidth");
      s = vci_integrator_create(&ih[0], mh[0], uniform(2e-3, 3e-2));
      check_listed(s, ST_CREATE, "vci_integrator_create");
      in[0] = mn[0];
      ik[0] = mkind[0];
      if (s == VCI_OK && mkind[0] != KIND_DISCRETE_MODEL && chance(60)) {
        int scheme, stages;
        random_scheme(&scheme, &stages);
        s = vci_set_scheme(ih[0], scheme, stages);
        check_listed(s, ST_CREATE | S(VCI_ERR_STATE), "vci_set_scheme");
      }
      for (c = 0; c < MAXC; ++c) {
        q0[c] = ref[c];
        q1[c] = ref[c] + uniform(-0.02, 0.02);
      }
      /* a pair that moves off the constraint gets a multiplier; one across a wall is refused */
      s = vci_init_from_pair(ih[0], 0.0, q0, q1);
      check_listed(s, ST_INIT, "vci_init_from_pair");
    }
  }
  for (c = 0; c < ncalls; ++c) {
    int k = chance(70) ? 0 : below(NI), j = chance(50) ? 0 : below(NM), s = VCI_OK, i;
    vci_integrator it = chance(3) ? stale : (chance(2) ? (vci_integrator)(uintptr_t)rnd() : ih[k]);
    int live = it != NULL && it == ih[k];
    double q0[MAXC], q1[MAXC], t, e, lambda[MAXCM];
    int64_t kk, st, im, ni, a, b;
    unsigned allowed = ST_BUSY_ARG;
    const char *fn = "?";
    vci_integrator about = it; /* whose message tells why a failure happened (NULL: the thread's) */
    int what = below(28);
    if (what >= 22) what = 5;   /* integrate most often */
    if (fuzz_trace)
      printf("call %d: case %d on integrator %d (model slot %d), %.2f s\n", c, what, k, j, (double)clock() / CLOCKS_PER_SEC),
          fflush(stdout);
    if (live && vci_get_stats(it, &steps_before, NULL, NULL) != VCI_OK) steps_before = 0;
    switch (what) {
    case 0: /* a model */
      vci_model_destroy(&mh[j]);
      mn[j] = 0;
      create_model(&mh[j], &mkind[j], &mn[j], &dmodels[j], &cmodels[j], 1);
      continue; /* checked inside */
    case 1: { /* an integrator */
      vci_model from = chance(5) ? (vci_model)ih[0] : mh[j];
      vci_integrator_destroy(&ih[k]);
      s = vci_integrator_create(&ih[k], from, chance(80) ? uniform(1e-3, 5e-2) : wild(1e-2));
      in[k] = mn[j];
      ik[k] = mkind[j];
      promise((s == VCI_OK) == (ih[k] != NULL), "integrator handle set iff VCI_OK");
      fn = "vci_integrator_create"; allowed = ST_CREATE; about = NULL;
      break;
    }
    case 2:
      if (chance(30)) stale = ih[k];
      vci_integrator_destroy(chance(5) ? NULL : &ih[k]);
      continue;
    case 3: case 4: { /* a start */
      for (i = 0; i < MAXC; ++i) {
        q0[i] = chance(95) ? ref[i] + uniform(-0.05, 0.05) : wild(1.0);
        q1[i] = q0[i] + (chance(90) ? uniform(-0.05, 0.05) : wild(0.05));
      }
      if (chance(50)) {
        fn = "vci_init_from_pair";
        s = vci_init_from_pair(it, chance(90) ? uniform(-5.0, 5.0) : wild(1.0), chance(3) ? NULL : q0, q1);
      } else {
        fn = "vci_init_from_momentum";
        s = vci_init_from_momentum(it, uniform(-5.0, 5.0), q0, chance(3) ? NULL : q1);
      }
      allowed = ST_INIT;
      break;
    }
    case 5: case 6: case 7:
      /* hostile counts are negative: a huge positive one is a long run, not a fault */
      s = vci_integrate(it, chance(95) ? below(200) : (chance(50) ? -1 - below(3) : INT64_MIN),
                        chance(90) ? (chance(70) ? 1 : -1) : wild_int(3));
      fn = "vci_integrate"; allowed = ST_STEP | (progress_set ? S(VCI_STOPPED) : 0u);
      break;
    case 8:
      s = vci_step(it, chance(90) ? (chance(70) ? 1 : -1) : wild_int(3));
      fn = "vci_step"; allowed = ST_STEP;
      break;
    case 9:
      s = vci_get_state(it, chance(80) ? &t : NULL, chance(80) ? q0 : NULL, chance(80) ? q1 : NULL);
      fn = "vci_get_state";
      if (s == VCI_OK && live) { s = vci_get_multipliers(it, lambda); fn = "vci_get_multipliers"; }
      break;
    case 10:
      fn = "vci_get_energy";
      s = vci_get_energy(it, chance(90) ? &e : NULL);
      if (s == VCI_OK) { s = vci_get_index(it, &kk); fn = "vci_get_index"; }
      if (s == VCI_OK) { s = vci_get_stats(it, &st, chance(80) ? &im : NULL, &ni); fn = "vci_get_stats"; }
      if (s == VCI_OK) promise(st >= 0 && ni >= 0, "counters are not negative");
      if (s == VCI_OK) { s = vci_get_energy_fallbacks(it, chance(90) ? &a : NULL); fn = "vci_get_energy_fallbacks"; }
      if (s == VCI_OK) { s = vci_get_split_steps(it, &a, chance(80) ? &b : NULL); fn = "vci_get_split_steps"; }
      if (s == VCI_OK) promise(a >= 0, "split steps not negative");
      break;
    case 11: {
      double atol = chance(70) ? 0.0 : wild(1e-10), rtol = chance(70) ? uniform(1e-13, 1e-6) : wild(1e-10);
      int maxit = chance(80) ? 1 + below(40) : wild_int(50);
      if (fuzz_trace) printf("  set_tolerances(%g, %g, %d)\n", atol, rtol, maxit);
      s = vci_set_tolerances(it, atol, rtol, maxit);
      fn = "vci_set_tolerances";
      break;
    }
    case 12:
      if (chance(50)) {
        s = vci_set_impact_energy(it, chance(90) ? below(2) : wild_int(3));
        fn = "vci_set_impact_energy";
      } else {
        s = vci_set_max_impacts(it, chance(80) ? 1 + below(20) : wild_int(30));
        fn = "vci_set_max_impacts";
      }
      break;
    case 13:
      s = vci_set_impact_callback(it, chance(80) ? cb_impact : NULL, NULL);
      fn = "vci_set_impact_callback";
      break;
    case 14:
      if (chance(70)) {
        const char *p = chance(95) ? path : (chance(50) ? "" : "/nonexistent-dir/f.h5");
        if (chance(50)) {
          s = vci_open_output(it, p);
          fn = "vci_open_output";
        } else {
          s = vci_open_output_every(it, p, chance(80) ? 1 + below(5) : wild_int(3), chance(80) ? below(10) : wild_int(12));
          fn = "vci_open_output_every";
        }
        allowed = ST_BUSY_ARG | S(VCI_ERR_IO) | S(VCI_ERR_MEMORY);
      } else {
        s = vci_close_output(it);
        fn = "vci_close_output"; allowed = ST_BUSY_ARG | S(VCI_ERR_IO);
      }
      break;
    case 15: { /* a scheme (a discrete model's integrator refuses any) */
      int scheme, stages;
      random_scheme(&scheme, &stages);
      if (fuzz_trace) printf("  set_scheme(%d %s, %d)\n", scheme, scheme_name(scheme), stages);
      s = vci_set_scheme(it, scheme, stages);
      fn = "vci_set_scheme"; allowed = ST_BUSY_ARG | S(VCI_ERR_MEMORY);
      break;
    }
    case 16:
      s = vci_set_step_splits(it, chance(80) ? 1 + below(32) : wild_int(2000));
      fn = "vci_set_step_splits";
      break;
    case 17: { /* a bandwidth, right or wrong, for integrators created later */
      int bw;
      if (chance(70)) {
        bw = mkind[j] != KIND_DISCRETE_MODEL ? cmodel_bandwidth(&cmodels[j]) : 0;
      } else {
        bw = wild_int(3);
        if (bw != INT_MIN) bw -= 1; /* (INT_MIN - 1 overflows: UBSan stopped seeds 433 and 444) */
      }
      s = vci_model_declare_bandwidth(chance(5) ? (vci_model)ih[0] : mh[j], chance(10) ? -1 : bw, chance(30));
      fn = "vci_model_declare_bandwidth"; about = NULL;
      break;
    }
    case 18: { /* a pattern, right or wrong */
      int colptr[MAXC + 2], rowind[MAXC * MAXC], n = mn[j] > 0 && mn[j] <= MAXC ? mn[j] : 1;
      int kind = random_pattern(n, colptr, rowind, MAXC * MAXC), nn = n;
      if (chance(10)) nn = chance(50) ? 0 : (chance(50) ? n + 1 : n - 1); /* withdraw, or not the model's n */
      for (i = n + 1; i < MAXC + 2; ++i) colptr[i] = colptr[n]; /* a wrong n + 1 reads a column of nothing */
      if (fuzz_trace) printf("  declare_pattern(n %d of %d, kind %d)\n", nn, n, kind);
      s = vci_model_declare_pattern(chance(5) ? (vci_model)ih[0] : mh[j], nn, chance(3) ? NULL : colptr,
                                    chance(3) ? NULL : rowind, chance(30));
      fn = "vci_model_declare_pattern"; allowed = ST_BUSY_ARG | S(VCI_ERR_MEMORY); about = NULL;
      break;
    }
    case 19: { /* the model checker */
      double worst = 0.0;
      char report[256];
      int passed = -1, size = chance(90) ? (int)sizeof report : 1 + below(8);
      for (i = 0; i < MAXC; ++i) {
        q0[i] = ref[i] + uniform(-0.1, 0.1);
        q1[i] = chance(95) ? q0[i] + uniform(-0.05, 0.05) : wild(1.0);
      }
      s = vci_check_model(chance(5) ? (vci_model)ih[0] : mh[j], q0, q1, chance(90) ? uniform(1e-3, 0.1) : wild(0.01),
                          chance(80) ? 0.0 : wild(1e-6), &passed, &worst, chance(70) ? report : NULL, size);
      fn = "vci_check_model"; allowed = S(VCI_OK) | S(VCI_ERR_ARGUMENT) | S(VCI_ERR_CALLBACK); about = NULL;
      if (s == VCI_OK) promise(passed == 0 || passed == 1, "check_model's passed is 0 or 1");
      break;
    }
    case 20:
      s = vci_set_progress(it, chance(80) ? cb_progress : NULL, chance(90) ? 0.0 : wild(1.0), NULL);
      fn = "vci_set_progress";
      if (s == VCI_OK) progress_set = 1;
      break;
    default:
      s = vci_last_error(chance(90) ? it : NULL, chance(95) ? msg : NULL, chance(95) ? (int)sizeof msg : wild_int(3));
      if (s == VCI_OK) promise(memchr(msg, '\0', sizeof msg) != NULL, "message NUL-terminated");
      check_listed(s, ST_BUSY_ARG, "vci_last_error");
      ++histogram[s];
      continue; /* its own failures carry no message */
    }
    check_listed(s, allowed, fn);
    ++histogram[s];
    check_message(s, about, fn);
    if (live && (what >= 3 && what <= 8)) {
      check_finite_state(it, in[k]);
      if (vci_get_stats(it, &st, NULL, NULL) == VCI_OK && st > steps_before) steps_by_kind[ik[k]] += st - steps_before;
    }
    (void)vci_status_string(s);
  }
  if (getenv("VCI_FUZZ_VERBOSE")) { /* what the program got done, for judging the harness */
    printf("seed %llu: %d calls, steps of discrete/lagrangian/separable models %lld %lld %lld, statuses",
           (unsigned long long)seed, ncalls, (long long)steps_by_kind[0], (long long)steps_by_kind[1],
           (long long)steps_by_kind[2]);
    for (c = 0; c <= VCI_STOPPED; ++c) printf(" %d", histogram[c]);
    printf("\n");
  }
  for (c = 0; c < NI; ++c) vci_integrator_destroy(&ih[c]);
  for (c = 0; c < NM; ++c) vci_model_destroy(&mh[c]);
  remove(path);
  if (vci_test_lapack_nonfinite_calls() != 0) _exit(71); /* (the guard exits at once anyway) */
}

/* VCI_FUZZ_RTOL_SCALE=f multiplies each run's drawn rtol by f (the draw itself is unchanged, so a
 * seed keeps its scene): an error the solves' tolerance makes falls with f, an asymmetry of the
 * algorithm does not (docs/BACKWARD.md, "Distance alone") */
static double rtol_scale(void) {
  const char *env = getenv("VCI_FUZZ_RTOL_SCALE");
  return env != NULL && atof(env) > 0.0 ? atof(env) : 1.0;
}

/* VCI_FUZZ_POKE_SAMPLES=0 turns the poke screen off (vci_set_poke_samples) in every reversal
 * integrator: the library as it was before poke24g, whose missed pokes were one-way impacts (3479,
 * 11036), to see the reproducibility judgement below fail a real asymmetry of the library */
static int poke_setting(vci_integrator it) {
  const char *env = getenv("VCI_FUZZ_POKE_SAMPLES");
  return env != NULL ? vci_set_poke_samples(it, atoi(env)) : VCI_OK;
}
/* p0 moved by e (1 + |p0|) along a fixed direction of alternating signs (moved_forward_end,
 * VCI_FUZZ_MOVE_START, the reproducibility reruns) */
static void moved_momentum(int n, const double *p0, double e, double *pm) {
  int i;
  for (i = 0; i < n; ++i) pm[i] = p0[i] + e * (1.0 + fabs(p0[i])) * (i % 2 ? -0.6 : 0.8);
}
/* The end of N forward steps from (q0, p0 + eps (1 + |p0|) d), d a fixed direction of alternating
 * signs, with the run's model, scheme and tolerance; returns the step's status */
static int moved_forward_end(vci_model model, int scheme, int stages, double h, double rtol, double t0, int n,
                             const double *q0, const double *p0, int nsteps, double eps, double *q, double *p) {
  vci_integrator it = NULL;
  double pm[MAXC], t;
  int j, s;
  moved_momentum(n, p0, eps, pm);
  s = vci_integrator_create(&it, model, h);
  if (s == VCI_OK) s = poke_setting(it);
  if (s == VCI_OK) s = vci_set_scheme(it, scheme, stages);
  if (s == VCI_OK) s = vci_set_tolerances(it, 0.0, rtol, 30);
  if (s == VCI_OK) s = vci_init_from_momentum(it, t0, q0, pm);
  for (j = 0; j < nsteps && s == VCI_OK; ++j) s = vci_step(it, 1);
  if (s == VCI_OK) s = vci_get_state(it, &t, q, p);
  vci_integrator_destroy(&it);
  return s;
}
/* How much the forward run amplifies a start moved by eps: the largest relative change of an end
 * coordinate (the reversal error's measure) over eps; negative when a moved run failed. The
 * backward run is the inverse map, whose derivative has the same largest singular value (the
 * map is symplectic), so a solve's error anywhere in the round trip is amplified at most about
 * this much */
static double forward_growth(vci_model model, int scheme, int stages, double h, double rtol, double t0, int n,
                             const double *q0, const double *p0, int nsteps, const double *qe, const double *pe,
                             double eps) {
  double q[MAXC], p[MAXC], d = 0.0;
  int i;
  if (moved_forward_end(model, scheme, stages, h, rtol, t0, n, q0, p0, nsteps, eps, q, p) != VCI_OK) return -1.0;
  for (i = 0; i < n; ++i)
    d = fmax(d, fmax(fabs(q[i] - qe[i]) / (1.0 + fabs(qe[i])), fabs(p[i] - pe[i]) / (1.0 + fabs(pe[i]))));
  return d / eps;
}

/* A run whose only fault is its distance (status OK, index 0, as many impacts both ways, no split,
 * fallback or irreversible impact) on a chaotic scene: the 2N solves' errors (rtol each) are
 * amplified by up to the forward growth G, which REVERSAL_C * 2N * rtol ignores (docs/BACKWARD.md,
 * "Distance alone"). The bound 2N * rtol * G, where G is measured linear (the growths of starts
 * moved by 1e-9 and 1e-10 within a factor 2), and the start perturbation 2N * rtol capped at 1e-9
 * (the largest one measured linear); none (negative) when G is not linear, a moved run failed or the
 * bound exceeds CHAOS_RESOLUTION (there the tolerance alone moves the end by O(1e-3): nothing to
 * judge, the run stays BROKEN). growth[2] receives the two growths. */
#define CHAOS_RESOLUTION 1e-3
static double chaos_bound(vci_model model, int scheme, int stages, double h, double rtol, double t0, int n,
                          const double *q0, const double *p0, int nsteps, const double *qe, const double *pe,
                          double growth[2]) {
  double bound;
  growth[0] = forward_growth(model, scheme, stages, h, rtol, t0, n, q0, p0, nsteps, qe, pe, 1e-9);
  growth[1] = forward_growth(model, scheme, stages, h, rtol, t0, n, q0, p0, nsteps, qe, pe, 1e-10);
  if (!(growth[0] > 0.0 && growth[1] > 0.0) || fmax(growth[0], growth[1]) > 2.0 * fmin(growth[0], growth[1]))
    return -1.0;
  bound = fmin(2.0 * nsteps * rtol, 1e-9) * fmin(growth[0], growth[1]);
  return bound <= CHAOS_RESOLUTION ? bound : -1.0;
}

/* VCI_FUZZ_ASYMMETRY=d moves every wall by d (1 + |offset|) outwards for the backward run only: a
 * deliberate asymmetry between the directions, to see the chaos judgement above fail it (the
 * reversal error is then d times the growth, not rtol times it) */
static double asymmetry(void) {
  const char *env = getenv("VCI_FUZZ_ASYMMETRY");
  return env != NULL ? atof(env) : 0.0;
}
static void move_walls(cmodel_t *md, double d) {
  int j;
  for (j = 0; j < md->ng; ++j) md->offset[j] -= d * (1.0 + fabs(md->offset[j]));
}

/* VCI_FUZZ_MOVE_START=e moves the start's p0 by e (1 + |p0|) along moved_forward_end's direction
 * (after the draws: the scene is the seed's): an error made by the round-off of the 2N solves and
 * amplified changes at random with a move of 1e-15, an asymmetry of the algorithm (smooth in the
 * start) does not (docs/BACKWARD.md, "Distance alone") */
static void move_start(int n, double *p0) {
  const char *env = getenv("VCI_FUZZ_MOVE_START");
  double moved[MAXC];
  moved_momentum(n, p0, env != NULL ? atof(env) : 0.0, moved);
  memcpy(p0, moved, (size_t)n * sizeof *p0);
}

/* Reproducibility of a distance-only error the chaos bound cannot judge (docs/BACKWARD.md,
 * "Distance alone"): the round trip is rerun with rtol/10 and with p0 moved by 1e-15 ... 1e-14
 * relative (far below the tolerance). An asymmetry of the algorithm is smooth in the start and
 * independent of the solves' tolerance, so its error comes back the same (the deliberate
 * VCI_FUZZ_ASYMMETRY: to 3 digits); the solves' errors, tolerance or round-off amplified by the
 * dynamics, change with one or both. A run is judged to be amplified solves' error only when every
 * rerun is again off in its distance alone and the errors' relative spread (max - min) / max
 * exceeds REPRODUCIBLE_SPREAD: above an asymmetry's own spread once it dominates (0-6 % where its
 * error is 30 times the run's own), below the smallest measured solves' spread (47 %, over the 16
 * runs of docs/BACKWARD.md's "Distance alone").
 * It lets through a wall moved one way whose error is up to 1.8-5.9 times the run's own and fails
 * it from 2.5-22 times (no test on the error alone can see one below the solves' own error). Only
 * for errors up to REPRODUCIBLE_RESOLUTION (all six): beyond, the runs have parted as far as a
 * different branch at an impact parts them, and reruns differ whatever the cause (41537: errors
 * 1.8 to 5.6 over its reruns, with or without a wall moved by 1e-6 one way). */
#define REPRODUCIBLE_SPREAD 0.30
#define REPRODUCIBLE_RESOLUTION 0.1
enum { NRERUNS = 5 };
/* Not where the impacts differ in number (seed 41537, 149/146): its end moves by O(1) for any start
 * move down to 1e-13, so its reruns differ whatever else differs, and an impact met one way only is
 * what the library's own one-way bugs looked like (docs/BACKWARD.md). VCI_FUZZ_REPRODUCE_ANY_COUNT=1
 * reruns those too, only to measure that (41537's spread is then 61 %, and 63 % with a wall moved
 * by 1e-6 one way; REPRODUCIBLE_RESOLUTION keeps it BROKEN). */
static int reproduce_any_count(void) { return getenv("VCI_FUZZ_REPRODUCE_ANY_COUNT") != NULL; }
static const double rerun_rtol_factor[NRERUNS] = {0.1, 1.0, 1.0, 1.0, 1.0};
static const double rerun_start_move[NRERUNS] = {0.0, 1e-15, 2e-15, 5e-15, 1e-14};
/* N steps forward from (q0, p0 moved by e) and N back, the backward walls moved as in the run
 * itself (VCI_FUZZ_ASYMMETRY); returns the round trip's error as the run's, or -1 when the rerun
 * is not again off in its distance alone (a step failed, a split, fallback or irreversible impact,
 * index not 0, or another number of impacts back than forward) */
static double round_trip_error(vci_model model, cmodel_t *md, int scheme, int stages, double h, double rtol,
                               double t0, const double *q0, const double *p0, int nsteps, double e) {
  vci_integrator it = NULL;
  double pm[MAXC], q[MAXC], p[MAXC], t, err = 0.0, offsets[MAXCG];
  int64_t before[NCOUNTERS], forward[NCOUNTERS], after[NCOUNTERS], k = -1;
  int i, j, s, n = md->n;
  moved_momentum(n, p0, e, pm);
  s = vci_integrator_create(&it, model, h);
  if (s == VCI_OK) s = poke_setting(it);
  if (s == VCI_OK) s = vci_set_scheme(it, scheme, stages);
  if (s == VCI_OK) s = vci_set_tolerances(it, 0.0, rtol, 30);
  if (s == VCI_OK) s = vci_init_from_momentum(it, t0, q0, pm);
  if (s == VCI_OK) read_counters(it, before);
  for (j = 0; j < nsteps && s == VCI_OK; ++j) s = vci_step(it, 1);
  if (s == VCI_OK) read_counters(it, forward);
  memcpy(offsets, md->offset, sizeof offsets);
  move_walls(md, asymmetry());
  for (j = 0; j < nsteps && s == VCI_OK; ++j) s = vci_step(it, -1);
  memcpy(md->offset, offsets, sizeof offsets);
  if (s == VCI_OK) read_counters(it, after);
  if (s == VCI_OK) s = vci_get_state(it, &t, q, p);
  if (s == VCI_OK) s = vci_get_index(it, &k);
  vci_integrator_destroy(&it);
  if (s != VCI_OK || k != 0 || after[COUNTER_SPLITS] != before[COUNTER_SPLITS] ||
      after[COUNTER_FALLBACKS] != before[COUNTER_FALLBACKS] ||
      after[COUNTER_IRREVERSIBLE] != before[COUNTER_IRREVERSIBLE] ||
      (after[COUNTER_IMPACTS] - forward[COUNTER_IMPACTS] != forward[COUNTER_IMPACTS] - before[COUNTER_IMPACTS] &&
       !reproduce_any_count()))
    return -1.0;
  for (i = 0; i < n; ++i)
    err = fmax(err, fmax(fabs(q[i] - q0[i]) / (1.0 + fabs(q0[i])), fabs(p[i] - pm[i]) / (1.0 + fabs(pm[i]))));
  return err;
}
/* The errors of the reruns (errors[NRERUNS], -1 for a rerun not off in its distance alone), the
 * largest with the run's own error in *worst, and their relative spread; -1 when a rerun was not
 * alike */
static double error_spread(vci_model model, cmodel_t *md, int scheme, int stages, double h, double rtol, double t0,
                           const double *q0, const double *p0, int nsteps, double err, double errors[NRERUNS],
                           double *worst) {
  double lo = err, hi = err;
  int r, alike = 1;
  for (r = 0; r < NRERUNS; ++r) {
    errors[r] = round_trip_error(model, md, scheme, stages, h, rtol * rerun_rtol_factor[r], t0, q0, p0, nsteps,
                                 rerun_start_move[r]);
    if (errors[r] < 0.0) alike = 0;
    lo = fmin(lo, errors[r]);
    hi = fmax(hi, errors[r]);
  }
  *worst = hi;
  return alike && hi > 0.0 ? (hi - lo) / hi : -1.0;
}

/* The reversal property on one random continuous scene: returns 0 (held), EXIT_REVERSAL_BROKEN or
 * EXIT_REVERSAL_UNJUDGED (a step failed, the net split a step or an energy fallback was taken). */
static int reversal(uint64_t seed) {
  static cmodel_t md;
  vci_model model = NULL;
  vci_integrator it = NULL;
  int separable, scheme, stages, s, i, n, nsteps, verdict = 0;
  double h, rtol, q0[MAXC], p0[MAXC], t0, q[MAXC], p[MAXC], t, err_q = 0.0, err_p = 0.0, tol, qe[MAXC], pe[MAXC];
  double chaos = -1.0, growth[2] = {-1.0, -1.0}, offsets[MAXCG], spread = -1.0, reruns[NRERUNS], worst = 0.0;
  int rerun = 0;
  int64_t imp_f = 0, imp_b = 0, split_f = 0, split_b = 0, fb_f = 0, fb_b = 0, irr_f = 0, irr_b = 0, k = -1;
  const char *verbose = getenv("VCI_FUZZ_VERBOSE");
  static impact_list list_f, list_b;
  static step_counts steps_f, steps_b;
  char parted[160] = "", irreversible_at[160] = "";
  int parted_step = 0;
  fuzz_seed(seed);
  list_f.count = 0; list_b.count = 0;
  list_f.md = &md; list_b.md = &md;
  list_f.worst_gap = 0.0; list_b.worst_gap = 0.0;
  for (i = 0; i < MAXC; ++i) ref[i] = uniform(-1.0, 1.0);
  separable = chance(35);
  random_cmodel(&md, ref, 1, separable);
  n = md.n;
  if (separable) {
    vci_separable_callbacks cb;
    separable_callbacks(&cb, md.ng, 0);
    int dense = chance(50);
    s = vci_model_create_separable(&model, n, 0, md.ng, dense ? VCI_MASS_DENSE : VCI_MASS_DIAGONAL,
                                   dense ? md.dense_mass : md.mass, &cb, &md);
  } else {
    vci_lagrangian_callbacks cb;
    lagrangian_callbacks(&cb, md.ng, 0);
    s = vci_model_create_lagrangian(&model, n, 0, md.ng, &cb, &md);
  }
  if (s != VCI_OK) {
    char msg[300];
    vci_last_error(NULL, msg, sizeof msg);
    printf("%s\n", msg);
  }
  promise(s == VCI_OK, "a benign model is created");
  if (md.kind == KIND_CHAIN && !separable && chance(50))
    promise(vci_model_declare_bandwidth(model, 1, 0) == VCI_OK, "bandwidth 1");
  h = uniform(0.005, 0.05);
  promise(vci_integrator_create(&it, model, h) == VCI_OK, "integrator created");
  promise(poke_setting(it) == VCI_OK, "poke setting");
  scheme = separable && chance(30) ? VCI_SCHEME_COMPOSITION : 1 + below(3);
  stages = scheme == VCI_SCHEME_COMPOSITION ? 2 * (1 + below(3)) : 1 + below(4);
  promise(vci_set_scheme(it, scheme, stages) == VCI_OK, "scheme set");
  rtol = pow(10.0, uniform(-13.0, -10.0)) * rtol_scale();
  promise(vci_set_tolerances(it, 0.0, rtol, 30) == VCI_OK, "tolerances set");
  t0 = uniform(-1.0, 1.0);
  for (i = 0; i < n; ++i) {
    q0[i] = ref[i];
    p0[i] = uniform(-2.0, 2.0);
  }
  move_start(n, p0);
  nsteps = 10 + below(91);
  promise(nsteps <= MAX_REVERSAL_STEPS, "the steps fit the per-step records");
  s = vci_init_from_momentum(it, t0, q0, p0);
  if (s == VCI_OK) s = vci_set_impact_callback(it, list_impact, &list_f);
  if (s == VCI_OK) s = recorded_steps(it, nsteps, 1, &list_f, &steps_f);
  if (s == VCI_OK) s = vci_get_state(it, &t, qe, pe);
  if (s == VCI_OK) {
    vci_get_stats(it, NULL, &imp_f, NULL);
    vci_get_split_steps(it, &split_f, NULL);
    vci_get_energy_fallbacks(it, &fb_f);
    vci_get_irreversible_impacts(it, &irr_f);
    s = vci_set_impact_callback(it, list_impact, &list_b);
    memcpy(offsets, md.offset, sizeof offsets);
    move_walls(&md, asymmetry());
    if (s == VCI_OK) s = recorded_steps(it, nsteps, -1, &list_b, &steps_b);
    memcpy(md.offset, offsets, sizeof offsets);
  }
  if (s == VCI_OK) {
    vci_get_stats(it, NULL, &imp_b, NULL);
    vci_get_split_steps(it, &split_b, NULL);
    vci_get_energy_fallbacks(it, &fb_b);
    vci_get_irreversible_impacts(it, &irr_b);
    imp_b -= imp_f; split_b -= split_f; fb_b -= fb_f; irr_b -= irr_f;
    promise(vci_get_state(it, &t, q, p) == VCI_OK && vci_get_index(it, &k) == VCI_OK, "state after the run");
    for (i = 0; i < n; ++i) {
      err_q = fmax(err_q, fabs(q[i] - q0[i]) / (1.0 + fabs(q0[i])));
      err_p = fmax(err_p, fabs(p[i] - p0[i]) / (1.0 + fabs(p0[i])));
    }
  }
  tol = REVERSAL_C * 2.0 * nsteps * rtol;
  /* an energy fallback is an impact's condition: never more of them than impacts in a direction
   * (seed 950 counted 17 forward with 4 impacts: those of the attempts the safety net discarded) */
  if (s == VCI_OK && (fb_f > imp_f || fb_b > imp_b)) verdict = EXIT_REVERSAL_BROKEN;
  /* an impact point beyond a wall (stage 1 solves a wall's gap row to rtol of its terms; a corner
   * leaves the other wall's gap at that level too, so 100 rtol is a wide margin) */
  else if (fmin(list_f.worst_gap, list_b.worst_gap) < -100.0 * rtol) {
    verdict = EXIT_REVERSAL_BROKEN;
    printf("reversal seed %llu: an impact point beyond a wall: gap %.2e relative to its terms (forward %.2e, "
           "backward %.2e)\n", (unsigned long long)seed, fmin(list_f.worst_gap, list_b.worst_gap), list_f.worst_gap,
           list_b.worst_gap);
  }
  else if (s == VCI_OK && (split_f != split_b || fb_f != fb_b)) {
    /* the left rule is not symmetric: its backward step solves the right rule's equations (another
     * nonlinear system, another Newton basin; E_d - H offsets O(h), not O(h^2)), so where a solve
     * fails or a condition blends may differ between the directions (docs/BACKWARD.md). A symmetric
     * scheme's one-sided run is explained only by an irreversible impact where the directions part */
    parted_step = parting_step(nsteps, &list_f, &steps_f, &list_b, &steps_b);
    verdict = scheme == VCI_SCHEME_LEFT ? EXIT_REVERSAL_ONE_SIDED_LEFT
              : irr_f + irr_b == 0      ? EXIT_REVERSAL_ONE_SIDED_UNEXPLAINED
              : irreversible_where_parted(parted_step, nsteps, &steps_f, &steps_b) ? EXIT_REVERSAL_ONE_SIDED
                                                                                  : EXIT_REVERSAL_ONE_SIDED_ELSEWHERE;
  }
  else if (s != VCI_OK || split_f + split_b + fb_f + fb_b + irr_f + irr_b > 0) verdict = EXIT_REVERSAL_UNJUDGED;
  else if (!(err_q <= tol && err_p <= tol) || k != 0 || imp_f != imp_b) {
    verdict = EXIT_REVERSAL_BROKEN;
    /* only the distance is at fault: judged against the scene's measured chaos */
    if (k == 0 && imp_f == imp_b) {
      chaos = chaos_bound(model, scheme, stages, h, rtol, t0, n, q0, p0, nsteps, qe, pe, growth);
      if (fmax(err_q, err_p) <= chaos) verdict = EXIT_REVERSAL_CHAOTIC;
    }
    /* is the error reproducible? Beyond what the bound can judge, that alone decides; within it too
     * (an asymmetry whose error the bound covers, 8-73 times the run's own on 39440, comes back in
     * the reruns: a run is chaotic only when its error does not) */
    if ((verdict == EXIT_REVERSAL_BROKEN || verdict == EXIT_REVERSAL_CHAOTIC) && k == 0 &&
        (imp_f == imp_b || reproduce_any_count())) {
      rerun = 1;
      spread = error_spread(model, &md, scheme, stages, h, rtol, t0, q0, p0, nsteps, fmax(err_q, err_p), reruns,
                            &worst);
      if (spread > REPRODUCIBLE_SPREAD && worst <= REPRODUCIBLE_RESOLUTION) {
        if (verdict == EXIT_REVERSAL_BROKEN) verdict = EXIT_REVERSAL_AMPLIFIED;
      }
      else if (verdict == EXIT_REVERSAL_CHAOTIC) verdict = EXIT_REVERSAL_BROKEN;
    }
  }
  if (verbose || verdict == EXIT_REVERSAL_BROKEN || verdict == EXIT_REVERSAL_ONE_SIDED ||
      verdict == EXIT_REVERSAL_ONE_SIDED_LEFT || verdict == EXIT_REVERSAL_ONE_SIDED_UNEXPLAINED ||
      verdict == EXIT_REVERSAL_ONE_SIDED_ELSEWHERE || verdict == EXIT_REVERSAL_CHAOTIC ||
      verdict == EXIT_REVERSAL_AMPLIFIED) { /* (to sort them) */
    char msg[600] = "";
    if (s != VCI_OK) vci_last_error(it, msg, sizeof msg);
    if (s == VCI_OK) {
      first_difference(&list_f, &list_b, parted, sizeof parted);
      if (parted_step == 0) parted_step = parting_step(nsteps, &list_f, &steps_f, &list_b, &steps_b);
      irreversible_steps(nsteps, &steps_f, &steps_b, irreversible_at, sizeof irreversible_at);
      snprintf(msg, sizeof msg, "[%s] first difference from the end: %s; parting step %d of %d, irreversible in steps %s",
               split_f != split_b ? "split-one-way" : fb_f != fb_b ? "fallbacks-differ" : "alike", parted, parted_step,
               nsteps, irreversible_at);
    }
    printf("reversal seed %llu: kind %d n %d ng %d %s s %d h %.4f N %d rtol %.1e: status %d, impacts %lld/%lld, "
           "splits %lld/%lld, fallbacks %lld/%lld, irreversible %lld/%lld, index %lld, err q %.2e p %.2e (%.2g of 2N "
           "rtol)%s %s\n",
           (unsigned long long)seed, md.kind, n, md.ng, scheme_name(scheme), stages, h, nsteps, rtol, s,
           (long long)imp_f, (long long)imp_b, (long long)split_f, (long long)split_b, (long long)fb_f, (long long)fb_b,
           (long long)irr_f, (long long)irr_b, (long long)k, err_q, err_p, fmax(err_q, err_p) / (2.0 * nsteps * rtol),
           verdict == EXIT_REVERSAL_BROKEN ? " BROKEN" : verdict == EXIT_REVERSAL_ONE_SIDED ? " one-sided" :
           verdict == EXIT_REVERSAL_ONE_SIDED_LEFT ? " one-sided-left" :
           verdict == EXIT_REVERSAL_ONE_SIDED_UNEXPLAINED ? " one-sided-unexplained" :
           verdict == EXIT_REVERSAL_ONE_SIDED_ELSEWHERE ? " one-sided-irreversible-elsewhere" :
           verdict == EXIT_REVERSAL_CHAOTIC ? " chaotic" :
           verdict == EXIT_REVERSAL_AMPLIFIED ? " amplified-round-off" :
           verdict ? " unjudged" : "", msg);
  }
  if (growth[0] != -1.0 || growth[1] != -1.0)
    printf("  forward growth %.3g (start moved by 1e-9), %.3g (1e-10); chaos bound %s %.2e (2N rtol x growth, "
           "the start's move capped at 1e-9), err %.2e\n", growth[0], growth[1], chaos < 0.0 ? "none:" : "",
           chaos < 0.0 ? fmin(2.0 * nsteps * rtol, 1e-9) * fmin(growth[0], growth[1]) : chaos, fmax(err_q, err_p));
  if (rerun) {
    printf("  reruns' errors: %.3g with rtol/10; %.3g, %.3g, %.3g, %.3g with p0 moved by 1e-15, 2e-15, 5e-15, 1e-14 "
           "(-1: not off in its distance alone); ", reruns[0], reruns[1], reruns[2], reruns[3], reruns[4]);
    if (spread < 0.0) printf("a rerun not alike: not judged\n");
    else printf("spread %.0f %% with the run's %.3g: %s\n", 100.0 * spread, fmax(err_q, err_p),
                worst > REPRODUCIBLE_RESOLUTION ? "an error beyond 0.1, not judged"
                : spread > REPRODUCIBLE_SPREAD  ? "not reproducible (the solves' errors amplified)"
                                                : "reproducible");
  }
  if (getenv("VCI_FUZZ_IMPACTS")) { /* both lists, the backward one reversed beside the forward one */
    int a = list_f.count < MAX_LISTED_IMPACTS ? list_f.count : MAX_LISTED_IMPACTS;
    int b = list_b.count < MAX_LISTED_IMPACTS ? list_b.count : MAX_LISTED_IMPACTS;
    for (i = 0; i < a || i < b; ++i) {
      if (i < a) printf("  forward  t %.9f wall %d impulse %+.9g", list_f.t[i], list_f.gap[i], list_f.impulse[i]);
      else printf("  forward  -");
      if (i < b)
        printf("   backward t %.9f wall %d impulse %+.9g\n", list_b.t[b - 1 - i], list_b.gap[b - 1 - i], list_b.impulse[b - 1 - i]);
      else printf("   backward -\n");
    }
  }
  vci_integrator_destroy(&it);
  vci_model_destroy(&model);
  if (vci_test_lapack_nonfinite_calls() != 0) _exit(71);
  return verdict;
}

static int reversal_mode = 0;

static void exit_guard(void) {
  if (!finished) {
    printf("exit() during the program (library code ended the process)\n");
    fflush(stdout);
    _exit(70);
  }
}

static void run_child(uint64_t seed) {
  int code = 0;
  atexit(exit_guard);
  /* a hang: 20 s of CPU time (SIGXCPU), or VCI_FUZZ_CHILD_SECONDS (the sanitizer build runs 4-5x
   * slower: a program of 5 s in release is no hang there); CPU time, so that a loaded machine does
   * not make a slow program a hang. A child blocked without using CPU: 10 times as long in wall
   * time (SIGALRM). */
  const char *env = getenv("VCI_FUZZ_CHILD_SECONDS");
  unsigned limit = env != NULL && atoi(env) > 0 ? (unsigned)atoi(env) : 20u;
  struct rlimit cpu;
  cpu.rlim_cur = limit;
  cpu.rlim_max = limit + 5;
  setrlimit(RLIMIT_CPU, &cpu);
  alarm(10u * limit);
  if (reversal_mode) code = reversal(seed);
  else program(seed);
  finished = 1;
  fflush(stdout);
  exit(code); /* normal exit: sanitizers report leaks here */
}

int main(int argc, char **argv) {
  long first, count, i, ran = 0, bad = 0, unjudged = 0, one_sided = 0, one_sided_left = 0, chaotic = 0, amplified = 0;
  long stopped = 0;
  double budget;
  time_t start = time(NULL);
  fuzz_trace = getenv("VCI_FUZZ_TRACE") != NULL;
  setenv("VCI_LAPACK_GUARD_EXIT", "1", 1); /* NaN/Inf to LAPACK ends the child at once: status 71 */
  if (argc > 1 && strcmp(argv[1], "--reversal") == 0) {
    reversal_mode = 1;
    --argc;
    ++argv;
  }
  if (argc == 3 && atol(argv[1]) == -1) { /* one seed in this process */
    run_child((uint64_t)atoll(argv[2]));
    return 0;
  }
  if (argc < 3) {
    fprintf(stderr, "usage: vci_fuzz [--reversal] SEED_FIRST SEED_COUNT [SECONDS] | vci_fuzz [--reversal] -1 SEED\n");
    return 2;
  }
  first = atol(argv[1]);
  count = atol(argv[2]);
  budget = argc > 3 ? atof(argv[3]) : 60.0;
  /* stop after this many failures (5: enough to act on in a check); VCI_FUZZ_MAX_FAILURES=0 runs
   * every seed, for a survey of a seed range (docs/TESTING.md) */
  const char *max_env = getenv("VCI_FUZZ_MAX_FAILURES");
  long max_failures = max_env != NULL ? atol(max_env) : 5;
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
    if (WIFSIGNALED(status)) {
      ++bad;
      int sig = WTERMSIG(status);
      printf("FAIL seed %ld: %s (signal %d)\n", first + i,
             sig == SIGXCPU ? "hang (CPU time limit)" : sig == SIGALRM ? "hang (blocked: wall time limit)" : "crash", sig);
    } else if (reversal_mode && WEXITSTATUS(status) == EXIT_REVERSAL_UNJUDGED) {
      ++unjudged;
    } else if (reversal_mode && WEXITSTATUS(status) == EXIT_REVERSAL_ONE_SIDED) {
      ++one_sided;
    } else if (reversal_mode && WEXITSTATUS(status) == EXIT_REVERSAL_ONE_SIDED_LEFT) {
      ++one_sided_left;
    } else if (reversal_mode && WEXITSTATUS(status) == EXIT_REVERSAL_CHAOTIC) {
      ++chaotic;
    } else if (reversal_mode && WEXITSTATUS(status) == EXIT_REVERSAL_AMPLIFIED) {
      ++amplified;
    } else if (WEXITSTATUS(status) != 0) {
      static const char *why[] = {"exit from library code", "NaN/Inf given to LAPACK", "broken promise",
                                  "reversal broken", "", "", "",
                                  "one-sided with a symmetric scheme, no cause reported by the library",
                                  "one-sided with a symmetric scheme, an irreversible impact reported but not in the"
                                  " step where the directions part"};
      int code = WEXITSTATUS(status);
      ++bad;
      printf("FAIL seed %ld: exit status %d (%s)\n", first + i, code,
             (code >= 70 && code <= 73) || code == EXIT_REVERSAL_ONE_SIDED_UNEXPLAINED ||
                     code == EXIT_REVERSAL_ONE_SIDED_ELSEWHERE ? why[code - 70]
                                                                                  : "sanitizer report or runtime error");
    }
    if (max_failures > 0 && bad >= max_failures) { /* enough to act on; the rest would repeat the reports */
      printf("stopping after %ld failures\n", max_failures);
      stopped = 1;
      break;
    }
  }
  printf("%ld %s (seeds %ld..%ld) in %.0f s: %ld failed", ran, reversal_mode ? "reversal runs" : "random programs",
         first, first + ran - 1, difftime(time(NULL), start), bad);
  if (reversal_mode)
    printf(", %ld not judged (a failed step, or splits or energy fallbacks alike both ways), %ld not judged as"
           " one-sided (splits or energy fallbacks differ between the directions) with a symmetric scheme and an"
           " irreversible impact reported, %ld with the left rule (not symmetric), %ld chaotic (beyond 100 2N rtol,"
           " within 2N rtol x the measured forward growth, an error not reproduced by reruns with rtol/10 and p0"
           " moved by 1e-15-1e-14), %ld amplified round-off (beyond that bound, not reproduced either)", unjudged, one_sided, one_sided_left,
           chaotic, amplified);
  printf("%s\n", ran < count && !stopped ? " (time budget reached)" : "");
  return bad ? 1 : 0;
}
