#!/bin/bash
# Every large allocation of an ensemble run into its file failing in turn (issue 24: item 2's rule
# for every allocation, with item 5's outcome). ens_alloc_driver makes the K-th allocation of at
# least MIN bytes inside vci_ensemble_run_file fail (test/alloc/malloc_counter.c; counting only
# those called from the shared object whose path contains OBJECT, unless it is "any"; with ranks
# on one rank only, ARMED), K = 1, 2, ... until a run no longer reaches it. Each run must end within
# the timeout (no rank left waiting in a collective call for a rank that failed), either succeed
# with a complete file bitwise as in memory (a failure HDF5 recovered from itself) or exit 1 with
# a status line on every rank (a Fortran runtime error, a signal or a crash at exit fail), and leave no
# file (a failure at creation: the message says it was removed) or a file that opens, is marked
# incomplete, and whose every member with a status is bitwise its in-memory run. The writer's own
# buffers must be among the failures: a block's ranks, and with ranks each fill buffer.
# Usage: alloc_failure.sh ALLOC_DRIVER DRIVER PYTHON WORKDIR MIN_BYTES OBJECT [RANKS ARMED MPIEXEC ARGS... NUMPROC_FLAG]
set -uo pipefail
alloc_driver=$1 driver=$2 py=$3 work=$4 min_bytes=$5 object=$6
shift 6
here=$(cd "$(dirname "$0")" && pwd)
ranks=1 mpi=0 armed=-1
if [ $# -gt 0 ]; then
  ranks=$1 armed=$2 mpi=1
  shift 2
fi
launcher=("$@")
if [ $mpi -eq 1 ]; then
  [ "$(id -u)" -eq 0 ] && launcher=("${launcher[0]}" --allow-run-as-root "${launcher[@]:1}")
  launcher+=("$ranks")
fi
rm -rf "$work"; mkdir -p "$work"; cd "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
# blocks of 2048 members: a block's ranks are 8192 bytes, the fill buffers of each rank's share
# 8192 bytes and more (each member's own allocations are below 7500 bytes)
args=(--members 4096 --nsteps 20 --chunk 2048 --stride 10)
arm=()
[ "$armed" -ge 0 ] && arm=(--fail-rank "$armed")
[ "$object" != any ] && arm+=(--fail-in "$object")

"${launcher[@]}" "$driver" run full.h5 "${args[@]}" > full.log 2>&1 || fail "the run without a failure: $(cat full.log)"
statuses=0 absorbed=0 removed=0 kept=0 ranks_seen=0 fill_seen=0
for k in $(seq 1 400); do
  rm -f e.h5
  timeout 120 "${launcher[@]}" "$alloc_driver" run e.h5 "${args[@]}" --fail-alloc "$k" "$min_bytes" "${arm[@]}" \
    > e.log 2>&1
  rc=$?
  [ $rc -ne 124 ] || fail "k = $k: no end within 120 s (a rank left in a collective call?): $(cat e.log)"
  if grep -q "allocation $k not reached" e.log; then
    [ $rc -eq 0 ] || fail "k = $k: not reached, yet exit $rc: $(tail -5 e.log)"
    echo "k = $k: not reached: every allocation of at least $min_bytes bytes failed once"
    break
  fi
  grep -q "allocation $k failed" e.log || fail "k = $k: the armed rank did not report: $(tail -5 e.log)"
  if [ $rc -eq 0 ]; then     # absorbed (inside HDF5, which recovered): the file is complete and right
    "$py" "$here/check_files.py" same e.h5 > check.log 2>&1 || fail "k = $k: a run that succeeded: $(cat check.log)"
    "$driver" verify e.h5 > verify.log 2>&1 || fail "k = $k: a run that succeeded: $(cat verify.log)"
    absorbed=$((absorbed + 1)); continue
  fi
  [ $rc -eq 1 ] || fail "k = $k: exit status $rc, expected 1 (a status, not a signal or a crash at exit): $(tail -5 e.log)"
  for r in $(seq 0 $((ranks - 1))); do
    grep -q "^rank $r: ensemble" e.log || fail "k = $k: rank $r reports no status: $(cat e.log)"
  done
  statuses=$((statuses + 1))
  grep -q "no memory for the ranks of members" e.log && ranks_seen=$((ranks_seen + 1))
  grep -q "no memory to fill /members" e.log && fill_seen=$((fill_seen + 1))
  echo "k = $k: exit $rc: $(grep -m1 '^rank 0: ensemble' e.log)"
  if [ ! -e e.h5 ]; then
    grep -q "the file was removed: it held no member yet" e.log || fail "k = $k: the file vanished unannounced"
    removed=$((removed + 1)); continue
  fi
  "$py" - e.h5 <<'PY' || fail "k = $k: the file left behind is not readable or claims completion"
import sys, h5py
with h5py.File(sys.argv[1], 'r') as f:
    assert int(f.attrs['complete']) == 0
PY
  held=$("$py" "$here/check_files.py" done e.h5)
  if [ "$held" -gt 0 ]; then
    mode=(--partial); [ "$held" -eq 4096 ] && mode=()
    "$driver" verify e.h5 "${mode[@]}" > verify.log 2>&1 || fail "k = $k: $(cat verify.log)"
  fi
  kept=$((kept + 1))
done
grep -q "not reached" e.log || fail "400 allocations failed and the run still reached more"
echo "ok: $statuses runs ended with a status ($removed removed their file, $kept kept a readable one), $absorbed absorbed the failure"
[ $ranks_seen -gt 0 ] || fail "no run met the failure at a block's ranks"
if [ $mpi -eq 1 ] && [ "$armed" -ne 0 ]; then [ $fill_seen -gt 0 ] || fail "no run met the failure at a fill buffer"; fi
echo "ok: $ranks_seen at a block's ranks, $fill_seen at a fill buffer"
