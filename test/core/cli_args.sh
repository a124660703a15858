#!/usr/bin/env bash
# Issue 11 item 10: the examples' command lines are read strictly. Every bad line below must end
# with a nonzero exit status, a message on stderr that names the offending flag (or path), no
# "status: ok", and no file written; the good lines must still run.
# Issue 24 item 6: sizes (steps, members, caps, strides, flush intervals) are bounded before
# anything is allocated or written; nothing wraps. ellipse_ensemble (when built) likewise.
# Usage: cli_args.sh <bin dir> <work dir> [hdf5: ON when the examples write HDF5]
set -uo pipefail
bin=$1; work=$2; hdf5=${3:-OFF}
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
  "--flush-every 2147483647|--flush-every"
  "--every 0|--every"
  "--every 2.5|--every"
  "--every 2147483647|--every"
  "--every 10 --output x.csv|--every"
  "--compress --output x.csv|--compress"
  "--stages 0|--stages"
  "--stages 9|--stages"
  "--scheme trapezoid|--scheme"
  "--impact-energy kinetic|--impact-energy"
  "--output /dev/full|--output"
  "--output .|--output"
  "--bogus|--bogus"
  "--append|--append"
)
# Issue 31 item 6: an option that needs a value never takes the next option (or nothing) as it.
valued=(--h --t-final --output --from --impact-energy --rtol --max-impacts --flush-every --every --scheme --stages)
for opt in "${valued[@]}"; do
  bad+=("$opt --quiet|$opt needs a value" "$opt --no-output|$opt needs a value" "$opt -h|$opt needs a value"
        "--h 0.01 $opt|$opt needs a value" "$opt ''|$opt")
done
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
# Issue 31 item 4: --check-model passes every shipped scene (each discretisation the examples offer),
# prints one line per supplied derivative, stops without running and writes nothing
for line in "ellipse" "ellipse --scheme midpoint" "ellipse --scheme lobatto --stages 3" "pendulum" \
            "pendulum --scheme left" "particle" "particle --scheme midpoint" "pendulum_walls"; do
  rm -f ./*.h5 ./*.csv
  "$bin"/$line --check-model > out.txt 2> err.txt; rc=$?
  if [ $rc -ne 0 ] || ! grep -q '^model check: passed' out.txt || ! grep -q 'gap_gradients' out.txt \
     || grep -q '^status' out.txt || ls ./*.h5 ./*.csv > /dev/null 2>&1; then
    echo "FAIL: $line --check-model (exit $rc): $(cat out.txt err.txt | head -c 600)"; fail=1
  fi
done
# Issue 31 item 1: --progress writes progress lines to stderr (here not a terminal: whole lines) and
# leaves stdout as it was; without it (stderr not a terminal) nothing
"$bin/ellipse" --h 1e-2 --t-final 2 --no-output --progress > with.txt 2> err.txt; rc=$?
"$bin/ellipse" --h 1e-2 --t-final 2 --no-output > without.txt 2> err0.txt
if [ $rc -ne 0 ] || ! grep -q '^progress 100.0%  step 200 of 200  t = ' err.txt || ! grep -q 'steps/s  ETA 0 s' err.txt \
   || [ -s err0.txt ] || ! diff <(grep -v '^wall time' with.txt) <(grep -v '^wall time' without.txt) > /dev/null; then
  echo "FAIL: --progress: $(cat err.txt err0.txt | head -c 600)"; fail=1
fi
# the ensemble example reads its own flags: the same rule
if [ -x "$bin/ellipse_ensemble" ]; then
  for opt in --members --t-final --h --min-size --max-size --tol --stride --impact-cap --threads --chunk --output; do
    for flags in "$opt --quiet" "$opt"; do
      rm -f ./*.h5
      "$bin/ellipse_ensemble" --members 2 --t-final 0.05 $flags > out.txt 2> err.txt; rc=$?
      if [ $rc -eq 0 ] || ! grep -qF -- "$opt" err.txt || ls ./*.h5 > /dev/null 2>&1; then
        echo "FAIL: ellipse_ensemble $flags (exit $rc): $(head -c 300 err.txt) $(ls)"; fail=1
      fi
    done
  done
fi
[ -e /dev/full.h5 ] && { echo "FAIL: /dev/full.h5 exists"; fail=1; }

# ellipse_ensemble: every size bounded before the table is allocated or the file written
if [ -x "$bin/ellipse_ensemble" ]; then
  ens_bad=(
    "--t-final 1e300|--t-final"
    "--t-final 1e12 --h 1e-6|2^53 steps"
    "--members 1000000000|--members"
    "--members 1|--members"
    "--impact-cap 2147483647|--impact-cap"
    "--impact-cap 0|--impact-cap"
    "--threads 100000|--threads"
    "--stride -1|--stride"
    "--chunk -1|--chunk"
    "--h 1e300|--h"
    "--members 1e9|--members"
  )
  if [ "$hdf5" = ON ]; then
    # within the flags' ranges, but a file no disk holds (fill values are written at creation):
    # refused before a byte is written. 1e7 members of 4.4e9 steps (no wrap: t-final / h counted in
    # 64 bits) at stride 10 are 4.4e8 samples of 7 doubles each: >= 1e7 * 4.4e8 * 56 = 2.46e17 bytes
    ens_bad+=("--members 10000000 --t-final 4.4e7|the file would take"
              "--stride 1 --t-final 1e7 --members 10000000|the file would take"
              "--impact-cap 1000000 --members 10000000|the file would take")
  fi
  for case in "${ens_bad[@]}"; do
    flags=${case%%|*}; want=${case#*|}
    rm -f ./*.h5
    eval "timeout 60 \"$bin/ellipse_ensemble\" $flags --quiet --output ens.h5" > out.txt 2> err.txt
    rc=$?
    if [ $rc -eq 0 ] || [ $rc -eq 124 ] || [ $rc -ge 128 ] || ! grep -qF -- "$want" err.txt; then
      echo "FAIL: ellipse_ensemble $flags (exit $rc): $(head -c 300 err.txt)"; fail=1
    elif [ -e ens.h5 ]; then
      echo "FAIL: ellipse_ensemble $flags wrote ens.h5 ($(stat -c %s ens.h5) bytes)"; fail=1
    fi
  done
  # a path longer than the parser's 512 characters (two directories of 200, a name of 200): refused,
  # not cut to another file (before: the ensemble written to d/d/ plus 110 characters of the name)
  x200=$(printf 'x%.0s' $(seq 1 200))
  mkdir -p "$x200/$x200"
  "$bin/ellipse_ensemble" --members 2 --t-final 0.05 --quiet --output "$x200/$x200/$x200.h5" > out.txt 2> err.txt
  rc=$?
  if [ $rc -eq 0 ] || ! grep -qF -- "--output" err.txt || [ -n "$(ls "$x200/$x200")" ]; then
    echo "FAIL: ellipse_ensemble --output (a path of 605 characters) (exit $rc): $(head -c 300 err.txt)" \
         "files: $(ls "$x200/$x200" | cut -c1-40)"; fail=1
  fi
  rm -rf "$x200"
  if [ "$hdf5" = ON ]; then
    # the 4.4e7 case: the size the message states is that of 4.4e9 steps, not of a wrapped count
    eval "\"$bin/ellipse_ensemble\" --members 10000000 --t-final 4.4e7 --quiet --output ens.h5" > out.txt 2> err.txt
    bytes=$(sed -n 's/.*the file would take *\([0-9.E+-]*\) bytes.*/\1/p' err.txt)
    awk -v b="$bytes" 'BEGIN { exit !(b + 0 >= 2.46e17) }' \
      || { echo "FAIL: --t-final 4.4e7: the file's size ($bytes bytes) is not that of 4.4e9 steps"; fail=1; }
  fi
fi
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
