/* Command-line numbers of the C examples, read strictly: the whole argument one finite decimal
 * number within its range (atof took "1,5" as 1 and "abc" as 0), and a step count bounded before
 * it becomes an integer (a double beyond int64_t has no defined conversion). Header-only. */
#ifndef VCI_C_ARGS_H
#define VCI_C_ARGS_H

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

/* argv[i] as a number in [lo, hi] (lo excluded when low_open) into *x, or `fallback` when
 * argc <= i; a message on stderr and 0 when it is not one. */
static int example_number(int argc, char **argv, int i, const char *name, double lo, double hi, int low_open,
                          double fallback, double *x) {
  char *end = NULL;
  *x = fallback;
  if (argc <= i) return 1;
  errno = 0;
  *x = strtod(argv[i], &end);
  if (end == argv[i] || *end != '\0' || errno == ERANGE || !isfinite(*x) || *x < lo || *x > hi ||
      (low_open && *x == lo)) {
    fprintf(stderr, "%s: %s must be a finite number in %s%g, %g] (got \"%s\")\n", argv[0], name, low_open ? "(" : "[",
            lo, hi, argv[i]);
    return 0;
  }
  return 1;
}

/* Steps of h from t to t_final (0 when it is behind), at most 2^53 (step indices stay exact in
 * the float64 time grid, as the Fortran examples' --t-final); 0 and a message when more. */
static int example_steps(const char *prog, double t, double t_final, double h, int64_t *nsteps) {
  double n = ceil((t_final - t) / h - 1e-9);
  if (!(n <= 9007199254740992.0)) {
    fprintf(stderr, "%s: reaching t_final = %g takes more than 2^53 steps of h = %g\n", prog, t_final, h);
    return 0;
  }
  *nsteps = n > 0 ? (int64_t)n : 0;
  return 1;
}

#endif
