#!/bin/bash
# The status a C program's HDF5 file records (api_test.c, suite output_status): the file of a run
# whose last vci_integrate failed says that failure, with its message, after vci_close_output or
# vci_integrator_destroy, and the file of a run that succeeded says 0 whatever call failed after it
# (the status of the call that closed the file was written: 0 beside a failed run, 1 beside a good one).
# Usage: output_status.sh VCI_API_TEST PYTHON WORKDIR
set -u
exe=$1; py=$2; dir=$3
mkdir -p "$dir" && cd "$dir" || exit 1
rm -f capi_status_*.h5
"$exe" output_status || { echo "FAIL: vci_api_test output_status"; exit 1; }
"$py" - <<'PY'
import sys, h5py
want = {'capi_status_callback.h5': (2, 'impact callback returned 1'),
        'capi_status_destroyed.h5': (2, 'impact callback returned 1'),
        'capi_status_ok.h5': (0, 'ok')}
bad = 0
for path, (status, part) in want.items():
    with h5py.File(path, 'r') as f:
        got, msg = int(f.attrs['status']), f.attrs['status_message'].decode()
        done = int(f.attrs['steps_completed'])
    ok = got == status and part in msg
    print(f"{'ok' if ok else 'FAIL'} {path}: status {got} (want {status}), message '{msg}', {done} steps")
    bad += not ok
sys.exit(1 if bad else 0)
PY
