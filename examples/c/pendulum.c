/* The paper's nonholonomic pendulum in a cylinder through the C API: the same run as
 * build/bin/pendulum (h = 1e-3, 5 s, Newton rtol 1e-12), one line per impact.
 * Usage: vci_c_pendulum [h [t_final]] (0 < h <= 1e6, |t_final| <= 1e12, at most 2^53 steps;
 * exit status 2 for anything else). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "vci.h"
#include "scenes.h"
#include "args.h"

static int print_impact(double t, double alpha, int gap, const double *q, double impulse, void *user) {
  int *count = (int *)user;
  (void)q;
  printf("impact %d t=%.15f wall=%d alpha=%f impulse=%.5e\n", ++*count, t, gap + 1, alpha, impulse);
  return 0;
}

int main(int argc, char **argv) {
  double h, t_final;
  double q0[2], q1[2], t, q[2], p[2], lambda[1];
  pendulum_params par = pendulum_default;
  vci_callbacks cb = pendulum_callbacks();
  vci_model model = NULL;
  vci_integrator integ = NULL;
  int64_t steps, impacts, iterations, nsteps;
  int count = 0, status;
  char msg[512];

  if (!example_number(argc, argv, 1, "h", 0.0, 1e6, 1, 1e-3, &h) ||
      !example_number(argc, argv, 2, "t_final", -1e12, 1e12, 0, 5.0, &t_final))
    return 2;
  cb.ld_fused = pendulum_fused; /* D1, D2, D3 and the Hessian in one call */
  status = vci_model_create(&model, 2, 1, 1, &cb, &par);
  if (status == VCI_OK) status = vci_integrator_create(&integ, model, h);
  if (status == VCI_OK) status = vci_set_tolerances(integ, 0.0, 1e-12, 30);
  if (status == VCI_OK) status = vci_set_impact_callback(integ, print_impact, &count);
  pendulum_initial_pair(h, q0, q1);
  if (status == VCI_OK) status = vci_init_from_pair(integ, 0.0, q0, q1);
  if (status == VCI_OK) {
    vci_get_state(integ, &t, NULL, NULL);
    if (!example_steps(argv[0], t, t_final, h, &nsteps)) {
      vci_integrator_destroy(&integ);
      vci_model_destroy(&model);
      return 2;
    }
    status = vci_integrate(integ, nsteps, +1);
  }
  if (status != VCI_OK) {
    vci_last_error(integ, msg, sizeof msg);
    fprintf(stderr, "pendulum: %s: %s\n", vci_status_string(status), msg);
  } else {
    vci_get_state(integ, &t, q, p);
    vci_get_multipliers(integ, lambda);
    vci_get_stats(integ, &steps, &impacts, &iterations);
    printf("impacts: %lld\nsteps: %lld   t = %.6f\nq = %.15e %.15e\nlambda = %.15e\n", (long long)impacts, (long long)steps, t, q[0], q[1],
           lambda[0]);
  }
  vci_integrator_destroy(&integ);
  vci_model_destroy(&model);
  return status == VCI_OK ? 0 : 1;
}
