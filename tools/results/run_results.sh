#!/bin/sh
# Regenerate docs/RESULTS.md and docs/figures/results_*.png: error against run time of vci and its
# peers (a compiled DOP853 with dense-output events, SUNDIALS CVODE, SciPy solve_ivp (interpreted),
# Siconos) on five scenes (the paper's three, the walled
# pendulum, the FPU chain between walls), every method from the same exact start, and the
# long-time energy of the ellipse and the walled pendulum (>= 10^5 impacts). Installs missing
# Debian packages, builds, runs everything one job at a time (the timings must not compete with
# each other), writes the page. The page states the time the command took (about 40 minutes on a
# 2-core machine shared with other builds; less on an idle one).
#
#   tools/results/run_results.sh
#   tools/results/run_results.sh --scene SCENE [--scene SCENE ...]
#
# With --scene (particle, ellipse, pendulum, pendulum_walls, fpu_walls, fpu_walls_1024) only that scene's compiled
# rows are rerun (vci, the compiled DOP853, CVODE: a few minutes instead of the whole command): they
# replace that scene's rows in the previous full run's output in $VCI_RESULTS_OUT, which must exist,
# and the page is rewritten from it. The SciPy and Siconos rows, the long runs and the profile stay
# from the full run (the profile is rerun with pendulum_walls, the scene it profiles); the page's
# header names every refreshed scene with its date and commit. fpu_walls_1024 is the FPU chain with
# n = 1024 (issue 28): its own reference (quad-precision Taylor, ~1 min) and rows (*_chain1024.csv),
# run at the end of the full command or alone with --scene.
# Environment: VCI_RESULTS_BUILD (build directory, default $TMPDIR/vci-results-build),
# VCI_RESULTS_OUT (raw CSV output, default $VCI_RESULTS_BUILD/out), VCI_RESULTS_BUDGET (seconds for
# the whole command, default 3600: each run gets what is left; a run that exceeds it is stopped and
# the command fails naming it, so a rerun on a slower or busier machine fails clearly, not silently).
set -eu

SCENES_ONLY=""
while [ $# -gt 0 ]; do
  case "$1" in
    --scene)
      [ $# -ge 2 ] || { echo "run_results.sh: --scene needs a scene name" >&2; exit 2; }
      case "$2" in
        particle|ellipse|pendulum|pendulum_walls|fpu_walls|fpu_walls_1024) SCENES_ONLY="$SCENES_ONLY $2" ;;
        *) echo "run_results.sh: unknown scene '$2' (particle, ellipse, pendulum, pendulum_walls, fpu_walls, fpu_walls_1024)" >&2; exit 2 ;;
      esac
      shift 2 ;;
    *) echo "run_results.sh: unknown argument '$1' (usage: run_results.sh [--scene SCENE ...])" >&2; exit 2 ;;
  esac
done

ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${VCI_RESULTS_BUILD:-${TMPDIR:-/tmp}/vci-results-build}
OUT=${VCI_RESULTS_OUT:-$BUILD/out}
PY=/usr/bin/python3
START=$(date +%s)
BUDGET=${VCI_RESULTS_BUDGET:-3600}

# run NAME CMD...: run one phase within what is left of the budget; on failure or timeout say which
# phase, how long it ran and where its messages are, and stop.
run() {
  name=$1; shift
  left=$((BUDGET - ($(date +%s) - START)))
  if [ "$left" -le 0 ]; then
    echo "run_results.sh: time budget of ${BUDGET} s used up before '$name' (set VCI_RESULTS_BUDGET)" >&2
    exit 1
  fi
  t0=$(date +%s)
  rc=0
  timeout "$left" "$@" || rc=$?
  if [ "$rc" -ne 0 ]; then
    if [ "$rc" -eq 124 ]; then
      echo "run_results.sh: '$name' stopped after $(( $(date +%s) - t0 )) s: the time budget of ${BUDGET} s ran out (set VCI_RESULTS_BUDGET)" >&2
    else
      echo "run_results.sh: '$name' failed (exit status $rc after $(( $(date +%s) - t0 )) s; its messages are above, raw output in $OUT)" >&2
    fi
    exit 1
  fi
}
# the FPU chain with n = 1024 (issue 28): reference, vci and CVODE-Adams, each its own file in $OUT
# (make_report.py adds the scene when they exist). Not the compiled DOP853: its event location
# evaluates the whole dense output and every gap at each iteration, written for the small scenes
# (1.3-3 s a run here, CPU; `dop853_results_driver sweep FILE fpu_walls_1024` runs it).
large_chain() {
  echo "== fpu_walls_1024: reference (quad-precision Taylor, checked at half the step)"
  run "reference (fpu_walls_1024)" "$BUILD/vci_results_driver" reference "$OUT/reference_chain1024.json" fpu_walls_1024
  echo "== fpu_walls_1024: vci step-size sweep"
  run "vci sweep (fpu_walls_1024)" sh -c '"$1" sweep "$2" "" fpu_walls_1024 2>"$3"' sh "$BUILD/vci_results_driver" "$OUT/vci_chain1024.csv" "$OUT/vci_chain1024.stderr"
  echo "== fpu_walls_1024: CVODE-Adams tolerance sweep"
  run "CVODE sweep (fpu_walls_1024)" "$BUILD/cvode_results_driver" sweep "$OUT/cvode_chain1024.csv" fpu_walls_1024
}
# single-threaded BLAS for every method: on a shared 2-core machine a threaded LU only adds
# contention (docs/SCHEMES.md, Cost), and CPU time would count both threads
export OPENBLAS_NUM_THREADS=1

# --- Debian packages -------------------------------------------------------------------------
PKGS="gfortran gcc cmake make liblapack-dev python3-numpy python3-scipy python3-matplotlib
      libsundials-dev libsundials-fortran-dev python3-siconos valgrind"
MISSING=""
for p in $PKGS; do
  dpkg -s "$p" >/dev/null 2>&1 || MISSING="$MISSING $p"
done
if [ -n "$MISSING" ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  echo "installing:$MISSING"
  $SUDO apt-get install -y $MISSING || { $SUDO apt-get update && $SUDO apt-get install -y $MISSING; }
fi

# --- build -----------------------------------------------------------------------------------
cmake -S "$ROOT/tools/results" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DVCI_ROOT="$ROOT" >"$BUILD.cmake.log" 2>&1 \
  || { cat "$BUILD.cmake.log"; exit 1; }
cmake --build "$BUILD" -j2 >"$BUILD.build.log" 2>&1 || { tail -40 "$BUILD.build.log"; exit 1; }
[ -x "$BUILD/cvode_results_driver" ] || { echo "CVODE driver not built (see $BUILD.cmake.log)"; exit 1; }
[ -x "$BUILD/dop853_results_driver" ] || { echo "DOP853 driver not built (see $BUILD.build.log)"; exit 1; }

if [ -n "$SCENES_ONLY" ]; then
  for f in vci_sweep.csv dop853_sweep.csv cvode_sweep.csv meta.json reference.json; do
    [ -f "$OUT/$f" ] || { echo "run_results.sh: --scene needs a previous full run's output in $OUT (missing $f): run tools/results/run_results.sh without --scene first, or set VCI_RESULTS_OUT" >&2; exit 1; }
  done
  COMMIT=$(git -C "$ROOT" describe --always --dirty 2>/dev/null || echo "${VCI_RESULTS_COMMIT:-unknown}")
  for scene in $SCENES_ONLY; do
    if [ "$scene" = fpu_walls_1024 ]; then
      t_scene=$(date +%s)
      large_chain
      $PY - "$OUT/meta.json" "$COMMIT" $(( $(date +%s) - t_scene )) "$(cut -d' ' -f1 /proc/loadavg)" <<'PYEOF'
import json, sys, time
path, commit, secs, load = sys.argv[1:5]
meta = json.load(open(path))
entry = {"scene": "fpu_walls_1024", "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
         "commit": commit, "elapsed_s": int(secs), "load": load}
meta["refreshed"] = [e for e in meta.get("refreshed", []) if e["scene"] != "fpu_walls_1024"] + [entry]
json.dump(meta, open(path, "w"), indent=1)
PYEOF
      continue
    fi
    PART="$OUT/part_$scene"
    mkdir -p "$PART"
    t_scene=$(date +%s)
    load0=$(cut -d' ' -f1 /proc/loadavg)
    echo "== $scene: vci step-size sweep"
    run "vci sweep ($scene)" sh -c '"$1" sweep "$2" "" "$3" 2>"$4"' sh "$BUILD/vci_results_driver" "$PART/vci_sweep.csv" "$scene" "$PART/vci_sweep.stderr"
    echo "== $scene: compiled DOP853 tolerance sweep"
    run "DOP853 sweep ($scene)" "$BUILD/dop853_results_driver" sweep "$PART/dop853_sweep.csv" "$scene"
    echo "== $scene: CVODE tolerance sweep"
    run "CVODE sweep ($scene)" "$BUILD/cvode_results_driver" sweep "$PART/cvode_sweep.csv" "$scene"
    if [ "$scene" = pendulum_walls ]; then
      echo "== where the time goes (callgrind, walled pendulum): DOP853 against vci's compositions"
      run "profile (callgrind)" "$ROOT/tools/results/profile_peers.sh" "$BUILD" "$OUT"
    fi
    run "merge ($scene)" $PY "$ROOT/tools/results/merge_scene_rows.py" "$OUT" "$PART" "$scene" "$COMMIT" $(( $(date +%s) - t_scene )) "$load0"
  done
  run "the page (make_report.py)" $PY "$ROOT/tools/results/make_report.py" "$OUT" "$ROOT"
  echo "rewrote $ROOT/docs/RESULTS.md with fresh rows of:$SCENES_ONLY in $(( $(date +%s) - START )) s (raw data: $OUT)"
  exit 0
fi

mkdir -p "$OUT/long"
rm -f "$OUT"/*.csv "$OUT"/*.md "$OUT"/*.txt "$OUT"/long/*.csv

# --- runs ------------------------------------------------------------------------------------
echo "== the compiled DOP853 checked: order 8, dense output order, event times against exact solutions"
run "DOP853 check" sh -c '"$1" check >"$2"; rc=$?; cat "$2"; exit $rc' sh "$BUILD/dop853_results_driver" "$OUT/dop853_check.txt"
echo "== references"
run "references" "$BUILD/vci_results_driver" reference "$OUT/reference.json"
echo "== vci step-size sweep (hand-written L_d, the schemes from L, the explicit compositions)"
run "vci sweep" sh -c '"$1" sweep "$2" 2>"$3"' sh "$BUILD/vci_results_driver" "$OUT/vci_sweep.csv" "$OUT/vci_sweep.stderr"
echo "== pendulum: reference vs Richardson extrapolation of vci"
run "Richardson check" "$BUILD/vci_results_driver" richardson "$OUT/richardson.csv"
echo "== compiled DOP853 tolerance sweep"
run "DOP853 sweep" sh -c '"$1" sweep "$2" 2>"$3"' sh "$BUILD/dop853_results_driver" "$OUT/dop853_sweep.csv" "$OUT/dop853_sweep.stderr"
echo "== CVODE tolerance sweep"
run "CVODE sweep" "$BUILD/cvode_results_driver" sweep "$OUT/cvode_sweep.csv"
echo "== SciPy tolerance sweep"
run "SciPy sweep" $PY "$ROOT/tools/results/peers_scipy.py" sweep "$OUT/reference.json" "$OUT/scipy_sweep.csv"
echo "== Siconos step-size sweep"
run "Siconos sweep" $PY "$ROOT/tools/results/peers_siconos.py" sweep "$OUT/reference.json" "$BUILD" "$OUT/siconos_sweep.csv"
echo "== long runs (>= 10^5 impacts): the ellipse over 1.1e5 s, the walled pendulum over 6e4 s"
for scene in ellipse pendulum_walls; do
  run "vci long run ($scene)" "$BUILD/vci_results_driver" long "$scene" "$OUT/long"
  # BDF (no better than Adams here, and the slowest) only at 1e-6 and 1e-10: the time budget
  for tol in 1e-6 1e-10; do
    run "CVODE long run ($scene, $tol)" "$BUILD/cvode_results_driver" long "$scene" "$OUT/long" $tol
  done
  for tol in 1e-8 1e-12; do
    run "CVODE-Adams long run ($scene, $tol)" "$BUILD/cvode_results_driver" long "$scene" "$OUT/long" $tol adams
  done
  for tol in 1e-8 1e-12; do
    run "DOP853 long run ($scene, $tol)" "$BUILD/dop853_results_driver" long "$scene" "$OUT/long" $tol
  done
done
# SciPy and Siconos pay ~1 ms of Python per impact (restart) or per few steps: over a tenth of the
# horizon (~10^4 impacts), to stay in the time budget; the page says so.
run "SciPy long run (ellipse)" $PY "$ROOT/tools/results/peers_scipy.py" long ellipse "$OUT/long" DOP853 1e-10 1.1e4
run "SciPy long run (pendulum_walls)" $PY "$ROOT/tools/results/peers_scipy.py" long pendulum_walls "$OUT/long" DOP853 1e-10 6e3
run "Siconos long run (ellipse)" $PY "$ROOT/tools/results/peers_siconos.py" long ellipse "$BUILD" "$OUT/long" 1e-2 1.1e4
run "Siconos long run (pendulum_walls)" $PY "$ROOT/tools/results/peers_siconos.py" long pendulum_walls "$BUILD" "$OUT/long" 1e-2 6e3

echo "== where the time goes (callgrind, walled pendulum): DOP853 against vci's compositions"
run "profile (callgrind)" "$ROOT/tools/results/profile_peers.sh" "$BUILD" "$OUT"
large_chain

# --- the page --------------------------------------------------------------------------------
END=$(date +%s)
ver() { dpkg-query -W -f='${Version}' "$1" 2>/dev/null || echo "?"; }
cat >"$OUT/meta.json" <<EOF
{"date": "$(date -u +%Y-%m-%d\ %H:%M\ UTC)", "nproc": $(nproc),
 "cpu": "$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //; s/"//g')",
 "elapsed_s": $((END - START)),
 "commit": "$(git -C "$ROOT" describe --always --dirty 2>/dev/null || echo "${VCI_RESULTS_COMMIT:-unknown}")",
 "sundials": "$(ver libsundials-dev)",
 "versions": "gfortran $(gfortran -dumpfullversion), LAPACK $(ver liblapack3), SUNDIALS $(ver libsundials-dev), SciPy $($PY -c 'import scipy; print(scipy.__version__)'), NumPy $($PY -c 'import numpy; print(numpy.__version__)'), Siconos $(ver python3-siconos)"}
EOF
run "the page (make_report.py)" $PY "$ROOT/tools/results/make_report.py" "$OUT" "$ROOT"
echo "wrote $ROOT/docs/RESULTS.md and $ROOT/docs/figures/results_*.png in $((END - START)) s (raw data: $OUT)"
