#!/bin/bash
# A full disk at a run file's very end (the last flush and the close): the ENOSPC shim
# (enospc_shim.c) counts the writes to the file in a first run, then fails each of its last 10 writes
# in turn (VCI_ENOSPC_OPEN=1, VCI_ENOSPC_WRITES). Every run must end with exit status 2 (the run's
# I/O error; not a signal: HDF5's close of a half-closed file at exit crashed with SIGSEGV) and a
# message naming the file, and leave a file that opens, whose steps_completed its rows cover, that
# never says status 0 (ok): the run returned an I/O error (a status flush whose last write failed
# left status 0 on disk beside exit status 2), and that a run continues from (--from).
# Usage: close_flush.sh EXE SHIM PYTHON WORKDIR
set -u
exe=$1; shim=$2; py=$3; dir=$4
rm -rf "$dir"; mkdir -p "$dir"; cd "$dir" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
args=(--h 1e-3 --t-final 1 --flush-every 100 --quiet)
# the last 10 writes: the status's flush, the message's, and the last rows' checkpoint and steps_completed
last=${VCI_CLOSE_FLUSH_LAST:-10}

LD_PRELOAD=$shim VCI_ENOSPC_LOG=$dir/writes "$exe" "${args[@]}" --output full.h5 > full.log 2>&1 \
  || fail "the run without a full disk: $(tail -3 full.log)"
full_done=$("$py" -c "import sys, h5py; f = h5py.File('full.h5', 'r'); assert int(f.attrs['status']) == 0; print(int(f.attrs['steps_completed']))") \
  || fail "the run without a full disk left no readable file with status 0"
writes=$(awk '/^open/ { w = 0 } /^write/ { w++ } END { print w + 0 }' writes.*)
echo "writes to the file after its open: $writes"
[ "$writes" -ge "$last" ] || fail "too few writes counted: $writes"
for ((w = writes - 1; w >= writes - last; w--)); do
  rm -f e.h5
  LD_PRELOAD=$shim VCI_ENOSPC_OPEN=1 VCI_ENOSPC_WRITES=$w timeout 120 "$exe" "${args[@]}" --output e.h5 > e.log 2>&1
  rc=$?
  [ $rc -eq 2 ] || fail "write $((w + 1)) of $writes failing: exit status $rc, expected 2: $(grep -v '^ ' e.log | tail -3)"
  grep -q "e.h5: .*No space left on device" e.log || fail "write $((w + 1)): no message naming the file and the cause: $(tail -3 e.log)"
  "$py" - e.h5 "$full_done" <<'PY' || fail "write $((w + 1)): the file left behind is not consistent"
import sys, h5py
with h5py.File(sys.argv[1], 'r') as f:
    done, status = int(f.attrs['steps_completed']), int(f.attrs['status'])
    assert f['t'].shape[0] >= done + 1 and f['q'].shape[0] >= done + 1, 'rows missing'
    # a status written only with every step: a run whose last flush failed is left `running`
    assert status != 0 or done == int(sys.argv[2]), f'status 0 (ok) beside {done} of {sys.argv[2]} steps'
    # and never a success the run did not have: every run here returned an I/O error
    assert status != 0, f'status 0 (ok) in the file of a run that returned an I/O error ({done} steps)'
    print('  steps_completed', done, 'rows', f['t'].shape[0], 'status', int(f.attrs['status']))
PY
  "$exe" --from e.h5 --t-final 1.1 --no-output --quiet > from.log 2>&1 || fail "write $((w + 1)): --from: $(tail -2 from.log)"
  echo "write $((w + 1)) of $writes failing: exit 2, $(grep -o 'e.h5: [^(]*' e.log | head -1)"
done
echo "ok: a full disk at each of the file's last $last writes ends with status 2 and a file a run continues from"
