#!/bin/bash
# A full disk (issue 11, item 5): the pendulum example writes HDF5 while enospc_shim (LD_PRELOAD)
# fails every write to *.h5 files with ENOSPC after a byte budget. The run must end with status 2
# (not a crash: no signal, no HDF5 shutdown crash at exit), a message naming the file and the OS's
# cause, and a file that still opens and restarts: its steps_completed within its rows (h5py) and
# `--from` accepted. A full disk at creation ends with status 1 and the same kind of message.
# `--output /dev/full` never creates a regular file /dev/full.h5 (the examples refuse devices).
# Usage: disk_full.sh PENDULUM_EXE SHIM_SO PYTHON WORKDIR
set -u
exe=$1; shim=$2; py=$3; dir=$4
mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }

run_full() {   # budget in bytes, output file, log
  rm -f "$2"
  LD_PRELOAD=$shim VCI_ENOSPC_BYTES=$1 "$exe" --h 1e-4 --t-final 10 --flush-every 1000 --quiet \
    --output "$2" > "$3" 2>&1
}

# 1. the disk fills up during the run (after a few flushes)
out=$dir/full_run.h5
run_full 300000 "$out" "$dir/full_run.log"; rc=$?
cat "$dir/full_run.log" | grep -v '^ ' | tail -3
[ $rc -eq 2 ] || fail "exit status $rc, expected 2 (the run's I/O error); log: $(tail -5 "$dir/full_run.log")"
grep -q "$out: writing rows failed: No space left on device" "$dir/full_run.log" \
  || fail "the message does not name the file and 'No space left on device'"
"$py" - "$out" <<'PY' || fail "the file left by the full disk is not consistent"
import sys, h5py
with h5py.File(sys.argv[1], 'r') as f:
    done = int(f.attrs['steps_completed'])
    rows = {k: f[k].shape[0] for k in ('t', 'q', 'p', 'energy', 'lambda')}
    print('steps_completed', done, 'rows', rows, 'status', int(f.attrs['status']))
    assert done >= 1000, 'no flush reached the disk before it was full'
    assert rows['t'] >= done + 1 and rows['q'] >= done + 1 and rows['p'] >= done + 1
    assert rows['energy'] >= done and rows['lambda'] >= done
PY
"$exe" --from "$out" --t-final 0.5 --no-output --quiet > "$dir/full_restart.log" 2>&1 \
  || fail "--from the file left by the full disk: $(tail -2 "$dir/full_restart.log")"

# 2. the disk is full when the file is created
out=$dir/full_open.h5
run_full 1000 "$out" "$dir/full_open.log"; rc=$?
cat "$dir/full_open.log"
[ $rc -eq 1 ] || fail "exit status $rc at creation, expected 1"
grep -q "$out: .*No space left on device" "$dir/full_open.log" || fail "no file name and OS cause at creation"

# 3. --output /dev/full: the device, not /dev/full.h5
if [ -c /dev/full ] && [ ! -e /dev/full.h5 ]; then
  "$exe" --h 1e-3 --t-final 0.1 --quiet --output /dev/full > "$dir/devfull.log" 2>&1; rc=$?
  cat "$dir/devfull.log"
  [ ! -e /dev/full.h5 ] || { rm -f /dev/full.h5; fail "--output /dev/full created /dev/full.h5"; }
  [ $rc -ne 0 ] && [ $rc -lt 128 ] || fail "--output /dev/full: exit status $rc"
  grep -q "/dev/full" "$dir/devfull.log" || fail "--output /dev/full: the message does not name it"
fi
echo "ok: a full disk ends the run with its cause, no crash, a consistent file"
