#!/bin/bash
# An ensemble and a full disk (issue 24, item 5): the test ensemble writes its file while
# enospc_shim (LD_PRELOAD, test/hdf5/enospc_shim.c) fails every write to *.h5 with ENOSPC after a
# byte budget (per process). Budgets from 1 % to 160 % of the complete file's size put the failure
# at the file's creation, at its first flush, at the table and in the middle of the members. Every
# run must end within the timeout (no deadlock between ranks), with exit status 1 (no signal, no
# crash at exit: with ranks the driver ends every rank through MPI_Finalize, where an HDF5 file
# left open crashed) and a message on every rank naming the file (and, serial, "No space left on
# device"); it leaves either no file (a failure at creation: the message says it was removed) or
# a file that opens, is marked incomplete, and whose every member with a status is bitwise its
# in-memory run (all of them when the failure came at the totals, after the last member).
# Usage: disk_full.sh DRIVER SHIM PYTHON WORKDIR [RANKS MPIEXEC ARGS... NUMPROC_FLAG]   (MPI: 1 or 2 ranks)
set -uo pipefail
driver=$1 shim=$2 py=$3 work=$4
shift 4
here=$(cd "$(dirname "$0")" && pwd)
ranks=1 mpi=0
if [ $# -gt 0 ]; then
  ranks=$1 mpi=1
  shift
fi
launcher=("$@")
if [ $mpi -eq 1 ]; then
  [ "$(id -u)" -eq 0 ] && launcher=("${launcher[0]}" --allow-run-as-root "${launcher[@]:1}")
  launcher+=("$ranks" -x LD_PRELOAD -x VCI_ENOSPC_BYTES)
fi
rm -rf "$work"; mkdir -p "$work"; cd "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
members=200
args=(--members $members --nsteps 100 --chunk 8 --stride 10)

"${launcher[@]}" "$driver" run full.h5 "${args[@]}" > full.log 2>&1 || fail "the run without a full disk: $(cat full.log)"
size=$(stat -c %s full.h5)
echo "complete file: $size bytes"
kept=0; removed=0
# (with ranks the budget is each rank's: rank 0 writes the file's metadata at creation (serially),
# every rank the fill of its share of members and then the members it claims, so 66-90 % put the
# failure among the members; 100-110 % may put it at the totals rank 0 records at the close, as
# the members each rank claims vary from run to run)
budgets="1 50 66 70 80 90 100 105 110 130 160"
for pct in $budgets; do
  budget=$((size * pct / 100))
  rm -f e.h5
  LD_PRELOAD=$shim VCI_ENOSPC_BYTES=$budget timeout 120 "${launcher[@]}" "$driver" run e.h5 "${args[@]}" > e.log 2>&1
  rc=$?
  echo "budget $pct % ($budget bytes): exit $rc: $(grep -m1 'rank 0:' e.log)"
  [ $rc -ne 124 ] || fail "budget $budget: no end within 120 s (ranks deadlocked?)"
  if [ $rc -eq 0 ]; then      # room enough after all: then the file is complete
    "$driver" verify e.h5 > verify.log 2>&1 || fail "budget $budget: a run that succeeded: $(cat verify.log)"
    continue
  fi
  [ $rc -eq 1 ] || fail "budget $budget: exit status $rc, expected 1 (a status, not a signal or a crash at exit): $(tail -5 e.log)"
  # (MPI-IO leaves the OS's reason out of HDF5's error stack: with ranks the file is named, not errno)
  cause="No space left on device"; [ $mpi -eq 1 ] && cause=""
  for r in $(seq 0 $((ranks - 1))); do
    grep -q "^rank $r: ensemble file e.h5: .*$cause" e.log \
      || fail "budget $budget: rank $r reports no status naming the file (and the cause): $(cat e.log)"
  done
  if [ ! -e e.h5 ]; then
    grep -q "the file was removed: it held no member yet" e.log || fail "budget $budget: the file vanished unannounced"
    removed=$((removed + 1)); continue
  fi
  "$py" - e.h5 <<'PY' || fail "budget $budget: the file left behind is not readable or claims completion"
import sys, h5py
with h5py.File(sys.argv[1], 'r') as f:
    assert int(f.attrs['complete']) == 0
    s = f['members/status'][:]
    print('  file opens; members held:', int((s != -1).sum()), 'of', s.size)
PY
  held=$("$py" "$here/check_files.py" done e.h5)
  if [ "$held" -eq "$members" ]; then   # (the totals failed: every member is in the file)
    "$driver" verify e.h5 > verify.log 2>&1 || fail "budget $budget: $(cat verify.log)"
    tail -1 verify.log
    kept=$((kept + 1))
  elif [ "$held" -gt 0 ]; then
    "$driver" verify e.h5 --partial > verify.log 2>&1 || fail "budget $budget: $(cat verify.log)"
    tail -1 verify.log
    kept=$((kept + 1))
  fi
done
[ $removed -gt 0 ] || fail "no budget ended the run at the file's creation"
[ $kept -gt 0 ] || fail "no budget ended the run with members in the file"
echo "ok: $removed runs failed at creation (file removed), $kept kept a readable file of their completed members"
