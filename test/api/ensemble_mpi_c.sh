#!/bin/bash
# vci_ensemble_run_file from C over MPI (test capi_ensemble_file in an MPI build): the file suite of
# ensemble_test.c on 1 and 2 ranks, then the two files' /members bitwise equal.
# Usage: ensemble_mpi_c.sh TEST CHECK_FILES_PY MPIEXEC [FLAGS...] NUMPROC_FLAG
set -eu
test_exe=$1 check=$2; shift 2
launcher=("$@")
if [ "$(id -u)" -eq 0 ]; then
  launcher=("${launcher[0]}" --allow-run-as-root "${launcher[@]:1}")
fi
for np in 1 2; do
  OMP_NUM_THREADS=1 "${launcher[@]}" "$np" "$test_exe" file "capi_ensemble_np$np.h5"
done
/usr/bin/python3 "$check" same capi_ensemble_np1.h5 capi_ensemble_np2.h5
