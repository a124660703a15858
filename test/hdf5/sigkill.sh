#!/bin/bash
# The SIGKILL test: start the pendulum over a horizon it cannot reach (10^6 s) writing HDF5 with a
# flush every 1000 steps, kill it with SIGKILL once it has done at least 3000 steps, then check
# the file it left. The kill waits for a condition the writer guarantees, not for a time: the
# pendulum's progress line (--progress, on stderr after every half second of the run) says N steps
# are done, and the writer flushes inside the step's on_step, before that report, whenever 1000
# rows are buffered; so the file then holds at least N - 999 flushed steps, and the checker asserts
# that many. The wait is bounded (a clear failure, not a hang, if no such line comes).
# Usage: sigkill.sh PENDULUM_EXE CHECKER_EXE OUTPUT_FILE
set -u
exe=$1; checker=$2; out=$3
h=1e-4
flush=1000       # --flush-every
want=3000        # steps done before the kill
wait_max=100     # seconds (the test's TIMEOUT is 120)
fail() { echo "FAIL: $*"; exit 1; }
rm -f "$out" "$out.log" "$out.progress"
"$exe" --h "$h" --t-final 1e6 --quiet --progress --flush-every "$flush" --output "$out" \
  > "$out.log" 2> "$out.progress" &
pid=$!
n=0
start=$SECONDS
while :; do
  last=$(sed -n 's/^progress .* step \([0-9][0-9]*\) of .*/\1/p' "$out.progress" | tail -n 1)
  [ -n "$last" ] && n=$last
  [ "$n" -ge "$want" ] && break
  if ! kill -0 "$pid" 2> /dev/null; then
    cat "$out.log" "$out.progress"; fail "the pendulum ended before it was killed (last progress: $n steps)"
  fi
  if [ $((SECONDS - start)) -ge "$wait_max" ]; then
    kill -9 "$pid" 2> /dev/null; wait "$pid" 2> /dev/null
    cat "$out.log" "$out.progress"
    fail "no progress line with >= $want steps within $wait_max s (last: $n steps; machine too loaded?)"
  fi
  sleep 0.1
done
kill -9 "$pid"
wait "$pid" 2> /dev/null
echo "killed pid $pid with SIGKILL after >= $n steps; file size $(stat -c %s "$out") bytes"
# the writer's promise: every step up to the last multiple of the flush interval is on disk
"$checker" "$out" "$h" $((n - flush + 1)) || fail "the killed file"
