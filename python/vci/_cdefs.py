"""The declarations of include/vci.h that the package uses, in one place.

Written by hand from the header (cffi's ABI mode needs them as C text). tests/test_header.py checks
them against the real header: the prototypes and typedefs are compiled together with vci.h (a C
compiler refuses a conflicting redeclaration), the constants by static assertions, the structs'
sizes and member offsets against a compiled program, and every function of the header must be
either bound here or listed in UNBOUND with the reason.
"""

#: Integer constants of vci.h (enum values and macros), name -> value.
CONSTANTS = {
    "VCI_OK": 0,
    "VCI_ERR_ARGUMENT": 1,
    "VCI_ERR_CALLBACK": 2,
    "VCI_ERR_NONFINITE": 3,
    "VCI_ERR_NEWTON": 4,
    "VCI_ERR_IMPACT": 5,
    "VCI_ERR_TOO_MANY_IMPACTS": 6,
    "VCI_ERR_INADMISSIBLE": 7,
    "VCI_ERR_IO": 8,
    "VCI_ERR_STATE": 9,
    "VCI_ERR_MEMORY": 10,
    "VCI_STOPPED": 11,
    "VCI_IMPACT_DISCRETE": 0,
    "VCI_IMPACT_HAMILTONIAN": 1,
    "VCI_SCHEME_DISCRETE": 0,
    "VCI_SCHEME_LEFT": 1,
    "VCI_SCHEME_MIDPOINT": 2,
    "VCI_SCHEME_LOBATTO": 3,
    "VCI_SCHEME_COMPOSITION": 4,
    "VCI_LOBATTO_MAX_STAGES": 8,
    "VCI_MASS_DIAGONAL": 0,
    "VCI_MASS_DENSE": 1,
    "VCI_VERSION_MAJOR": 0,
    "VCI_VERSION_MINOR": 2,
}

#: Typedefs and prototypes, valid C that may be redeclared after #include "vci.h".
DECLARATIONS = """
typedef struct vci_model_s *vci_model;
typedef struct vci_integrator_s *vci_integrator;

typedef int (*vci_ld_grad_fn)(int n, const double *q, const double *v, double h, double *out, void *user);
typedef int (*vci_ld_dh_fn)(int n, const double *q, const double *v, double h, double *out, void *user);
typedef int (*vci_hessian_fn)(int n, const double *q, const double *v, double h, double *hess, void *user);
typedef int (*vci_forms_fn)(int n, int m, const double *q, double *omega, void *user);
typedef int (*vci_dconstraint_fn)(int n, int m, const double *base, const double *other, double h,
                                  double *out, void *user);
typedef int (*vci_gaps_fn)(int n, int ngaps, const double *q, double *g, void *user);
typedef int (*vci_gap_grads_fn)(int n, int ngaps, const double *q, double *dg, void *user);
typedef int (*vci_energy_fn)(int n, const double *q, const double *p, double *e, void *user);
typedef int (*vci_impact_fn)(double t, double alpha, int gap_index, const double *q, double impulse, void *user);
typedef int (*vci_lagrangian_value_fn)(int n, const double *q, const double *v, double *l, void *user);
typedef int (*vci_lagrangian_grad_fn)(int n, const double *q, const double *v, double *out, void *user);
typedef int (*vci_lagrangian_hessians_fn)(int n, const double *q, const double *v, double *lqq, double *lqv,
                                          double *lvv, void *user);
typedef int (*vci_lagrangian_band_hessians_fn)(int n, int bw, const double *q, const double *v, double *lqq,
                                               double *lqv, double *lvv, void *user);
typedef int (*vci_lagrangian_sparse_hessians_fn)(int n, int nnz, const double *q, const double *v, double *lqq,
                                                 double *lqv, double *lvv, void *user);
typedef int (*vci_potential_fn)(int n, const double *q, double *out, void *user);

int  vci_model_create_v2(vci_model *model, int n, int m, int ngaps, const vci_callbacks *cb, void *user);
int  vci_model_create_lagrangian(vci_model *model, int n, int m, int ngaps, const vci_lagrangian_callbacks *cb,
                                 void *user);
int  vci_set_scheme(vci_integrator integ, int scheme, int stages);
void vci_model_destroy(vci_model *model);
int  vci_model_declare_bandwidth(vci_model model, int bw, int check);
int  vci_model_declare_pattern(vci_model model, int n, const int *colptr, const int *rowind, int check);
int  vci_sparse_available(void);
int  vci_integrator_create(vci_integrator *integ, vci_model model, double h);
void vci_integrator_destroy(vci_integrator *integ);
int  vci_set_tolerances(vci_integrator integ, double atol, double rtol, int max_iterations);
int  vci_set_impact_energy(vci_integrator integ, int mode);
int  vci_set_max_impacts(vci_integrator integ, int max_impacts);
int  vci_set_step_splits(vci_integrator integ, int max_splits);
int  vci_set_poke_samples(vci_integrator integ, int on);
int  vci_init_from_pair(vci_integrator integ, double t0, const double *q0, const double *q1);
int  vci_init_from_momentum(vci_integrator integ, double t0, const double *q0, const double *p0);
int  vci_step(vci_integrator integ, int direction);
int  vci_integrate(vci_integrator integ, int64_t nsteps, int direction);
int  vci_get_state(vci_integrator integ, double *t, double *q, double *p);
int  vci_get_multipliers(vci_integrator integ, double *lambda);
int  vci_get_energy(vci_integrator integ, double *energy);
int  vci_get_index(vci_integrator integ, int64_t *k);
int  vci_get_stats(vci_integrator integ, int64_t *steps, int64_t *impacts, int64_t *newton_iterations);
int  vci_get_energy_fallbacks(vci_integrator integ, int64_t *count);
int  vci_get_irreversible_impacts(vci_integrator integ, int64_t *count);
int  vci_get_split_steps(vci_integrator integ, int64_t *steps, int64_t *largest);
int  vci_set_impact_callback(vci_integrator integ, vci_impact_fn fn, void *user);
int  vci_open_output(vci_integrator integ, const char *path);
int  vci_close_output(vci_integrator integ);
int  vci_append_output(vci_integrator integ, const char *path);
int  vci_open_output_every(vci_integrator integ, const char *path, int every, int compress);
int  vci_restore_from_file(vci_integrator integ, const char *path);
int  vci_last_error(vci_integrator integ, char *buffer, int size);
const char *vci_status_string(int status);
int  vci_version(void);
int  vci_set_progress(vci_integrator integ, vci_progress_fn fn, double interval, void *user);
int  vci_check_model(vci_model model, const double *q, const double *v, double h, double tol, int *passed,
                     double *worst, char *report, int size);
int  vci_model_create_separable(vci_model *model, int n, int m, int ngaps, int mass_kind, const double *mass,
                                const vci_separable_callbacks *cb, void *user);
"""

#: The two callback structs, member for member (cffi needs the whole layout).
STRUCTS = """
typedef struct vci_callbacks {
  size_t size;
  vci_ld_grad_fn d1_ld, d2_ld; vci_ld_dh_fn d3_ld;
  vci_hessian_fn mixed_hessian;
  vci_forms_fn constraint_forms;
  vci_dconstraint_fn discrete_constraint;
  vci_gaps_fn gaps;
  vci_gap_grads_fn gap_gradients;
  vci_energy_fn energy;
  vci_dconstraint_fn discrete_constraint_jacobian;
  int (*ld_fused)(int, const double *, const double *, double, double *, double *, double *, double *, void *);
} vci_callbacks;

typedef struct vci_progress {
  int64_t steps_done, steps_total, impacts;
  double t, elapsed, steps_per_second, eta;
} vci_progress;
typedef int (*vci_progress_fn)(const vci_progress *info, void *user);

typedef struct vci_lagrangian_callbacks {
  size_t size;
  vci_lagrangian_value_fn lagrangian;
  vci_lagrangian_grad_fn dl_dq, dl_dv;
  vci_lagrangian_hessians_fn hessians;
  vci_forms_fn constraint_forms;
  vci_gaps_fn gaps;
  vci_gap_grads_fn gap_gradients;
  vci_energy_fn energy;
  vci_lagrangian_band_hessians_fn hessians_band;
  vci_lagrangian_sparse_hessians_fn hessians_sparse;
} vci_lagrangian_callbacks;

typedef struct vci_separable_callbacks {
  size_t size;
  vci_potential_fn potential, potential_gradient, potential_hessian;
  vci_gaps_fn gaps;
  vci_gap_grads_fn gap_gradients;
} vci_separable_callbacks;
"""

#: Functions of vci.h deliberately not bound, with the reason.
UNBOUND = {
    "vci_model_create": "a macro for vci_model_create_v2; the symbol is the 0.1 entry (struct without size)",
}


# ---- Ensembles (vci_ensemble_run, vci_ensemble_run_file): one block, appended ----
CONSTANTS.update({
    "VCI_START_PAIR": 0,
    "VCI_START_MOMENTUM": 1,
    "VCI_MEMBER_NOT_RUN": -1,
})
ENSEMBLE_STRUCTS = """
typedef struct vci_ensemble_config {
  size_t size;
  double h;
  int64_t nsteps, direction, start_kind, scheme, stages;
  double atol, rtol;
  int64_t max_iterations, impact_energy, max_impacts_per_step, impact_cap, stride, threads, chunk;
} vci_ensemble_config;

typedef struct vci_ensemble_results {
  size_t size;
  int *status;
  double *t, *q, *p;
  int64_t *steps, *impacts, *newton_iterations;
  double *energy_start, *energy_end, *impact_t;
  int *impact_gap;
  char *messages;
  int64_t message_size;
} vci_ensemble_results;
"""
STRUCTS += ENSEMBLE_STRUCTS
DECLARATIONS += """int  vci_ensemble_run(vci_model model, const vci_ensemble_config *config, int64_t members, const double *t0,
                      const double *q0, const double *v0, const vci_ensemble_results *results);
int  vci_ensemble_run_file(vci_model model, const vci_ensemble_config *config, int64_t members,
                           const double *t0, const double *q0, const double *v0, const char *path,
                           int overwrite, int mpi_comm, int64_t *members_failed);
"""

DECLARATIONS += """int  vci_set_bordered_impacts(vci_integrator integ, int on, int min_unknowns);
int  vci_get_bordered_directions(vci_integrator integ, int64_t *count);
"""


def cdef_text():
    """The whole text handed to ffi.cdef (the structs need the typedefs before them)."""
    head, _, protos = DECLARATIONS.partition("int  vci_model_create_v2")
    return head + STRUCTS + "int  vci_model_create_v2" + protos
