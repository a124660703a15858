/* The sparse LU of vci_sparse.f90 (issue 28): SuiteSparse KLU behind four calls, so that the
 * Fortran side never sees klu_common's layout. A handle is one matrix pattern (one symbolic
 * analysis) and the numeric factors of its last matrix. Without KLU (VCI_SPARSE=OFF) the same
 * calls exist and answer "not built" (vci_klu_available() == 0, vci_klu_analyze returns NULL). */
#include <stdlib.h>
#ifdef VCI_HAVE_KLU
#include <klu.h>
#endif

/* Pivots below this fraction of the largest (klu_rcond) count as singular, as vci_newton judges a
 * dense LU: the caller then factorises densely (least squares if need be). */
#define VCI_KLU_RCOND_MIN 1.0e-14

int vci_klu_available(void) {
#ifdef VCI_HAVE_KLU
  return 1;
#else
  return 0;
#endif
}

#ifdef VCI_HAVE_KLU
typedef struct {
  klu_common common;
  klu_symbolic *symbolic;
  klu_numeric *numeric;
  int n;
} vci_klu_t;
#endif

/* Symbolic analysis of the n x n pattern in CSC form (0-based ap[n + 1], ai[ap[n]], rows sorted
 * within each column). NULL: not built, out of memory or an invalid pattern. */
void *vci_klu_analyze(int n, const int *ap, const int *ai) {
#ifdef VCI_HAVE_KLU
  vci_klu_t *h = calloc(1, sizeof *h);
  if (!h) return NULL;
  klu_defaults(&h->common);
  h->n = n;
  h->symbolic = klu_analyze(n, (int *)ap, (int *)ai, &h->common);
  if (!h->symbolic) {
    free(h);
    return NULL;
  }
  return h;
#else
  (void)n; (void)ap; (void)ai;
  return NULL;
#endif
}

/* Numeric factors of the matrix ax (values in the analysed pattern): the refactor path (the last
 * factorisation's pivot order) when there is one and its pivots stay regular, else a new
 * factorisation with pivoting. 0: done; 1: singular or numerically so; -1: no handle or memory. */
int vci_klu_factor(void *handle, const int *ap, const int *ai, const double *ax) {
#ifdef VCI_HAVE_KLU
  vci_klu_t *h = handle;
  if (!h) return -1;
  if (h->numeric) {
    if (klu_refactor((int *)ap, (int *)ai, (double *)ax, h->symbolic, h->numeric, &h->common) &&
        klu_rcond(h->symbolic, h->numeric, &h->common) && h->common.rcond > VCI_KLU_RCOND_MIN)
      return 0;
    klu_free_numeric(&h->numeric, &h->common);
  }
  h->numeric = klu_factor((int *)ap, (int *)ai, (double *)ax, h->symbolic, &h->common);
  if (!h->numeric) return h->common.status == KLU_OUT_OF_MEMORY ? -1 : 1;
  if (!klu_rcond(h->symbolic, h->numeric, &h->common) || !(h->common.rcond > VCI_KLU_RCOND_MIN)) {
    klu_free_numeric(&h->numeric, &h->common);
    return 1;
  }
  return 0;
#else
  (void)handle; (void)ap; (void)ai; (void)ax;
  return -1;
#endif
}

/* b := A^{-1} b with the last factors. 0: done; -1: no factors. */
int vci_klu_solve(void *handle, double *b) {
#ifdef VCI_HAVE_KLU
  vci_klu_t *h = handle;
  if (!h || !h->numeric) return -1;
  return klu_solve(h->symbolic, h->numeric, h->n, 1, b, &h->common) ? 0 : -1;
#else
  (void)handle; (void)b;
  return -1;
#endif
}

/* Free the handle and everything it holds (NULL: nothing). */
void vci_klu_free(void *handle) {
#ifdef VCI_HAVE_KLU
  vci_klu_t *h = handle;
  if (!h) return;
  if (h->numeric) klu_free_numeric(&h->numeric, &h->common);
  if (h->symbolic) klu_free_symbolic(&h->symbolic, &h->common);
  free(h);
#else
  (void)handle;
#endif
}
