/** \file vci.h
 * \brief C interface of vci, variational collision integrators for nonholonomic Lagrangian
 * systems with impacts. Hand-written; the Fortran side is src/bindings/vci_capi.F90.
 *
 * Usage: fill a vci_callbacks initialised with VCI_CALLBACKS_INIT, vci_model_create,
 * vci_integrator_create, vci_init_from_pair (or _from_momentum), vci_integrate, vci_get_state,
 * then vci_integrator_destroy and vci_model_destroy. Every int-returning call returns VCI_OK (0)
 * or a status from the enum below; after a failure vci_last_error(integ, ...) says which step, at
 * which time and why. The library never prints, exits or aborts, and hands nothing non-finite to
 * LAPACK.
 *
 * Handles: a handle is a token, not an address, checked against a registry of live objects before
 * anything is done with it. NULL, destroyed (also after the memory was reused), foreign or garbage
 * handles give VCI_ERR_ARGUMENT; the message is then read with vci_last_error(NULL, ...).
 *
 * Threads (docs/C_API.md, "Threads"): every function may be called from any thread at any time.
 *  - A model is immutable once created and may be shared: several threads may create integrators
 *    from it at once, and destroy it meanwhile. Each integrator keeps its own copy of the model and
 *    its own status and message: integrators in different threads share nothing (but the `user`
 *    data their callbacks receive, which the callbacks must then guard themselves).
 *  - An integrator is used by one call at a time. A call on an integrator while another call on it
 *    runs (from another thread, or from one of its own callbacks) returns VCI_ERR_STATE and leaves
 *    the integrator alone (message: vci_last_error(NULL, ...)); vci_integrator_destroy in that
 *    situation kills the handle at once and frees the integrator when the running call returns
 *    (which then stops after its current step and returns VCI_ERR_STATE).
 *  - Failures with no live integrator to hold them are kept per thread: vci_last_error(NULL, ...)
 *    gives the calling thread's last one.
 *  - Output files (HDF5) are written under one library-wide lock.
 *
 * Callback contract (all model callbacks; SUNDIALS style): return 0 on success; a positive value
 * for a recoverable failure: at a trial point of Newton's line search the solver backs off to a
 * shorter step, anywhere else the step fails with VCI_ERR_CALLBACK; a negative value for an
 * unrecoverable failure: the step fails at once with VCI_ERR_CALLBACK. vci_last_error then names
 * the callback and the value it returned. NaN or Inf in an output counts as a recoverable failure
 * (VCI_ERR_NONFINITE if it ends the step). The state stays at the last accepted step. Codes are
 * never carried over: a failure the line search absorbed is forgotten once its step is accepted.
 *
 * Arrays are caller-owned, of doubles, and column-major; sizes use the model's n (configuration
 * dimension), m (number of constraint one-forms) and ngaps (number of gap functions).
 */
#ifndef VCI_H
#define VCI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Major version of this header (docs/VERSIONING.md: the soname is libvci.so.MAJOR). */
#define VCI_VERSION_MAJOR 0
/** Minor version of this header (additions to the C ABI). */
#define VCI_VERSION_MINOR 2
/** Patch version of this header (fixes only). */
#define VCI_VERSION_PATCH 0
/** Version of this header as one number; vci_version() gives the library's (major*10000 + minor*100 + patch). */
#define VCI_VERSION_NUMBER (VCI_VERSION_MAJOR * 10000 + VCI_VERSION_MINOR * 100 + VCI_VERSION_PATCH)

/** Status codes (same numbering as the Fortran module vci_status). */
enum {
  VCI_OK = 0,               /**< 0: success */
  VCI_ERR_ARGUMENT,         /**< 1: bad input: NULL or dead handle, NULL array, bad size or value */
  VCI_ERR_CALLBACK,         /**< 2: a user callback returned nonzero */
  VCI_ERR_NONFINITE,        /**< 3: NaN or Inf from a callback or a solve, or a time that overflows */
  VCI_ERR_NEWTON,           /**< 4: Newton iteration did not converge */
  VCI_ERR_IMPACT,           /**< 5: the impact stages had no admissible solution */
  VCI_ERR_TOO_MANY_IMPACTS, /**< 6: more impacts in one step than allowed (contact, chatter) */
  VCI_ERR_INADMISSIBLE,     /**< 7: a state lies outside the admissible set (some g_j < 0) */
  VCI_ERR_IO,               /**< 8: output could not be written, or HDF5 not built in */
  VCI_ERR_STATE,            /**< 9: call out of order (step before init), or the integrator is busy */
  VCI_ERR_MEMORY,           /**< 10: an allocation failed (sizes too large for this machine) */
  VCI_STOPPED               /**< 11: the caller stopped the run (a progress callback returned nonzero) */
};

/** Impact energy conditions for vci_set_impact_energy. */
enum {
  VCI_IMPACT_DISCRETE = 0,   /**< E_d(alpha h) = E_d((1 - alpha) h): the paper's condition, default */
  VCI_IMPACT_HAMILTONIAN = 1 /**< H(q~, p+) = H(q~, p-): needs the energy callback */
};

/** Opaque handle of a model (vci_model_create, vci_model_create_lagrangian; vci_model_destroy). */
typedef struct vci_model_s *vci_model;
/** Opaque handle of an integrator (vci_integrator_create; vci_integrator_destroy). */
typedef struct vci_integrator_s *vci_integrator;

/* Callbacks return 0, > 0 (recoverable failure) or < 0 (unrecoverable): the contract above.
 * Matrices are column-major: omega[i + n*mu] is component i of the one-form omega^mu;
 * hess[i + n*j] = d2 L_d / dq_i dv_j. `user` is the pointer given to vci_model_create. */

/** out[n] = D1 L_d(q, v, h) or D2 L_d(q, v, h); q[n], v[n]. */
typedef int (*vci_ld_grad_fn)(int n, const double *q, const double *v, double h, double *out, void *user);
/** out[0] = D3 L_d(q, v, h) = dL_d/dh (the discrete energy is E_d = -D3 L_d). */
typedef int (*vci_ld_dh_fn)(int n, const double *q, const double *v, double h, double *out /* [1] */, void *user);
/** hess[n*n] = d2 L_d / dq dv at (q, v, h), hess[i + n*j] = d2 L_d / dq_i dv_j. */
typedef int (*vci_hessian_fn)(int n, const double *q, const double *v, double h, double *hess, void *user);
/** omega[n*m]: the constraint one-forms at q[n], column mu = omega^mu. */
typedef int (*vci_forms_fn)(int n, int m, const double *q, double *omega, void *user);
/** out[m] = omega_d(base, other, h), the discrete constraint; base[n], other[n]. The forward
 *  scheme imposes omega_d(q_k, q_k+1, h) = 0, the backward one omega_d(q_k+1, q_k, h) = 0. */
typedef int (*vci_dconstraint_fn)(int n, int m, const double *base, const double *other, double h,
                                  double *out, void *user);
/** g[ngaps] = gap functions at q[n]; the admissible set is {q : g_j(q) >= 0 for all j}. */
typedef int (*vci_gaps_fn)(int n, int ngaps, const double *q, double *g, void *user);
/** dg[n*ngaps]: column j (dg[i + n*j]) = gradient of g_j at q[n]. */
typedef int (*vci_gap_grads_fn)(int n, int ngaps, const double *q, double *dg /* column j = grad g_j */,
                                void *user);
/** e[0] = H(q, p), a step-independent energy (normally the Hamiltonian); q[n], p[n]. */
typedef int (*vci_energy_fn)(int n, const double *q, const double *p, double *e /* [1] */, void *user);
/** Everything a Newton iteration needs of L_d at (q[n], v[n], h) in one call (issue 26):
 *  d1[n] = D1 L_d, d2[n] = D2 L_d, d3[0] = D3 L_d, hess[n*n] = d2 L_d / dq dv (hess[i + n*j] =
 *  d2 L_d / dq_i dv_j), the values d1_ld, d2_ld, d3_ld and mixed_hessian return; shared work (sines,
 *  cosines) is done once. The library keeps the last point's values: a residual, the Newton matrix
 *  and the new momentum at one point cost one call. */
typedef int (*vci_ld_fused_fn)(int n, const double *q, const double *v, double h, double *d1, double *d2,
                               double *d3 /* [1] */, double *hess, void *user);
/** Called for each impact: time t, fraction alpha of the step, gap_index j (0-based, the index into
 *  g[] of vci_gaps_fn), the configuration q[n] on the wall and the normal impulse (p after minus p
 *  before = impulse * grad g_j, forward time). Nonzero return (either sign): VCI_ERR_CALLBACK, but
 *  the step that contains the impact has been accepted (the state is after it). */
typedef int (*vci_impact_fn)(double t, double alpha, int gap_index, const double *q, double impulse, void *user);

/** The model's callbacks. `size` says how large the struct was in the header the caller was
 *  built with: always initialise with VCI_CALLBACKS_INIT, then set the members you need.
 *  Members are only ever added at the end; the library treats those beyond `size` as NULL, and
 *  refuses a struct from a newer header that sets members it does not know. */
typedef struct vci_callbacks {
  size_t size;                                              /**< = sizeof(vci_callbacks): VCI_CALLBACKS_INIT */
  vci_ld_grad_fn d1_ld;                                     /**< required: D1 L_d */
  vci_ld_grad_fn d2_ld;                                     /**< required: D2 L_d */
  vci_ld_dh_fn d3_ld;                                       /**< required: D3 L_d */
  vci_hessian_fn mixed_hessian;                             /**< optional (NULL: differenced) */
  vci_forms_fn constraint_forms;                            /**< required iff m > 0 */
  vci_dconstraint_fn discrete_constraint;                   /**< required iff m > 0 */
  vci_gaps_fn gaps;                                         /**< required iff ngaps > 0 */
  vci_gap_grads_fn gap_gradients;                           /**< optional (NULL: differenced) */
  vci_energy_fn energy;                                     /**< optional; needed by VCI_IMPACT_HAMILTONIAN */
  /** optional (NULL: differenced): jac[mu + m*i] = d omega_d^mu / d other_i at (base, other, h) */
  vci_dconstraint_fn discrete_constraint_jacobian;
  /** optional (NULL: d1_ld, d2_ld, d3_ld, mixed_hessian called one by one): all four in one call;
   *  it replaces mixed_hessian in the solves (issue 26) */
  vci_ld_fused_fn ld_fused;
  /* new members here */
} vci_callbacks;

/** Initialiser: `vci_callbacks cb = VCI_CALLBACKS_INIT;` (size set, every callback NULL). The C form
 *  is designated (no -Wmissing-field-initializers warning); the C++ one lists every member. */
#ifdef __cplusplus
#define VCI_CALLBACKS_INIT {sizeof(vci_callbacks), 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}
#else
#define VCI_CALLBACKS_INIT {.size = sizeof(vci_callbacks)}
#endif

/** Create a model of n coordinates, m constraints, ngaps walls. The callbacks are copied; `user`
 *  is passed to every callback. On failure *model = NULL (if model is not NULL).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: model or cb NULL, cb->size not that of a vci_callbacks of
 *  some header (the size field and a whole number of members: not initialised with
 *  VCI_CALLBACKS_INIT), a callback set that this library does not know (a newer
 *  header), n < 1, m < 0, m > n, ngaps < 0, n + m + 1 > 46340, n * ngaps >= 2^31, a required
 *  callback NULL, or a gaps callback given with ngaps = 0; VCI_ERR_MEMORY.
 *  (vci_model_create is a macro: the symbol vci_model_create keeps the 0.1 struct without `size`,
 *  for binaries built against vci 0.1.) */
int  vci_model_create_v2(vci_model *model, int n, int m, int ngaps, const vci_callbacks *cb, void *user);
/** vci_model_create(model, n, m, ngaps, cb, user): create a discrete model, vci_model_create_v2 (the
 *  name programs use; the symbol of that name is the 0.1 entry point, kept for 0.1 binaries). */
#define vci_model_create vci_model_create_v2

/* ---- Continuous Lagrangian models (docs/SCHEMES.md): the library builds L_d from L by a scheme ---- */

/** Schemes for vci_set_scheme (the Fortran VCI_SCHEME_* values). */
enum {
  VCI_SCHEME_DISCRETE = 0, /**< the model is a discrete L_d (vci_model_create): the only scheme it has */
  VCI_SCHEME_LEFT = 1,     /**< L_d = h L(q, (v - q)/h): the paper's retraction, order 1 */
  VCI_SCHEME_MIDPOINT = 2, /**< L_d = h L((q + v)/2, (v - q)/h): order 2, the default for a continuous model */
  VCI_SCHEME_LOBATTO = 3,  /**< Galerkin with s + 1 Lobatto points, s = 1..VCI_LOBATTO_MAX_STAGES: order 2s, with or without constraints */
  VCI_SCHEME_COMPOSITION = 4 /**< explicit Verlet compositions, order 2, 4, 6, 8, 10 (the stages argument): separable
                                  models only (vci_model_create_separable; another model gets VCI_ERR_ARGUMENT) */
};
/** The largest number of stages s of VCI_SCHEME_LOBATTO. */
#define VCI_LOBATTO_MAX_STAGES 8

/** l[0] = L(q, v), the Lagrangian at (q[n], v[n]). */
typedef int (*vci_lagrangian_value_fn)(int n, const double *q, const double *v, double *l /* [1] */, void *user);
/** out[n] = dL/dq or dL/dqdot at (q[n], v[n]). */
typedef int (*vci_lagrangian_grad_fn)(int n, const double *q, const double *v, double *out, void *user);
/** The three Hessian blocks at (q, v), each n x n column-major: lqq[i + n*j] = d2L/dq_i dq_j,
 *  lqv[i + n*j] = d2L/dq_i dv_j, lvv[i + n*j] = d2L/dv_i dv_j. */
typedef int (*vci_lagrangian_hessians_fn)(int n, const double *q, const double *v, double *lqq, double *lqv,
                                          double *lvv, void *user);

/** The three Hessian blocks on a declared band |i - j| <= bw (vci_model_declare_bandwidth) in
 *  LAPACK band storage, each (2 bw + 1) x n column-major: lqq[(bw + i - j) + (2*bw + 1)*j] =
 *  d2L/dq_i dq_j for |i - j| <= bw (0-based i, j), and so lqv, lvv; the other slots are ignored. */
typedef int (*vci_lagrangian_band_hessians_fn)(int n, int bw, const double *q, const double *v, double *lqq,
                                               double *lqv, double *lvv, void *user);

/** The three Hessian blocks in a declared sparse pattern (vci_model_declare_pattern), each an array
 *  of the declared nnz = colptr[n] values in the declared order: lqq[k] = d2L/dq_i dq_j for
 *  i = rowind[k] in column j (colptr[j] <= k < colptr[j+1]), and so lqv, lvv. Entries the library
 *  adds to the pattern (transposes, the diagonal) not declared are zero: declare every nonzero. */
typedef int (*vci_lagrangian_sparse_hessians_fn)(int n, int nnz, const double *q, const double *v, double *lqq,
                                                 double *lqv, double *lvv, void *user);

/** The callbacks of a continuous model, a struct of its own with its own leading size (same
 *  rules as vci_callbacks: initialise with VCI_LAGRANGIAN_CALLBACKS_INIT; members are only ever
 *  added at the end). Same return contract and conventions as the discrete callbacks. */
typedef struct vci_lagrangian_callbacks {
  size_t size;                                  /**< = sizeof(vci_lagrangian_callbacks) */
  vci_lagrangian_value_fn lagrangian;           /**< required: L(q, v) */
  vci_lagrangian_grad_fn dl_dq;                 /**< required: dL/dq */
  vci_lagrangian_grad_fn dl_dv;                 /**< required: dL/dqdot (the momentum) */
  vci_lagrangian_hessians_fn hessians;          /**< optional (NULL: differenced from dl_dq, dl_dv) */
  vci_forms_fn constraint_forms;                /**< required iff m > 0 */
  vci_gaps_fn gaps;                             /**< required iff ngaps > 0 */
  vci_gap_grads_fn gap_gradients;               /**< optional (NULL: differenced) */
  vci_energy_fn energy;                         /**< optional H(q, p) (NULL: Legendre inversion of dl_dv) */
  vci_lagrangian_band_hessians_fn hessians_band; /**< optional, used with a declared bandwidth by
                                                      VCI_SCHEME_LEFT and _MIDPOINT (no n x n block) */
  vci_lagrangian_sparse_hessians_fn hessians_sparse; /**< optional, used with a declared pattern by
                                                          VCI_SCHEME_LEFT and _MIDPOINT (Newton's matrix
                                                          assembled in the pattern, no n x n block) */
  /* new members here */
} vci_lagrangian_callbacks;

/** Initialiser: `vci_lagrangian_callbacks cb = VCI_LAGRANGIAN_CALLBACKS_INIT;` (size set, every
 *  callback NULL), as VCI_CALLBACKS_INIT. */
#ifdef __cplusplus
#define VCI_LAGRANGIAN_CALLBACKS_INIT {sizeof(vci_lagrangian_callbacks), 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}
#else
#define VCI_LAGRANGIAN_CALLBACKS_INIT {.size = sizeof(vci_lagrangian_callbacks)}
#endif

/** Create a continuous model L(q, qdot) of n coordinates, m constraints, ngaps walls (the
 *  callbacks are copied; `user` goes to every one). An integrator made from it uses
 *  VCI_SCHEME_MIDPOINT until vci_set_scheme chooses another. On failure *model = NULL.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: as vci_model_create (cb->size a whole number of members of a
 *  vci_lagrangian_callbacks), with lagrangian, dl_dq, dl_dv required; VCI_ERR_MEMORY. */
int  vci_model_create_lagrangian(vci_model *model, int n, int m, int ngaps, const vci_lagrangian_callbacks *cb,
                                 void *user);

/** Declare the Hessian blocks of a model banded (docs/DESIGN.md, "Structured Newton matrices"):
 *  entries with |i - j| > bw vanish (L_qq, L_qv, L_vv of a continuous model; D1 D2 L_d of a
 *  discrete one); bw < 0: dense again (the default). The left, midpoint and discrete schemes then
 *  factorise their Newton matrices in band storage, and a continuous model's hessians_band (if
 *  given) replaces the n x n blocks. check != 0: the debug check (O(n^2)): the band against the
 *  dense Hessians (or differences) at the start, and every Newton matrix, reported as
 *  VCI_ERR_ARGUMENT with a message naming the entry. Applies to integrators created afterwards.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: not a live model handle, or a separable model. */
int  vci_model_declare_bandwidth(vci_model model, int bw, int check);

/** Declare the Hessian blocks of a model sparse with a pattern (docs/C_API.md, "Sparse Hessian
 *  pattern"; issue 28): entries outside it vanish (L_qq, L_qv, L_vv of a continuous model; D1 D2
 *  L_d of a discrete one). The pattern is n x n in compressed columns, 0-based: column j's nonzero
 *  rows are rowind[colptr[j] .. colptr[j+1] - 1], strictly increasing; colptr[n + 1] starts at
 *  colptr[0] = 0 and never decreases, rowind[colptr[n]] lies in 0..n-1. The library closes it
 *  under transposition and adds the diagonal (neither need be given). The left, midpoint and
 *  discrete schemes then factorise their Newton matrices by sparse LU (SuiteSparse KLU).
 *  n = 0 withdraws the declaration (colptr, rowind may then be NULL). check != 0: the debug check
 *  (O(n^2)): every Newton matrix is checked for a nonzero outside the pattern, reported as
 *  VCI_ERR_ARGUMENT with a message naming the entry. A model with both a bandwidth and a pattern
 *  is refused by vci_integrator_create. Applies to integrators created afterwards.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT (vci_last_error(NULL, ...) says which): not a live model
 *  handle, a separable model, n not the model's n (nor 0), colptr or rowind NULL, colptr[0] != 0,
 *  a decreasing colptr, a row out of range or not strictly increasing in its column, or this
 *  library built without the sparse solver (vci_sparse_available() == 0: CMake VCI_SPARSE=OFF);
 *  VCI_ERR_MEMORY. */
int  vci_model_declare_pattern(vci_model model, int n, const int *colptr /* [n+1] */,
                               const int *rowind /* [colptr[n]] */, int check);
/** 1 if this library was built with the sparse solver for vci_model_declare_pattern (CMake
 *  VCI_SPARSE, SuiteSparse KLU), else 0. */
int  vci_sparse_available(void);

/* ---- Separable models (docs/C_API.md, "Separable models"): L = 1/2 qdot^T M qdot - V(q), M constant ---- */

/** mass_kind of vci_model_create_separable: how `mass` holds the constant mass matrix M. */
enum {
  VCI_MASS_DIAGONAL = 0, /**< mass[n]: the diagonal of M (each entry > 0) */
  VCI_MASS_DENSE = 1     /**< mass[n*n]: M column-major, symmetric positive definite */
};

/** out[0] = V(q) (the potential), out[n] = grad V(q), or out[n*n] = the Hessian of V
 *  (out[i + n*j] = d2V/dq_i dq_j) at q[n]. */
typedef int (*vci_potential_fn)(int n, const double *q, double *out, void *user);

/** The callbacks of a separable model, a struct of its own with its own leading size (same rules as
 *  vci_callbacks: initialise with VCI_SEPARABLE_CALLBACKS_INIT; members are only ever added at the
 *  end). Same return contract as the other callbacks. L, its derivatives and H are derived from M
 *  and V, so every scheme of a continuous model runs it, and VCI_SCHEME_COMPOSITION needs it. */
typedef struct vci_separable_callbacks {
  size_t size;                           /**< = sizeof(vci_separable_callbacks) */
  vci_potential_fn potential;            /**< required: V(q), out[1] */
  vci_potential_fn potential_gradient;   /**< required: grad V(q), out[n] */
  vci_potential_fn potential_hessian;    /**< optional (NULL: the implicit schemes difference grad V) */
  vci_gaps_fn gaps;                      /**< required iff ngaps > 0 */
  vci_gap_grads_fn gap_gradients;        /**< required iff ngaps > 0 (the explicit impact uses it) */
  /* new members here */
} vci_separable_callbacks;

/** Initialiser: `vci_separable_callbacks cb = VCI_SEPARABLE_CALLBACKS_INIT;` (size set, every
 *  callback NULL), as VCI_CALLBACKS_INIT. */
#ifdef __cplusplus
#define VCI_SEPARABLE_CALLBACKS_INIT {sizeof(vci_separable_callbacks), 0, 0, 0, 0, 0}
#else
#define VCI_SEPARABLE_CALLBACKS_INIT {.size = sizeof(vci_separable_callbacks)}
#endif

/** Create a separable model L = 1/2 qdot^T M qdot - V(q) of n coordinates and ngaps walls with the
 *  constant mass matrix M in mass (mass_kind VCI_MASS_DIAGONAL: mass[n]; VCI_MASS_DENSE: mass[n*n]),
 *  copied with the callbacks; `user` goes to every callback. An integrator made from it uses
 *  VCI_SCHEME_MIDPOINT until vci_set_scheme chooses another (VCI_SCHEME_COMPOSITION: the explicit
 *  Verlet compositions, no linear solve). On failure *model = NULL.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: as vci_model_create (cb->size a whole number of members of a
 *  vci_separable_callbacks), m != 0 (a separable model has no nonholonomic constraints: give such a
 *  model with vci_model_create_lagrangian and VCI_SCHEME_LOBATTO, order 2s with constraints, or midpoint), potential or potential_gradient
 *  NULL, gaps or gap_gradients NULL with ngaps > 0, unknown mass_kind, mass NULL, a diagonal entry
 *  not positive and finite, a dense M not symmetric positive definite and finite; VCI_ERR_MEMORY. */
int  vci_model_create_separable(vci_model *model, int n, int m, int ngaps, int mass_kind, const double *mass,
                                const vci_separable_callbacks *cb, void *user);

/** Choose the scheme of an integrator made from a continuous model: VCI_SCHEME_LEFT, _MIDPOINT,
 *  or _LOBATTO with `stages` = s in 1..VCI_LOBATTO_MAX_STAGES, or VCI_SCHEME_COMPOSITION of order
 *  `stages` (ignored for left and midpoint). Call after vci_integrator_create and before
 *  initialising. Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, a discrete model, unknown scheme,
 *  s out of range, a composition order not 2, 4, 6, 8 or 10, a composition for a model not made by
 *  vci_model_create_separable (the integrator keeps its scheme); VCI_ERR_MEMORY: the scheme's
 *  workspace could not be allocated (about 3 (s n + 1)^2 doubles for lobatto): the integrator then
 *  has no usable scheme, and initialising it returns VCI_ERR_STATE until a vci_set_scheme
 *  succeeds; VCI_ERR_STATE: busy, already initialised (the run stays as it was: create a new
 *  integrator for another scheme), or an open output file holds steps. */
int  vci_set_scheme(vci_integrator integ, int scheme, int stages);

/** Release the model and set *model = NULL. NULL-safe (model or *model NULL: nothing happens).
 *  Integrators created from it keep their own copy: it may be destroyed right after
 *  vci_integrator_create. */
void vci_model_destroy(vci_model *model);

/** Create an integrator of step length h (> 0, finite) for model. On failure *integ = NULL.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: integ NULL, model NULL or not live, h not positive and finite,
 *  a declared sparse pattern that cannot be used (invalid, a bandwidth declared too, or this library
 *  built without the sparse solver); VCI_ERR_MEMORY: the workspace (about 3 (n + m + 1)^2 doubles)
 *  could not be allocated, or no handle is left. */
int  vci_integrator_create(vci_integrator *integ, vci_model model, double h);

/** Destroy the integrator (finishing its output file, if any) and set *integ = NULL. NULL-safe.
 *  When a call on it is running, the integrator is freed as that call returns (see Threads). */
void vci_integrator_destroy(vci_integrator *integ);

/** Newton tolerances: row i converges when |r_i| <= atol + rtol * (size of row i's terms); at most
 *  max_iterations per solve. Defaults: atol = 0, rtol = 1e-12, max_iterations = 30.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, atol or rtol negative or not finite, both zero,
 *  rtol >= 1 (any iterate would pass), max_iterations < 1; VCI_ERR_STATE: busy. */
int  vci_set_tolerances(vci_integrator integ, double atol, double rtol, int max_iterations);

/** Impact energy condition, VCI_IMPACT_DISCRETE (default) or VCI_IMPACT_HAMILTONIAN. The explicit
 *  compositions (VCI_SCHEME_COMPOSITION) use hamiltonian until this chooses one (docs/SCHEMES.md).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, unknown mode, or hamiltonian without the energy
 *  callback; VCI_ERR_STATE: busy. */
int  vci_set_impact_energy(vci_integrator integ, int mode);

/** Impacts allowed inside one step before VCI_ERR_TOO_MANY_IMPACTS (default max(16, 4 ngaps)); the records
 *  grow on demand, so a large bound costs nothing up front.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, max_impacts < 1; VCI_ERR_STATE: busy. */
int  vci_set_max_impacts(vci_integrator integ, int max_impacts);

/** The safety net: a step whose Newton solve or impact stages fail (VCI_ERR_NEWTON, VCI_ERR_IMPACT)
 *  or that exceeds the impacts-per-step bound is retried as 2, 4, ... equal sub-steps of the same
 *  scheme, up to max_splits of them (default 16); 1 turns it off (the step then fails with its own
 *  status). Counted by vci_get_split_steps (docs/DESIGN.md §2, "Steps that cannot be solved").
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, max_splits outside 1..1024; VCI_ERR_STATE: busy. */
int  vci_set_step_splits(vci_integrator integ, int max_splits);

/** The poke screen (docs/BACKWARD.md, "A wall poked within one sub-step"): 1 (the default) looks
 *  inside each sub-step that may come near a wall for a wall crossed and left again within it (the
 *  grid-point test alone misses it: a graze, or a second bounce off the same wall in one long step),
 *  where the sub-step resolves the motion; 0 tests the gaps at the sub-steps' ends only (cheaper;
 *  docs/bench/poke.md). The explicit compositions' dip screen follows it too (docs/DESIGN.md §9: 0
 *  checks their ends and stage points only). Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, on not
 *  0 or 1; VCI_ERR_STATE: busy. */
int  vci_set_poke_samples(vci_integrator integ, int on);

/** Start from the pair q0[n] at t0 and q1[n] at t0 + h. The current state becomes
 *  (t0 + h, q1, p1) with p1 = D2 L_d(q0, q1, h), step index 1; the discrete energy is E_d(q0, q1, h).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, q0 or q1 NULL, NaN/Inf in t0, q0 or q1, t0 + h
 *  overflows, a required constraint callback missing, VCI_SCHEME_COMPOSITION (it starts from a
 *  momentum: vci_init_from_momentum), or the debug check of a declared bandwidth (check != 0)
 *  found an entry outside the band, or the check of a hessians_sparse callback (once, against
 *  differences of the gradients) found a wrong value or a nonzero outside the declared pattern;
 *  VCI_ERR_INADMISSIBLE: q0 or q1 outside the admissible set;
 *  VCI_ERR_CALLBACK or VCI_ERR_NONFINITE: a callback failed or gave NaN/Inf; VCI_ERR_NEWTON:
 *  lobatto's interior stages of the pair could not be solved; VCI_ERR_MEMORY: the probes of the
 *  model could not be allocated; VCI_ERR_STATE: busy, an open output file already holds steps
 *  (close it first), or the last vci_set_scheme failed (no usable scheme). After a failure the
 *  integrator has no state (VCI_ERR_STATE from stepping) until initialised again. */
int  vci_init_from_pair(vci_integrator integ, double t0, const double *q0, const double *q1);

/** Start from (q0[n], p0[n]) at t0, step index 0 (no discrete energy until the first step).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, q0 or p0 NULL, NaN/Inf in t0, q0 or p0, a
 *  required constraint callback missing, or the debug check of a declared bandwidth (check != 0)
 *  found an entry outside the band, or the check of a hessians_sparse callback found a wrong value
 *  or a nonzero outside the declared pattern; VCI_ERR_INADMISSIBLE: q0 outside the admissible set;
 *  VCI_ERR_CALLBACK: a callback failed or gave NaN/Inf at q0; VCI_ERR_NONFINITE: a Hessian of the
 *  bandwidth check gave NaN/Inf; VCI_ERR_MEMORY, VCI_ERR_STATE: as vci_init_from_pair. Nothing is
 *  solved (no VCI_ERR_NEWTON). After a failure the integrator has no state. */
int  vci_init_from_momentum(vci_integrator integ, double t0, const double *q0, const double *p0);

/** One step: direction +1 forward ((+) scheme), -1 backward ((-) scheme).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle or direction, or the debug check of a declared
 *  bandwidth or pattern (check != 0) found a Newton matrix entry outside it; VCI_ERR_STATE: not
 *  initialised, busy, an open output file holds a run in the other direction, or the integrator
 *  was destroyed during the call (see Threads); VCI_ERR_NONFINITE: also when the time of the next
 *  state overflows;
 *  VCI_ERR_CALLBACK, VCI_ERR_NONFINITE, VCI_ERR_NEWTON, VCI_ERR_IMPACT, VCI_ERR_TOO_MANY_IMPACTS,
 *  VCI_ERR_MEMORY: the step failed and the state stays at the last accepted step; VCI_ERR_CALLBACK
 *  also when the impact callback returned nonzero, VCI_ERR_IO when the output file failed, and
 *  VCI_ERR_MEMORY when the checkpoint the output file stores at a flush could not be allocated
 *  (for these three the step was accepted and the integrator goes on from it; VCI_ERR_IO or
 *  VCI_ERR_MEMORY before the step when the file could not start the run); VCI_ERR_INADMISSIBLE:
 *  the state lies beyond a wall by more than the solver's tolerance although the gaps callback
 *  gave g >= 0 there when the step before ended (a gaps callback that is not a function of q
 *  alone, or a model changed under the integrator; the state stays). */
int  vci_step(vci_integrator integ, int direction);                 /* +1 forward, -1 backward */

/** nsteps (>= 0) steps in one direction; stops at the first failure (state = last accepted step).
 *  Returns as vci_step, VCI_ERR_ARGUMENT also for nsteps < 0, VCI_ERR_IO also when the output file
 *  fails at the start or the end of the run, VCI_ERR_MEMORY also when the checkpoint of the run's
 *  last state could not be allocated for the file's last flush (the file then has none of that
 *  state; the state is kept), and VCI_STOPPED when the progress callback
 *  (vci_set_progress) asked to stop (the state is that of the last step it was told of). */
int  vci_integrate(vci_integrator integ, int64_t nsteps, int direction);

/** The current state: *t, q[n], p[n]. Any of t, q, p may be NULL to skip it.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle; VCI_ERR_STATE: not initialised, or busy. */
int  vci_get_state(vci_integrator integ, double *t, double *q, double *p);

/** The multipliers lambda[m] of the last step (nothing is written when m = 0).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, lambda NULL with m > 0; VCI_ERR_STATE: not
 *  initialised, busy. */
int  vci_get_multipliers(vci_integrator integ, double *lambda);

/** The discrete energy E_d of the last step (of its last sub-step if it had impacts); NaN after
 *  vci_init_from_momentum until the first step.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, energy NULL; VCI_ERR_STATE: not initialised, busy. */
int  vci_get_energy(vci_integrator integ, double *energy);

/** The index k of the current state (t = t0 + k h). Returns as vci_get_energy. */
int  vci_get_index(vci_integrator integ, int64_t *k);

/** Counters over the integrator's life; any pointer may be NULL to skip it.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle; VCI_ERR_STATE: busy. */
int  vci_get_stats(vci_integrator integ, int64_t *steps, int64_t *impacts, int64_t *newton_iterations);

/** Soft impacts (the normal kinetic energy comparable to E_d's O(h^2) mismatch with H) at which the
 *  discrete energy condition was blended with H (a reversible condition, docs/BACKWARD.md) or, as a
 *  last resort or with constraints, H(q, p) was kept instead; only with a model that supplies energy
 *  (else an impact without a discrete root fails the step). Only impacts of the steps taken count:
 *  not those of an attempt the safety net discarded (vci_set_step_splits). count may be NULL.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle; VCI_ERR_STATE: busy. */
int  vci_get_energy_fallbacks(vci_integrator integ, int64_t *count);

/** Impacts the library could not make reversible (docs/BACKWARD.md, "Impacts that cannot be tied"):
 *  in a step with several impacts, an impact's energy condition is held on the sub-step that leaves
 *  it up to the next wall, which is what a reversed run poses; where the search finds no impulse
 *  that does (as measured: the impulse that would hold it lets the motion miss that wall), the
 *  impact keeps its condition on the rest of the step, and a run back through it need not return
 *  to its start. Also counted: a step taken without an impact in which a reversed run, sampling
 *  the step from its end, finds a wall poked that this run, sampling from its start, does not
 *  (a graze shallower than the scheme's error; docs/DESIGN.md, "A poke seen from the end only"),
 *  and a touch (an impact without impulse) whose arriving momentum leaves the wall: a reversed run
 *  arrives with that momentum, moving into the wall, and reflects there (docs/BACKWARD.md, "The odd
 *  ones"), and an impact whose energy condition has a second root of the other kind: another impulse
 *  whose motion meets a wall within the rest of the step where the impulse taken leaves it free, or
 *  the other way round (a soft impact: the step has two solutions and a run back may take the other;
 *  docs/BACKWARD.md, "Two solutions of a step with a soft impact").
 *  Only impacts of the steps taken count (as vci_get_energy_fallbacks). count may be NULL.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle; VCI_ERR_STATE: busy. */
int  vci_get_irreversible_impacts(vci_integrator integ, int64_t *count);

/** Steps the safety net (vci_set_step_splits) took as equal sub-steps, and the most sub-steps one
 *  of them needed (0 when none); either pointer may be NULL.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle; VCI_ERR_STATE: busy. */
int  vci_get_split_steps(vci_integrator integ, int64_t *steps, int64_t *largest);

/** Call fn(..., user) at every impact of later steps; fn = NULL removes it.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle; VCI_ERR_STATE: busy. */
int  vci_set_impact_callback(vci_integrator integ, vci_impact_fn fn, void *user);

/** Write the trajectory of later steps to the HDF5 file path (replaced if it exists); the file is
 *  finished by vci_close_output, vci_integrator_destroy or the next vci_open_output. One file holds
 *  one run: steps in one direction from one initialisation (other calls give VCI_ERR_STATE).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, path NULL or empty; VCI_ERR_IO: the file cannot
 *  be created, the previous output file could not be finished, or this library was built without
 *  HDF5 (vci_last_error says which); VCI_ERR_MEMORY: the writer could not be allocated;
 *  VCI_ERR_STATE: busy. */
int  vci_open_output(vci_integrator integ, const char *path);      /* HDF5; VCI_ERR_IO when unavailable */

/** vci_open_output keeping every `every`-th state (those whose index from the file's first state is
 *  a multiple of it, and the run's last; impacts all: docs/OUTPUT.md) and, with compress = 1..9,
 *  gzip of that level with shuffle on the datasets (0: none). vci_open_output is every = 1,
 *  compress = 0. Returns as vci_open_output; VCI_ERR_ARGUMENT also when every is not in [1, 2^30]
 *  or compress not in [0, 9]. */
int  vci_open_output_every(vci_integrator integ, const char *path, int every, int compress);

/** Finish and close the output file, if any (vci_integrator_destroy does the same). The file's
 *  status and status_message are those of the last vci_step or vci_integrate on it, not of this
 *  call. Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle; VCI_ERR_IO: the file could not be finished
 *  (the message says why); VCI_ERR_MEMORY: the checkpoint of the last state could not be
 *  allocated, the file is finished without it; VCI_ERR_STATE: busy. */
int  vci_close_output(vci_integrator integ);

/* ---- Restart (docs/C_API.md, "Restart"): continue a run from its HDF5 file, bit for bit ---- */

/** Continue the HDF5 file `path` with the later steps (instead of replacing it, as vci_open_output
 *  does). The file is one written by vci_open_output, the Fortran writer or the examples'
 *  --output; the run must go on from its last state in its direction, with the same n, m, ngaps
 *  and h (restore that state first with vci_restore_from_file). Finished like vci_open_output's.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, path NULL or empty; VCI_ERR_IO: the file does not
 *  exist, is not a regular file, not an HDF5 file of this library or not writable, the previous
 *  output file could not be finished, or this library was built without HDF5 (vci_last_error says
 *  which); VCI_ERR_MEMORY; VCI_ERR_STATE: busy.
 *  The first step after it returns VCI_ERR_IO (nothing written) when the run does not continue the
 *  file: another state, direction, n, m, ngaps or h. */
int  vci_append_output(vci_integrator integ, const char *path);

/** Start from the last state of the HDF5 file `path`. Every flush of the file stores a checkpoint
 *  (the state of its last row and the solver's memory): from it the run continues bit for bit, as
 *  if it had never stopped (same t, q, p, step index and discrete energy as the uninterrupted run,
 *  step after step). A file without a checkpoint gives its last (t, q, p) at index 0, as
 *  vci_init_from_momentum would. The integrator must have the file's model sizes and step length.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, path NULL or empty, the file's n or m differ from
 *  the model's, or its h from the integrator's; VCI_ERR_IO: the file cannot be read (missing, not
 *  a regular file, not an HDF5 file of this library, damaged) or this library was built without
 *  HDF5; VCI_ERR_ARGUMENT, VCI_ERR_INADMISSIBLE, VCI_ERR_CALLBACK, VCI_ERR_NONFINITE,
 *  VCI_ERR_MEMORY: the file's state is refused as vci_init_from_momentum refuses one;
 *  VCI_ERR_STATE: busy, an open output file already holds steps (close it first), or the last
 *  vci_set_scheme failed. After a failure the integrator has no state until initialised again. */
int  vci_restore_from_file(vci_integrator integ, const char *path);

/** Copy the message of the last call on integ (empty after a success) into buffer[size],
 *  truncated to size - 1 characters and NUL-terminated. integ = NULL: the calling thread's last
 *  failure that had no live integrator to hold it (failed create, NULL, dead or busy handle).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: buffer NULL or size < 1 (nothing written), or integ not live
 *  (buffer then says so); VCI_ERR_STATE: a call on integ is running (buffer says so). */
int  vci_last_error(vci_integrator integ, char *buffer, int size);  /* NUL-terminated, truncated to size */

/** A static description of a status code ("unknown status" for other values); never NULL. */
const char *vci_status_string(int status);

/** The library's version: major*10000 + minor*100 + patch. */
int  vci_version(void);

/** Progress of a run (vci_set_progress): steps done of this vci_integrate call and its total,
 *  impacts so far, model time, wall seconds of this call, rate, estimated seconds left (-1: unknown). */
typedef struct vci_progress {
  int64_t steps_done;          /**< steps done in this vci_integrate call */
  int64_t steps_total;         /**< steps this call was asked for */
  int64_t impacts;             /**< impacts so far */
  double t;                    /**< model time of the current state */
  double elapsed;              /**< wall seconds of this call */
  double steps_per_second;     /**< rate so far */
  double eta;                  /**< estimated wall seconds left (-1: unknown) */
} vci_progress;
/** Return 0 to go on, nonzero to stop the run after this step (vci_integrate then returns VCI_STOPPED). */
typedef int (*vci_progress_fn)(const vci_progress *info, void *user);
/** Call fn at most once per `interval` seconds of wall time during vci_integrate, and after its last
 *  step; fn = NULL: no more reports. The library prints nothing itself. Returns VCI_OK;
 *  VCI_ERR_ARGUMENT: bad handle, interval < 0, > 1e9 or NaN; VCI_ERR_STATE: busy. */
int  vci_set_progress(vci_integrator integ, vci_progress_fn fn, double interval, void *user);

/** The model checker: compares every derivative callback the model supplies with central
 *  differences at one point (discrete L_d: D1/D2/D3 against each other, the mixed Hessian, the
 *  discrete constraint's Jacobian, the constraint forms against the discrete form; continuous L:
 *  dl_dq, dl_dv against L, the Hessian blocks, energy against the Legendre transform; both: gap
 *  gradients). q[n], v[n]: the point (v the second configuration of L_d(q, v, h), or the velocity
 *  for L); tol <= 0: the default 1e-6. *passed = 1 when every worst relative mismatch <= tol,
 *  *worst = the largest; report (NULL: none) gets one line per comparison, truncated to size - 1.
 *  Returns VCI_OK when the check ran; VCI_ERR_ARGUMENT (NULL pointers, dead handle, h <= 0 or not
 *  finite, NaN/Inf in q or v, report given with size < 1); VCI_ERR_CALLBACK: a callback failed at
 *  the point (vci_last_error(NULL, ...) names it); VCI_ERR_MEMORY: the check's n x n work arrays
 *  could not be allocated. */
int  vci_check_model(vci_model model, const double *q, const double *v, double h, double tol, int *passed,
                     double *worst, char *report, int size);

/* ---- Ensembles (docs/ENSEMBLES.md, "From C"): many members of one model, over OpenMP threads
 *      and, in a library built with MPI, over the ranks of a communicator ---- */

/** What v0 of vci_ensemble_run is (vci_ensemble_config.start_kind). */
enum {
  VCI_START_PAIR = 0,     /**< v0 is q1 at t0 + h: the paper's initial pair, as vci_init_from_pair */
  VCI_START_MOMENTUM = 1  /**< v0 is p0 at t0, as vci_init_from_momentum */
};
/** The status of a member that was not run (the fill value of vci_ensemble_results.status). */
#define VCI_MEMBER_NOT_RUN (-1)

/** What every member of an ensemble shares. Versioned like vci_callbacks: initialise with
 *  VCI_ENSEMBLE_CONFIG_INIT (size and the defaults below), then set members. Every member is 8
 *  bytes; `size` must be a whole number of them (at least up to nsteps). Members are only ever
 *  added at the end; those beyond a caller's size keep their defaults. */
typedef struct vci_ensemble_config {
  size_t size;                  /**< = sizeof(vci_ensemble_config): VCI_ENSEMBLE_CONFIG_INIT */
  double h;                     /**< step length (> 0, finite) */
  int64_t nsteps;               /**< steps per member (>= 0) */
  int64_t direction;            /**< +1 forward (default), -1 backward */
  int64_t start_kind;           /**< VCI_START_PAIR (default) or VCI_START_MOMENTUM */
  int64_t scheme;               /**< continuous model: VCI_SCHEME_LEFT, _MIDPOINT or _LOBATTO; -1 (default):
                                     midpoint for a continuous model, and the only value for a discrete one */
  int64_t stages;               /**< s of VCI_SCHEME_LOBATTO (1..VCI_LOBATTO_MAX_STAGES) */
  double atol;                  /**< Newton's absolute tolerance; < 0 (default): vci_set_tolerances' default */
  double rtol;                  /**< Newton's relative tolerance; < 0 (default): the default */
  int64_t max_iterations;       /**< Newton iteration cap; 0 (default): the default */
  int64_t impact_energy;        /**< VCI_IMPACT_DISCRETE or VCI_IMPACT_HAMILTONIAN; -1 (default): discrete */
  int64_t max_impacts_per_step; /**< as vci_set_max_impacts; 0 (default): the default */
  int64_t impact_cap;           /**< impact times kept per member (results impact_t/impact_gap); default 0 */
  int64_t stride;               /**< vci_ensemble_run_file: keep the state every stride steps (0: none) */
  int64_t threads;              /**< OpenMP threads; 0 (default): OMP_NUM_THREADS */
  int64_t chunk;                /**< vci_ensemble_run_file: members a rank takes at a time (0: automatic) */
  /* new members here */
} vci_ensemble_config;

/** Initialiser: `vci_ensemble_config c = VCI_ENSEMBLE_CONFIG_INIT;` then set h and nsteps. */
#ifdef __cplusplus
#define VCI_ENSEMBLE_CONFIG_INIT {sizeof(vci_ensemble_config), 0.0, 0, 1, 0, -1, 0, -1.0, -1.0, 0, -1, 0, 0, 0, 0, 0}
#else
#define VCI_ENSEMBLE_CONFIG_INIT {.size = sizeof(vci_ensemble_config), .direction = 1, .scheme = -1, \
                                  .atol = -1.0, .rtol = -1.0, .impact_energy = -1}
#endif

/** Where vci_ensemble_run puts each member's results: caller-owned arrays, any of them NULL to skip
 *  it; N = members, member k's entries at [k] (or [i + n*k], [j + impact_cap*k]). Versioned like
 *  vci_ensemble_config (initialise with VCI_ENSEMBLE_RESULTS_INIT; 8-byte members). */
typedef struct vci_ensemble_results {
  size_t size;                  /**< = sizeof(vci_ensemble_results): VCI_ENSEMBLE_RESULTS_INIT */
  int *status;                  /**< [N] VCI_OK, or the status that stopped the member */
  double *t;                    /**< [N] time of the member's last accepted state (NaN: none) */
  double *q;                    /**< [n*N] its configuration, q[i + n*k] */
  double *p;                    /**< [n*N] its momentum */
  int64_t *steps;               /**< [N] steps taken */
  int64_t *impacts;             /**< [N] impacts found */
  int64_t *newton_iterations;   /**< [N] Newton iterations */
  double *energy_start;         /**< [N] H(q, p) at the start (energy callback), else E_d of the first step */
  double *energy_end;           /**< [N] the same at the end */
  double *impact_t;             /**< [impact_cap*N] the first impact_cap impact times (NaN beyond the last) */
  int *impact_gap;              /**< [impact_cap*N] their gap indices, from 0 (-1 beyond the last) */
  char *messages;               /**< [message_size*N] why member k failed ("" if not), NUL-terminated at
                                     messages + message_size*k, truncated to message_size - 1 */
  int64_t message_size;         /**< bytes per member in messages (>= 1 when messages is given) */
  /* new members here */
} vci_ensemble_results;

/** Initialiser: `vci_ensemble_results r = VCI_ENSEMBLE_RESULTS_INIT;` (every array NULL). */
#ifdef __cplusplus
#define VCI_ENSEMBLE_RESULTS_INIT {sizeof(vci_ensemble_results), 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}
#else
#define VCI_ENSEMBLE_RESULTS_INIT {.size = sizeof(vci_ensemble_results)}
#endif

/** Run `members` members of `model` (discrete, or continuous discretised by config->scheme and
 *  stages) on OpenMP threads; member k starts from t0[k], q0[n*k .. n*k+n-1] and v0 (q1 or p0, as
 *  config->start_kind says), each with its own copy of the model and its own integrator, and
 *  yields what vci_integrate from that start would: bit for bit, whatever the threads. The model's
 *  callbacks are called from several threads at once with the one `user` pointer: they must be
 *  thread-safe (config->threads = 1 runs the members one after another on one thread).
 *  A member that fails is recorded (results->status, messages) and does not stop the others.
 *  Returns VCI_OK when the ensemble ran, whatever its members did; VCI_ERR_ARGUMENT: model not
 *  live, config, t0, q0, v0 or results NULL, a struct size that is no header's (or members set
 *  that this library does not know), members < 1 or members * n >= 2^31, h, nsteps, direction,
 *  start_kind, scheme, stages, impact_energy or a count invalid or beyond an int, atol and rtol
 *  both 0, a scheme for a discrete model, a separable model (vci_model_create_separable: not in
 *  ensembles yet); VCI_ERR_MEMORY: the starts or the results (impact_cap and trajectory samples
 *  per member) could not be allocated. The message: vci_last_error(NULL, ...). */
int  vci_ensemble_run(vci_model model, const vci_ensemble_config *config, int64_t members, const double *t0,
                      const double *q0, const double *v0, const vci_ensemble_results *results);

/** vci_ensemble_run writing every member's results (and, with config->stride > 0, its states every
 *  stride steps) to the ensemble HDF5 file `path` (layout: docs/ENSEMBLES.md), as the Fortran
 *  vci_ensemble_run_file does. In a library built with MPI (VCI_WITH_MPI) the call is collective
 *  over the communicator mpi_comm, given as its Fortran handle (MPI_Comm_c2f(comm); -1:
 *  MPI_COMM_WORLD; MPI must be initialised), every rank passing the same arguments; otherwise one
 *  process runs every member and mpi_comm is not looked at. An existing file is kept (VCI_ERR_IO)
 *  unless overwrite != 0. *members_failed (may be NULL) = members whose status is not VCI_OK.
 *  Returns VCI_OK when every member was run and written; the statuses of vci_ensemble_run, path
 *  NULL or empty or ranks given different member counts (VCI_ERR_ARGUMENT), VCI_ERR_IO (the file,
 *  or no HDF5 in this library), VCI_ERR_MEMORY (also the file writer's buffers: a block's ranks,
 *  under MPI the fill values), VCI_ERR_STATE (MPI not initialised); under MPI the ranks all
 *  return the same status (and message). */
int  vci_ensemble_run_file(vci_model model, const vci_ensemble_config *config, int64_t members,
                           const double *t0, const double *q0, const double *v0, const char *path,
                           int overwrite, int mpi_comm, int64_t *members_failed);

/* ---- impact stages by bordering (issue 28) ---- */

/** Impact stages 1 and 2 solved by bordering (on = 1, the default): the sub-step's Newton block is
 *  factorised in its own structure (dense, declared band or pattern) and the alpha/mu row and column
 *  eliminated by their Schur complement; on = 0 factorises each whole stage matrix (the comparison
 *  path; same answers to solver tolerance). min_unknowns >= 2: border only stage systems of at least
 *  this many unknowns (default 16: below, the whole matrix costs less); 0 keeps the current bound
 *  (docs/DESIGN.md, "Impact systems by bordering").
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, on not 0 or 1, min_unknowns 1 or negative;
 *  VCI_ERR_STATE: busy. */
int  vci_set_bordered_impacts(vci_integrator integ, int on, int min_unknowns);

/** *count = impact-stage Newton directions solved by bordering over the integrator's life.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, count NULL; VCI_ERR_STATE: busy. */
int  vci_get_bordered_directions(vci_integrator integ, int64_t *count);

#ifdef __cplusplus
}
#endif

#endif /* VCI_H */
