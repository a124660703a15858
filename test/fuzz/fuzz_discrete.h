/* fuzz_discrete.h: the discrete model of the fuzz harness (vci_model_create with L_d callbacks). */
#ifndef VCI_FUZZ_DISCRETE_H
#define VCI_FUZZ_DISCRETE_H
#include "fuzz_util.h"

enum { MAXN = 4, MAXM = 2, MAXG = 6, NCALLBACKS = 9 };
typedef struct {
  int n, m, ng;
  double mass[MAXN], grav[MAXN], stiff[MAXN], a[MAXM][MAXN], normal[MAXG][MAXN], offset[MAXG];
  fault_t fault;
  long calls[NCALLBACKS];
} model_t;

/* a random model whose walls leave the point ref[MAXN] inside the admissible set */
void random_model(model_t *md, const double *ref);
/* its callbacks, each optional one present at random; gaps only with ngaps > 0 (mostly: a gaps
 * callback with ngaps = 0 is refused) */
void discrete_callbacks(vci_callbacks *cb, int ngaps);
#endif
