#!/bin/bash
# The poke screen's cost (issues 24, 25; docs/bench/poke.md): callgrind instructions per regular and
# per impact step with the screen off (VCI_BENCH_POKE=0: set_poke_samples(.false.), read by the bench
# programs only) and on (the default), one markdown row per scene.
#
#   bench/poke_cost.sh                      # the bench programs of $BUILD_DIR (default build-bench)
#   BUILD_DIR=/some/other/build bench/poke_cost.sh
#
# Each program runs its split steps (bench/step_split.f90) and prints how many of each kind it took
# ("regular N impact M"); callgrind counts only counted_regular_step (then counted_impact_step), so
# a cell is the run's total Ir over those steps divided by their number. Instruction counts do not
# depend on the machine's load; the build must be Release (-O3), as nonholo_vs_cvode.sh builds it.
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build-bench}
BIN="$BUILD_DIR/bin"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
export OPENBLAS_NUM_THREADS=1

# one callgrind run: $1 = poke (0 off, 1 on), $2 = function pattern, rest = the command; prints Ir/step
count() {
  local poke=$1 fn=$2; shift 2
  local out="$WORK/cg.out" log="$WORK/log" kind
  case "$fn" in *regular*) kind=regular ;; *) kind=impact ;; esac
  if [ "$poke" = 0 ]; then
    VCI_BENCH_POKE=0 valgrind --tool=callgrind --callgrind-out-file="$out" --toggle-collect="$fn" "$@" >"$log" 2>/dev/null
  else
    valgrind --tool=callgrind --callgrind-out-file="$out" --toggle-collect="$fn" "$@" >"$log" 2>/dev/null
  fi
  local ir steps
  ir=$(sed -n 's/^totals: *\([0-9]*\).*/\1/p' "$out" | head -n 1)
  steps=$(sed -n "s/.*$kind \([0-9][0-9]*\).*/\1/p" "$log" | tail -n 1)
  awk -v a="$ir" -v b="$steps" 'BEGIN { printf "%.0f", a / b }'
}

row() {
  local label=$1; shift
  local r0 r1 i0 i1
  r0=$(count 0 '*counted_regular_step*' "$@"); r1=$(count 1 '*counted_regular_step*' "$@")
  i0=$(count 0 '*counted_impact_step*' "$@"); i1=$(count 1 '*counted_impact_step*' "$@")
  awk -v l="$label" -v r0="$r0" -v r1="$r1" -v i0="$i0" -v i1="$i1" 'BEGIN {
    printf "| %s | %d | %d (%+.0f %%) | %d | %d (%+.0f %%) |\n", l, r0, r1, 100 * (r1 / r0 - 1), i0, i1, 100 * (i1 / i0 - 1) }'
}

echo "| scene | regular step, off | on | impact step, off | on |"
echo "|---|---:|---:|---:|---:|"
row "ellipse (midpoint, analytic H)" "$BIN/vci_bench_throughput" --profile-steps ellipse 1 20
row "pendulum (the throughput scene, midpoint)" "$BIN/vci_bench_throughput" --profile-steps pendulum 1 2
row "walled pendulum, Lobatto s = 4" "$BIN/vci_bench_lobatto_steps" 4 2 walled
row "nonholonomic pendulum, Lobatto s = 3, h = 0.05" "$BIN/vci_bench_lobatto_nonholo" 3 0.05 1 run 1e-14
row "nonholonomic pendulum, Lobatto s = 4, h = 0.04167" "$BIN/vci_bench_lobatto_nonholo" 4 0.0416666666666667 1 run 1e-14
row "nonholonomic pendulum, Lobatto s = 3, h = 0.025, rtol 1e-8" "$BIN/vci_bench_lobatto_nonholo" 3 0.025 1 run 1e-8
