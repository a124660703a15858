#!/bin/bash
# SIGTERM and SIGINT in a running example (issue 31): the run ends after the current step with exit
# status 128 + the signal (143, 130), its file is closed with status VCI_STOPPED (11) and a message
# saying it was interrupted; `--from FILE --append` then continues it to a later time, and the
# result equals an uninterrupted run to that time bit for bit (every dataset and attribute but
# `created` and `resumes`, which records the continuation). The signal is sent once the run's
# progress line (--progress, on stderr) reports 3000 steps done (as in sigkill.sh; a bounded wait),
# to a run over a horizon it cannot reach (10^6 s), so the test does not depend on the machine's speed.
# The second case (SIGINT) writes every 7th state, compressed: the continued file equals the
# uninterrupted one plus the row of the state where the signal ended the first part.
# Usage: interrupt.sh PENDULUM_EXE PYTHON WORKDIR
set -u
exe=$1; py=$2; dir=$3
h=1e-4
mkdir -p "$dir"
fail() { echo "FAIL: $*"; exit 1; }

# case SIGNAL CODE EXTRA_FLAGS...
run_case() {
  local sig=$1 code=$2; shift 2
  local out="$dir/interrupted_$sig.h5" ref="$dir/uninterrupted_$sig.h5"
  rm -f "$out" "$ref"
  "$exe" --h "$h" --t-final 1e6 --quiet --progress --flush-every 1000 "$@" --output "$out" > "$out.log" 2> "$out.progress" &
  local pid=$! done_steps=0 last start=$SECONDS
  while [ "$done_steps" -lt 3000 ]; do
    last=$(sed -n 's/^progress .* step \([0-9][0-9]*\) of .*/\1/p' "$out.progress" | tail -n 1)
    [ -n "$last" ] && done_steps=$last
    kill -0 "$pid" 2> /dev/null || break
    if [ $((SECONDS - start)) -ge 100 ]; then
      kill -9 "$pid"; fail "$sig: no progress line with >= 3000 steps within 100 s (last: $done_steps)"
    fi
    sleep 0.1
  done
  kill -0 "$pid" 2> /dev/null || { cat "$out.log"; fail "the pendulum ended before the signal"; }
  kill -s "$sig" "$pid"
  local rc=0
  wait "$pid" || rc=$?
  [ "$rc" = "$code" ] || { cat "$out.log"; fail "$sig: exit status $rc, expected $code"; }
  grep -q "^status: interrupted by SIG$sig" "$out.log" || { cat "$out.log"; fail "$sig: no 'interrupted' status line"; }
  local n
  n=$(sed -n 's/^steps: \([0-9]*\) .*/\1/p' "$out.log")
  [ -n "$n" ] && [ "$n" -gt 1000 ] || { cat "$out.log"; fail "$sig: steps before the signal: '$n'"; }
  echo "$sig after $n steps: exit status $rc"
  # the file says it was interrupted
  "$py" - "$out" "$sig" "$n" "$*" <<'PY' || fail "$sig: the interrupted file"
import sys, h5py
f = h5py.File(sys.argv[1], 'r')
if '--compress' in sys.argv[4]:                       # the filters reached the datasets
    assert int(f.attrs['compression']) == 1
    for k in ('t', 'q', 'p', 'energy', 'step', 'impacts/time'):
        assert f[k].compression == 'gzip' and f[k].compression_opts == 1 and f[k].shuffle, k
else:
    assert int(f.attrs['compression']) == 0 and f['q'].compression is None
st, msg = int(f.attrs['status']), f.attrs['status_message'].decode()
print('  file status', st, repr(msg[:70]))
assert st == 11, st                                    # VCI_STOPPED
assert msg.startswith('interrupted by SIG' + sys.argv[2]), msg
assert int(f.attrs['steps_completed']) == len(f['t']) - 1
last = int(f['step'][-1]) if 'step' in f else len(f['t']) - 1
assert last == int(sys.argv[3]), (last, sys.argv[3])  # the file ends at the run's last step
PY
  # continue it 5000 steps further, and run the same span in one go
  local t2
  t2=$("$py" -c "print(repr(($n + 5000) * $h))")
  "$exe" --from "$out" --append --t-final "$t2" --quiet --no-progress --flush-every 1000 > "$out.append.log" 2>&1 \
    || { cat "$out.append.log"; fail "$sig: --append"; }
  "$exe" --h "$h" --t-final "$t2" --quiet --no-progress --flush-every 1000 "$@" --output "$ref" > "$ref.log" 2>&1 \
    || { cat "$ref.log"; fail "$sig: the uninterrupted run"; }
  "$py" - "$out" "$ref" "$n" <<'PY' || fail "$sig: the continued file differs from the uninterrupted run"
import sys, h5py, numpy as np
a, b, n = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r'), int(sys.argv[3])
names = []
b.visititems(lambda k, v: names.append(k) if isinstance(v, h5py.Dataset) else None)
names_a = []
a.visititems(lambda k, v: names_a.append(k) if isinstance(v, h5py.Dataset) else None)
assert sorted(names) == sorted(names_a), (names, names_a)
keep_s = keep_e = slice(None)
if 'step' in b and n % int(b.attrs['every']) != 0:     # thinned: a's extra row is the state at n
    rows = a['step'][:] != n
    keep_s, keep_e = rows, rows[1:]
for k in names:
    x, y = a[k][:], b[k][:]
    if k in ('t', 'q', 'p', 'step'):
        x = x[keep_s]
    elif k in ('energy', 'lambda'):
        x = x[keep_e]
    elif k == 'checkpoint/record':
        x, y = x[1:], y[1:]                            # the row number aside
    assert x.shape == y.shape and x.dtype == y.dtype, (k, x.shape, y.shape)
    assert np.array_equal(x.view(np.uint8), y.view(np.uint8)), 'not bit for bit: ' + k
for k in b.attrs:
    if k in ('created', 'steps_completed') and 'step' in b:
        continue
    if k not in ('created', 'resumes'):
        assert a.attrs[k] == b.attrs[k], (k, a.attrs[k], b.attrs[k])
assert set(a.attrs) == set(b.attrs)
resumes = a.attrs['resumes'].decode()                 # the continuation is recorded, the other file has none
assert b.attrs['resumes'].decode() == '' and resumes.count(' from index %d (t = ' % n) == 1, resumes
print('  continued file == uninterrupted run:', len(names), 'datasets,', len(b['t']), 'rows of b,',
      len(b['impacts/time']), 'impacts')
PY
}

run_case TERM 143
run_case INT 130 --every 7 --compress
echo "interrupt: ok"
