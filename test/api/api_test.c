/* Tests of the C API against include/vci.h: every function, the numbers it gives on the paper's
 * scenes, and bad input (NULL and destroyed handles, NULL arrays, bad sizes, failing callbacks,
 * NaN from callbacks). Usage: vci_api_test <suite>; one CTest entry per suite (CMakeLists.txt).
 * Each check prints what it compared; the exit status is the number of failed checks. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>
#include "vci.h"
#include "scenes.h"
#include "lapack_guard.h"

static int failures = 0;

/* Library code must never end the process: an exit() before main returns (a Fortran STOP, LAPACK's
 * XERBLA) is a failure with status 70, not a silent success. */
static int finished = 0;
static void exit_guard(void) {
  if (finished) return;
  printf("FAIL: the process exited inside a test (exit or STOP in library code)\n");
  fflush(stdout);
  _exit(70);
}

#define CHECK(cond) check((cond), #cond, __FILE__, __LINE__)
#define CHECK_STATUS(call, expected) check_status((call), (expected), #call, __LINE__)
#define CHECK_CLOSE(actual, expected, tol) check_close((actual), (expected), (tol), #actual, __LINE__)

static void check(int ok, const char *what, const char *file, int line) {
  if (!ok) {
    ++failures;
    printf("FAIL %s:%d: %s\n", file, line, what);
  }
}

static void check_status(int actual, int expected, const char *what, int line) {
  if (actual != expected) {
    ++failures;
    printf("FAIL line %d: %s returned %d (%s), expected %d (%s)\n", line, what, actual, vci_status_string(actual),
           expected, vci_status_string(expected));
  }
}

/* |actual - expected| <= tol, and never passes for NaN */
static void check_close(double actual, double expected, double tol, const char *what, int line) {
  if (!(fabs(actual - expected) <= tol)) {
    ++failures;
    printf("FAIL line %d: %s = %.17g, expected %.17g within %.3g (off by %.3g)\n", line, what, actual, expected, tol,
           fabs(actual - expected));
  }
}

/* the message of the last call on integ (or the library-wide one for NULL) contains `part` */
static void check_message(vci_integrator integ, const char *part, int line) {
  char msg[512];
  vci_last_error(integ, msg, sizeof msg);
  if (strstr(msg, part) == NULL) {
    ++failures;
    printf("FAIL line %d: message \"%s\" does not contain \"%s\"\n", line, msg, part);
  }
}
#define CHECK_MESSAGE(integ, part) check_message((integ), (part), __LINE__)

/* The first impact time of the ellipse at h = 1e-2 with rtol = 1e-12, from the Fortran API
 * (vci_integrator_t on examples/scenes/vci_scene_ellipse.f90; build/bin/ellipse prints it
 * rounded as t=.750564104357). The C callbacks do the same arithmetic, so the C run agrees to
 * round-off; 1e-12 is the Newton tolerance. */
static const double ELLIPSE_FIRST_IMPACT = 7.50564104356950312e-01;
static const double ELLIPSE_SECOND_IMPACT = 1.15253289965270556e+00;

/* ---- helpers: an ellipse integrator at h = 1e-2 started from the paper's pair ---- */
static ellipse_params ellipse_par;

static vci_integrator make_ellipse(vci_model *model, const vci_callbacks *cb, double h) {
  vci_integrator integ = NULL;
  double t0, q0[3], q1[3];
  ellipse_par = ellipse_default;
  CHECK_STATUS(vci_model_create(model, 3, 0, 1, cb, &ellipse_par), VCI_OK);
  CHECK_STATUS(vci_integrator_create(&integ, *model, h), VCI_OK);
  CHECK_STATUS(vci_set_tolerances(integ, 0.0, 1e-12, 30), VCI_OK);
  ellipse_initial_pair(h, &t0, q0, q1);
  CHECK_STATUS(vci_init_from_pair(integ, t0, q0, q1), VCI_OK);
  return integ;
}

/* what the impact callback saw; g_at_q = the ellipse's gap at q when `ellipse` is set */
typedef struct { int ellipse, count; double t[16], alpha[16], impulse[16], g_at_q[16]; int gap[16]; } impact_log;

static int log_impact(double t, double alpha, int gap, const double *q, double impulse, void *user) {
  impact_log *log = (impact_log *)user;
  double g = NAN;
  if (log->count < 16) {
    log->t[log->count] = t; log->alpha[log->count] = alpha; log->gap[log->count] = gap;
    log->impulse[log->count] = impulse;
    if (log->ellipse) ellipse_gaps(3, 1, q, &g, &ellipse_par);
    log->g_at_q[log->count] = g;
  }
  log->count++;
  return 0;
}

/* ================================================================================================ */
static void suite_version(void) {
  static const char *names[] = {"ok", "invalid argument", "user callback failed", "non-finite value",
                                "Newton iteration did not converge", "impact could not be resolved",
                                "too many impacts in one step", "state outside the admissible set",
                                "input/output error", "call out of order", "out of memory", "stopped by the caller"};
  int s;
  CHECK(vci_version() == VCI_VERSION_NUMBER);
  CHECK(vci_version() == 200); /* 0.2.0, as project(VERSION) in CMakeLists.txt */
  for (s = VCI_OK; s <= VCI_STOPPED; ++s) {
    CHECK(vci_status_string(s) != NULL);
    if (strcmp(vci_status_string(s), names[s]) != 0) {
      ++failures;
      printf("FAIL: vci_status_string(%d) = \"%s\", expected \"%s\"\n", s, vci_status_string(s), names[s]);
    }
  }
  CHECK(strcmp(vci_status_string(-1), "unknown status") == 0);
  CHECK(strcmp(vci_status_string(12), "unknown status") == 0);
  CHECK(strcmp(vci_status_string(123456), "unknown status") == 0);
  CHECK(VCI_ERR_STATE == 9 && VCI_ERR_IO == 8 && VCI_ERR_ARGUMENT == 1 && VCI_ERR_MEMORY == 10 && VCI_STOPPED == 11);
}

/* An impact callback that calls back into its own integrator: mode 0 tries vci_step, mode 1
 * destroys it. */
typedef struct { vci_integrator integ; int mode, calls, status; char message[256]; } reentry;

static int reenter_on_impact(double t, double alpha, int gap, const double *q, double impulse, void *user) {
  reentry *r = (reentry *)user;
  (void)t; (void)alpha; (void)gap; (void)q; (void)impulse;
  ++r->calls;
  if (r->mode == 0) {
    r->status = vci_step(r->integ, 1);
    vci_last_error(NULL, r->message, sizeof r->message);
  } else {
    vci_integrator_destroy(&r->integ);
  }
  return 0;
}

/* ================================================================================================ */
static void suite_handles(void) {
  vci_callbacks cb = ellipse_callbacks();
  vci_model model = NULL, model_copy, null_model = NULL;
  vci_integrator integ = NULL, copy, null_integ = NULL;
  double t, q[3], p[3], lambda[1], e;
  int64_t k, steps, impacts, iters;
  char buf[256];

  /* destroy functions are NULL-safe */
  vci_model_destroy(NULL);
  vci_model_destroy(&null_model);
  vci_integrator_destroy(NULL);
  vci_integrator_destroy(&null_integ);
  CHECK(null_model == NULL && null_integ == NULL);

  /* NULL handles: every call gives VCI_ERR_ARGUMENT and a library-wide message */
  CHECK_STATUS(vci_integrator_create(&integ, NULL, 1e-2), VCI_ERR_ARGUMENT);
  CHECK(integ == NULL);
  CHECK_MESSAGE(NULL, "model handle is NULL");
  CHECK_STATUS(vci_set_tolerances(NULL, 0.0, 1e-12, 30), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "vci_set_tolerances: the integrator handle is NULL");
  CHECK_STATUS(vci_set_impact_energy(NULL, 0), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_set_max_impacts(NULL, 4), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_init_from_pair(NULL, 0.0, q, q), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_init_from_momentum(NULL, 0.0, q, p), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_step(NULL, 1), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_integrate(NULL, 10, 1), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_get_state(NULL, &t, q, p), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_get_multipliers(NULL, lambda), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_get_energy(NULL, &e), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_get_index(NULL, &k), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_get_stats(NULL, &steps, &impacts, &iters), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_set_impact_callback(NULL, log_impact, NULL), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_open_output(NULL, "x.h5"), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_close_output(NULL), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "vci_close_output: the integrator handle is NULL");

  /* NULL out-pointers of the create functions */
  CHECK_STATUS(vci_model_create(NULL, 3, 0, 1, &cb, NULL), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "vci_model_create: the model argument is NULL");
  integ = make_ellipse(&model, &cb, 1e-2);
  CHECK_STATUS(vci_integrator_create(NULL, model, 1e-2), VCI_ERR_ARGUMENT);

  /* a model handle is not an integrator handle, and the reverse */
  CHECK_STATUS(vci_step((vci_integrator)model, 1), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "not a live integrator handle");
  {
    vci_integrator other = NULL;
    CHECK_STATUS(vci_integrator_create(&other, (vci_model)integ, 1e-2), VCI_ERR_ARGUMENT);
    CHECK_MESSAGE(NULL, "not a live model handle");
    CHECK(other == NULL);
  }

  /* the integrator keeps its model alive: destroy the model first and keep integrating */
  model_copy = model;
  vci_model_destroy(&model);
  CHECK(model == NULL);
  CHECK_STATUS(vci_integrate(integ, 100, 1), VCI_OK);
  CHECK_STATUS(vci_get_index(integ, &k), VCI_OK);
  CHECK(k == 101);
  /* ... but the destroyed model handle (a stale copy) is refused */
  {
    vci_integrator other = NULL;
    CHECK_STATUS(vci_integrator_create(&other, model_copy, 1e-2), VCI_ERR_ARGUMENT);
    CHECK_MESSAGE(NULL, "not a live model handle");
  }
  vci_model_destroy(&model_copy); /* destroying it again through the copy: ignored */
  CHECK(model_copy == NULL);

  /* destroyed integrator: the variable is NULL; a stale copy is refused, not dereferenced */
  copy = integ;
  vci_integrator_destroy(&integ);
  CHECK(integ == NULL);
  CHECK_STATUS(vci_step(copy, 1), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "vci_step: not a live integrator handle");
  CHECK_STATUS(vci_get_state(copy, &t, q, p), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_last_error(copy, buf, sizeof buf), VCI_ERR_ARGUMENT);
  CHECK(strstr(buf, "not a live integrator handle") != NULL);
  vci_integrator_destroy(&copy); /* double destroy through the copy: ignored */
  CHECK(copy == NULL);

  /* a stale copy stays dead after a new integrator is made (glibc hands the freed memory out
   * again at once: with handles that were addresses, the copy named the new integrator) */
  {
    vci_model m2 = NULL;
    vci_integrator a = NULL, stale, b = NULL;
    a = make_ellipse(&m2, &cb, 1e-2);
    stale = a;
    vci_integrator_destroy(&a);
    CHECK_STATUS(vci_integrator_create(&b, m2, 1e-2), VCI_OK);
    CHECK(b != stale);
    CHECK_STATUS(vci_set_max_impacts(stale, 3), VCI_ERR_ARGUMENT);
    CHECK_STATUS(vci_step(stale, 1), VCI_ERR_ARGUMENT);
    vci_integrator_destroy(&stale); /* ignored: must not destroy b */
    CHECK_STATUS(vci_set_max_impacts(b, 3), VCI_OK);
    vci_integrator_destroy(&b);
    vci_model_destroy(&m2);
    /* garbage that is no handle at all */
    CHECK_STATUS(vci_step((vci_integrator)(uintptr_t)0x1234, 1), VCI_ERR_ARGUMENT);
    CHECK_STATUS(vci_step((vci_integrator)(uintptr_t)-8, 1), VCI_ERR_ARGUMENT);
  }

  /* calls on an integrator from its own callback: refused (busy); destroying it there is carried
   * out when the running call returns, which stops after the step under way */
  {
    vci_model m2 = NULL;
    reentry r;
    r.integ = make_ellipse(&m2, &cb, 1e-2);
    r.mode = 0; r.calls = 0; r.status = -1;
    CHECK_STATUS(vci_set_impact_callback(r.integ, reenter_on_impact, &r), VCI_OK);
    CHECK_STATUS(vci_integrate(r.integ, 200, 1), VCI_OK);
    CHECK(r.calls == 2);
    CHECK_STATUS(r.status, VCI_ERR_STATE);      /* vci_step from inside the impact callback */
    CHECK(strstr(r.message, "busy") != NULL);
    r.mode = 1; r.calls = 0;
    CHECK_STATUS(vci_integrate(r.integ, 200, 1), VCI_ERR_STATE); /* destroyed at its first impact */
    CHECK(r.integ == NULL);
    CHECK_MESSAGE(NULL, "destroyed during the call");
    vci_model_destroy(&m2);
  }

  /* many handles at once (the registry grows), destroyed in another order */
  {
    vci_model models[20];
    vci_integrator integs[20];
    int i;
    ellipse_par = ellipse_default;
    for (i = 0; i < 20; ++i) {
      CHECK_STATUS(vci_model_create(&models[i], 3, 0, 1, &cb, &ellipse_par), VCI_OK);
      CHECK_STATUS(vci_integrator_create(&integs[i], models[i], 1e-2), VCI_OK);
    }
    for (i = 0; i < 20; i += 2) vci_model_destroy(&models[i]);
    for (i = 19; i >= 0; --i) CHECK_STATUS(vci_set_max_impacts(integs[i], 8), VCI_OK);
    for (i = 0; i < 20; ++i) vci_integrator_destroy(&integs[i]);
    for (i = 1; i < 20; i += 2) vci_model_destroy(&models[i]);
    for (i = 0; i < 20; ++i) CHECK(models[i] == NULL && integs[i] == NULL);
  }
}

/* ================================================================================================ */
static void suite_arguments(void) {
  vci_callbacks cb = ellipse_callbacks(), partial;
  vci_model model = (vci_model)&cb; /* garbage that create must overwrite with NULL on failure */
  vci_integrator integ = NULL;
  double t0, q0[3], q1[3], bad[3], t, q[3], e, lambda[1];
  int64_t k;
  char buf[16];
  int i;

  ellipse_par = ellipse_default;
  /* sizes */
  CHECK_STATUS(vci_model_create(&model, 0, 0, 1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK(model == NULL);
  CHECK_MESSAGE(NULL, "n = 0");
  CHECK_STATUS(vci_model_create(&model, 3, -1, 1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_model_create(&model, 3, 4, 1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_model_create(&model, 3, 0, -1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_model_create(&model, -5, 0, 0, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  /* callbacks */
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, NULL, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "callbacks argument is NULL");
  partial = cb; partial.d1_ld = NULL;
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &partial, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "d1_ld is NULL");
  partial = cb; partial.d3_ld = NULL;
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &partial, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "d3_ld is NULL");
  partial = cb; partial.gaps = NULL;
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &partial, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "gaps (needed as ngaps > 0)");
  CHECK_STATUS(vci_model_create(&model, 3, 0, 0, &partial, &ellipse_par), VCI_OK); /* no walls: fine */
  vci_model_destroy(&model);
  /* issue 31: a gaps callback with ngaps = 0 ran with no impacts and status 0; now refused */
  CHECK_STATUS(vci_model_create(&model, 3, 0, 0, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "ngaps = 0");
  CHECK(model == NULL);
  CHECK_STATUS(vci_model_create(&model, 3, 1, 1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "constraint");
  CHECK(model == NULL);

  /* step length */
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &cb, &ellipse_par), VCI_OK);
  CHECK_STATUS(vci_integrator_create(&integ, model, 0.0), VCI_ERR_ARGUMENT);
  CHECK(integ == NULL);
  CHECK_MESSAGE(NULL, "step length");
  CHECK_STATUS(vci_integrator_create(&integ, model, -1e-2), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_integrator_create(&integ, model, NAN), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_integrator_create(&integ, model, INFINITY), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_integrator_create(&integ, model, 1e-2), VCI_OK);

  /* settings */
  CHECK_STATUS(vci_set_tolerances(integ, -1.0, 1e-12, 30), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(integ, "set_tolerances");
  CHECK_STATUS(vci_set_tolerances(integ, 0.0, 0.0, 30), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_set_tolerances(integ, 0.0, NAN, 30), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_set_tolerances(integ, 0.0, 1e-12, 0), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_set_tolerances(integ, 0.0, 1e-12, 30), VCI_OK);
  CHECK_MESSAGE(integ, ""); /* success clears the message */
  CHECK_STATUS(vci_set_impact_energy(integ, 2), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(integ, "unknown mode 2");
  CHECK_STATUS(vci_set_impact_energy(integ, -1), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_set_max_impacts(integ, 0), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_set_max_impacts(integ, 16), VCI_OK);

  /* calls out of order */
  CHECK_STATUS(vci_step(integ, 1), VCI_ERR_STATE);
  CHECK_MESSAGE(integ, "initialise the integrator first");
  CHECK_STATUS(vci_integrate(integ, 5, 1), VCI_ERR_STATE);
  CHECK_STATUS(vci_get_state(integ, &t, q, NULL), VCI_ERR_STATE);
  CHECK_STATUS(vci_get_energy(integ, &e), VCI_ERR_STATE);
  CHECK_STATUS(vci_get_index(integ, &k), VCI_ERR_STATE);

  /* NULL and non-finite initial data; inadmissible initial data */
  ellipse_initial_pair(1e-2, &t0, q0, q1);
  CHECK_STATUS(vci_init_from_pair(integ, t0, NULL, q1), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(integ, "q0 or q1 is NULL");
  CHECK_STATUS(vci_init_from_pair(integ, t0, q0, NULL), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_init_from_momentum(integ, t0, q0, NULL), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_init_from_momentum(integ, t0, NULL, q0), VCI_ERR_ARGUMENT);
  for (i = 0; i < 3; ++i) bad[i] = q1[i];
  bad[1] = NAN;
  CHECK_STATUS(vci_init_from_pair(integ, t0, q0, bad), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(integ, "NaN or Inf");
  CHECK_STATUS(vci_init_from_pair(integ, INFINITY, q0, q1), VCI_ERR_ARGUMENT);
  bad[1] = q1[1];
  bad[2] = 0.1; /* the ellipse's centre below the floor */
  CHECK_STATUS(vci_init_from_pair(integ, t0, bad, bad), VCI_ERR_INADMISSIBLE);
  CHECK_MESSAGE(integ, "outside the admissible set");
  CHECK_STATUS(vci_step(integ, 1), VCI_ERR_STATE); /* a failed init leaves no state */

  /* now properly initialised: bad directions and counts */
  CHECK_STATUS(vci_init_from_pair(integ, t0, q0, q1), VCI_OK);
  CHECK_STATUS(vci_step(integ, 0), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(integ, "direction 0");
  CHECK_STATUS(vci_step(integ, 2), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_integrate(integ, 10, -2), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_integrate(integ, -1, 1), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(integ, "nsteps = -1");
  CHECK_STATUS(vci_integrate(integ, 0, 1), VCI_OK);
  CHECK_STATUS(vci_get_index(integ, &k), VCI_OK);
  CHECK(k == 1);

  /* getters: NULL outputs */
  CHECK_STATUS(vci_get_state(integ, NULL, NULL, NULL), VCI_OK); /* all skipped */
  CHECK_STATUS(vci_get_energy(integ, NULL), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_get_index(integ, NULL), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_get_multipliers(integ, NULL), VCI_OK); /* m = 0: nothing to write */
  CHECK_STATUS(vci_get_multipliers(integ, lambda), VCI_OK);
  CHECK_STATUS(vci_get_stats(integ, NULL, NULL, NULL), VCI_OK);

  /* vci_last_error: NULL buffer, size < 1, truncation with NUL */
  CHECK_STATUS(vci_step(integ, 5), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_last_error(integ, NULL, 16), VCI_ERR_ARGUMENT);
  memset(buf, 'x', sizeof buf);
  CHECK_STATUS(vci_last_error(integ, buf, 0), VCI_ERR_ARGUMENT);
  CHECK(buf[0] == 'x'); /* nothing written */
  CHECK_STATUS(vci_last_error(integ, buf, -3), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_last_error(integ, buf, 1), VCI_OK);
  CHECK(buf[0] == '\0' && buf[1] == 'x');
  CHECK_STATUS(vci_last_error(integ, buf, 8), VCI_OK);
  CHECK(strcmp(buf, "step: d") == 0 && buf[8] == 'x'); /* 7 characters, NUL, untouched after */

  /* output: NULL or empty path */
  CHECK_STATUS(vci_open_output(integ, NULL), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(integ, "path is NULL");
  CHECK_STATUS(vci_open_output(integ, ""), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_close_output(integ), VCI_OK); /* nothing open: no-op */

  /* hamiltonian impact condition without the energy callback */
  {
    vci_callbacks no_energy = cb;
    vci_model m2 = NULL;
    vci_integrator i2 = NULL;
    no_energy.energy = NULL;
    CHECK_STATUS(vci_model_create(&m2, 3, 0, 1, &no_energy, &ellipse_par), VCI_OK);
    CHECK_STATUS(vci_integrator_create(&i2, m2, 1e-2), VCI_OK);
    CHECK_STATUS(vci_set_impact_energy(i2, VCI_IMPACT_HAMILTONIAN), VCI_ERR_ARGUMENT);
    CHECK_MESSAGE(i2, "energy");
    CHECK_STATUS(vci_set_impact_energy(i2, VCI_IMPACT_DISCRETE), VCI_OK);
    vci_integrator_destroy(&i2);
    vci_model_destroy(&m2);
  }
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
}

/* ================================================================================================ */
/* failing callbacks: a wrapper around the ellipse that fails (or returns NaN) from a given call on */
typedef struct {
  ellipse_params e;
  int which;        /* 1 d1, 2 d2, 3 d3, 4 hessian, 7 gaps, 8 gap grads, 9 energy */
  int nan;          /* 0: return fail_rc; 1: return 0 with a NaN output */
  int calls, fail_from, fail_rc;
} failing_params;

static int failing_now(failing_params *f, int which) {
  if (f->which != which) return 0;
  return ++f->calls >= f->fail_from;
}

#define FAILING(name, which, call, out, nout)                                                         \
  static int name##_f(int n, const double *q, const double *v, double h, double *out_, void *user) { \
    failing_params *f = (failing_params *)user;                                                       \
    int rc = call(n, q, v, h, out_, &f->e), i;                                                        \
    if (failing_now(f, which)) {                                                                      \
      if (!f->nan) return f->fail_rc;                                                                 \
      for (i = 0; i < (nout); ++i) out_[i] = NAN;                                                     \
    }                                                                                                 \
    return rc;                                                                                        \
  }
FAILING(d1, 1, ellipse_d1, out, 3)
FAILING(d2, 2, ellipse_d2, out, 3)
FAILING(d3, 3, ellipse_d3, out, 1)
FAILING(hess, 4, ellipse_hessian, out, 9)

static int gaps_f(int n, int ng, const double *q, double *g, void *user) {
  failing_params *f = (failing_params *)user;
  int rc = ellipse_gaps(n, ng, q, g, &f->e);
  if (failing_now(f, 7)) {
    if (!f->nan) return f->fail_rc;
    g[0] = NAN;
  }
  return rc;
}

static int energy_f(int n, const double *q, const double *p, double *e, void *user) {
  failing_params *f = (failing_params *)user;
  int rc = ellipse_energy(n, q, p, e, &f->e);
  if (failing_now(f, 9)) {
    if (!f->nan) return f->fail_rc;
    e[0] = NAN;
  }
  return rc;
}

/* Run the ellipse for 200 steps with callback `which` failing from its call number `from`; check
 * the status, the message and that the state is a state of the clean run (the last accepted one). */
static void run_failing(int which, int nan, int from, int hamiltonian, int expected, const char *part, int line) {
  failing_params f;
  vci_callbacks cb = VCI_CALLBACKS_INIT;
  vci_model model = NULL;
  vci_integrator integ = NULL, clean = NULL;
  vci_model clean_model = NULL;
  vci_callbacks clean_cb = ellipse_callbacks();
  double t0, q0[3], q1[3], q[3], qc[3], t, tc;
  int64_t k = -1, kc;
  int status, i;
  char msg[512];

  f.e = ellipse_default; f.which = which; f.nan = nan; f.calls = 0; f.fail_from = from; f.fail_rc = 7;
  cb.d1_ld = d1_f; cb.d2_ld = d2_f; cb.d3_ld = d3_f; cb.mixed_hessian = hess_f; cb.gaps = gaps_f;
  cb.gap_gradients = NULL; cb.energy = energy_f;
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &cb, &f), VCI_OK);
  CHECK_STATUS(vci_integrator_create(&integ, model, 1e-2), VCI_OK);
  CHECK_STATUS(vci_set_tolerances(integ, 0.0, 1e-12, 30), VCI_OK);
  if (hamiltonian) CHECK_STATUS(vci_set_impact_energy(integ, VCI_IMPACT_HAMILTONIAN), VCI_OK);
  ellipse_initial_pair(1e-2, &t0, q0, q1);
  status = vci_init_from_pair(integ, t0, q0, q1);
  if (status == VCI_OK) status = vci_integrate(integ, 200, 1);
  check_status(status, expected, "failing-callback run", line);
  vci_last_error(integ, msg, sizeof msg);
  if (strstr(msg, part) == NULL) {
    ++failures;
    printf("FAIL line %d: message \"%s\" does not contain \"%s\"\n", line, msg, part);
  } else {
    printf("  line %d: %s: %s\n", line, vci_status_string(status), msg);
  }
  /* the state is the last accepted one: equal to the clean run's state at the same index */
  if (vci_get_index(integ, &k) == VCI_OK && k >= 1) {
    vci_get_state(integ, &t, q, NULL);
    clean = make_ellipse(&clean_model, &clean_cb, 1e-2);
    if (hamiltonian) vci_set_impact_energy(clean, VCI_IMPACT_HAMILTONIAN);
    vci_integrate(clean, k - 1, 1);
    vci_get_state(clean, &tc, qc, NULL);
    vci_get_index(clean, &kc);
    check(kc == k, "clean run reaches the same index", __FILE__, line);
    for (i = 0; i < 3; ++i) check_close(q[i], qc[i], 1e-13 * (1.0 + fabs(qc[i])), "state after failure", line);
    check_close(t, tc, 1e-14, "time after failure", line);
    vci_integrator_destroy(&clean);
    vci_model_destroy(&clean_model);
  }
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
}

static int stop_at_second_impact(double t, double alpha, int gap, const double *q, double impulse, void *user) {
  int *count = (int *)user;
  (void)t; (void)alpha; (void)gap; (void)q; (void)impulse;
  return ++*count == 2 ? 42 : 0;
}

static void suite_callbacks(void) {
  /* failing and NaN-producing callbacks, at the initial pair and in mid-run */
  run_failing(2, 0, 1, 0, VCI_ERR_CALLBACK, "the C callback d2_ld returned 7", __LINE__);   /* D2 at the pair */
  run_failing(2, 1, 1, 0, VCI_ERR_NONFINITE, "init_from_pair", __LINE__);           /* NaN momentum at the pair */
  run_failing(1, 0, 50, 0, VCI_ERR_CALLBACK, "step from index", __LINE__);          /* D1 mid-run */
  run_failing(1, 0, 50, 0, VCI_ERR_CALLBACK, "d1_ld returned 7", __LINE__);
  run_failing(1, 1, 50, 0, VCI_ERR_NONFINITE, "d1_ld returned NaN", __LINE__);           /* NaN D1 mid-run */
  run_failing(3, 0, 5, 0, VCI_ERR_CALLBACK, "D3", __LINE__);                        /* D3 (energy) */
  run_failing(3, 1, 5, 0, VCI_ERR_NONFINITE, "D3", __LINE__);
  run_failing(4, 0, 30, 0, VCI_ERR_CALLBACK, "Hessian", __LINE__);                  /* analytic Hessian */
  run_failing(4, 1, 30, 0, VCI_ERR_NONFINITE, "Hessian", __LINE__);
  run_failing(7, 0, 2, 0, VCI_ERR_CALLBACK, "gaps returned 7", __LINE__);                     /* gaps at the pair */
  run_failing(7, 0, 100, 0, VCI_ERR_CALLBACK, "gap", __LINE__);                     /* gaps mid-run */
  run_failing(7, 1, 100, 0, VCI_ERR_NONFINITE, "gap", __LINE__);
  run_failing(9, 0, 2, 1, VCI_ERR_CALLBACK, "energy", __LINE__);                    /* H at the first impact */
  run_failing(9, 1, 2, 1, VCI_ERR_NONFINITE, "energy", __LINE__);

  /* a failing impact callback: VCI_ERR_CALLBACK, its code in the message, the step was accepted */
  {
    vci_callbacks cb = ellipse_callbacks();
    vci_model model = NULL;
    vci_integrator integ = make_ellipse(&model, &cb, 1e-2);
    int count = 0;
    double t;
    CHECK_STATUS(vci_set_impact_callback(integ, stop_at_second_impact, &count), VCI_OK);
    CHECK_STATUS(vci_integrate(integ, 200, 1), VCI_ERR_CALLBACK);
    CHECK_MESSAGE(integ, "impact callback returned 42");
    CHECK(count == 2);
    CHECK_STATUS(vci_get_state(integ, &t, NULL, NULL), VCI_OK);
    /* the state is the end of the step containing the second impact */
    CHECK(t > ELLIPSE_SECOND_IMPACT && t - 1e-2 < ELLIPSE_SECOND_IMPACT);
    /* the run continues from there once the callback is removed */
    CHECK_STATUS(vci_set_impact_callback(integ, NULL, NULL), VCI_OK);
    CHECK_STATUS(vci_integrate(integ, 10, 1), VCI_OK);
    vci_integrator_destroy(&integ);
    vci_model_destroy(&model);
  }
}

/* ================================================================================================ */
static void suite_ellipse(void) {
  vci_callbacks cb = ellipse_callbacks();
  vci_model model = NULL;
  vci_integrator integ;
  impact_log log;
  double h = 1e-2, t0, q0[3], q1[3], t, q[3], p[3], p1[3], e, e1, qf[3], pf[3];
  int64_t k, steps, impacts, iters;
  int i;

  integ = make_ellipse(&model, &cb, h);
  /* the state vci_init_from_pair leaves: (t0 + h, q1, D2 L_d(q0, q1, h)), index 1, E_d(q0, q1, h) */
  ellipse_initial_pair(h, &t0, q0, q1);
  ellipse_d2(3, q0, q1, h, p1, &ellipse_par);
  ellipse_d3(3, q0, q1, h, &e1, &ellipse_par);
  CHECK_STATUS(vci_get_state(integ, &t, q, p), VCI_OK);
  CHECK_STATUS(vci_get_index(integ, &k), VCI_OK);
  CHECK_STATUS(vci_get_energy(integ, &e), VCI_OK);
  CHECK(k == 1);
  CHECK_CLOSE(t, t0 + h, 1e-15);
  for (i = 0; i < 3; ++i) {
    CHECK(q[i] == q1[i]); /* copied */
    CHECK_CLOSE(p[i], p1[i], 1e-14 * (1.0 + fabs(p1[i])));
  }
  CHECK_CLOSE(e, -e1, 1e-13 * fabs(e1)); /* E_d = -D3 L_d */

  /* 200 steps to t = 2.005: two impacts, at the Fortran API's times (1e-12: Newton tolerance) */
  memset(&log, 0, sizeof log);
  log.ellipse = 1;
  CHECK_STATUS(vci_set_impact_callback(integ, log_impact, &log), VCI_OK);
  CHECK_STATUS(vci_integrate(integ, 200, 1), VCI_OK);
  CHECK_STATUS(vci_get_stats(integ, &steps, &impacts, &iters), VCI_OK);
  CHECK(steps == 200);
  CHECK(impacts == 2 && log.count == 2);
  CHECK(iters >= 200); /* at least one Newton iteration per step */
  CHECK_CLOSE(log.t[0], ELLIPSE_FIRST_IMPACT, 1e-12);
  CHECK_CLOSE(log.t[1], ELLIPSE_SECOND_IMPACT, 1e-12);
  for (i = 0; i < 2; ++i) {
    CHECK(log.gap[i] == 0);                      /* 0-based gap index */
    CHECK(log.alpha[i] > 0.0 && log.alpha[i] < 1.0);
    CHECK(log.impulse[i] > 0.0);                 /* the floor pushes up */
    CHECK_CLOSE(log.g_at_q[i], 0.0, 1e-10);      /* the impact configuration is on the wall */
  }
  CHECK_CLOSE(log.alpha[0], 0.556410, 5e-7);     /* as printed by build/bin/ellipse */
  CHECK_STATUS(vci_get_state(integ, &t, qf, pf), VCI_OK);
  CHECK_CLOSE(t, 2.005, 1e-13);
  CHECK_STATUS(vci_get_index(integ, &k), VCI_OK);
  CHECK(k == 201);

  /* backward with the (-) scheme retraces the run through both impacts back to the pair */
  CHECK_STATUS(vci_integrate(integ, 200, -1), VCI_OK);
  CHECK_STATUS(vci_get_state(integ, &t, q, p), VCI_OK);
  CHECK_CLOSE(t, t0 + h, 1e-13);
  for (i = 0; i < 3; ++i) CHECK_CLOSE(q[i], q1[i], 1e-8); /* Newton tolerance amplified over 400 steps */
  CHECK(log.count == 4);
  CHECK_CLOSE(log.t[2], ELLIPSE_SECOND_IMPACT, 1e-8);
  CHECK_CLOSE(log.t[3], ELLIPSE_FIRST_IMPACT, 1e-8);

  /* single steps agree with vci_integrate bit for bit */
  {
    vci_model m2 = NULL;
    vci_integrator i2 = make_ellipse(&m2, &cb, h);
    for (i = 0; i < 200; ++i) CHECK_STATUS(vci_step(i2, 1), VCI_OK);
    CHECK_STATUS(vci_get_state(i2, &t, q, p), VCI_OK);
    for (i = 0; i < 3; ++i) CHECK(q[i] == qf[i] && p[i] == pf[i]);
    vci_integrator_destroy(&i2);
    vci_model_destroy(&m2);
  }

  /* starting from (q1, p1) at t0 + h instead of the pair gives the same run to the solver tolerance */
  CHECK_STATUS(vci_init_from_momentum(integ, t0 + h, q1, p1), VCI_OK);
  CHECK_STATUS(vci_get_index(integ, &k), VCI_OK);
  CHECK(k == 0);
  CHECK_STATUS(vci_get_energy(integ, &e), VCI_OK);
  CHECK(e != e); /* NaN: no step taken yet */
  CHECK_STATUS(vci_integrate(integ, 200, 1), VCI_OK);
  CHECK_STATUS(vci_get_state(integ, &t, q, p), VCI_OK);
  CHECK_CLOSE(t, 2.005, 1e-13);
  for (i = 0; i < 3; ++i) CHECK_CLOSE(q[i], qf[i], 1e-9 * (1.0 + fabs(qf[i])));
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);

  /* without the optional callbacks (differenced Hessian and gap gradients): same impacts to 1e-8 */
  {
    vci_callbacks minimal = cb;
    vci_model m3 = NULL;
    vci_integrator i3;
    minimal.mixed_hessian = NULL; minimal.gap_gradients = NULL; minimal.energy = NULL;
    i3 = make_ellipse(&m3, &minimal, h);
    memset(&log, 0, sizeof log);
    CHECK_STATUS(vci_set_impact_callback(i3, log_impact, &log), VCI_OK);
    CHECK_STATUS(vci_integrate(i3, 200, 1), VCI_OK);
    CHECK(log.count == 2);
    CHECK_CLOSE(log.t[0], ELLIPSE_FIRST_IMPACT, 1e-8);
    vci_integrator_destroy(&i3);
    vci_model_destroy(&m3);
  }
}

/* ================================================================================================ */
/* issue 7: the Hamiltonian impact condition through the C API (energy callback + setter) */
static void suite_hamiltonian(void) {
  vci_callbacks cb = ellipse_callbacks();
  double h0, hd, hh, q[3], p[3];
  int mode;
  for (mode = VCI_IMPACT_DISCRETE; mode <= VCI_IMPACT_HAMILTONIAN; ++mode) {
    vci_model model = NULL;
    vci_integrator integ = make_ellipse(&model, &cb, 1e-2);
    int64_t impacts;
    CHECK_STATUS(vci_set_impact_energy(integ, mode), VCI_OK);
    CHECK_STATUS(vci_get_state(integ, NULL, q, p), VCI_OK);
    ellipse_energy(3, q, p, &h0, &ellipse_par);
    CHECK_STATUS(vci_integrate(integ, 1000, 1), VCI_OK); /* 10 s, about 10 impacts */
    CHECK_STATUS(vci_get_stats(integ, NULL, &impacts, NULL), VCI_OK);
    CHECK(impacts >= 5);
    CHECK_STATUS(vci_get_state(integ, NULL, q, p), VCI_OK);
    ellipse_energy(3, q, p, mode == VCI_IMPACT_DISCRETE ? &hd : &hh, &ellipse_par);
    printf("  impact energy %s: %lld impacts, H - H0 = %.3e\n", mode ? "hamiltonian" : "discrete", (long long)impacts,
           (mode ? hh : hd) - h0);
    vci_integrator_destroy(&integ);
    vci_model_destroy(&model);
  }
  /* discrete: O(h^2) energy jumps at impacts; hamiltonian: H kept to the solver's tolerance */
  CHECK(fabs(hd - h0) > 1e-4);
  CHECK_CLOSE(hh, h0, 1e-8);
  {
    /* soft impacts under the discrete condition (test_stab_grazing: theta0 = 0.32, omega = 0.05,
     * 1e-6 above the floor): no impulse matches E_d at some, which keep H and are counted */
    vci_model model = NULL;
    vci_integrator integ = make_ellipse(&model, &cb, 1e-2);
    const double th = 0.32, inertia = (1.0 + 0.25) / 4.0;
    double q0[3], p0[3];
    int64_t fallbacks = -1, impacts = 0;
    q0[0] = th; q0[1] = 0.0; q0[2] = sqrt(sin(th) * sin(th) + 0.25 * cos(th) * cos(th)) + 1e-6;
    p0[0] = inertia * 0.05; p0[1] = 0.3; p0[2] = 0.0;
    CHECK_STATUS(vci_init_from_momentum(integ, 0.0, q0, p0), VCI_OK);
    CHECK_STATUS(vci_integrate(integ, 40, 1), VCI_OK);
    CHECK_STATUS(vci_get_stats(integ, NULL, &impacts, NULL), VCI_OK);
    CHECK_STATUS(vci_get_energy_fallbacks(integ, &fallbacks), VCI_OK);
    CHECK_STATUS(vci_get_energy_fallbacks(integ, NULL), VCI_OK);
    CHECK_STATUS(vci_get_energy_fallbacks(NULL, &fallbacks), VCI_ERR_ARGUMENT);
    {
      /* the accessor (the count itself: fuzz_capi_reversal_seed_13, _17338, _17959) */
      int64_t irreversible = -1;
      CHECK_STATUS(vci_get_irreversible_impacts(integ, &irreversible), VCI_OK);
      CHECK_STATUS(vci_get_irreversible_impacts(integ, NULL), VCI_OK);
      CHECK_STATUS(vci_get_irreversible_impacts(NULL, &irreversible), VCI_ERR_ARGUMENT);
      CHECK(irreversible >= 0 && irreversible <= impacts);
    }
    printf("  soft impacts, discrete condition: %lld impacts, %lld kept H\n", (long long)impacts, (long long)fallbacks);
    CHECK(fallbacks > 0 && fallbacks < impacts);
    vci_integrator_destroy(&integ);
    vci_model_destroy(&model);
  }
}

/* ================================================================================================ */
static long jacobian_calls = 0;
static int counting_dconstraint_jacobian(int n, int m, const double *base, const double *other, double h,
                                         double *jac, void *user) {
  ++jacobian_calls;
  return pendulum_dconstraint_jacobian(n, m, base, other, h, jac, user);
}

static void suite_pendulum(void) {
  /* the Fortran example's impact times (build/bin/pendulum prints them to 12 decimals); the C
   * callbacks round differently, which 5000 steps amplify to ~1e-12 */
  static const double expected[3] = {1.232288308117, 2.547498996101, 3.862275285217};
  pendulum_params par = pendulum_default;
  vci_callbacks cb = pendulum_callbacks(), partial = cb;
  vci_model model = NULL;
  vci_integrator integ = NULL;
  double h = 1e-3, q0[2], q1[2], q[2], p[2], qn[2], lambda[1] = {NAN}, w, omega[2], d1[2], pn[2];
  int64_t impacts;
  int i;

  /* a constrained model needs both constraint callbacks */
  partial.discrete_constraint = NULL;
  CHECK_STATUS(vci_model_create(&model, 2, 1, 1, &partial, &par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "discrete_constraint (needed as m > 0)");
  partial = cb; partial.constraint_forms = NULL;
  CHECK_STATUS(vci_model_create(&model, 2, 1, 1, &partial, &par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "constraint_forms (needed as m > 0)");

  CHECK_STATUS(vci_model_create(&model, 2, 1, 1, &cb, &par), VCI_OK);
  CHECK_STATUS(vci_integrator_create(&integ, model, h), VCI_OK);
  CHECK_STATUS(vci_set_tolerances(integ, 0.0, 1e-12, 30), VCI_OK);
  pendulum_initial_pair(h, q0, q1);
  CHECK_STATUS(vci_init_from_pair(integ, 0.0, q0, q1), VCI_OK);
  CHECK_STATUS(vci_get_multipliers(integ, NULL), VCI_ERR_ARGUMENT); /* m = 1: lambda needed */
  CHECK_MESSAGE(integ, "lambda is NULL");

  /* one step by hand: the (+) scheme's equations hold at the solver's tolerance */
  CHECK_STATUS(vci_get_state(integ, NULL, q, p), VCI_OK);
  CHECK_STATUS(vci_step(integ, 1), VCI_OK);
  CHECK_STATUS(vci_get_state(integ, NULL, qn, pn), VCI_OK);
  CHECK_STATUS(vci_get_multipliers(integ, lambda), VCI_OK);
  pendulum_dconstraint(2, 1, q, qn, h, &w, &par);
  CHECK_CLOSE(w, 0.0, 1e-9);                            /* omega_d(q_k, q_k+1, h) = 0 */
  pendulum_d1(2, q, qn, h, d1, &par);
  pendulum_forms(2, 1, q, omega, &par);
  for (i = 0; i < 2; ++i)                               /* D1 L_d + p_k - Omega lambda = 0 */
    CHECK_CLOSE(d1[i] + p[i] - omega[i] * lambda[0], 0.0, 1e-9 * (1.0 + fabs(p[i])));
  {
    double p2[2];
    pendulum_d2(2, q, qn, h, p2, &par);                 /* p_k+1 = D2 L_d(q_k, q_k+1, h) */
    for (i = 0; i < 2; ++i) CHECK_CLOSE(pn[i], p2[i], 1e-13 * (1.0 + fabs(p2[i])));
  }

  /* to t = 5: three impacts at the Fortran example's times */
  CHECK_STATUS(vci_init_from_pair(integ, 0.0, q0, q1), VCI_OK);
  {
    impact_log log;
    memset(&log, 0, sizeof log);
    CHECK_STATUS(vci_set_impact_callback(integ, log_impact, &log), VCI_OK);
    CHECK_STATUS(vci_integrate(integ, 4999, 1), VCI_OK);
    CHECK_STATUS(vci_get_stats(integ, NULL, &impacts, NULL), VCI_OK);
    CHECK(impacts == 3 && log.count == 3);
    for (i = 0; i < 3 && i < log.count; ++i) CHECK_CLOSE(log.t[i], expected[i], 5e-11);
  }
  CHECK_STATUS(vci_get_multipliers(integ, lambda), VCI_OK);
  CHECK(lambda[0] == lambda[0]);
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);

  /* the optional constraint Jacobian: it is called, and the run has the impacts of the differenced one
   * (NULL member) to the solver's tolerance, in no more Newton iterations (an exact Newton matrix) */
  {
    int64_t it_analytic = 0, it_differenced = 0;
    double t_analytic[3] = {0}, t_differenced[3] = {0};
    int pass;
    for (pass = 0; pass < 2; ++pass) {
      impact_log log;
      vci_callbacks c2 = pendulum_callbacks();
      memset(&log, 0, sizeof log);
      jacobian_calls = 0;
      c2.discrete_constraint_jacobian = pass == 0 ? counting_dconstraint_jacobian : NULL;
      CHECK_STATUS(vci_model_create(&model, 2, 1, 1, &c2, &par), VCI_OK);
      CHECK_STATUS(vci_integrator_create(&integ, model, h), VCI_OK);
      CHECK_STATUS(vci_set_tolerances(integ, 0.0, 1e-12, 30), VCI_OK);
      CHECK_STATUS(vci_init_from_pair(integ, 0.0, q0, q1), VCI_OK);
      CHECK_STATUS(vci_set_impact_callback(integ, log_impact, &log), VCI_OK);
      CHECK_STATUS(vci_integrate(integ, 4999, 1), VCI_OK);
      CHECK(log.count == 3);
      CHECK_STATUS(vci_get_stats(integ, NULL, NULL, pass == 0 ? &it_analytic : &it_differenced), VCI_OK);
      for (i = 0; i < 3; ++i) (pass == 0 ? t_analytic : t_differenced)[i] = log.t[i];
      if (pass == 0) CHECK(jacobian_calls > 4999);
      else CHECK(jacobian_calls == 0);
      vci_integrator_destroy(&integ);
      vci_model_destroy(&model);
    }
    for (i = 0; i < 3; ++i) CHECK_CLOSE(t_analytic[i], t_differenced[i], 5e-11);
    CHECK(it_analytic <= it_differenced);
  }
}

#ifdef VCI_TEST_HDF5
/* 3000 steps of integ into capi_every.h5 through vci_open_output_every; the file's size in bytes
 * (-1 when something failed). */
static long run_to_file_size(vci_integrator integ, int every, int compress) {
  FILE *f;
  long size = -1;
  remove("capi_every.h5");
  CHECK_STATUS(vci_open_output_every(integ, "capi_every.h5", every, compress), VCI_OK);
  CHECK_STATUS(vci_integrate(integ, 3000, 1), VCI_OK);
  CHECK_STATUS(vci_close_output(integ), VCI_OK);
  f = fopen("capi_every.h5", "rb");
  CHECK(f != NULL);
  if (f) {
    if (fseek(f, 0, SEEK_END) == 0) size = ftell(f);
    fclose(f);
  }
  return size;
}
#endif

/* ================================================================================================ */
static void suite_output(void) {
  vci_callbacks cb = ellipse_callbacks();
  vci_model model = NULL;
  vci_integrator integ = make_ellipse(&model, &cb, 1e-2);
  int64_t k;
#ifdef VCI_TEST_HDF5
  {
    const char *path = "capi_output_test.h5";
    unsigned char sig[8] = {0};
    static const unsigned char hdf5_sig[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
    FILE *f;
    remove(path);
    CHECK_STATUS(vci_open_output(integ, path), VCI_OK);
    CHECK_STATUS(vci_integrate(integ, 50, 1), VCI_OK);
    CHECK_STATUS(vci_step(integ, 1), VCI_OK);
    CHECK_STATUS(vci_integrate(integ, 49, 1), VCI_OK);
    CHECK_STATUS(vci_close_output(integ), VCI_OK);
    f = fopen(path, "rb");
    CHECK(f != NULL);
    if (f) {
      CHECK(fread(sig, 1, 8, f) == 8);
      fclose(f);
    }
    CHECK(memcmp(sig, hdf5_sig, 8) == 0);
    /* a second file, left for vci_integrator_destroy to finish */
    CHECK_STATUS(vci_open_output(integ, path), VCI_OK);
    CHECK_STATUS(vci_integrate(integ, 10, 1), VCI_OK);
    CHECK_STATUS(vci_open_output(integ, "/nonexistent-dir/x.h5"), VCI_ERR_IO);
    CHECK_MESSAGE(integ, "nonexistent-dir");
    remove(path);
  }
  {
    /* vci_open_output_every: its arguments are checked; every and compress reach the file: the
     * same 3000 steps make a smaller file with every = 10 (one chunk of rows instead of three) and
     * with compress = 1 than with neither */
    long size_plain, size_every, size_gzip;
    CHECK_STATUS(vci_open_output_every(integ, "capi_every.h5", 0, 0), VCI_ERR_ARGUMENT);
    CHECK_MESSAGE(integ, "every must be in [1, 2^30]");
    CHECK_STATUS(vci_open_output_every(integ, "capi_every.h5", (1 << 30) + 1, 0), VCI_ERR_ARGUMENT);
    CHECK_STATUS(vci_open_output_every(integ, "capi_every.h5", 1, 10), VCI_ERR_ARGUMENT);
    CHECK_MESSAGE(integ, "compress must be a gzip level");
    CHECK_STATUS(vci_open_output_every(integ, "capi_every.h5", 1, -1), VCI_ERR_ARGUMENT);
    CHECK_STATUS(vci_open_output_every(integ, NULL, 1, 0), VCI_ERR_ARGUMENT);
    size_plain = run_to_file_size(integ, 1, 0);
    size_every = run_to_file_size(integ, 10, 0);
    size_gzip = run_to_file_size(integ, 1, 1);
    printf("  vci_open_output_every: 3000 steps: %ld bytes, every 10: %ld, gzip 1: %ld\n", size_plain, size_every,
           size_gzip);
    CHECK(size_plain > 0 && size_every > 0 && size_gzip > 0);
    CHECK(size_every < size_plain);
    CHECK(size_gzip < size_plain);
    remove("capi_every.h5");
  }
#else
  CHECK_STATUS(vci_open_output(integ, "capi_output_test.h5"), VCI_ERR_IO);
  CHECK_MESSAGE(integ, "built without HDF5");
  /* the integrator is unharmed */
  CHECK_STATUS(vci_integrate(integ, 10, 1), VCI_OK);
#endif
  CHECK_STATUS(vci_get_index(integ, &k), VCI_OK);
  CHECK(k > 1);
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
}

/* ================================================================================================ */
/* The run a file records ends with the last vci_step / vci_integrate that wrote to it: its status
 * and message are the file's (`status`, `status_message`), whatever calls came between it and
 * vci_close_output or vci_integrator_destroy. Writes three files that test/api/output_status.sh
 * reads back: (1) an impact callback stops the run (VCI_ERR_CALLBACK), then vci_close_output;
 * (2) the same, then a getter that succeeds, then destroy; (3) a run that succeeds, then a getter
 * refused (energy NULL: VCI_ERR_ARGUMENT), then destroy. The files must say 2, 2 and 0. */
static int refuse_impact(double t, double alpha, int gap, const double *q, double impulse, void *user) {
  (void)t; (void)alpha; (void)gap; (void)q; (void)impulse; (void)user;
  return 1;
}

static void suite_output_status(void) {
#ifdef VCI_TEST_HDF5
  vci_callbacks cb = ellipse_callbacks();
  vci_model model = NULL;
  vci_integrator integ;
  double t;
  integ = make_ellipse(&model, &cb, 1e-2);   /* (1) the ellipse's first impact is at t = 0.75 */
  CHECK_STATUS(vci_open_output(integ, "capi_status_callback.h5"), VCI_OK);
  CHECK_STATUS(vci_set_impact_callback(integ, refuse_impact, NULL), VCI_OK);
  CHECK_STATUS(vci_integrate(integ, 200, 1), VCI_ERR_CALLBACK);
  CHECK_STATUS(vci_close_output(integ), VCI_OK);
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
  integ = make_ellipse(&model, &cb, 1e-2);   /* (2) */
  CHECK_STATUS(vci_open_output(integ, "capi_status_destroyed.h5"), VCI_OK);
  CHECK_STATUS(vci_set_impact_callback(integ, refuse_impact, NULL), VCI_OK);
  CHECK_STATUS(vci_integrate(integ, 200, 1), VCI_ERR_CALLBACK);
  CHECK_STATUS(vci_get_state(integ, &t, NULL, NULL), VCI_OK);
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
  integ = make_ellipse(&model, &cb, 1e-2);   /* (3) */
  CHECK_STATUS(vci_open_output(integ, "capi_status_ok.h5"), VCI_OK);
  CHECK_STATUS(vci_integrate(integ, 200, 1), VCI_OK);
  CHECK_STATUS(vci_get_energy(integ, NULL), VCI_ERR_ARGUMENT);
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
#else
  printf("  built without HDF5: nothing to check\n");
#endif
}

/* ================================================================================================ */
/* Restart from the C ABI: a run split in two (the first half written to a file, the second started
 * from that file by vci_restore_from_file and appended to it by vci_append_output) ends in exactly
 * the state of the uninterrupted run: bit for bit (memcmp), index and energy too. The ellipse hits
 * its wall in both halves (impacts at t = 0.75, 1.15; the split is at t = 1.0). */
#ifdef VCI_TEST_HDF5
/* The paper's nonholonomic pendulum (m = 1: multipliers, the predictor's history) split at `split`
 * of `nsteps` steps through a file: 1 when the end state is the uninterrupted run's, bit for bit. */
static int pendulum_restart_matches(int64_t nsteps, int64_t split) {
  vci_callbacks cb = pendulum_callbacks();
  pendulum_params par = pendulum_default;
  vci_model model = NULL;
  vci_integrator integ[3] = {NULL, NULL, NULL};
  const char *path = "capi_restart_pendulum.h5";
  double h = 1e-2, q0[2], q1[2], t[3] = {0, 0, 0}, q[3][2], p[3][2], lam[3] = {0, 0, 0};
  int64_t impacts = 0;
  int i, same;
  memset(q, 0, sizeof q);
  memset(p, 0, sizeof p);
  pendulum_initial_pair(h, q0, q1);
  remove(path);
  CHECK_STATUS(vci_model_create(&model, 2, 1, 1, &cb, &par), VCI_OK);
  for (i = 0; i < 3; ++i) {
    CHECK_STATUS(vci_integrator_create(&integ[i], model, h), VCI_OK);
    CHECK_STATUS(vci_set_tolerances(integ[i], 0.0, 1e-14, 30), VCI_OK);
  }
  CHECK_STATUS(vci_init_from_pair(integ[0], 0.0, q0, q1), VCI_OK);
  CHECK_STATUS(vci_integrate(integ[0], nsteps, 1), VCI_OK);
  CHECK_STATUS(vci_init_from_pair(integ[1], 0.0, q0, q1), VCI_OK);
  CHECK_STATUS(vci_open_output(integ[1], path), VCI_OK);
  CHECK_STATUS(vci_integrate(integ[1], split, 1), VCI_OK);
  CHECK_STATUS(vci_close_output(integ[1]), VCI_OK);
  CHECK_STATUS(vci_restore_from_file(integ[2], path), VCI_OK);
  CHECK_STATUS(vci_append_output(integ[2], path), VCI_OK);
  CHECK_STATUS(vci_integrate(integ[2], nsteps - split, 1), VCI_OK);
  CHECK_STATUS(vci_get_stats(integ[0], NULL, &impacts, NULL), VCI_OK);
  CHECK(impacts >= 1);
  for (i = 0; i < 3; i += 2) {
    CHECK_STATUS(vci_get_state(integ[i], &t[i], q[i], p[i]), VCI_OK);
    CHECK_STATUS(vci_get_multipliers(integ[i], &lam[i]), VCI_OK);
  }
  same = memcmp(&t[0], &t[2], sizeof t[0]) == 0 && memcmp(q[0], q[2], sizeof q[0]) == 0 &&
         memcmp(p[0], p[2], sizeof p[0]) == 0 && memcmp(&lam[0], &lam[2], sizeof lam[0]) == 0;
  if (!same) printf("pendulum restart: q = %.17g %.17g, uninterrupted %.17g %.17g\n", q[2][0], q[2][1], q[0][0], q[0][1]);
  for (i = 0; i < 3; ++i) vci_integrator_destroy(&integ[i]);
  vci_model_destroy(&model);
  remove(path);
  return same;
}
#endif

static void suite_restart(void) {
  vci_callbacks cb = ellipse_callbacks();
  vci_model model = NULL;
  vci_integrator whole = make_ellipse(&model, &cb, 1e-2), half = NULL, other = NULL;
  double t_a = 0, t_b = 1, q_a[3] = {0}, q_b[3] = {1}, p_a[3] = {0}, p_b[3] = {1}, e_a = 0, e_b = 1;
  int64_t k_a = 0, k_b = 1, impacts_b = 0;
#ifdef VCI_TEST_HDF5
  const char *path = "capi_restart_test.h5", *bare = "capi_restart_not_h5.txt";
  FILE *f;
  remove(path);
  CHECK_STATUS(vci_integrate(whole, 200, 1), VCI_OK);
  CHECK_STATUS(vci_get_state(whole, &t_a, q_a, p_a), VCI_OK);
  CHECK_STATUS(vci_get_energy(whole, &e_a), VCI_OK);
  CHECK_STATUS(vci_get_index(whole, &k_a), VCI_OK);
  vci_integrator_destroy(&whole);

  /* first half: 99 steps from the pair (index 1 -> 100), into the file */
  half = make_ellipse(&model, &cb, 1e-2);
  CHECK_STATUS(vci_open_output(half, path), VCI_OK);
  CHECK_STATUS(vci_integrate(half, 99, 1), VCI_OK);
  CHECK_STATUS(vci_close_output(half), VCI_OK);
  vci_integrator_destroy(&half);

  /* second half: a fresh integrator continues from the file and appends to it */
  CHECK_STATUS(vci_integrator_create(&half, model, 1e-2), VCI_OK);
  CHECK_STATUS(vci_set_tolerances(half, 0.0, 1e-12, 30), VCI_OK);
  CHECK_STATUS(vci_restore_from_file(half, path), VCI_OK);
  CHECK_STATUS(vci_get_index(half, &k_b), VCI_OK);
  CHECK(k_b == 100);
  CHECK_STATUS(vci_append_output(half, path), VCI_OK);
  CHECK_STATUS(vci_integrate(half, 101, 1), VCI_OK);
  CHECK_STATUS(vci_get_state(half, &t_b, q_b, p_b), VCI_OK);
  CHECK_STATUS(vci_get_energy(half, &e_b), VCI_OK);
  CHECK_STATUS(vci_get_index(half, &k_b), VCI_OK);
  CHECK_STATUS(vci_get_stats(half, NULL, &impacts_b, NULL), VCI_OK);
  CHECK_STATUS(vci_close_output(half), VCI_OK);
  CHECK(k_a == 201 && k_b == k_a);
  CHECK(impacts_b >= 1); /* the second half has an impact of its own */
  CHECK(memcmp(&t_a, &t_b, sizeof t_a) == 0);
  CHECK(memcmp(q_a, q_b, sizeof q_a) == 0);
  CHECK(memcmp(p_a, p_b, sizeof p_a) == 0);
  CHECK(memcmp(&e_a, &e_b, sizeof e_a) == 0);

  CHECK(pendulum_restart_matches(400, 173));

  /* the appended file restarts too: at its new end, the state just reached */
  CHECK_STATUS(vci_integrator_create(&other, model, 1e-2), VCI_OK);
  CHECK_STATUS(vci_restore_from_file(other, path), VCI_OK);
  CHECK_STATUS(vci_get_state(other, &t_b, q_b, p_b), VCI_OK);
  CHECK_STATUS(vci_get_index(other, &k_b), VCI_OK);
  CHECK(k_b == k_a && memcmp(q_a, q_b, sizeof q_a) == 0 && memcmp(p_a, p_b, sizeof p_a) == 0);
  vci_integrator_destroy(&other);

  /* refusals, each with its status and a message naming the cause */
  CHECK_STATUS(vci_integrator_create(&other, model, 2e-2), VCI_OK);
  CHECK_STATUS(vci_restore_from_file(other, path), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(other, "step length");
  CHECK_STATUS(vci_step(other, 1), VCI_ERR_STATE); /* no state after a failed restore */
  CHECK_STATUS(vci_restore_from_file(other, NULL), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(other, "path is NULL");
  CHECK_STATUS(vci_restore_from_file(other, ""), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_restore_from_file(other, "capi_restart_missing.h5"), VCI_ERR_IO);
  CHECK_MESSAGE(other, "does not exist");
  f = fopen(bare, "w");
  if (f) {
    fputs("not hdf5\n", f);
    fclose(f);
  }
  CHECK_STATUS(vci_restore_from_file(other, bare), VCI_ERR_IO);
  CHECK_MESSAGE(other, "not an HDF5 file");
  CHECK_STATUS(vci_append_output(other, "capi_restart_missing.h5"), VCI_ERR_IO);
  CHECK_MESSAGE(other, "does not exist");
  CHECK_STATUS(vci_append_output(other, NULL), VCI_ERR_ARGUMENT);
  vci_integrator_destroy(&other);
  CHECK_STATUS(vci_restore_from_file(NULL, path), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_append_output(NULL, path), VCI_ERR_ARGUMENT);
  {
    /* a file of another model (n = 2) is refused by size */
    vci_callbacks pcb = pendulum_callbacks();
    vci_model pm = NULL;
    pendulum_params pp = pendulum_default;
    CHECK_STATUS(vci_model_create(&pm, 2, 1, 1, &pcb, &pp), VCI_OK);
    CHECK_STATUS(vci_integrator_create(&other, pm, 1e-2), VCI_OK);
    CHECK_STATUS(vci_restore_from_file(other, path), VCI_ERR_ARGUMENT);
    CHECK_MESSAGE(other, "another model");
    vci_integrator_destroy(&other);
    vci_model_destroy(&pm);
  }
  /* appending a run that does not continue the file: the first step says so, nothing written */
  other = make_ellipse(&model, &cb, 1e-2);
  CHECK_STATUS(vci_append_output(other, path), VCI_OK);
  CHECK_STATUS(vci_integrate(other, 5, 1), VCI_ERR_IO);
  CHECK_MESSAGE(other, "does not start from the file's last state");
  /* an output that holds steps blocks a restore (one file, one run) */
  CHECK_STATUS(vci_open_output(other, "capi_restart_other.h5"), VCI_OK);
  CHECK_STATUS(vci_init_from_pair(other, 0.0, q_a, q_a), VCI_OK);
  CHECK_STATUS(vci_integrate(other, 2, 1), VCI_OK);
  CHECK_STATUS(vci_restore_from_file(other, path), VCI_ERR_STATE);
  CHECK_MESSAGE(other, "close it");
  vci_integrator_destroy(&other);
  remove(path);
  remove(bare);
  remove("capi_restart_other.h5");
#else
  CHECK_STATUS(vci_restore_from_file(whole, "capi_restart_test.h5"), VCI_ERR_IO);
  CHECK_MESSAGE(whole, "built without HDF5");
  CHECK_STATUS(vci_append_output(whole, "capi_restart_test.h5"), VCI_ERR_IO);
  CHECK_MESSAGE(whole, "built without HDF5");
  vci_integrator_destroy(&whole);
  (void)half; (void)other; (void)t_a; (void)t_b; (void)q_a; (void)q_b; (void)p_a; (void)p_b;
  (void)e_a; (void)e_b; (void)k_a; (void)k_b; (void)impacts_b;
#endif
  vci_model_destroy(&model);
}

/* ================================================================================================ */
/* Callbacks that return huge finite values (1e308, whose differences overflow) or NaN now and then:
 * every run ends with a status (never a hang), and no NaN/Inf ever reaches LAPACK (lapack_guard.c
 * counts LAPACK calls with non-finite input). The faults hit from the `from`-th call of one
 * callback on, at the calls a fixed linear congruential sequence picks (one in four). */
typedef struct { ellipse_params e; int which, mode, calls, from; unsigned seed; } erratic_params;

static double erratic_value(const erratic_params *p) {
  static const double values[] = {1e308, -1e308, 1e200, NAN, INFINITY};
  return values[p->mode];
}

static int erratic_hit(erratic_params *p, int which) {
  if (p->which != which || ++p->calls < p->from) return 0;
  p->seed = p->seed * 1103515245u + 12345u;
  return ((p->seed >> 16) & 3u) == 0;
}

static int erratic_d1(int n, const double *q, const double *v, double h, double *o, void *u) {
  erratic_params *p = (erratic_params *)u;
  int rc = ellipse_d1(n, q, v, h, o, &p->e);
  if (erratic_hit(p, 1)) o[p->calls % 3] = erratic_value(p);
  return rc;
}
static int erratic_d2(int n, const double *q, const double *v, double h, double *o, void *u) {
  erratic_params *p = (erratic_params *)u;
  int rc = ellipse_d2(n, q, v, h, o, &p->e);
  if (erratic_hit(p, 2)) o[p->calls % 3] = erratic_value(p);
  return rc;
}
static int erratic_d3(int n, const double *q, const double *v, double h, double *o, void *u) {
  erratic_params *p = (erratic_params *)u;
  int rc = ellipse_d3(n, q, v, h, o, &p->e);
  if (erratic_hit(p, 3)) o[0] = erratic_value(p);
  return rc;
}
static int erratic_gaps(int n, int ng, const double *q, double *g, void *u) {
  erratic_params *p = (erratic_params *)u;
  int rc = ellipse_gaps(n, ng, q, g, &p->e);
  if (erratic_hit(p, 4)) g[0] = erratic_value(p);
  return rc;
}

/* A gap callback that is not a function of q alone (issue 24, "nothing silently wrong"): a free
 * particle (separable, n = 1, m = 1, V = 0) moving at speed 1 towards the wall g = q - offset >= 0.
 * While `lie` is set the callback returns |q - offset| + 1e-3 (never 0: |q - offset| alone is 0
 * half-way through the step, where the composition's dip screen now finds a touch and reflects,
 * expl24l), so the step across the wall is accepted beyond it (the library cannot see that); told the truth again, the next step starts 5e-3 beyond
 * the wall, six orders above the solver's tolerance. Moving `offset` past the particle between
 * calls (a model changed under the integrator, as fuzz_capi seeds 60 and 473 did through a reused
 * user pointer) does the same. Such a step fails with VCI_ERR_INADMISSIBLE naming the wall, the
 * state stays at the last accepted step, and the integrator goes on once the model is consistent.
 * Before, the start was taken as "on" the wall and reflected from inside it with VCI_OK. */
typedef struct { int lie; double offset; } lying_params;
static int lying_zero(int n, const double *q, double *out, void *u) {
  (void)q; (void)u;
  memset(out, 0, (size_t)n * sizeof *out); /* V = 0 and grad V = 0 (n >= 1 outputs either way) */
  return 0;
}
static int lying_gaps(int n, int ng, const double *q, double *g, void *u) {
  const lying_params *p = (const lying_params *)u;
  (void)n; (void)ng;
  g[0] = p->lie ? fabs(q[0] - p->offset) + 1e-3 : q[0] - p->offset;
  return 0;
}
static int lying_gap_grads(int n, int ng, const double *q, double *dg, void *u) {
  (void)n; (void)ng; (void)q; (void)u;
  dg[0] = 1.0;
  return 0;
}

/* one step that must fail with VCI_ERR_INADMISSIBLE, say where (the step, its time, the wall and
 * its gap: `said`), and leave (t, q, p) exactly as they were */
static void check_refused_start(vci_integrator integ, const char *said, int line) {
  double t0, q0, p0, t1, q1, p1;
  vci_get_state(integ, &t0, &q0, &p0);
  check_status(vci_step(integ, 1), VCI_ERR_INADMISSIBLE, "vci_step from beyond the wall", line);
  check_message(integ, said, line);
  vci_get_state(integ, &t1, &q1, &p1);
  check(t1 == t0 && q1 == q0 && p1 == p0, "state kept after the refused step", __FILE__, line);
}

static void erratic_lying_gap(void) {
  static const int schemes[] = {VCI_SCHEME_MIDPOINT, VCI_SCHEME_LOBATTO, VCI_SCHEME_COMPOSITION};
  int i;
  for (i = 0; i < 3; ++i) {
    lying_params p = {0, 0.0};
    vci_separable_callbacks cb = VCI_SEPARABLE_CALLBACKS_INIT;
    vci_model model = NULL;
    vci_integrator integ = NULL;
    double mass = 1.0, q = 0.015, v = -1.0, t;
    cb.potential = lying_zero; cb.potential_gradient = lying_zero;
    cb.gaps = lying_gaps; cb.gap_gradients = lying_gap_grads;
    CHECK_STATUS(vci_model_create_separable(&model, 1, 0, 1, VCI_MASS_DIAGONAL, &mass, &cb, &p), VCI_OK);
    CHECK_STATUS(vci_integrator_create(&integ, model, 1e-2), VCI_OK);
    CHECK_STATUS(vci_set_scheme(integ, schemes[i], 2), VCI_OK);
    CHECK_STATUS(vci_init_from_momentum(integ, 0.0, &q, &v), VCI_OK);
    CHECK_STATUS(vci_step(integ, 1), VCI_OK);           /* q = 0.005 (free flight: exact to round-off) */
    p.lie = 1;
    CHECK_STATUS(vci_step(integ, 1), VCI_OK);           /* across the wall, hidden by the lie */
    CHECK_STATUS(vci_get_state(integ, &t, &q, NULL), VCI_OK);
    CHECK_CLOSE(q, -0.005, 1e-12);
    p.lie = 0;
    check_refused_start(integ, "step from index 2 (t =  2.0000000E-02, forward): the step starts beyond wall 1 (g = "
                               "-5.000E-03", __LINE__);
    /* the wall moved past the particle: a fresh start at q = 0.5, 10 steps to q = 0.4, the wall to 0.45 */
    q = 0.5; v = -1.0;
    CHECK_STATUS(vci_init_from_momentum(integ, 0.0, &q, &v), VCI_OK);
    CHECK_STATUS(vci_integrate(integ, 10, 1), VCI_OK);  /* q = 0.4 */
    p.offset = 0.45;
    check_refused_start(integ, "step from index 10 (t =  1.0000000E-01, forward): the step starts beyond wall 1 (g = "
                               "-5.000E-02", __LINE__);
    p.offset = 0.0;                                     /* consistent again: the run goes on */
    CHECK_STATUS(vci_step(integ, 1), VCI_OK);
    CHECK_STATUS(vci_get_state(integ, &t, &q, NULL), VCI_OK);
    CHECK_CLOSE(q, 0.39, 1e-12);
    vci_integrator_destroy(&integ);
    vci_model_destroy(&model);
  }
}

/* The two refusals of a stage-1 miss inside a step (wall24j: refuse_start_beyond at a wall point of
 * this step, refuse_landing_beyond), which only fuzz seed 473 reached: a free particle above a floor
 * (wall 1, g = q) under a ceiling (wall 3, g = c - q), and wall 2 (g = q + 1, far below) whose gaps
 * callback lies: once the step has evaluated V (the impact's energy, after stage 1 has checked
 * every gap at its wall point), it says wall 2 is 1e-3 beyond at the floor's point (q = 0). So
 * stage 1's own check of that point saw it admissible and the next look at it (the next sub-step's
 * start, or the landed end's check) sees it beyond: what a miss of stage 1 looks like to the step.
 * Net off: VCI_ERR_IMPACT naming the step, its time and both walls, the state kept. The lie ends
 * when the callback is asked about the step's start q0 again (the safety net's retry; no sub-step
 * of the first attempt ends there): net on, the retry as 2 sub-steps is exact free flight. */
typedef struct { int armed, latched, told; double ceiling, q_reset; } miss_params;
static int miss_potential(int n, const double *q, double *out, void *u) {
  miss_params *p = (miss_params *)u;
  (void)q;
  if (p->armed) p->latched = 1;
  memset(out, 0, (size_t)n * sizeof *out); /* V = 0 (out[0]) and grad V = 0 */
  return 0;
}
static int miss_gradient(int n, const double *q, double *out, void *u) {
  (void)q; (void)u;
  memset(out, 0, (size_t)n * sizeof *out);
  return 0;
}
static int miss_gaps(int n, int ng, const double *q, double *g, void *u) {
  miss_params *p = (miss_params *)u;
  (void)n; (void)ng;
  if (p->latched && q[0] == p->q_reset) p->latched = p->armed = 0; /* the retry: honest from now on */
  g[0] = q[0];
  g[1] = q[0] + 1.0;
  g[2] = p->ceiling - q[0];
  if (p->latched && q[0] == 0.0) {
    g[1] = -1e-3;
    ++p->told;
  }
  return 0;
}
static int miss_gap_grads(int n, int ng, const double *q, double *dg, void *u) {
  (void)n; (void)ng; (void)q; (void)u;
  dg[0] = 1.0; dg[1] = 1.0; dg[2] = -1.0;
  return 0;
}

/* From q0 at t = 0.25 (v = -1, h = 1e-2, ceiling c), the step in which wall 2 lies; with the net
 * (splits > 1) the retry must end at (q_end, p_end), one step split in 2. */
static void stage1_miss_step(int scheme, double q0, double c, int splits, int expected, const char *said,
                             double q_end, double p_end, int line) {
  miss_params par = {0, 0, 0, 0.0, 0.0};
  vci_separable_callbacks cb = VCI_SEPARABLE_CALLBACKS_INIT;
  vci_model model = NULL;
  vci_integrator integ = NULL;
  double mass = 1.0, q = q0, v = -1.0, t0, qa, pa, t, p;
  int64_t split_steps = -1, largest = -1;
  cb.potential = miss_potential; cb.potential_gradient = miss_gradient;
  cb.gaps = miss_gaps; cb.gap_gradients = miss_gap_grads;
  par.ceiling = c; par.q_reset = q0;
  check_status(vci_model_create_separable(&model, 1, 0, 3, VCI_MASS_DIAGONAL, &mass, &cb, &par), VCI_OK, "create", line);
  check_status(vci_integrator_create(&integ, model, 1e-2), VCI_OK, "integrator", line);
  check_status(vci_set_scheme(integ, scheme, 2), VCI_OK, "scheme", line);
  check_status(vci_set_step_splits(integ, splits), VCI_OK, "splits", line);
  check_status(vci_init_from_momentum(integ, 0.25, &q, &v), VCI_OK, "init", line);
  vci_get_state(integ, &t0, &qa, &pa);
  par.armed = 1;
  check_status(vci_step(integ, 1), expected, "the step with the lie", line);
  if (expected != VCI_OK) check_message(integ, said, line);
  check(par.told > 0, "the lie was told (the test reached its point)", __FILE__, line);
  vci_get_state(integ, &t, &q, &p);
  if (expected != VCI_OK) {
    check(t == t0 && q == qa && p == pa, "state kept after the refused step", __FILE__, line);
  } else {
    check(fabs(t - 0.26) <= 1e-15, "the step was taken", __FILE__, line);
    /* free flight between walls is exact for these schemes: round-off only */
    check(fabs(q - q_end) <= 1e-12 && fabs(p - p_end) <= 1e-12, "free flight between the walls after the split",
          __FILE__, line);
    check_status(vci_get_split_steps(integ, &split_steps, &largest), VCI_OK, "split steps", line);
    check(split_steps == 1 && largest == 2, "the net split that step in 2", __FILE__, line);
  }
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
}

static void erratic_stage1_miss(void) {
  static const int schemes[] = {VCI_SCHEME_MIDPOINT, VCI_SCHEME_LOBATTO};
  int i;
  for (i = 0; i < 2; ++i) {
    /* from 0.003 under a ceiling at 0.004: the floor at t = 0.253, then 0.007 up, beyond the
     * ceiling: the next sub-step starts at the floor's point, which wall 2 now says is beyond it */
    stage1_miss_step(schemes[i], 0.003, 0.004, 1, VCI_ERR_IMPACT,
                     "step from index 0 (t =  2.5000000E-01, forward): stage 1 reached wall 1 at a point beyond wall 2 "
                     "(g = -1.000E-03): the motion crossed it first, unseen", 0.0, 0.0, __LINE__);
    /* net on: 2 sub-steps, the floor at t = 0.253, the ceiling at 0.257, down to 0.001 at 0.26 */
    stage1_miss_step(schemes[i], 0.003, 0.004, 16, VCI_OK, NULL, 0.001, -1.0, __LINE__);
    /* from 1e-2 - 1e-13: the step ends 1e-13 beyond the floor, stage 1 lands on it at the step's
     * end (within 1e-10 of it), and the landed point is checked against wall 2 */
    stage1_miss_step(schemes[i], 0.01 - 1e-13, 1.0, 1, VCI_ERR_IMPACT,
                     "step from index 0 (t =  2.5000000E-01, forward): stage 1 reached wall 1 at the step's end at a "
                     "point beyond wall 2 (g = -1.000E-03): the motion crossed it first, unseen", 0.0, 0.0, __LINE__);
    stage1_miss_step(schemes[i], 0.01 - 1e-13, 1.0, 16, VCI_OK, NULL, 0.0, -1.0, __LINE__);
  }
}

static void suite_erratic(void) {
  int which, mode, from, seed, runs = 0, failed_runs = 0;
  int64_t before = vci_test_lapack_calls();
  for (which = 1; which <= 4; ++which)
    for (mode = 0; mode < 5; ++mode)
      for (from = 1; from < 200; from += 19)
        for (seed = 0; seed < 2; ++seed) {
          erratic_params p;
          vci_callbacks cb = VCI_CALLBACKS_INIT;
          vci_model model = NULL;
          vci_integrator integ = NULL;
          double t0, q0[3], q1[3], t;
          int status;
          p.e = ellipse_default; p.which = which; p.mode = mode; p.calls = 0; p.from = from; p.seed = (unsigned)seed;
          cb.d1_ld = erratic_d1; cb.d2_ld = erratic_d2; cb.d3_ld = erratic_d3; cb.gaps = erratic_gaps;
          CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &cb, &p), VCI_OK);
          CHECK_STATUS(vci_integrator_create(&integ, model, 1e-2), VCI_OK);
          ellipse_initial_pair(1e-2, &t0, q0, q1);
          status = vci_init_from_pair(integ, t0, q0, q1);
          if (status == VCI_OK) status = vci_integrate(integ, 150, 1);
          ++runs;
          if (status != VCI_OK) {
            char msg[512];
            ++failed_runs;
            vci_last_error(integ, msg, sizeof msg);
            CHECK(msg[0] != '\0'); /* a failure always says why */
          } else {
            CHECK_STATUS(vci_get_state(integ, &t, NULL, NULL), VCI_OK);
            CHECK(isfinite(t));
          }
          vci_integrator_destroy(&integ);
          vci_model_destroy(&model);
        }
  printf("  %d erratic runs, %d ended with an error status, %ld LAPACK calls\n", runs, failed_runs,
         vci_test_lapack_calls() - before);
  CHECK(vci_test_lapack_calls() > before); /* the guard sees vci's LAPACK calls (else this suite proves nothing) */
  CHECK(vci_test_lapack_nonfinite_calls() == 0);
  erratic_lying_gap();
  erratic_stage1_miss();
}

/* ================================================================================================ */
/* Sizes the library cannot handle are refused; allocations that fail give VCI_ERR_MEMORY (the
 * Fortran runtime would otherwise print "Error allocating" and exit). RLIMIT_AS makes the
 * allocation fail deterministically. */
static int one_gap(int n, int ng, const double *q, double *g, void *u) {
  int j;
  (void)n; (void)u;
  for (j = 0; j < ng; ++j) g[j] = q[0] + 10.0;
  return 0;
}

static void suite_limits(void) {
  vci_callbacks cb = ellipse_callbacks();
  vci_model model = NULL;
  vci_integrator integ = NULL;
  struct rlimit old, tight;
  ellipse_par = ellipse_default;
  /* dense Newton matrices of (n + m + 1)^2 entries with 32-bit LAPACK indices */
  CHECK_STATUS(vci_model_create(&model, 100000, 0, 1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "46340");
  CHECK_STATUS(vci_model_create(&model, 46340, 0, 1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_model_create(&model, 30000, 16340, 1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_model_create(&model, 2147483647, 0, 0, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  /* gradients of ngaps walls indexed dg[i + n*j] with int */
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1000000000, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "n_gaps");
  CHECK(model == NULL);

  /* within the limits but beyond the memory: VCI_ERR_MEMORY, and the process goes on */
  cb.gaps = one_gap;
  cb.gap_gradients = NULL;
  CHECK_STATUS(vci_model_create(&model, 1, 0, 1000000000, &cb, &ellipse_par), VCI_OK);
  if (getrlimit(RLIMIT_AS, &old) == 0) {
    tight = old;
    tight.rlim_cur = 1024UL * 1024UL * 1024UL * 4UL; /* 4 GB: the workspace needs 8 GB per gap array */
    if (old.rlim_cur != RLIM_INFINITY && old.rlim_cur < tight.rlim_cur) tight.rlim_cur = old.rlim_cur;
    if (getenv("VCI_TEST_NO_RLIMIT") == NULL && setrlimit(RLIMIT_AS, &tight) == 0) {
      CHECK_STATUS(vci_integrator_create(&integ, model, 1e-2), VCI_ERR_MEMORY);
      CHECK_MESSAGE(NULL, "out of memory");
      CHECK(integ == NULL);
      setrlimit(RLIMIT_AS, &old);
    } else {
      printf("  (RLIMIT_AS not set: the allocation failure is not exercised)\n");
    }
  }
  vci_model_destroy(&model);

  /* a huge bound on impacts per step allocates nothing up front */
  cb = ellipse_callbacks();
  integ = make_ellipse(&model, &cb, 1e-2);
  CHECK_STATUS(vci_set_max_impacts(integ, 2147483647), VCI_OK);
  CHECK_STATUS(vci_integrate(integ, 200, 1), VCI_OK);
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
}

/* ================================================================================================ */
/* The callback return contract: 0 success, > 0 recoverable (Newton backs off at a trial point of
 * its line search), < 0 unrecoverable (the step fails at once). d1_ld fails at exactly one call,
 * number `fail_at`, of a 150-step ellipse run, with code `rc`. */
typedef struct { ellipse_params e; int calls, fail_at, rc, noisy_from; } contract_params;

static int contract_d1(int n, const double *q, const double *v, double h, double *o, void *u) {
  contract_params *c = (contract_params *)u;
  int rc = ellipse_d1(n, q, v, h, o, &c->e);
  ++c->calls;
  if (c->noisy_from > 0 && c->calls >= c->noisy_from) o[2] += 1e-3 * (double)((c->calls * 7919) % 13 - 6);
  return c->calls == c->fail_at ? c->rc : rc;
}
static int contract_d2(int n, const double *q, const double *v, double h, double *o, void *u) {
  return ellipse_d2(n, q, v, h, o, &((contract_params *)u)->e);
}
static int contract_d3(int n, const double *q, const double *v, double h, double *o, void *u) {
  return ellipse_d3(n, q, v, h, o, &((contract_params *)u)->e);
}
static int contract_gaps(int n, int ng, const double *q, double *g, void *u) {
  return ellipse_gaps(n, ng, q, g, &((contract_params *)u)->e);
}

/* One run; its status, its message in msg[512]. */
static int contract_run(int fail_at, int rc, int noisy_from, char *msg, int64_t *k) {
  contract_params c;
  vci_callbacks cb = VCI_CALLBACKS_INIT;
  vci_model model = NULL;
  vci_integrator integ = NULL;
  double t0, q0[3], q1[3];
  int status;
  c.e = ellipse_default; c.calls = 0; c.fail_at = fail_at; c.rc = rc; c.noisy_from = noisy_from;
  cb.d1_ld = contract_d1; cb.d2_ld = contract_d2; cb.d3_ld = contract_d3; cb.gaps = contract_gaps;
  vci_model_create(&model, 3, 0, 1, &cb, &c);
  vci_integrator_create(&integ, model, 1e-2);
  ellipse_initial_pair(1e-2, &t0, q0, q1);
  status = vci_init_from_pair(integ, t0, q0, q1);
  if (status == VCI_OK) status = vci_integrate(integ, 150, 1);
  vci_last_error(integ, msg, 512);
  *k = -1;
  vci_get_index(integ, k);
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
  return status;
}

static void suite_contract(void) {
  int fail_at, pos_ok = 0, pos_failed = 0, neg_ok = 0, neg_failed = 0, absorbed_then_newton = 0;
  char msg[512];
  int64_t k;
  /* every call: a sweep by 3 missed the polishing Newton step's residual, where an unrecoverable code
   * was dropped (the step kept its converged x), until the call count shifted */
  for (fail_at = 1; fail_at < 400; ++fail_at) {
    int sp = contract_run(fail_at, 3, 0, msg, &k), sn;
    if (sp == VCI_OK) {
      ++pos_ok; /* the failing call was a trial point: Newton backed off */
    } else {
      ++pos_failed;
      CHECK_STATUS(sp, VCI_ERR_CALLBACK);
      if (!strstr(msg, "the C callback d1_ld returned 3")) printf("FAIL: positive code, message \"%s\"\n", msg), ++failures;
    }
    sn = contract_run(fail_at, -3, 0, msg, &k);
    if (sn == VCI_OK) {
      ++neg_ok;
    } else {
      ++neg_failed;
      CHECK_STATUS(sn, VCI_ERR_CALLBACK);
      if (!strstr(msg, "the C callback d1_ld returned -3")) printf("FAIL: negative code, message \"%s\"\n", msg), ++failures;
      if (!strstr(msg, "unrecoverable")) printf("FAIL: negative code, message \"%s\"\n", msg), ++failures;
    }
    /* a recoverable failure absorbed early, a genuine Newton failure (noisy D1) 100+ calls later:
     * the later failure is Newton's, and the absorbed code is not reported for it */
    if (sp == VCI_OK) {
      int s2 = contract_run(fail_at, 3, fail_at + 300, msg, &k);
      if (s2 == VCI_ERR_NEWTON) ++absorbed_then_newton;
      CHECK(s2 != VCI_ERR_CALLBACK);
      if (strstr(msg, "returned 3")) printf("FAIL: stale code in \"%s\"\n", msg), ++failures;
    }
  }
  printf("  positive code: %d runs completed (absorbed), %d failed; negative code: %d completed, %d failed; "
         "%d absorbed-then-Newton-failure runs\n", pos_ok, pos_failed, neg_ok, neg_failed, absorbed_then_newton);
  CHECK(pos_ok > 0);            /* recoverable failures at trial points are backed off from */
  CHECK(neg_ok == 0);           /* unrecoverable ones always end the run */
  CHECK(neg_failed > 0);
  CHECK(absorbed_then_newton > 0);
}

/* ================================================================================================ */
/* Statuses and messages are those of the call just made: stale messages, step lengths that make
 * time overflow, a failing constraint_forms. */
static int free_d1(int n, const double *q, const double *v, double h, double *o, void *u) {
  int i;
  (void)u;
  for (i = 0; i < n; ++i) o[i] = -(v[i] - q[i]) / h;
  return 0;
}
static int free_d2(int n, const double *q, const double *v, double h, double *o, void *u) {
  int i;
  (void)u;
  for (i = 0; i < n; ++i) o[i] = (v[i] - q[i]) / h;
  return 0;
}
static int free_d3(int n, const double *q, const double *v, double h, double *o, void *u) {
  int i;
  (void)u;
  o[0] = 0.0;
  for (i = 0; i < n; ++i) o[0] -= 0.5 * (v[i] - q[i]) * (v[i] - q[i]) / (h * h);
  return 0;
}
static int failing_forms(int n, int m, const double *q, double *omega, void *u) {
  (void)n; (void)m; (void)q; (void)omega; (void)u;
  return 5;
}

static void suite_status(void) {
  vci_callbacks cb = ellipse_callbacks();
  vci_model model = NULL;
  vci_integrator integ = make_ellipse(&model, &cb, 1e-2);
  double t;
  int64_t k, steps;
  char msg[512];

  /* after a failure, every successful call leaves an empty message */
  CHECK_STATUS(vci_step(integ, 7), VCI_ERR_ARGUMENT);
  CHECK_STATUS(vci_integrate(integ, 0, 1), VCI_OK);
  vci_last_error(integ, msg, sizeof msg);
  CHECK(msg[0] == '\0');
#define CLEARS(call)                                                                   \
  do {                                                                                 \
    CHECK_STATUS(vci_step(integ, 7), VCI_ERR_ARGUMENT);                               \
    CHECK_STATUS(call, VCI_OK);                                                        \
    vci_last_error(integ, msg, sizeof msg);                                            \
    if (msg[0] != '\0') printf("FAIL: after %s the message is \"%s\"\n", #call, msg), ++failures; \
  } while (0)
  CLEARS(vci_get_state(integ, &t, NULL, NULL));
  CLEARS(vci_get_index(integ, &k));
  CLEARS(vci_get_stats(integ, &steps, NULL, NULL));
  CLEARS(vci_set_impact_callback(integ, NULL, NULL));
  CLEARS(vci_close_output(integ));
  CLEARS(vci_set_max_impacts(integ, 16));
#undef CLEARS
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);

  /* h = 1e308: the time of the second state overflows; refused, never t = Inf with VCI_OK */
  {
    vci_callbacks fcb = VCI_CALLBACKS_INIT;
    double q0[1] = {0.0}, q1[1] = {0.0};
    int status;
    fcb.d1_ld = free_d1; fcb.d2_ld = free_d2; fcb.d3_ld = free_d3;
    CHECK_STATUS(vci_model_create(&model, 1, 0, 0, &fcb, NULL), VCI_OK);
    CHECK_STATUS(vci_integrator_create(&integ, model, 1e308), VCI_OK);
    CHECK_STATUS(vci_init_from_pair(integ, 1e308, q0, q1), VCI_ERR_ARGUMENT); /* t0 + h overflows */
    CHECK_MESSAGE(integ, "overflows");
    CHECK_STATUS(vci_init_from_pair(integ, 0.0, q0, q1), VCI_OK);
    status = vci_step(integ, 1);
    CHECK_STATUS(status, VCI_ERR_NONFINITE);
    CHECK_MESSAGE(integ, "overflows");
    CHECK_STATUS(vci_get_state(integ, &t, NULL, NULL), VCI_OK);
    CHECK(isfinite(t));
    vci_integrator_destroy(&integ);
    vci_model_destroy(&model);
  }

  /* constraint_forms returning 5: a callback failure naming it and its code */
  {
    pendulum_params par = pendulum_default;
    vci_callbacks pcb = pendulum_callbacks();
    double q0[2], q1[2];
    pcb.constraint_forms = failing_forms;
    CHECK_STATUS(vci_model_create(&model, 2, 1, 1, &pcb, &par), VCI_OK);
    CHECK_STATUS(vci_integrator_create(&integ, model, 1e-3), VCI_OK);
    pendulum_initial_pair(1e-3, q0, q1);
    CHECK_STATUS(vci_init_from_pair(integ, 0.0, q0, q1), VCI_ERR_CALLBACK);
    CHECK_MESSAGE(integ, "the C callback constraint_forms returned 5");
    vci_integrator_destroy(&integ);
    vci_model_destroy(&model);
  }
}

/* ================================================================================================ */
/* The versioned callbacks struct: the library reads cb->size bytes. A struct from an older header
 * (smaller size) has its missing members taken as NULL; one from a newer header is accepted when
 * the members this library does not know are NULL and refused otherwise; an uninitialised size is
 * refused. (test/api/compat_v0_1.c runs a client built against the 0.1 header.) */
static void suite_abi(void) {
  vci_callbacks cb = ellipse_callbacks();
  vci_model model = NULL;
  vci_integrator integ = NULL;
  struct { vci_callbacks cb; void (*later)(void); } newer;
  double t0, q0[3], q1[3];
  ellipse_par = ellipse_default;
  CHECK(cb.size == sizeof(vci_callbacks));

  /* an older header without `energy`: the energy member (set here) lies beyond size, unread */
  cb.size = offsetof(vci_callbacks, energy);
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &cb, &ellipse_par), VCI_OK);
  CHECK_STATUS(vci_integrator_create(&integ, model, 1e-2), VCI_OK);
  CHECK_STATUS(vci_set_impact_energy(integ, VCI_IMPACT_HAMILTONIAN), VCI_ERR_ARGUMENT); /* no energy */
  ellipse_initial_pair(1e-2, &t0, q0, q1);
  CHECK_STATUS(vci_init_from_pair(integ, t0, q0, q1), VCI_OK);
  CHECK_STATUS(vci_integrate(integ, 100, 1), VCI_OK);
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);

  /* size 0 (a struct zeroed with {0}) and sizes that are no vci_callbacks */
  cb.size = 0;
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "VCI_CALLBACKS_INIT");
  cb.size = 1u << 20;
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  cb.size = offsetof(vci_callbacks, energy) + 3; /* part of a pointer: no header has that size */
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  cb.size = SIZE_MAX; /* printed as C prints a size_t, not as -1 */
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &cb, &ellipse_par), VCI_ERR_ARGUMENT);
  {
    char expect[64];
    snprintf(expect, sizeof expect, "cb->size = %zu ", (size_t)SIZE_MAX);
    CHECK_MESSAGE(NULL, expect);
  }
  cb.size = sizeof(vci_callbacks);

  /* a newer header with one more member: NULL is fine, set is refused */
  memset(&newer, 0, sizeof newer);
  newer.cb = ellipse_callbacks();
  newer.cb.size = sizeof newer;
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &newer.cb, &ellipse_par), VCI_OK);
  vci_model_destroy(&model);
  newer.later = (void (*)(void))exit_guard;
  CHECK_STATUS(vci_model_create(&model, 3, 0, 1, &newer.cb, &ellipse_par), VCI_ERR_ARGUMENT);
  CHECK_MESSAGE(NULL, "newer vci.h");
  CHECK(model == NULL);
}

/* ================================================================================================ */
/* The fused callback (vci_callbacks.ld_fused, issue 26): D1, D2, D3 and the Hessian in one call. The
 * scenes' fused callbacks do the arithmetic of the separate ones, so the runs are the same bits; a
 * fused callback that fails or returns NaN where the separate ones do gives the same status at the
 * same step. fused_mode: 0 as given, 1 fail (return 3), 2 NaN in D1, once x passes 1. */
static int fused_mode = 0, fused_calls = 0;

static int beyond_x1(const double *q, const double *v) { return q[1] > 1.0 || v[1] > 1.0; }

static int spoiled_d1(int n, const double *q, const double *v, double h, double *out, void *user) {
  int rc = ellipse_d1(n, q, v, h, out, user);
  if (fused_mode == 1 && beyond_x1(q, v)) return 3;
  if (fused_mode == 2 && beyond_x1(q, v)) out[0] = NAN;
  return rc;
}

static int spoiled_fused(int n, const double *q, const double *v, double h, double *d1, double *d2, double *d3,
                         double *hess, void *user) {
  int rc = ellipse_fused(n, q, v, h, d1, d2, d3, hess, user);
  ++fused_calls;
  if (fused_mode == 1 && beyond_x1(q, v)) return 3;
  if (fused_mode == 2 && beyond_x1(q, v)) d1[0] = NAN;
  return rc;
}

static void suite_fused(void) {
  vci_callbacks sep = ellipse_callbacks(), fus = ellipse_callbacks();
  vci_model ms = NULL, mf = NULL;
  vci_integrator is, inf;
  double ts, tf, qs[3], qf[3], ps[3], pf[3];
  int mode, ss, sf, i;
  pendulum_params ppar = pendulum_default;
  double p0[2], p1[2], pq[2][2], pp[2][2], pt[2];

  /* the ellipse, forward 200 steps (2 impacts) and back: the same bits */
  fused_mode = 0; fused_calls = 0;
  sep.d1_ld = spoiled_d1; fus.d1_ld = spoiled_d1; fus.ld_fused = spoiled_fused;
  is = make_ellipse(&ms, &sep, 1e-2);
  inf = make_ellipse(&mf, &fus, 1e-2);
  CHECK_STATUS(vci_integrate(is, 200, 1), VCI_OK);
  CHECK_STATUS(vci_integrate(inf, 200, 1), VCI_OK);
  CHECK_STATUS(vci_integrate(is, 150, -1), VCI_OK);
  CHECK_STATUS(vci_integrate(inf, 150, -1), VCI_OK);
  vci_get_state(is, &ts, qs, ps);
  vci_get_state(inf, &tf, qf, pf);
  CHECK(fused_calls > 0);
  CHECK(ts == tf && memcmp(qs, qf, sizeof qs) == 0 && memcmp(ps, pf, sizeof ps) == 0);
  vci_integrator_destroy(&is); vci_integrator_destroy(&inf);
  vci_model_destroy(&ms); vci_model_destroy(&mf);

  /* failures: the same status at the same step, the same last state */
  for (mode = 1; mode <= 2; ++mode) {
    fused_mode = 0;
    is = make_ellipse(&ms, &sep, 1e-2);
    inf = make_ellipse(&mf, &fus, 1e-2);
    fused_mode = mode;
    ss = vci_integrate(is, 200, 1);
    sf = vci_integrate(inf, 200, 1);
    CHECK(ss == (mode == 1 ? VCI_ERR_CALLBACK : VCI_ERR_NONFINITE));
    CHECK(sf == ss);
    if (mode == 1) CHECK_MESSAGE(inf, "the C callback ld_fused returned 3");
    vci_get_state(is, &ts, qs, ps);
    vci_get_state(inf, &tf, qf, pf);
    CHECK(ts == tf && ts > 0.4 && ts < 0.6);
    CHECK(memcmp(qs, qf, sizeof qs) == 0);
    vci_integrator_destroy(&is); vci_integrator_destroy(&inf);
    vci_model_destroy(&ms); vci_model_destroy(&mf);
  }
  fused_mode = 0;

  /* the pendulum (m = 1, 3 impacts in 5 s): the same bits */
  pendulum_initial_pair(1e-3, p0, p1);
  for (i = 0; i < 2; ++i) {
    vci_callbacks cb = pendulum_callbacks();
    vci_model model = NULL;
    vci_integrator integ = NULL;
    if (i == 1) cb.ld_fused = pendulum_fused;
    CHECK_STATUS(vci_model_create(&model, 2, 1, 1, &cb, &ppar), VCI_OK);
    CHECK_STATUS(vci_integrator_create(&integ, model, 1e-3), VCI_OK);
    CHECK_STATUS(vci_set_tolerances(integ, 0.0, 1e-12, 30), VCI_OK);
    CHECK_STATUS(vci_init_from_pair(integ, 0.0, p0, p1), VCI_OK);
    CHECK_STATUS(vci_integrate(integ, 4999, 1), VCI_OK);
    vci_get_state(integ, &pt[i], pq[i], pp[i]);
    vci_integrator_destroy(&integ);
    vci_model_destroy(&model);
  }
  CHECK(pt[0] == pt[1] && memcmp(pq[0], pq[1], sizeof pq[0]) == 0 && memcmp(pp[0], pp[1], sizeof pp[0]) == 0);
}

/* ================================================================================================ */
int main(int argc, char **argv) {
  static const struct { const char *name; void (*run)(void); } suites[] = {
      {"version", suite_version},     {"handles", suite_handles},   {"arguments", suite_arguments},
      {"callbacks", suite_callbacks}, {"ellipse", suite_ellipse},   {"hamiltonian", suite_hamiltonian},
      {"pendulum", suite_pendulum},   {"output", suite_output},     {"erratic", suite_erratic},
      {"limits", suite_limits},       {"contract", suite_contract}, {"status", suite_status},
      {"abi", suite_abi},             {"restart", suite_restart},   {"fused", suite_fused},
      {"output_status", suite_output_status}};
  size_t i, n = sizeof suites / sizeof suites[0];
  int ran = 0;
  atexit(exit_guard);
  for (i = 0; i < n; ++i) {
    if (argc < 2 || strcmp(argv[1], suites[i].name) == 0 || strcmp(argv[1], "all") == 0) {
      int before = failures;
      suites[i].run();
      printf("%s: %s (%d failed checks)\n", suites[i].name, failures == before ? "passed" : "FAILED", failures - before);
      ++ran;
    }
  }
  finished = 1;
  if (!ran) {
    fprintf(stderr, "unknown suite %s\n", argv[1]);
    return 2;
  }
  /* whatever ran: no NaN/Inf ever reached LAPACK */
  if (vci_test_lapack_nonfinite_calls() != 0) {
    ++failures;
    printf("FAIL: %ld LAPACK calls with NaN/Inf input\n", vci_test_lapack_nonfinite_calls());
  }
  return failures ? 1 : 0;
}
