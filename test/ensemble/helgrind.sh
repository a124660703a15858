#!/bin/bash
# helgrind.sh VALGRIND DRIVER clean|racy
#   clean: 3 threads run the ensemble's members under helgrind; no error may be reported and the
#          results must equal a one-thread run.
#   racy:  the same with a deliberate race in the models; helgrind must report it (proof that the
#          check can fail).
set -uo pipefail
valgrind=$1 driver=$2 mode=$3
log=$(mktemp)
trap 'rm -f "$log"' EXIT
arg=
[ "$mode" = racy ] && arg=racy
"$valgrind" --tool=helgrind --error-exitcode=99 --suppressions="$(dirname "$0")/helgrind.supp" \
  --log-file="$log" "$driver" 3 $arg
rc=$?
grep -E "ERROR SUMMARY|Possible data race" "$log" | sort | uniq -c
if [ "$mode" = clean ]; then
  if [ $rc -ne 0 ]; then
    echo "FAIL: helgrind reported errors or the results differ (exit $rc)"; cat "$log"; exit 1
  fi
  echo "helgrind: no errors"
else
  if [ $rc -ne 99 ] || ! grep -q "Possible data race" "$log" || ! grep -q "racy_d1" "$log"; then
    echo "FAIL: the deliberate race in racy_d1 was not reported (exit $rc)"; cat "$log"; exit 1
  fi
  echo "helgrind reported the deliberate race in racy_d1"
fi
