#!/bin/sh
# Throughput benchmark of vci against hand-written loops (issue 2 item 9, issue 6, issue 14).
# Builds the benchmarks in Release, runs them (one process each: trajectory check, timed repeats,
# peak memory; callgrind instruction counts; the chain against n) and writes docs/bench/throughput.md
# with the machine it ran on. The ratios that issue 14 asks for: library / same-algorithm loop and
# library / closed-form loop per regular step, impact step / regular step, and for the chain the
# step against one LU factorisation. OpenBLAS runs single-threaded in the chain table (vci's Newton
# matrices are small; the threaded run is shown beside it).
#
#   tools/bench/run_bench.sh                 # full run (~30 s), writes docs/bench/throughput.md
#   tools/bench/run_bench.sh --quick         # short repeats, for a smoke test
#   BUILD_DIR=/tmp/b tools/bench/run_bench.sh
#
# Compare ratios within one run only: absolute times move with the machine and its load.
set -eu
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD_DIR=${BUILD_DIR:-$ROOT/build-bench}
OUT=${OUT:-$ROOT/docs/bench/throughput.md}

cmake -S "$ROOT" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release \
  -DVCI_BUILD_BENCH=ON -DVCI_BUILD_TESTS=OFF -DVCI_BUILD_EXAMPLES=OFF >/dev/null
cmake --build "$BUILD_DIR" -j"$(nproc 2>/dev/null || echo 2)" --target vci_bench_throughput vci_bench_chain >/dev/null

EXE="$BUILD_DIR/bin/vci_bench_throughput"
TMP=$(mktemp)
trap 'rm -f "$TMP"' EXIT
status=0
"$EXE" "$@" >"$TMP" || status=$?

# Instructions per step (valgrind's callgrind, only the timed loop): reproducible where wall time is
# not (a loaded machine moves the times, not the counts). CALLGRIND=0 skips it.
CG=""
if [ "${CALLGRIND:-1}" != 0 ] && command -v valgrind >/dev/null 2>&1; then
  CG=$(mktemp)
  trap 'rm -f "$TMP" "$CG"' EXIT
  {
    echo "### Instructions per step (callgrind)"
    echo
    echo "Counted by \`valgrind --tool=callgrind --toggle-collect='*run_timed*'\` on \`vci_bench_throughput --profile\`"
    echo "(episodes: particle and ellipse 20, pendulum 2). Ratios: library / closed-form hand loop (the floor),"
    echo "library / same-algorithm hand loop (the yardstick). The last columns: the library with analytic H on"
    echo "its general Newton path only (\`VCI_BENCH_GENERAL=1\`: no fused regular-step solve), and what the fused"
    echo "solve (src/schemes/vci_scheme_discrete_fused.f90) leaves of it."
    echo
    echo "| scene | library, analytic H | library, differenced H | closed-form loop | same-algorithm loop | analytic / closed form | analytic / same alg. | differenced / same alg. | analytic H, general path | fused / general |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    for spec in particle:300:20 ellipse:200:20 pendulum:4999:2 ellipse-free:200:20 pendulum-free:4999:2; do
      name=${spec%%:*}; rest=${spec#*:}; nst=${rest%%:*}; eps=${rest#*:}
      set_counts=""
      for v in 1 2 3 4; do
        if [ "$name" = particle ] && [ "$v" = 4 ]; then set_counts="$set_counts 0"; continue; fi
        ir=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null --toggle-collect='*run_timed*' \
               "$EXE" --profile "$name" "$v" "$eps" 2>&1 | awk '/Collected/ {print $4}')
        set_counts="$set_counts $(( ir / (nst * eps) ))"
      done
      ir=$(VCI_BENCH_GENERAL=1 valgrind --tool=callgrind --callgrind-out-file=/dev/null --toggle-collect='*run_timed*' \
             "$EXE" --profile "$name" 1 "$eps" 2>&1 | awk '/Collected/ {print $4}')
      set_counts="$set_counts $(( ir / (nst * eps) ))"
      echo "$set_counts" | awk -v s="$name" '{ if ($4 > 0) printf "| %s | %d | %d | %d | %d | %.1f | %.2f | %.2f | %d | %.2f |\n", s, $1, $2, $3, $4, $1/$3, $1/$4, $2/$4, $5, $1/$5;
                                               else printf "| %s | %d | %d | %d | n/a | %.1f | n/a | n/a | %d | %.2f |\n", s, $1, $2, $3, $1/$3, $5, $1/$5 }'
    done
    echo
  } >"$CG"
fi

# Impact steps against regular steps in instructions: --profile-steps takes the steps a first episode
# found with and without an impact through two procedures (bench/step_split.f90); callgrind counts
# each one's instructions apart (the timed table below them is the same ratio in time).
IS=""
if [ "${CALLGRIND:-1}" != 0 ] && command -v valgrind >/dev/null 2>&1; then
  IS=$(mktemp)
  trap 'rm -f "$TMP" "$CG" "$IS"' EXIT
  {
    echo "### Impact and regular steps in instructions (callgrind)"
    echo
    echo "\`valgrind --tool=callgrind --toggle-collect='*counted_regular_step*'\` (and \`'*counted_impact_step*'\`) on"
    echo "\`vci_bench_throughput --profile-steps SCENE 1 EPISODES\` (library, analytic H; episodes: ellipse 20, pendulum 2)."
    echo
    echo "| scene | regular steps | impact steps | instructions / regular step | instructions / impact step | impact / regular |"
    echo "|---|---:|---:|---:|---:|---:|"
    for spec in ellipse:20 pendulum:2; do
      name=${spec%%:*}; eps=${spec#*:}
      row=""
      for w in regular impact; do
        out=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null --toggle-collect="*counted_${w}_step*" \
                "$EXE" --profile-steps "$name" 1 "$eps" 2>&1)
        ir=$(echo "$out" | awk '/Collected/ {print $4}')
        cnt=$(echo "$out" | awk -v w="$w" '$1 == "regular" { print (w == "regular") ? $2 : $4 }')
        row="$row $cnt $ir"
      done
      echo "$row" | awk -v s="$name" '{ printf "| %s | %d | %d | %.0f | %.0f | %.2f |\n", s, $1, $3, $2 / $1, $4 / $3, ($4 / $3) / ($2 / $1) }'
    done
    echo
  } >"$IS"
fi

# Where the instructions of a library step go (callgrind, analytic Hessian, self cost per function
# group): the profile that explains a missed target. PROFILE=0 skips it.
PR=""
if [ "${CALLGRIND:-1}" != 0 ] && [ "${PROFILE:-1}" != 0 ] && command -v callgrind_annotate >/dev/null 2>&1; then
  PR=$(mktemp); CGO=$(mktemp)
  trap 'rm -f "$TMP" "$CG" "$IS" "$PR" "$CGO"' EXIT
  {
    echo "### Where a library step's instructions go (callgrind, analytic H)"
    echo
    echo "Self instructions per step by function group, from \`valgrind --tool=callgrind --toggle-collect='*run_timed*'"
    echo "vci_bench_throughput --profile SCENE 1 EPISODES\` and \`callgrind_annotate --inclusive=no\` (impact steps included;"
    echo "groups by function name: see tools/bench/run_bench.sh)."
    echo
    echo "The last two columns: the steps with an impact only (\`--profile-steps SCENE 1 EPISODES\`,"
    echo "\`--toggle-collect='*counted_impact_step*'\`), per impact step."
    echo
    echo "| group | ellipse | pendulum | ellipse, impact step | pendulum, impact step |"
    echo "|---|---:|---:|---:|---:|"
    # columns: a regular-step profile (every step of the episodes, impacts included) and an
    # impact-step profile (--profile-steps: only the steps with an impact) per scene
    for spec in ellipse:20:all pendulum:2:all ellipse:20:impact pendulum:2:impact; do
      name=${spec%%:*}; rest=${spec#*:}; eps=${rest%%:*}; kind=${rest#*:}
      if [ "$kind" = all ]; then
        out=$(valgrind --tool=callgrind --callgrind-out-file="$CGO" --toggle-collect='*run_timed*' \
          "$EXE" --profile "$name" 1 "$eps" 2>&1)
        steps=$(( $( [ "$name" = ellipse ] && echo 200 || echo 4999 ) * eps )); col=$name
      else
        out=$(valgrind --tool=callgrind --callgrind-out-file="$CGO" --toggle-collect='*counted_impact_step*' \
          "$EXE" --profile-steps "$name" 1 "$eps" 2>&1)
        steps=$(echo "$out" | awk '$1 == "regular" { print $4 }'); col="$name-impact"
      fi
      callgrind_annotate --inclusive=no --threshold=100 "$CGO" 2>/dev/null | awk -v steps="$steps" -v scene="$col" '
        /:/ && $1 ~ /^[0-9,]+$/ {
          n = $1; gsub(",", "", n); f = $0
          if (f ~ /newton_MOD_(lu_|linear)|kernels_MOD_(small_lu|equilibrate|substep_direction)|dgetr|dgelsd/) g = "4 LU factorisation and solves (incl. row equilibration)"
          else if (f ~ /newton_MOD|kernels_MOD_scaled_merit|MOD_fused_substep/) g = "5 Newton iteration (merit, finiteness, line search, copies)"
          else if (f ~ /scene_|vci_scene/ || f ~ /libm|sincos|s_sin|s_cos/) g = "1 model callbacks (scene code, libm)"
          else if (f ~ /scheme_discrete_MOD_(step_jacobian|fd_column|momentum_block|constraint_block)|fused_jacobian|kernels_MOD_jacobian_sizes|dispatch_jacobian|check_matrix|impulse_jacobian/) g = "3 Jacobian assembly (incl. differenced rows)"
          else if (f ~ /scheme_discrete_MOD_(step_residual|rows|d1s|check_fast)|fused_residual|kernels_MOD_(momentum_terms|kinetic_and_floor|substep_rows)|dispatch_residual|scheme_MOD_check/) g = "2 residual and row scales"
          else if (f ~ /energy_out|momentum_out|impact_momentum|hamiltonian/) g = "6 new momentum and E_d"
          else if (f ~ /gaps|gap_grad/) g = "7 gap tests"
          else if (f ~ /probe|bracket_crossing|energy_gap|energy_along/) g = "8 impact starts (stage 1 bracket, stage 2 energy line)"
          else if (f ~ /stepper_MOD|impacts_MOD|predictor_MOD|state_MOD|integrator_MOD|scheme_MOD|scheme_discrete_MOD/) g = "9 stepper/driver bookkeeping (pose, put/get, copies)"
          else g = "A other (runtime, memcpy)"
          tot[g] += n; all += n
        }
        END { for (g in tot) printf "%s|%s|%.0f\n", scene, g, tot[g] / steps; printf "%s|0 total|%.0f\n", scene, all / steps }'
    done | sort -t'|' -k2,2 | awk -F'|' '
      { v[$2, $1] = $3; if (!($2 in seen)) { seen[$2] = 1; order[++n] = $2 } }
      END { for (i = 1; i <= n; i++) { g = order[i]
              printf "| %s | %s | %s | %s | %s |\n", substr(g, 3), v[g, "ellipse"], v[g, "pendulum"], v[g, "ellipse-impact"], v[g, "pendulum-impact"] } }'
    echo
  } >"$PR"
fi

cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name:[[:space:]]*//p' | head -n 1)
lapack=$(ldd "$EXE" 2>/dev/null | awk '/liblapack|libopenblas|libblas/ {print $3}' | while read -r l; do readlink -f "$l"; done | sort -u | tr '\n' ' ')
libvci=$(ldd "$EXE" 2>/dev/null | awk '/libvci/ {print "shared"}' | head -n 1)
mkdir -p "$(dirname "$OUT")"
{
  echo "# Throughput: library vs hand-specialised loops"
  echo
  echo "Generated by \`tools/bench/run_bench.sh${*:+ $*}\` — do not edit by hand."
  echo
  echo "- date: $(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "- machine: ${cpu:-unknown CPU}, $(nproc 2>/dev/null || echo '?') cores, $(uname -sr)"
  echo "- compiler: $(gfortran --version | head -n 1), CMake Release (-O3)"
  echo "- libvci: ${libvci:-static}; LAPACK/BLAS: ${lapack:-unknown}"
  echo "- commit: $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$ROOT" diff --quiet HEAD 2>/dev/null || echo ' (with uncommitted changes)')"
  echo
  echo "Scenes as in the examples (docs/DESIGN.md §8): particle h = 1e-2 over 3 s, ellipse h = 1e-2 over"
  echo "2 s, pendulum h = 1e-3 over 5 s; each episode starts again from the initial pair. Variants:"
  echo "the library with the model's analytic mixed Hessian, the library differencing it, and the"
  echo "hand loop of bench/hand_loops.f90 (closed-form free flight and impacts for the particle and"
  echo "the ellipse, 3x3 Newton with analytic Jacobian and closed-form impact for the pendulum)."
  echo
  cat "$TMP"
  if [ -n "$CG" ]; then echo; cat "$CG"; fi
  if [ -n "$IS" ]; then cat "$IS"; fi
  if [ -n "$PR" ]; then cat "$PR"; fi
  echo
  echo "### Cost per step against n (FPU-beta chain, midpoint, analytic Hessians)"
  echo
  echo "\`OPENBLAS_NUM_THREADS=1 vci_bench_chain\` (bench/chain.f90): an FPU-beta chain of n unit masses between"
  echo "fixed ends, walls on every particle (2n gaps, not reached), h = 0.05; each row times the step and one"
  echo "dgetrf of a dense n x n matrix in the same process (medians of 5 interleaved repeats). From n = 16 the"
  echo "Newton matrix's factors are reused across steps (simplified Newton, src/core/vci_newton.f90)."
  echo
  OPENBLAS_NUM_THREADS=1 "$BUILD_DIR/bin/vci_bench_chain"
  echo
  echo "The same with OpenBLAS's default threads ($(nproc 2>/dev/null || echo '?') cores, shared):"
  echo
  env -u OPENBLAS_NUM_THREADS "$BUILD_DIR/bin/vci_bench_chain"
} >"$OUT"
cat "$OUT"

# docs/bench/summary.md: the ratios of this run against the targets of issue 14, quoted by
# docs/RESULTS.md (Throughput) through tools/results/make_report.py.
SUMMARY=${SUMMARY:-$(dirname "$OUT")/summary.md}
awk -v cmd="tools/bench/run_bench.sh${*:+ $*}" '
  function t(x) { gsub(/^ +| +$/, "", x); return x }
  /^### / { sec = $0 }
  sec ~ /Time per step/ && $0 ~ /^\| (ellipse|pendulum) \|/ {
    split($0, f, "|"); sc = t(f[2]); v = t(f[4])
    if (v == "library, analytic H") { ns[sc] = t(f[5]); same_t[sc] = t(f[10]); cf_t[sc] = t(f[9]) } }
  sec ~ /Instructions per step/ && $0 ~ /^\| (ellipse|pendulum) \|/ {
    split($0, f, "|"); sc = t(f[2]); ir[sc] = t(f[3]); irs[sc] = t(f[6]); same_i[sc] = t(f[8]); cf_i[sc] = t(f[7]); gen[sc] = t(f[10]) }
  sec ~ /Regular and impact/ && $0 ~ /^\| (ellipse|pendulum) \| library, analytic H/ {
    split($0, f, "|"); imp[t(f[2])] = t(f[8]) }
  sec ~ /Impact and regular steps in instructions/ && $0 ~ /^\| (ellipse|pendulum) \|/ {
    split($0, f, "|"); impi[t(f[2])] = t(f[7]) }
  sec ~ /Cost per step against n/ && $0 ~ /^\| 128 \|/ && !chain { split($0, f, "|"); chain = t(f[8]) }
  sec ~ /Where a library step/ && $0 ~ /^\| model callbacks/ { split($0, f, "|"); cb["ellipse"] = t(f[3]); cb["pendulum"] = t(f[4]) }
  END {
    print ""
    print "Command: `" cmd "` (Release build; writes [`docs/bench/throughput.md`](bench/throughput.md) with the"
    print "machine, compiler, LAPACK and commit, the full tables and the profile; this section quotes that run)."
    print ""
    print "Regular steps of the examples'"'"' scenes through the library (analytic Hessian), against a hand loop doing"
    print "the same algorithm (bench/same_loops.f90: the same predictor, Newton, convergence test, polish, gap test"
    print "and E_d, written for one scene) and against the closed-form loops (bench/hand_loops.f90, the floor):"
    print ""
    print "| scene | ns/step | instructions/step | vs same algorithm: time | instructions | vs closed form: time | instructions | impact step / regular step: time | instructions |"
    print "|---|---:|---:|---:|---:|---:|---:|---:|---:|"
    for (i = 1; i <= 2; i++) { sc = (i == 1) ? "ellipse" : "pendulum"
      printf "| %s | %s | %s | %sx | %sx | %sx | %sx | %sx | %sx |\n", sc, ns[sc], ir[sc], same_t[sc], same_i[sc], cf_t[sc], cf_i[sc], imp[sc], impi[sc] }
    print ""
    print "Targets of issue 14: a regular step within 1.5x the same-algorithm loop (**missed**: " same_t["ellipse"] "x / " same_t["pendulum"] "x"
    print "in time, " same_i["ellipse"] "x / " same_i["pendulum"] "x in instructions), within 3x the closed-form ellipse loop (**missed**: " cf_t["ellipse"] "x), an impact"
    lab_i = (impi["ellipse"] + 0 <= 10 && impi["pendulum"] + 0 <= 10) ? "**met**" : "**missed**"
    lab_t = (imp["ellipse"] + 0 <= 10 && imp["pendulum"] + 0 <= 10) ? "**met**" : "**missed**"
    print "step within 10x a regular step (in instructions " lab_i ": " impi["ellipse"] "x / " impi["pendulum"] "x; in time " lab_t ": " imp["ellipse"] "x / " imp["pendulum"] "x), and at n = 128 a step within 2x one LU"
    print "factorisation (**met**: " chain "x, FPU chain, simplified Newton)."
    print ""
    print "Why the regular-step targets are missed (profile table of docs/bench/throughput.md): the regular step'"'"'s"
    print "solve is already fused (src/schemes/vci_scheme_discrete_fused.f90: the same algorithm in one routine on the"
    print "scheme'"'"'s storage, without the generic layers), which took the ellipse from " gen["ellipse"] " to " ir["ellipse"] " and the pendulum"
    print "from " gen["pendulum"] " to " ir["pendulum"] " instructions a step (same run, `VCI_BENCH_GENERAL=1`). What is left is no single"
    print "layer: the model'"'"'s callbacks (reached through the type-bound interface with array descriptors, each"
    print "recomputing its sines and cosines) cost " cb["ellipse"] " / " cb["pendulum"] " instructions a step,"
    printf "%.2fx / %.2fx the whole same-algorithm step, and the library'"'"'s own code adds %.1fx / %.1fx of it,\n", cb["ellipse"] / irs["ellipse"], cb["pendulum"] / irs["pendulum"], (ir["ellipse"] - cb["ellipse"]) / irs["ellipse"], (ir["pendulum"] - cb["pendulum"]) / irs["pendulum"]
    print "spread over some twenty routines of 50 to 300 instructions a call whose loops run over n = 2 or 3"
    print "with sizes known only at run time (the hand loop'"'"'s are constants, unrolled and inlined). With one"
    print "callback per quantity, 1.5x is out of reach for the pendulum whatever the library costs; closing the"
    print "rest would take code compiled for each small n and a fused model callback (an interface change)."
  }' "$OUT" >"$SUMMARY"
{
  echo
  echo "### Targets of issue 14"
  echo
  sed -n '/^Targets of issue 14/,$p' "$SUMMARY" | sed 's/^Targets of issue 14: //'
  echo
  echo "In detail, from the profile table above. Done in issue 14: the quadratic predictor, the hot loops as"
  echo "explicit-shape kernels (src/core/vci_kernels.f90), the model's constraint Jacobian instead of differences,"
  echo "one finiteness test per matrix, no per-step blanking of message buffers, no heap temporaries (test"
  echo "alloc_free), and the fused regular-step solve (the instruction table's last columns: what it leaves of"
  echo "the general path). The remaining cost per step is spread: the callbacks, the residual's kernels (row"
  echo "terms, sizes, the kinetic term |J||x - a| and the round-off floor), the LU with its equilibration, the"
  echo "new momentum and E_d, the gap test, and the stepper and driver (posing the sub-problem, copies of the"
  echo "state); each routine costs 50 to 300 instructions a call at n = 3, mostly loop and call overhead that"
  echo "a loop written for one n does not have."
  echo
  echo "An impact step (the profile's last two columns) is the regular step that found the wall, then"
  echo "Newton solves on the general path: stage 1 (alpha, b on the wall) from the chord's crossing,"
  echo "bracketed by 7 samples and Illinois steps on the gap (was 20 bisections), its alpha column"
  echo "differenced without the gap row; stage 2 (the reflection) from the linearised reflection, its"
  echo "sensitivity solved with the factors the fused solve of the no-impulse sub-step kept, then moved"
  echo "towards E_d = E- by secant steps on the impulse line (one Newton iteration where the mirror took"
  echo "three on the ellipse), with its differenced E_d row; the checks that the motion departs from and"
  echo "leaves the wall; the impact record. Before these changes (commit 21b4a64, the same callgrind"
  echo "commands) an impact step cost 79352 (ellipse) / 80639 (pendulum) instructions, 14.5x / 8.5x a"
  echo "regular step. What is left is spread like a regular step's cost, over the general path's layers"
  echo "(residual rows, Jacobian assembly, LU, bookkeeping), for three Newton solves: stage 1 takes 3"
  echo "iterations on the ellipse (2 on the pendulum) from its chord start, O(h^2) off the trajectory; a"
  echo "start on the parabola through the previous point (exact for the ellipse's flight: one iteration)"
  echo "was tried and dropped for its failures at tangential touches (docs/DESIGN.md §6). In time an"
  echo "impact step also pays for code that regular steps leave cold (one step in 100 on the ellipse, in"
  echo "1700 on the pendulum): its time ratio is above its instruction ratio and moves between runs."
} >>"$OUT"
BUILD_DIR="$BUILD_DIR" sh "$ROOT/tools/bench/run_chain.sh" || status=$?   # the chain's impact steps (docs/bench/chain.md)
if [ "$status" -ne 0 ]; then
  echo "run_bench.sh: benchmark failed (status $status); see the trajectory check in $OUT" >&2
fi
exit "$status"
