#!/bin/bash
# A full disk at the ensemble file's very end (the totals and `complete` that close records): the
# ENOSPC shim (test/hdf5/enospc_shim.c) counts, in a first run, the opens of the file and the writes
# after the last open of the process that opens it most (serial: the only one; with ranks rank 0,
# which reopens the file alone to record the totals). Then the run is repeated with the failure put
# at each of the last writes of that process in turn (VCI_ENOSPC_OPEN, VCI_ENOSPC_WRITES). A run
# that fails must exit 1 with a status naming the file and leave a readable file that does NOT say
# complete = 1, whose members are bitwise their in-memory runs.
# Usage: totals_flush.sh DRIVER SHIM PYTHON WORKDIR [RANKS MPIEXEC ARGS... NUMPROC_FLAG]
set -uo pipefail
driver=$1 shim=$2 py=$3 work=$4
shift 4
ranks=1 mpi=0
if [ $# -gt 0 ]; then
  ranks=$1 mpi=1
  shift
fi
launcher=("$@")
if [ $mpi -eq 1 ]; then
  [ "$(id -u)" -eq 0 ] && launcher=("${launcher[0]}" --allow-run-as-root "${launcher[@]:1}")
  launcher+=("$ranks" -x LD_PRELOAD -x VCI_ENOSPC_LOG -x VCI_ENOSPC_OPEN -x VCI_ENOSPC_WRITES)
fi
rm -rf "$work"; mkdir -p "$work"; cd "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
members=40
args=(--members $members --nsteps 100 --chunk 8 --stride 10)

LD_PRELOAD=$shim VCI_ENOSPC_LOG=$work/writes timeout 300 "${launcher[@]}" "$driver" run full.h5 "${args[@]}" > full.log 2>&1 \
  || fail "the run without a full disk: $(cat full.log)"
"$driver" verify full.h5 > verify.log 2>&1 || fail "the run without a full disk: $(cat verify.log)"
"$py" -c "import sys, h5py; sys.exit(int(h5py.File('full.h5', 'r').attrs['complete']) != 1)" \
  || fail "the run without a full disk left complete != 1"
# the process that opened the file most often, its opens and its writes after the last open
read -r opens after < <(for f in writes.*; do
  awk '/^open/ { o++; w = 0 } /^write/ { w++ } END { print o + 0, w + 0 }' "$f"
done | sort -n -k1,1 | tail -1)
echo "the file's last opener: $opens opens, $after writes after the last"
[ "${after:-0}" -ge 1 ] || fail "no write after the last open: $(head -50 writes.*)"
last=$((after < 8 ? after : 8))
failed_runs=0
for ((w = after - 1; w >= after - last; w--)); do
  rm -f e.h5 writes.*
  LD_PRELOAD=$shim VCI_ENOSPC_OPEN=$opens VCI_ENOSPC_WRITES=$w timeout 300 "${launcher[@]}" "$driver" run e.h5 "${args[@]}" \
    > e.log 2>&1
  rc=$?
  [ $rc -ne 124 ] || fail "writes $w: no end within 300 s"
  [ $rc -eq 0 ] && { "$driver" verify e.h5 > verify.log 2>&1 || fail "writes $w: a run that succeeded: $(cat verify.log)"; continue; }
  [ $rc -eq 1 ] || fail "writes $w: exit status $rc, expected 1: $(tail -5 e.log)"
  grep -q "^rank 0: ensemble file e.h5" e.log || fail "writes $w: no status naming the file: $(cat e.log)"
  failed_runs=$((failed_runs + 1))
  held=$("$py" - e.h5 <<'PY'
import sys, h5py
with h5py.File(sys.argv[1], 'r') as f:
    c, run, nm = int(f.attrs['complete']), int(f.attrs['members_run']), int(f.attrs['n_members'])
    if c != 0:
        print(f'FAIL: a run that failed left complete = {c} (members_run = {run} of {nm})')
        sys.exit(1)
    print(int((f['members/status'][:] != -1).sum()))
PY
) || fail "writes $w (of $after after open $opens): $held; $(grep 'rank 0:' e.log)"
  if [ "$held" -eq "$members" ]; then
    "$driver" verify e.h5 > verify.log 2>&1 || fail "writes $w: $(cat verify.log)"
  else
    "$driver" verify e.h5 --partial > verify.log 2>&1 || fail "writes $w: $(cat verify.log)"
  fi
  echo "writes $w of $after after open $opens: exit 1, complete = 0, $held members held: $(tail -1 verify.log)"
done
[ $failed_runs -ge 1 ] || fail "no run failed: the shim never reached the file's last writes"
echo "ok: $failed_runs runs failed at one of the file's last $last writes, none recorded complete = 1"
