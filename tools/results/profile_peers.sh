#!/bin/sh
# Where the time goes on the walled pendulum: instructions (callgrind) of one whole run of the
# compiled DOP853 and of vci's rows at about the same final error, and the share of each spent
# locating impacts. Writes $OUT/profile.md, which make_report.py puts on docs/RESULTS.md. Called by
# run_results.sh after the sweeps; alone:
#
#   tools/results/profile_peers.sh BUILD_DIR OUT_DIR
#
# (BUILD_DIR holds the results drivers, as built by run_results.sh.)
set -eu
BUILD=$1
OUT=$2
command -v valgrind >/dev/null || { echo "profile_peers.sh: valgrind not found (Debian: valgrind)" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# prof NAME TOGGLES IMPACT_FUNCS CMD...: instructions inside the functions TOGGLES (space-separated
# callgrind --toggle-collect patterns: the whole run, set-up included, and nothing else: not the
# reference solution nor the output the drivers compute after it), the inclusive instructions of
# the step loop (vci: integrate; DOP853: the same as the run) and of the impact search (the first
# function matching the grep -E pattern IMPACT_FUNCS); one table row. LD_BIND_NOW=1: the dynamic
# linker resolves every symbol at start-up, outside the measured functions (a process pays that
# once, not per run; bound lazily, the resolution was 92k instructions of vci's
# first run, inside its set-up).
prof() {
  name=$1; toggles=$2; impact=$3; shift 3
  set -f   # (the patterns are callgrind's, not the shell's)
  set -- $(for t in $toggles; do printf -- '--toggle-collect=%s ' "$t"; done) "$@"
  set +f
  line=$(LD_BIND_NOW=1 valgrind --tool=callgrind --callgrind-out-file="$TMP/cg.out" "$@" 2>/dev/null)
  callgrind_annotate --inclusive=yes "$TMP/cg.out" >"$TMP/cg.txt" 2>/dev/null
  total=$(awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1; exit}' "$TMP/cg.txt")
  loop=$(grep -E '__vci_integrator_MOD_integrate |run_dop' "$TMP/cg.txt" | head -1 | awk '{gsub(",", "", $1); print $1}')
  imp=$(grep -E "$impact" "$TMP/cg.txt" | head -1 | awk '{gsub(",", "", $1); print $1}')
  [ -n "$imp" ] || imp=0
  [ -n "$loop" ] || loop=$total
  err=$(echo "$line" | sed 's/.*final error *//')
  echo "| $name | $err | $total | $loop | $(awk -v a="$imp" -v b="$total" 'BEGIN { printf "%.0f %%", 100 * a / b }') |"
}

{
  echo "Instructions of one whole run of the walled pendulum (T = 10 s, 18 impacts, from the exact start),"
  echo "\`valgrind --tool=callgrind\` around the run only (\`tools/results/profile_peers.sh\`; symbols bound at"
  echo "load, \`LD_BIND_NOW=1\`, and the reference solution outside the count): \"whole run\""
  echo "includes vci's set-up (create, set_scheme, init_from_momentum; DOP853's init), \"step loop\" is"
  echo "\`integrate\` alone. \"Impacts\": inclusive instructions of locating the impacts (DOP853: \`crossing\`"
  echo "on the dense output; the compositions: \`gap_on_map\`, the composed map evaluated along the root"
  echo "iteration; Lobatto: \`resolve_impacts\`, both stages), as a share of the whole run."
  echo
  echo "| run | final error | instructions, whole run | step loop | impacts |"
  echo "|---|---|---|---|---|"
  for tol in 1e-8 1e-10 1e-12; do
    prof "dop853 rtol $tol" '*run_dop*' 'crossing' "$BUILD/dop853_results_driver" once pendulum_walls $tol
  done
  for row in "vci-composition6-hamiltonian 0.1" "vci-composition8-hamiltonian 0.1" \
             "vci-composition8-hamiltonian 0.05" "vci-composition10-hamiltonian 0.2" \
             "vci-composition10-hamiltonian 0.1"; do
    set -- $row
    prof "$1 h $2" 'start start.* __vci_integrator_MOD_integrate' 'gap_on_map' "$BUILD/vci_results_driver" once pendulum_walls "$1" "$2"
  done
  prof "vci-lobatto4-hamiltonian h 0.1" 'start start.* __vci_integrator_MOD_integrate' 'resolve_impacts' "$BUILD/vci_results_driver" once pendulum_walls \
    vci-lobatto4-hamiltonian 0.1
} >"$OUT/profile.md"
cat "$OUT/profile.md"
