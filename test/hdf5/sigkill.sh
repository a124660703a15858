#!/bin/bash
# The SIGKILL test: start the pendulum over a very long horizon writing HDF5 (flush every 1000 steps),
# kill it with SIGKILL once it has flushed for a while, then check the file it left.
# Usage: sigkill.sh PENDULUM_EXE CHECKER_EXE OUTPUT_FILE
set -eu
exe=$1; checker=$2; out=$3
h=1e-4
rm -f "$out"
"$exe" --h "$h" --t-final 1e6 --quiet --flush-every 1000 --output "$out" > "$out.log" 2>&1 &
pid=$!
# wait for the file, then let it stream for a second
for _ in $(seq 1 100); do
  [ -s "$out" ] && break
  sleep 0.1
done
sleep 0.5
if ! kill -0 "$pid" 2> /dev/null; then
  echo "FAIL: the pendulum ended before it was killed"; cat "$out.log"; exit 1
fi
kill -9 "$pid"
wait "$pid" 2> /dev/null || true
echo "killed pid $pid with SIGKILL; file size $(stat -c %s "$out") bytes"
"$checker" "$out" "$h"
