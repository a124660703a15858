/* vci_ensemble_run (the C ABI's in-memory ensemble) when memory runs out (issue 24, item 2's rule for
 * every allocation): each allocation of at least MIN bytes fails in turn, k = 1, 2, ... until a run
 * no longer reaches the k-th. MIN is the size of one of the run's tables (n * members doubles), so
 * the failures fall on the starts' table, the results' tables and anything of that size the call
 * makes on the way. Each call must return VCI_OK with the same results as a run that never failed
 * (bit for bit), or VCI_ERR_MEMORY with a message; before the fix the copy of the results into the
 * caller's arrays made reshape temporaries of a table's size without stat=, and the first such
 * failure ended this program ("Error allocating ... bytes"). Usage: vci_alloc_capi_ensemble [MIN
 * [MEMBERS]] (defaults: a table's size, 4096; ctest also runs 256 8, where the members' own
 * allocations fail: each must be that member's VCI_ERR_MEMORY); the exit status is the number of
 * failed checks. Below 256 bytes the C ABI's copy of the model handle (an intrinsic assignment of a
 * type with allocatable components, no stat=) still ends the program (SIGSEGV). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "vci.h"
#include "../api/walls_lagrangian.h"

void vci_test_malloc_fail(long long k, long long min_bytes);
long long vci_test_malloc_fail_pending(void);

static int failures = 0;
#define CHECK(c, ...) do { if (!(c)) { printf("FAIL line %d: %s: ", __LINE__, #c); printf(__VA_ARGS__); printf("\n"); ++failures; } } while (0)

#define M 4096   /* members: a table of n * M doubles is 32 KiB */
#define CAP 4    /* impact times kept per member */

static int l_dq(int n, const double *q, const double *v, double *out, void *user) {
  (void)n; (void)v; (void)user;
  out[0] = -9.8 * sin(q[0]);
  return 0;
}

typedef struct {
  int status[M];
  double t[M], q[M], p[M], impact_t[CAP * M];
  int64_t steps[M], impacts[M];
  int impact_gap[CAP * M];
  char messages[160 * M];
} outcome;

static outcome reference, trial;
static double t0[M], q0[M], p0[M];
static int members = M;   /* argv[2]: fewer members, for a small MIN */

static int run(vci_model model, outcome *o) {
  vci_ensemble_config c = VCI_ENSEMBLE_CONFIG_INIT;
  vci_ensemble_results r = VCI_ENSEMBLE_RESULTS_INIT;
  c.h = 0.05; c.nsteps = 40; c.start_kind = VCI_START_MOMENTUM; c.threads = 1; c.impact_cap = CAP;
  memset(o, 0xff, sizeof *o);
  r.status = o->status; r.t = o->t; r.q = o->q; r.p = o->p; r.steps = o->steps; r.impacts = o->impacts;
  r.impact_t = o->impact_t; r.impact_gap = o->impact_gap; r.messages = o->messages; r.message_size = 160;
  return vci_ensemble_run(model, &c, members, t0, q0, p0, &r);
}

/* member j of the trial as in the reference, bit for bit (status, state, counts, impacts) */
static int member_equal(int j) {
  return trial.status[j] == reference.status[j] && memcmp(&trial.t[j], &reference.t[j], sizeof(double)) == 0 &&
         memcmp(&trial.q[j], &reference.q[j], sizeof(double)) == 0 &&
         memcmp(&trial.p[j], &reference.p[j], sizeof(double)) == 0 && trial.steps[j] == reference.steps[j] &&
         trial.impacts[j] == reference.impacts[j] &&
         memcmp(&trial.impact_t[CAP * j], &reference.impact_t[CAP * j], CAP * sizeof(double)) == 0 &&
         memcmp(&trial.impact_gap[CAP * j], &reference.impact_gap[CAP * j], CAP * sizeof(int)) == 0;
}

int main(int argc, char **argv) {
  vci_lagrangian_callbacks cb = VCI_LAGRANGIAN_CALLBACKS_INIT;
  vci_model model = NULL;
  long long k, min_bytes = argc > 1 ? atoll(argv[1]) : (long long)sizeof(double) * M;
  int met = 0, absorbed = 0, memory = 0, member_memory = 0;
  cb.lagrangian = l_value; cb.dl_dq = l_dq; cb.dl_dv = l_dv; cb.hessians = l_hess;
  cb.gaps = walls; cb.gap_gradients = wall_grads;
  if (vci_model_create_lagrangian(&model, 1, 0, 2, &cb, NULL) != VCI_OK) return 1;
  if (argc > 2) members = atoi(argv[2]);
  if (members < 2 || members > M) return 2;
  for (int j = 0; j < members; ++j) { t0[j] = 0.0; q0[j] = 0.0; p0[j] = 0.5 + 5.5 * j / (members - 1); }
  CHECK(run(model, &reference) == VCI_OK, "the run without a failure");
  CHECK(reference.impacts[members - 1] > 0, "the fastest member bounces (%lld impacts)",
        (long long)reference.impacts[members - 1]);
  for (k = 1; k <= 2000; ++k) {
    char msg[512];
    long long pending;
    int st;
    vci_test_malloc_fail(k, min_bytes);
    st = run(model, &trial);
    pending = vci_test_malloc_fail_pending();
    vci_test_malloc_fail(0, 0);
    vci_last_error(NULL, msg, sizeof msg);
    if (getenv("VCI_TEST_VERBOSE")) { printf("k = %lld: status %d pending %lld %s\n", k, st, pending, msg); fflush(stdout); }
    if (pending != 0) break;   /* the k-th allocation of that size was not reached: every one failed once */
    ++met;
    if (st == VCI_OK) {
      int bad = 0, lost = 0;
      for (int j = 0; j < members; ++j) {
        if (member_equal(j)) continue;
        if (trial.status[j] == VCI_ERR_MEMORY && trial.steps[j] < reference.steps[j]) ++lost;
        else {
          ++bad;
          printf("  k = %lld member %d: status %d (alone %d), steps %lld (%lld), impacts %lld (%lld)\n", k, j,
                 trial.status[j], reference.status[j], (long long)trial.steps[j], (long long)reference.steps[j],
                 (long long)trial.impacts[j], (long long)reference.impacts[j]);
          printf("    %s\n", trial.messages + 160 * j);
        }
      }
      if (lost > 0) ++member_memory; else ++absorbed;
      CHECK(bad == 0 && lost <= 1, "k = %lld: VCI_OK after a failure: %d members other than alone, %d out of memory",
            k, bad, lost);
    } else {
      ++memory;
      CHECK(st == VCI_ERR_MEMORY, "k = %lld: status %d: %s", k, st, msg);
      CHECK(strstr(msg, "memory") != NULL, "k = %lld: the message does not say memory: %s", k, msg);
    }
  }
  CHECK(met >= 3, "only %d large allocations met (the starts' and the results' tables are at least 3)", met);
  CHECK(k <= 2000, "the 2000th allocation was still reached");
  /* the library is still usable after the failures */
  CHECK(run(model, &trial) == VCI_OK && memcmp(&trial, &reference, sizeof trial) == 0, "a run after the failures");
  printf("vci_ensemble_run, allocations of at least %lld bytes failing in turn: %d met, %d a VCI_ERR_MEMORY, "
         "%d a member's VCI_ERR_MEMORY, %d absorbed\n", min_bytes, met, memory, member_memory, absorbed);
  vci_model_destroy(&model);
  return failures;
}
