/* fuzz_continuous.h: the continuous models of the fuzz harness: a Lagrangian L(q, qdot)
 * (vci_model_create_lagrangian) and a separable one (vci_model_create_separable) from closed forms. */
#ifndef VCI_FUZZ_CONTINUOUS_H
#define VCI_FUZZ_CONTINUOUS_H
#include "fuzz_util.h"

enum { MAXC = 8, MAXCM = 2, MAXCG = 4, NCCALLBACKS = 12 };
/* the closed forms: a particle in gravity, pendulums, L quartic in the velocity, a chain */
enum { KIND_GRAVITY, KIND_PENDULUM, KIND_QUARTIC, KIND_CHAIN, NKINDS };
typedef struct {
  int kind, n, m, ng;
  double mass[MAXC], grav[MAXC], stiff[MAXC], quart, pend, kchain, beta;
  double a[MAXCM][MAXC], normal[MAXCG][MAXC], offset[MAXCG];
  double dense_mass[MAXC * MAXC]; /* the separable model's M when dense */
  fault_t fault;
  long calls[NCCALLBACKS];
} cmodel_t;

/* A random model of a random kind; walls leave ref[MAXC] inside. benign != 0: no faults, no hostile
 * parameters, no constraints (the reversal property's scenes). separable != 0: quadratic in qdot. */
void random_cmodel(cmodel_t *md, const double *ref, int benign, int separable);
/* the callbacks (hostile != 0: optional ones present at random, gaps now and then with ngaps = 0;
 * otherwise all of them, gaps iff ngaps > 0) */
void lagrangian_callbacks(vci_lagrangian_callbacks *cb, int ngaps, int hostile);
void separable_callbacks(vci_separable_callbacks *cb, int ngaps, int hostile);
/* the Hessians' bandwidth: 1 for a chain, 0 otherwise */
int cmodel_bandwidth(const cmodel_t *md);
#endif
