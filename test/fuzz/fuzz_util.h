/* fuzz_util.h: what every part of the C-ABI fuzz harness shares: the seeded generator, hostile
 * values, callback faults, and the promises the API makes (the statuses vci.h lists per function). */
#ifndef VCI_FUZZ_UTIL_H
#define VCI_FUZZ_UTIL_H
#include <stdint.h>
#include "vci.h"

/* ---- a small deterministic generator (xorshift64*) ---- */
void fuzz_seed(uint64_t seed);
uint64_t rnd(void);
int below(int n);
double uniform(double a, double b);
int chance(int percent);
/* a double that is often ordinary (typical * U(-2, 2)) and sometimes NaN, Inf or extreme */
double wild(double typical);
/* an int that is often in 0..typical and sometimes 0, -1, INT_MAX, INT_MIN or large */
int wild_int(int typical);

/* A callback fault: from call `from` on, every `every`-th call of callback `which` returns `code`
 * (kind 0) or writes NaN (1), +-Inf (2) or +-1e308 (3) into one of its outputs. */
typedef struct {
  int which, from, every, kind, code;
} fault_t;
void random_fault(fault_t *f, int ncallbacks);
/* counts the call of callback `which` in calls[]; returns the code the callback must return */
int apply_fault(const fault_t *f, long *calls, int which, double *out, int nout);

/* ---- the promises (exit status 72 when one is broken) ---- */
void promise(int ok, const char *what);
/* bit masks of statuses */
#define S(x) (1u << (x))
#define ST_BUSY_ARG (S(VCI_OK) | S(VCI_ERR_ARGUMENT) | S(VCI_ERR_STATE))
#define ST_STEP (ST_BUSY_ARG | S(VCI_ERR_CALLBACK) | S(VCI_ERR_NONFINITE) | S(VCI_ERR_NEWTON) | S(VCI_ERR_IMPACT) | \
                 S(VCI_ERR_TOO_MANY_IMPACTS) | S(VCI_ERR_MEMORY) | S(VCI_ERR_IO) | S(VCI_ERR_INADMISSIBLE))
#define ST_INIT (ST_BUSY_ARG | S(VCI_ERR_INADMISSIBLE) | S(VCI_ERR_CALLBACK) | S(VCI_ERR_NONFINITE) | \
                 S(VCI_ERR_NEWTON) | S(VCI_ERR_MEMORY))
#define ST_CREATE (S(VCI_OK) | S(VCI_ERR_ARGUMENT) | S(VCI_ERR_MEMORY))
/* s must be one of the statuses in `allowed` (vci.h's list for function `fn`) */
void check_listed(int s, unsigned allowed, const char *fn);
/* a failure always says why: the integrator's message, or the thread's (integ may be NULL) */
void check_message(int s, vci_integrator integ, const char *fn);

extern int fuzz_trace; /* VCI_FUZZ_TRACE set: print each call */
#endif
