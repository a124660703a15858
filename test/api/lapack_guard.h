/* lapack_guard.c: counts of LAPACK calls from vci, and of those that had NaN/Inf input. */
#ifndef VCI_LAPACK_GUARD_H
#define VCI_LAPACK_GUARD_H
long vci_test_lapack_nonfinite_calls(void);
long vci_test_lapack_calls(void);
#endif
