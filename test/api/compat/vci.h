/* vci.h as released in vci 0.1.0, unchanged but for this line (for the ABI test compat_v0_1.c) --
 * C interface of vci, variational collision integrators for nonholonomic Lagrangian
 * systems with impacts. Hand-written; the Fortran side is src/vci_capi.F90.
 *
 * Usage: fill a vci_callbacks (zero-initialise it: `vci_callbacks cb = {0};`), vci_model_create,
 * vci_integrator_create, vci_init_from_pair (or _from_momentum), vci_integrate, vci_get_state,
 * then vci_integrator_destroy and vci_model_destroy. Every int-returning call returns VCI_OK (0)
 * or a status from the enum below; after a failure vci_last_error(integ, ...) says which step, at
 * which time and why. The library never prints, exits or aborts.
 *
 * Handles: NULL, destroyed or foreign handles are detected (a registry of live handles is
 * consulted before any handle is used) and give VCI_ERR_ARGUMENT; the message is then read with
 * vci_last_error(NULL, ...). A stale copy of a destroyed handle is detected as long as its
 * memory has not been handed out again to a new handle.
 *
 * Threads: different integrators may run in different threads, but creating and destroying
 * handles, and calls with invalid handles (which write the library-wide message), must not
 * overlap with other vci calls.
 *
 * Arrays are caller-owned, of doubles, and column-major; sizes use the model's n (configuration
 * dimension), m (number of constraint one-forms) and ngaps (number of gap functions).
 */
#ifndef VCI_H
#define VCI_H

#ifdef __cplusplus
extern "C" {
#endif

/** Version of this header; vci_version() gives the library's (major*10000 + minor*100 + patch). */
#define VCI_VERSION_MAJOR 0
#define VCI_VERSION_MINOR 1
#define VCI_VERSION_PATCH 0
#define VCI_VERSION_NUMBER (VCI_VERSION_MAJOR * 10000 + VCI_VERSION_MINOR * 100 + VCI_VERSION_PATCH)

/** Status codes (same numbering as the Fortran module vci_status). */
enum {
  VCI_OK = 0,
  VCI_ERR_ARGUMENT,         /* 1: bad input: NULL or dead handle, NULL array, bad size or value */
  VCI_ERR_CALLBACK,         /* 2: a user callback returned nonzero */
  VCI_ERR_NONFINITE,        /* 3: NaN or Inf from a callback or a solve */
  VCI_ERR_NEWTON,           /* 4: Newton iteration did not converge */
  VCI_ERR_IMPACT,           /* 5: the impact stages had no admissible solution */
  VCI_ERR_TOO_MANY_IMPACTS, /* 6: more impacts in one step than allowed (contact, chatter) */
  VCI_ERR_INADMISSIBLE,     /* 7: a state lies outside the admissible set (some g_j < 0) */
  VCI_ERR_IO,               /* 8: output could not be written, or HDF5 not built in */
  VCI_ERR_STATE             /* 9: call out of order (e.g. step before init) */
};

/** Impact energy conditions for vci_set_impact_energy. */
enum {
  VCI_IMPACT_DISCRETE = 0,   /* E_d(alpha h) = E_d((1 - alpha) h): the paper's condition, default */
  VCI_IMPACT_HAMILTONIAN = 1 /* H(q~, p+) = H(q~, p-): needs the energy callback */
};

typedef struct vci_model_s *vci_model;           /* opaque */
typedef struct vci_integrator_s *vci_integrator; /* opaque */

/* Callbacks return 0 on success; anything else stops the step with VCI_ERR_CALLBACK (and
 * vci_last_error reports the value returned). Non-finite outputs give VCI_ERR_NONFINITE.
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
/** Called for each impact: time t, fraction alpha of the step, gap_index j (0-based, the index into
 *  g[] of vci_gaps_fn), the configuration q[n] on the wall and the normal impulse (p after minus p
 *  before = impulse * grad g_j, forward time). Nonzero return: VCI_ERR_CALLBACK, but the step that
 *  contains the impact has been accepted (the state is after it). */
typedef int (*vci_impact_fn)(double t, double alpha, int gap_index, const double *q, double impulse, void *user);

/** The model's callbacks. Zero-initialise the struct: members may be added at its end only. */
typedef struct vci_callbacks {
  vci_ld_grad_fn d1_ld, d2_ld; vci_ld_dh_fn d3_ld;          /* required */
  vci_hessian_fn mixed_hessian;                             /* optional (NULL: differenced) */
  vci_forms_fn constraint_forms;                            /* required iff m > 0 */
  vci_dconstraint_fn discrete_constraint;                   /* required iff m > 0 */
  vci_gaps_fn gaps;                                         /* required iff ngaps > 0 */
  vci_gap_grads_fn gap_gradients;                           /* optional (NULL: differenced) */
  vci_energy_fn energy;                                     /* optional; needed by VCI_IMPACT_HAMILTONIAN */
} vci_callbacks;

/** Create a model of n coordinates, m constraints, ngaps walls. The callbacks are copied; `user`
 *  is passed to every callback. On failure *model = NULL (if model is not NULL).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: model or cb NULL, n < 1, m < 0, m > n, ngaps < 0, or a
 *  required callback NULL. */
int  vci_model_create(vci_model *model, int n, int m, int ngaps, const vci_callbacks *cb, void *user);

/** Release the model and set *model = NULL. NULL-safe (model or *model NULL: nothing happens).
 *  Integrators created from it keep it alive: it may be destroyed right after vci_integrator_create. */
void vci_model_destroy(vci_model *model);

/** Create an integrator of step length h (> 0, finite) for model. On failure *integ = NULL.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: integ NULL, model NULL or not live, h not positive and finite. */
int  vci_integrator_create(vci_integrator *integ, vci_model model, double h);

/** Destroy the integrator (finishing its output file, if any) and set *integ = NULL. NULL-safe. */
void vci_integrator_destroy(vci_integrator *integ);

/** Newton tolerances: row i converges when |r_i| <= atol + rtol * (size of row i's terms); at most
 *  max_iterations per solve. Defaults: atol = 0, rtol = 1e-12, max_iterations = 30.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, atol or rtol negative or not finite, both zero,
 *  max_iterations < 1. */
int  vci_set_tolerances(vci_integrator integ, double atol, double rtol, int max_iterations);

/** Impact energy condition, VCI_IMPACT_DISCRETE (default) or VCI_IMPACT_HAMILTONIAN.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, unknown mode, or hamiltonian without the energy
 *  callback. */
int  vci_set_impact_energy(vci_integrator integ, int mode);

/** Impacts allowed inside one step before VCI_ERR_TOO_MANY_IMPACTS (default 16).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, max_impacts < 1. */
int  vci_set_max_impacts(vci_integrator integ, int max_impacts);

/** Start from the pair q0[n] at t0 and q1[n] at t0 + h. The current state becomes
 *  (t0 + h, q1, p1) with p1 = D2 L_d(q0, q1, h), step index 1; the discrete energy is E_d(q0, q1, h).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, q0 or q1 NULL, NaN/Inf in t0, q0 or q1, a
 *  required constraint callback missing; VCI_ERR_INADMISSIBLE: q0 or q1 outside the admissible
 *  set; VCI_ERR_CALLBACK or VCI_ERR_NONFINITE: D2, D3 or gaps failed or gave NaN/Inf. After a
 *  failure the integrator has no state (VCI_ERR_STATE from stepping) until initialised again. */
int  vci_init_from_pair(vci_integrator integ, double t0, const double *q0, const double *q1);

/** Start from (q0[n], p0[n]) at t0, step index 0 (no discrete energy until the first step).
 *  Returns as vci_init_from_pair (p0 NULL instead of q1). */
int  vci_init_from_momentum(vci_integrator integ, double t0, const double *q0, const double *p0);

/** One step: direction +1 forward ((+) scheme), -1 backward ((-) scheme).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle or direction; VCI_ERR_STATE: not initialised;
 *  VCI_ERR_CALLBACK, VCI_ERR_NONFINITE, VCI_ERR_NEWTON, VCI_ERR_IMPACT, VCI_ERR_TOO_MANY_IMPACTS:
 *  the step failed and the state stays at the last accepted step; VCI_ERR_CALLBACK also when the
 *  impact callback returned nonzero, VCI_ERR_IO when the output file failed (for these two the
 *  step was accepted). */
int  vci_step(vci_integrator integ, int direction);                 /* +1 forward, -1 backward */

/** nsteps (>= 0) steps in one direction; stops at the first failure (state = last accepted step).
 *  Returns as vci_step, and VCI_ERR_ARGUMENT for nsteps < 0. */
int  vci_integrate(vci_integrator integ, long nsteps, int direction);

/** The current state: *t, q[n], p[n]. Any of t, q, p may be NULL to skip it.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle; VCI_ERR_STATE: not initialised. */
int  vci_get_state(vci_integrator integ, double *t, double *q, double *p);

/** The multipliers lambda[m] of the last step (nothing is written when m = 0).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, lambda NULL with m > 0; VCI_ERR_STATE. */
int  vci_get_multipliers(vci_integrator integ, double *lambda);

/** The discrete energy E_d of the last step (of its last sub-step if it had impacts); NaN after
 *  vci_init_from_momentum until the first step.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, energy NULL; VCI_ERR_STATE: not initialised. */
int  vci_get_energy(vci_integrator integ, double *energy);

/** The index k of the current state (t = t0 + k h). Returns as vci_get_energy. */
int  vci_get_index(vci_integrator integ, long *k);

/** Counters over the integrator's life; any pointer may be NULL to skip it.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle. */
int  vci_get_stats(vci_integrator integ, long *steps, long *impacts, long *newton_iterations);

/** Call fn(..., user) at every impact of later steps; fn = NULL removes it.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle. */
int  vci_set_impact_callback(vci_integrator integ, vci_impact_fn fn, void *user);

/** Write the trajectory of later steps to the HDF5 file path (replaced if it exists); the file is
 *  finished by vci_close_output, vci_integrator_destroy or the next vci_open_output.
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle, path NULL or empty; VCI_ERR_IO: the file cannot
 *  be created, or this library was built without HDF5 (vci_last_error says which). */
int  vci_open_output(vci_integrator integ, const char *path);      /* HDF5; VCI_ERR_IO when unavailable */

/** Finish and close the output file, if any. Returns VCI_OK; VCI_ERR_ARGUMENT: bad handle;
 *  VCI_ERR_IO: the file could not be finished. */
int  vci_close_output(vci_integrator integ);

/** Copy the message of the last call on integ (empty after a success) into buffer[size],
 *  truncated to size - 1 characters and NUL-terminated. integ = NULL: the last failure that had no
 *  live integrator to hold it (failed create, NULL or dead handle).
 *  Returns VCI_OK; VCI_ERR_ARGUMENT: buffer NULL or size < 1 (nothing written), or integ not live
 *  (buffer then says so). */
int  vci_last_error(vci_integrator integ, char *buffer, int size);  /* NUL-terminated, truncated to size */

/** A static description of a status code ("unknown status" for other values); never NULL. */
const char *vci_status_string(int status);

/** The library's version: major*10000 + minor*100 + patch. */
int  vci_version(void);

#ifdef __cplusplus
}
#endif

#endif /* VCI_H */
