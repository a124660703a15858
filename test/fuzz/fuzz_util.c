/* fuzz_util.c: the generator, hostile values, faults and promises of the fuzz harness. */
#include "fuzz_util.h"
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

int fuzz_trace = 0;
static uint64_t rng_state;

void fuzz_seed(uint64_t seed) { rng_state = seed * 0x9E3779B97F4A7C15ULL + 1; }
uint64_t rnd(void) {
  rng_state ^= rng_state >> 12;
  rng_state ^= rng_state << 25;
  rng_state ^= rng_state >> 27;
  return rng_state * 2685821657736338717ULL;
}
int below(int n) { return n <= 0 ? 0 : (int)(rnd() % (uint64_t)n); }
double uniform(double a, double b) { return a + (b - a) * (double)(rnd() >> 11) / 9007199254740992.0; }
int chance(int percent) { return below(100) < percent; }

double wild(double typical) {
  static const double hostile[] = {0.0, -0.0, 1e308, -1e308, 1e-308, 5e-324, 1e20, -1e20};
  switch (below(12)) {
  case 0: return NAN;
  case 1: return chance(50) ? INFINITY : -INFINITY;
  case 2: return hostile[below(8)];
  default: return typical * uniform(-2.0, 2.0);
  }
}
int wild_int(int typical) {
  static const int hostile[] = {0, -1, 1, 2147483647, -2147483647 - 1, 46341, 100000, 1000000000};
  return chance(20) ? hostile[below(8)] : below(typical + 1);
}

void random_fault(fault_t *f, int ncallbacks) {
  f->which = chance(60) ? below(ncallbacks) : -1;
  f->from = 1 + below(400);
  f->every = 1 + below(chance(50) ? 3 : 50);
  f->kind = below(4);
  f->code = chance(50) ? 1 + below(100) : -1 - below(100);
  if (chance(3)) f->code = chance(50) ? 2147483647 : -2147483647 - 1;
}

int apply_fault(const fault_t *f, long *calls, int which, double *out, int nout) {
  long c = ++calls[which];
  if (f->which != which || c < f->from || (c - f->from) % f->every != 0) return 0;
  switch (f->kind) {
  case 0: return f->code;                              /* failure code, either sign */
  case 1: if (nout > 0) out[c % nout] = NAN; return 0;
  case 2: if (nout > 0) out[c % nout] = (c & 1) ? INFINITY : -INFINITY; return 0;
  case 3: if (nout > 0) out[c % nout] = (c & 1) ? 1e308 : -1e308; return 0;
  default: return 0;
  }
}

void promise(int ok, const char *what) {
  if (!ok) {
    printf("broken promise: %s\n", what);
    fflush(stdout);
    _exit(72);
  }
}

void check_listed(int s, unsigned allowed, const char *fn) {
  char what[160];
  if (s >= 0 && s < 32 && (allowed & S(s))) return;
  snprintf(what, sizeof what, "%s returned %d (%s), not in its list in vci.h", fn, s, vci_status_string(s));
  promise(0, what);
}

void check_message(int s, vci_integrator integ, const char *fn) {
  char msg[600], what[160];
  if (s == VCI_OK) return;
  msg[0] = '\0';
  if (integ == NULL || vci_last_error(integ, msg, sizeof msg) != VCI_OK) vci_last_error(NULL, msg, sizeof msg);
  snprintf(what, sizeof what, "%s failed with %d and an empty message", fn, s);
  promise(msg[0] != '\0', what);
  if (fuzz_trace) printf("  -> %d: %s\n", s, msg);
}
