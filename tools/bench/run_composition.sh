#!/bin/sh
# Cost of the explicit compositions (issue 32): the library's regular step against a hand-written
# loop of the same composition (bench/composition.f90; the two end in the same bits), and the
# walled run's extra cost per impact step. Writes docs/bench/composition.md: callgrind instructions
# per step (reproducible) and best-of-5 wall times (move with the machine's load).
#
#   tools/bench/run_composition.sh            # uses $BUILD_DIR (default: build), target built here
set -eu
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build}
OUT=${OUT:-$ROOT/docs/bench/composition.md}
cmake --build "$BUILD_DIR" --target vci_bench_composition -j1 >/dev/null
EXE="$BUILD_DIR/bin/vci_bench_composition"
N=200000
{
  echo "# Explicit compositions: cost of a step"
  echo
  echo "Written by \`tools/bench/run_composition.sh\` ($(date -u +%Y-%m-%d), $(uname -m), $(nproc) cores). Pendulum"
  echo "(n = 1), θ(0) = 0, θ'(0) = 4, h = 0.01, $N steps; the walled run (walls ±1 rad) has 3520 impacts."
  echo "Instructions per step by \`valgrind --tool=callgrind --toggle-collect='*run_timed*'\`."
  echo "\"Impact step\" is the walled run's extra instructions over the free library run, per impact step,"
  echo "in units of a free regular step: it includes the sampling of the internal stages that every"
  echo "walled step pays (s − 1 gap evaluations)."
  echo
  echo "| order | stages | library / step | hand loop / step | library / hand | walled / step | impact step / regular step |"
  echo "|---:|---:|---:|---:|---:|---:|---:|"
  for o in 2 4 6 8 10; do
    for w in lib hand walls; do
      ir=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null --toggle-collect='*run_timed*' \
             "$EXE" --profile $w $o 2>&1 | awk '/Collected/ {print $4}')
      eval "ir_$w=$ir"
    done
    case $o in 2) s=1;; 4) s=3;; 6) s=9;; 8) s=17;; 10) s=35;; esac
    awk -v o=$o -v s=$s -v l=$ir_lib -v hd=$ir_hand -v w=$ir_walls -v n=$N 'BEGIN {
      imp = 3520; printf "| %d | %d | %d | %d | %.2f | %d | %.1f |\n", o, s, l/n, hd/n, l/hd, w/n, (w - l*(n-imp)/n)/imp/(l/n) }'
  done
  echo
  echo "Wall times (best of 5; same bits checked):"
  echo
  echo '```'
  for o in 2 6 10; do "$EXE" $o; done
  echo '```'
  echo
  echo "Error against CPU time on the walled pendulum over 10 s (18 impacts) from the exact start, final"
  echo "error against the exact solution (\`vci_bench_composition --sweep\`, best of 7 per run):"
  echo
  echo '```'
  "$EXE" --sweep 2>/dev/null
  echo '```'
} >"$OUT"
cat "$OUT"
