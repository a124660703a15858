#!/bin/bash
# The C examples' arguments (examples/c/args.h): a number that is not one whole finite decimal in its
# range, or a t_final more than 2^53 steps away, ends the program with exit status 2 and a message
# naming the argument, before anything runs (atof took "1,5" as 1 and "abc" as 0, and 1e300 / h was
# converted to int64_t, undefined in C); the defaults and good values still run.
# Usage: examples_args.sh C_ELLIPSE C_PENDULUM
set -u
fail=0
for exe in "$1" "$2"; do
  for case in "abc|h must be" "1,5|h must be" "0|h must be" "-1e-2|h must be" "nan|h must be" "1e-2 inf|t_final must be" \
              "1e-2 1e300|t_final must be" "1e-2 2x|t_final must be" "1e-6 1e12|2^53 steps"; do
    args=${case%%|*}; want=${case#*|}
    # shellcheck disable=SC2086
    timeout 60 "$exe" $args > out.txt 2> err.txt; rc=$?
    if [ $rc -ne 2 ] || ! grep -qF -- "$want" err.txt || grep -q '^impact' out.txt; then
      echo "FAIL: $(basename "$exe") $args: exit $rc, expected 2 and \"$want\": $(head -c 200 err.txt)"; fail=1
    else
      echo "ok   $(basename "$exe") $args: $(head -c 120 err.txt)"
    fi
  done
  "$exe" > out.txt 2> err.txt || { echo "FAIL: $(basename "$exe") with its defaults: $(cat err.txt)"; fail=1; }
  "$exe" 2e-3 0.5 > out.txt 2> err.txt || { echo "FAIL: $(basename "$exe") 2e-3 0.5: $(cat err.txt)"; fail=1; }
done
exit $fail
