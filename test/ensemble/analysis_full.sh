#!/bin/bash
# ellipse_ensemble on a disk that fills while it writes /analysis (after the ensemble file is
# closed): the ENOSPC shim (test/hdf5/enospc_shim.c) counts, in a first run, the opens of the file
# and the writes after the last one (the /analysis reopen), then fails each of those writes in
# turn. Every run must end with exit status 0 or 1 (never a signal: HDF5 crashed at exit with
# SIGSEGV after a failed flush or a failed superblock write at the close), a failure must say so,
# and the file must still open with complete = 1 and its members (/analysis too when exit 0).
# Usage: analysis_full.sh ELLIPSE_ENSEMBLE SHIM PYTHON WORKDIR
set -u
exe=$1; shim=$2; py=$3; dir=$4
rm -rf "$dir"; mkdir -p "$dir"; cd "$dir" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
args=(--members 11 --t-final 2 --quiet --output ens.h5)
LD_PRELOAD=$shim VCI_ENOSPC_LOG=$dir/writes "$exe" "${args[@]}" > full.log 2>&1 || fail "the run without a full disk: $(tail -3 full.log)"
read -r opens after < <(awk '/^open/ { o++; w = 0 } /^write/ { w++ } END { print o + 0, w + 0 }' writes.*)
echo "opens of the file: $opens; writes after the last (the /analysis reopen): $after"
[ "$after" -ge 1 ] || fail "no write after the last open"
for ((w = 0; w <= after; w++)); do
  rm -f ens.h5
  LD_PRELOAD=$shim VCI_ENOSPC_OPEN=$opens VCI_ENOSPC_WRITES=$w timeout 120 "$exe" "${args[@]}" > e.log 2>&1
  rc=$?
  [ $rc -eq 0 ] || [ $rc -eq 1 ] || fail "write $((w + 1)) failing: exit status $rc: $(grep -v '^#\|^ ' e.log | tail -3)"
  [ $rc -eq 0 ] || grep -q "ellipse_ensemble: .*analysis" e.log || fail "write $((w + 1)): exit 1 without a message"
  "$py" - "$rc" <<'PY' || fail "write $((w + 1)) failing (exit $rc): the file is not the ensemble"
import sys, h5py
with h5py.File('ens.h5', 'r') as f:
    assert int(f.attrs['complete']) == 1, 'complete != 1'
    assert f['members/status'].shape[0] == 11, 'members missing'
    assert sys.argv[1] != '0' or 'analysis/divergence_time' in f, 'exit 0 without /analysis'
PY
  echo "write $((w + 1)) of $after failing: exit $rc"
done
echo "ok: a full disk at each write of /analysis ends with a status and leaves the ensemble readable"
