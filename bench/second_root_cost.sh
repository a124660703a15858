#!/bin/bash
# The cost of looking for a second root after a step's last impact (second_root_exists, issue 24;
# docs/bench/poke.md, "The second root's search"): callgrind instructions per impact step and per
# regular step, and the whole program's wall seconds, with another build's library (MAIN_LIB: a
# directory holding its libvci.so.0, e.g. main's) and with this build's, one markdown row per scene.
#
#   MAIN_LIB=/path/to/main/build/src bench/second_root_cost.sh     # the bench programs of $BUILD_DIR (default build)
#
# The same bench binaries run with either library (LD_LIBRARY_PATH wins over their RUNPATH); each
# prints how many steps of each kind it took ("regular N impact M"), and callgrind counts only
# counted_impact_step (then counted_regular_step), so a cell is the run's Ir over those steps divided
# by their number. Instruction counts do not depend on the machine's load; the seconds do (they
# are the median of 3 runs, beside the counts only to show the order of magnitude).
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build}
BIN="$BUILD_DIR/bin"
THIS_LIB="$BUILD_DIR/src"
: "${MAIN_LIB:?set MAIN_LIB to the directory of the library to compare with}"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
export OPENBLAS_NUM_THREADS=1

# $1 = library directory, $2 = function pattern, rest = the command; prints Ir per step of that kind
count() {
  local lib=$1 fn=$2; shift 2
  local out="$WORK/cg.out" log="$WORK/log" kind ir steps
  case "$fn" in *regular*) kind=regular ;; *) kind=impact ;; esac
  LD_LIBRARY_PATH="$lib" valgrind --tool=callgrind --callgrind-out-file="$out" --toggle-collect="$fn" "$@" >"$log" 2>/dev/null
  ir=$(sed -n 's/^totals: *\([0-9]*\).*/\1/p' "$out" | head -n 1)
  steps=$(sed -n "s/.*$kind \([0-9][0-9]*\).*/\1/p" "$log" | tail -n 1)
  awk -v a="$ir" -v b="$steps" 'BEGIN { printf "%.0f", a / b }'
}

# $1 = library directory, rest = the command: median wall seconds of 3 runs
seconds() {
  local lib=$1; shift
  local k t
  for k in 1 2 3; do
    LD_LIBRARY_PATH="$lib" /usr/bin/time -f '%e' -o "$WORK/t" "$@" >/dev/null 2>&1
    tail -n 1 "$WORK/t"
  done | sort -n | sed -n 2p
}

row() {
  local label=$1; shift
  local i0 i1 r0 r1 s0 s1
  i0=$(count "$MAIN_LIB" '*counted_impact_step*' "$@"); i1=$(count "$THIS_LIB" '*counted_impact_step*' "$@")
  r0=$(count "$MAIN_LIB" '*counted_regular_step*' "$@"); r1=$(count "$THIS_LIB" '*counted_regular_step*' "$@")
  s0=$(seconds "$MAIN_LIB" "$@"); s1=$(seconds "$THIS_LIB" "$@")
  awk -v l="$label" -v i0="$i0" -v i1="$i1" -v r0="$r0" -v r1="$r1" -v s0="$s0" -v s1="$s1" 'BEGIN {
    printf "| %s | %d | %d (%.3f) | %d | %d (%.3f) | %s | %s |\n", l, i0, i1, i1 / i0, r0, r1, r1 / r0, s0, s1 }'
}

echo "| scene | impact step, MAIN_LIB | this build (ratio) | regular step, MAIN_LIB | this build (ratio) | s, MAIN_LIB | s, this build |"
echo "|---|---:|---:|---:|---:|---:|---:|"
row "ellipse (midpoint, analytic H)" "$BIN/vci_bench_throughput" --profile-steps ellipse 1 20
row "pendulum (the throughput scene, midpoint)" "$BIN/vci_bench_throughput" --profile-steps pendulum 1 2
row "walled pendulum, Lobatto s = 4" "$BIN/vci_bench_lobatto_steps" 4 2 walled

# the fuzz harness's scenes with soft impacts, where the search runs at most impacts: one reversal run
# (forward and back) in process, its whole Ir and seconds
whole() {
  local label=$1; shift
  local i0 i1 s0 s1
  LD_LIBRARY_PATH="$MAIN_LIB" valgrind --tool=callgrind --callgrind-out-file="$WORK/w0" "$@" >/dev/null 2>&1 || true
  LD_LIBRARY_PATH="$THIS_LIB" valgrind --tool=callgrind --callgrind-out-file="$WORK/w1" "$@" >/dev/null 2>&1 || true
  i0=$(sed -n 's/^totals: *\([0-9]*\).*/\1/p' "$WORK/w0" | head -n 1)
  i1=$(sed -n 's/^totals: *\([0-9]*\).*/\1/p' "$WORK/w1" | head -n 1)
  s0=$(seconds "$MAIN_LIB" "$@"); s1=$(seconds "$THIS_LIB" "$@")
  awk -v l="$label" -v i0="$i0" -v i1="$i1" -v s0="$s0" -v s1="$s1" 'BEGIN {
    printf "| %s | %d | %d (%.3f) | | | %s | %s |\n", l, i0, i1, i1 / i0, s0, s1 }'
}
FUZZ="$BUILD_DIR/test/fuzz/vci_fuzz"
whole "vci_fuzz --reversal -1 98668 (midpoint chain, whole run)" "$FUZZ" --reversal -1 98668
whole "vci_fuzz --reversal -1 31255 (midpoint chain, whole run)" "$FUZZ" --reversal -1 31255
