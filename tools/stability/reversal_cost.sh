#!/bin/sh
# The cost of the regular step's root check by time reversal (confirm_by_reversal, issue 27):
# callgrind instructions of each run, of the check (inclusive) and its calls, on the walled
# pendulum and Kepler runs of docs/STABILITY.md "Long steps". docs/bench/reversal_check.md.
#   tools/stability/reversal_cost.sh [build-dir]      (default: build; ~3 min on 2 shared cores)
set -e
build=${1:-build}
cmake --build "$build" --target pendulum_walls vci_long_steps_trace >/dev/null
out=$(mktemp -d)
export OPENBLAS_NUM_THREADS=1
printf '| run | steps | Ir in the steps | Ir in the check | checks | Ir per check | Ir per step without the check |\n'
printf '|---|---|---|---|---|---|---|\n'
run() {   # label steps command...
  label=$1; steps=$2; shift 2
  # only inside the integrator's step (not the program's start or its output)
  valgrind --tool=callgrind --toggle-collect='__vci_integrator_MOD_step' --callgrind-out-file="$out/cg" "$@" \
    >/dev/null 2>&1
  total=$(callgrind_annotate "$out/cg" | awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1; exit}')
  check=$(callgrind_annotate --inclusive=yes "$out/cg" | awk '/confirm_by_reversal/ {gsub(",", "", $1); print $1; exit}')
  # calls: the lines calls=N after each cfn=(id) of the check (callgrind names a function once, by id after)
  calls=$(awk '/confirm_by_reversal/ && match($0, /\([0-9]+\)/) {id = substr($0, RSTART, RLENGTH)}
    /^cfn=/ {c = (id != "" && index($0, id) == 5)}
    /^calls=/ && c {split($1, a, "="); n += a[2]; c = 0}
    END {print n + 0}' "$out/cg")
  check=${check:-0}
  awk -v l="$label" -v s="$steps" -v t="$total" -v c="$check" -v n="$calls" 'BEGIN {
    per = (n > 0) ? sprintf("%.3g", c / n) : "-"
    printf "| %s | %d | %.4g | %.3g (%.2f %%) | %d | %s | %.4g |\n", l, s, t, c, 100 * c / t, n, per, (t - c) / s }'
}
run 'pendulum_walls lobatto s=4 h=0.4' 25 "$build/bin/pendulum_walls" --scheme lobatto --stages 4 --h 0.4 --no-output
run 'pendulum_walls lobatto s=2 h=0.8' 13 "$build/bin/pendulum_walls" --scheme lobatto --stages 2 --h 0.8 --no-output
run 'pendulum_walls lobatto s=4 h=0.05' 200 "$build/bin/pendulum_walls" --scheme lobatto --stages 4 --h 0.05 --no-output
run 'Kepler below the wall s=2 h=0.6' 33 "$build/bin/vci_long_steps_trace" 4 2 0.6 16 1
run 'Kepler below the wall s=4 h=0.8' 25 "$build/bin/vci_long_steps_trace" 4 4 0.8 16 1
run 'Kepler in the circle s=2 h=0.8' 25 "$build/bin/vci_long_steps_trace" 2 2 0.8 16 1
run 'free Kepler s=2 h=0.8' 25 "$build/bin/vci_long_steps_trace" 2 2 0.8 1 0
run 'free Kepler s=2 h=0.8, first step from rest' 25 "$build/bin/vci_long_steps_trace" 2 2 0.8 16 0 1
rm -rf "$out"
