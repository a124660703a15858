/* Test-only interposer of the LAPACK routines vci calls (dgetrf, dgetrs, dgelsd): linked into a
 * test executable, these definitions take precedence over liblapack's for calls from libvci (ELF
 * symbol interposition), check that no input is NaN or Inf, count the calls that had one, and
 * forward to the real routine (dlsym RTLD_NEXT). With NaN input OpenBLAS's dgelsd can loop forever
 * and reference LAPACK prints through XERBLA; vci promises that nothing non-finite reaches LAPACK. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "lapack_guard.h"

static _Atomic long nonfinite_calls = 0, guarded_calls = 0; /* atomic: the threads test links it too */

long vci_test_lapack_nonfinite_calls(void) { return nonfinite_calls; }
long vci_test_lapack_calls(void) { return guarded_calls; }

/* One line on stderr for the first offence; with VCI_LAPACK_GUARD_EXIT set, the process ends at
 * once with status 71 (before LAPACK can hang on the input). */
static void offence(const char *routine) {
  if (++nonfinite_calls == 1) fprintf(stderr, "lapack_guard: %s called with NaN/Inf\n", routine);
  if (getenv("VCI_LAPACK_GUARD_EXIT")) _exit(71);
}

static int finite_matrix(int m, int n, const double *a, int lda) {
  int i, j;
  for (j = 0; j < n; ++j)
    for (i = 0; i < m; ++i)
      if (!isfinite(a[i + (long)lda * j])) return 0;
  return 1;
}

/* the next definition of `name` (liblapack's); memcpy: ISO C has no object-to-function pointer cast */
static void real_symbol(const char *name, void *fn, size_t size) {
  void *f = dlsym(RTLD_NEXT, name);
  if (!f) fprintf(stderr, "lapack_guard: %s not found\n", name);
  memcpy(fn, &f, size);
}

typedef void (*getrf_fn)(const int *, const int *, double *, const int *, int *, int *);
void dgetrf_(const int *m, const int *n, double *a, const int *lda, int *ipiv, int *info) {
  static getrf_fn real;
  if (!real) real_symbol("dgetrf_", &real, sizeof real);
  ++guarded_calls;
  if (!finite_matrix(*m, *n, a, *lda)) {
    offence("dgetrf");
  }
  real(m, n, a, lda, ipiv, info);
}

typedef void (*getrs_fn)(const char *, const int *, const int *, const double *, const int *, const int *, double *,
                         const int *, int *, size_t);
void dgetrs_(const char *trans, const int *n, const int *nrhs, const double *a, const int *lda, const int *ipiv,
             double *b, const int *ldb, int *info, size_t trans_len) {
  static getrs_fn real;
  if (!real) real_symbol("dgetrs_", &real, sizeof real);
  ++guarded_calls;
  if (!finite_matrix(*n, *n, a, *lda) || !finite_matrix(*n, *nrhs, b, *ldb)) {
    offence("dgetrs");
  }
  real(trans, n, nrhs, a, lda, ipiv, b, ldb, info, trans_len);
}

typedef void (*gelsd_fn)(const int *, const int *, const int *, double *, const int *, double *, const int *, double *,
                         const double *, int *, double *, const int *, int *, int *);
void dgelsd_(const int *m, const int *n, const int *nrhs, double *a, const int *lda, double *b, const int *ldb,
             double *s, const double *rcond, int *rank, double *work, const int *lwork, int *iwork, int *info) {
  static gelsd_fn real;
  if (!real) real_symbol("dgelsd_", &real, sizeof real);
  ++guarded_calls;
  if (*lwork != -1 && (!finite_matrix(*m, *n, a, *lda) || !finite_matrix(*m, *nrhs, b, *ldb))) {
    offence("dgelsd");
  }
  real(m, n, nrhs, a, lda, b, ldb, s, rcond, rank, work, lwork, iwork, info);
}
