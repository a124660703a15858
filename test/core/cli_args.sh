#!/usr/bin/env bash
# Issue 11 item 10: the examples' command lines are read strictly. Every bad line below must end
# with a nonzero exit status, a message on stderr that names the offending flag (or path), no
# "status: ok", and no file written; the good lines must still run.
# Usage: cli_args.sh <bin dir> <work dir>
set -uo pipefail
bin=$1; work=$2
mkdir -p "$work" && cd "$work" || exit 1
fail=0
# "<flags>|<text the message must contain>"
bad=(
  "--t-final inf|--t-final"
  "--t-final nan|--t-final"
  "--t-final -inf|--t-final"
  "--t-final 1e300|--t-final"
  "--t-final 1e12 --h 1e-6|2^53 steps"
  "--h 1,5|--h"
  "--h 0|--h"
  "--h -0.01|--h"
  "--h 1e308|--h"
  "--h 0x10|--h"
  "--h 1e|--h"
  "--h .|--h"
  "--h ''|--h"
  "--h|--h needs a value"
  "--max-impacts 1e20|--max-impacts"
  "--max-impacts 2.5|--max-impacts"
  "--max-impacts 99999999999999999999|--max-impacts"
  "--max-impacts 0|--max-impacts"
  "--max-impacts -3|--max-impacts"
  "--rtol 1|--rtol"
  "--rtol 0|--rtol"
  "--rtol nan|--rtol"
  "--flush-every 0|--flush-every"
  "--flush-every 1e3|--flush-every"
  "--stages 0|--stages"
  "--stages 9|--stages"
  "--scheme trapezoid|--scheme"
  "--impact-energy kinetic|--impact-energy"
  "--output /dev/full|--output"
  "--output .|--output"
  "--bogus|--bogus"
  "--append|--append"
)
for ex in ellipse pendulum pendulum_walls; do
  [ -x "$bin/$ex" ] || { echo "missing $bin/$ex"; exit 1; }
  for case in "${bad[@]}"; do
    flags=${case%%|*}; want=${case#*|}
    rm -f ./*.h5 ./*.csv
    eval "\"$bin/$ex\" $flags" > out.txt 2> err.txt
    rc=$?
    if [ $rc -eq 0 ] || grep -q '^status: ok' out.txt || ! grep -qF -- "$want" err.txt; then
      echo "FAIL: $ex $flags (exit $rc): $(head -c 300 err.txt)"; fail=1
    elif ls ./*.h5 ./*.csv > /dev/null 2>&1; then
      echo "FAIL: $ex $flags wrote a file"; fail=1
    fi
  done
done
[ -e /dev/full.h5 ] && { echo "FAIL: /dev/full.h5 exists"; fail=1; }
# good lines still run (numbers in every accepted spelling)
for flags in "--h 1e-2 --t-final 0.05" "--h 0.01 --t-final +5E-2" "--h 1.0d-2 --t-final 5e-2 --max-impacts 4" \
             "--h .01 --t-final 0.05 --rtol 1e-10 --flush-every 7"; do
  "$bin/ellipse" $flags --no-output --quiet > out.txt 2> err.txt
  grep -q '^status: ok' out.txt || { echo "FAIL: good line refused: ellipse $flags: $(cat err.txt)"; fail=1; }
done
# a name without an extension gets the default one, also when a folder on its path has a dot
rm -f ./run.h5 ./run.csv ./run
"$bin/ellipse" --h 1e-2 --t-final 0.05 --quiet --output ./run > out.txt 2> err.txt
if ! grep -q '^status: ok' out.txt || ! { [ -f ./run.h5 ] || [ -f ./run.csv ]; } || [ -e ./run ]; then
  echo "FAIL: --output ./run did not write ./run.h5 (or ./run.csv): $(ls) $(cat err.txt)"; fail=1
fi
[ $fail -eq 0 ] && echo "all bad command lines refused with a message; good ones run"
exit $fail
