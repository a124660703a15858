#!/bin/bash
# A developer tool given a bad argument must stop with exit status 2 and a message on stderr that
# names the argument (not a Fortran runtime error, not a run on a partly read number).
# Usage: check_usage_error.sh EXPECTED_MESSAGE PROGRAM [ARGS...]
expected=$1; shift
err=$("$@" 2>&1 > /dev/null); rc=$?
echo "exit status $rc; stderr: $err"
[ "$rc" -eq 2 ] || { echo "FAIL: exit status $rc, expected 2"; exit 1; }
case "$err" in
  *"$expected"*) echo "ok" ;;
  *) echo "FAIL: stderr does not say: $expected"; exit 1 ;;
esac
