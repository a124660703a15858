#!/usr/bin/python3
"""Cost of the Python package against the C client, on the same run: the walled pendulum
(theta'' = -9.8 sin theta, walls at +-1 rad, theta(0) = 0, theta'(0) = 4), lobatto s = 4,
h = 0.05, Newton rtol 1e-15.

  C         bench/python/pendulum_walls.c through vci.h (compiled here with cc -O3)
  formula   vci.formula.lagrangian_model (sympy -> numba cfuncs), Integrator.integrate
  numba     hand-written numba cfuncs
  python    Python callables (cffi callbacks); a shorter run, compared per step
  formula-python   the formula's generated code run by the interpreter (backend="python")

Each timing is of the library's integrate call alone (model building, numba compilation and
integrator creation are timed apart), the best over REPEATS rounds that run every path once each. The runs' final states are compared with
the C client's, so the ratios are of the same computation.

Usage: /usr/bin/python3 bench/python/bench_python.py [--steps N] [--repeats R] [--callgrind]
  --callgrind: also count the instructions of the integrate call of the C and the formula runs
  (min(steps, 2000) steps; callgrind: --toggle-collect=vci_integrate for C; for Python, client
  requests around Integrator.integrate from a small shim library, so that numba compiles
  uninstrumented).
Environment: VCI_LIBRARY (default build/src/libvci.so).
"""
import argparse
import glob
import math
import os
import re
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, os.pardir, os.pardir))
sys.path.insert(0, os.path.join(REPO, "python"))
os.environ.setdefault("VCI_LIBRARY", os.path.join(REPO, "build", "src", "libvci.so"))

H, STAGES, RTOL = 0.05, 4, 1e-15


def build_c(tmp):
    exe = os.path.join(tmp, "pendulum_walls_c")
    libdir = os.path.dirname(os.path.abspath(os.environ["VCI_LIBRARY"]))
    subprocess.run(["cc", "-O3", "-std=c11", "-I", os.path.join(REPO, "include"),
                    os.path.join(HERE, "pendulum_walls.c"), "-o", exe, "-L", libdir, "-lvci", "-lm",
                    f"-Wl,-rpath,{libdir}"], check=True)
    return exe


def run_c(exe, steps, repeats, prefix=()):
    out = subprocess.run([*prefix, exe, str(steps), str(repeats)], check=True, capture_output=True, text=True)
    lines = out.stdout.split("\n")
    best = float(lines[0])
    t, q, p, imp = lines[1].split()
    return best, (float(t), float(q), float(p), int(imp)), out.stderr


def timed(model, steps, repeats):
    import vci
    best = math.inf
    for _ in range(repeats):
        it = vci.Integrator(model, H, scheme="lobatto", stages=STAGES, rtol=RTOL)
        it.init_from_momentum(0.0, [0.0], [4.0])
        t0 = time.perf_counter()
        st = it.integrate(steps)
        best = min(best, time.perf_counter() - t0)
    return best, (st.t, st.q[0], st.p[0], it.stats.impacts)


def python_model():
    import vci
    g = 9.8
    return vci.LagrangianModel(
        1, 0, 2,
        lagrangian=lambda q, v: 0.5 * v[0] ** 2 + g * math.cos(q[0]),
        dl_dq=lambda q, v: [-g * math.sin(q[0])],
        dl_dv=lambda q, v: [v[0]],
        hessians=lambda q, v: ([[-g * math.cos(q[0])]], [[0.0]], [[1.0]]),
        gaps=lambda q: [1.0 - q[0], q[0] + 1.0],
        gap_gradients=lambda q: [[-1.0], [1.0]])


def formula_model(backend="numba"):
    import sympy as sp
    import vci.formula
    th, om = sp.symbols("theta omega")
    return vci.formula.lagrangian_model(om ** 2 / 2 + 9.8 * sp.cos(th), [th], [om], gaps=[1 - th, th + 1],
                                        backend=backend)


def numba_model():
    sys.path.insert(0, os.path.join(REPO, "python", "tests"))
    import models  # the hand-written cfuncs of the tests
    return models.walls_numba()


SHIM = r"""
#include <valgrind/callgrind.h>
void vci_bench_cg_start(void) { CALLGRIND_START_INSTRUMENTATION; }
void vci_bench_cg_stop(void) { CALLGRIND_STOP_INSTRUMENTATION; }
"""


def build_shim(tmp):
    """A library whose two functions switch callgrind's instrumentation on and off (valgrind's
    client requests; no-ops outside valgrind): the Python process is instrumented only around its
    integrate call, so that numba's compilation runs at (valgrind's) native speed."""
    src = os.path.join(tmp, "cgshim.c")
    with open(src, "w") as f:
        f.write(SHIM)
    so = os.path.join(tmp, "libcgshim.so")
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", src, "-o", so], check=True)
    return so


def callgrind_ir(cmd, tmp, tag, toggle):
    """Instructions callgrind counts: inside vci_integrate (toggle=True: --toggle-collect), or
    between the shim's start and stop (the Python child)."""
    # one file per process (%p): a Python process forks helpers, whose files would overwrite its own
    out = os.path.join(tmp, f"callgrind.{tag}.%p")
    opts = ["--collect-atstart=no", "--toggle-collect=vci_integrate"] if toggle else ["--instr-atstart=no"]
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *opts, *cmd], check=True,
                   capture_output=True, text=True, env=dict(os.environ, PYTHONPATH=os.path.join(REPO, "python")))
    counts = []
    for name in glob.glob(os.path.join(tmp, f"callgrind.{tag}.*")):
        text = open(name).read()
        # "totals:" (at the end) is the count; "summary:" in the header stays 0 with --instr-atstart=no
        m = re.search(r"^totals:\s+(\d+)", text, flags=re.M) or re.search(r"^summary:\s+(\d+)", text, flags=re.M)
        counts.append(int(m.group(1)) if m else 0)
    return max(counts)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("--python-steps", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--callgrind", action="store_true")
    ap.add_argument("--one", choices=["formula", "python"], help=argparse.SUPPRESS)  # the callgrind child
    ap.add_argument("--shim", help=argparse.SUPPRESS)
    args = ap.parse_args()

    if args.one:  # under callgrind: instrument the integrate call only
        import ctypes
        import vci
        shim = ctypes.CDLL(args.shim)
        m = formula_model() if args.one == "formula" else python_model()
        it = vci.Integrator(m, H, scheme="lobatto", stages=STAGES, rtol=RTOL)
        it.init_from_momentum(0.0, [0.0], [4.0])
        shim.vci_bench_cg_start()
        it.integrate(args.steps)
        shim.vci_bench_cg_stop()
        return

    import vci
    print(f"libvci: {vci.library_path}")
    print(f"run: walled pendulum, lobatto s = {STAGES}, h = {H}, rtol = {RTOL}, {args.steps} steps "
          f"(t = {args.steps * H:g} s), best of {args.repeats} rounds (Python callables: {max(1, args.repeats // 3)})")
    with tempfile.TemporaryDirectory() as tmp:
        exe = build_c(tmp)
        t0 = time.perf_counter()
        fm = formula_model()
        build_formula = time.perf_counter() - t0
        t0 = time.perf_counter()
        nm = numba_model()
        build_numba = time.perf_counter() - t0
        pm = python_model()
        t0 = time.perf_counter()
        fpm = formula_model("python")
        build_fp = time.perf_counter() - t0
        ps = args.python_steps

        # rounds: every path once a round, best over the rounds (on a shared machine a quiet
        # moment then favours none of them)
        best = {}

        def keep(key, result):
            if key not in best or result[0] < best[key][0]:
                best[key] = result

        for r in range(args.repeats):
            keep("c", run_c(exe, args.steps, 1)[:2])
            keep("formula", timed(fm, args.steps, 1))
            keep("numba", timed(nm, args.steps, 1))
            keep("c_short", run_c(exe, ps, 1)[:2])
            keep("formula_python", timed(fpm, ps, 1))
            if r < max(1, args.repeats // 3):
                keep("python", timed(pm, ps, 1))
        c_time, c_state = best["c"]
        c_short, c_short_state = best["c_short"]
        rows = [("C (vci.h, cc -O3)", c_time, c_state, args.steps, None),
                ("formula (sympy -> numba)", *best["formula"], args.steps, build_formula),
                ("numba cfuncs by hand", *best["numba"], args.steps, build_numba),
                ("C, short run", c_short, c_short_state, ps, None),
                ("Python callables", *best["python"], ps, 0.0),
                ("formula, backend='python'", *best["formula_python"], ps, build_fp)]
        f_time, p_time = best["formula"][0], best["python"][0]

        print(f"{'path':28s} {'steps':>6s} {'seconds':>10s} {'us/step':>9s} {'x C':>8s} {'build s':>8s}  final state - C's")
        per_step_c = c_time / args.steps
        for name, sec, state, steps, build in rows:
            ref_state = c_state if steps == args.steps else c_short_state
            diff = max(abs(state[1] - ref_state[1]), abs(state[2] - ref_state[2]))
            same = state[3] == ref_state[3] and state[0] == ref_state[0]
            b = "" if build is None else f"{build:8.2f}"
            # "x C": time a step over the long C run's time a step (a short run is too short to time well)
            print(f"{name:28s} {steps:6d} {sec:10.4f} {1e6 * sec / steps:9.2f} {sec / steps / per_step_c:8.2f} {b:>8s}  "
                  f"{diff:.1e}{'' if same else ' (impacts or t differ!)'}")
        print(f"formula / C = {f_time / c_time:.2f} (target <= 1.5)")
        print(f"Python callables / C = {p_time / ps / per_step_c:.1f} a step")

        if args.callgrind:
            shim = build_shim(tmp)
            me = [sys.executable, os.path.abspath(__file__)]
            for tag, steps in (("formula", min(args.steps, 2000)), ("python", min(args.python_steps, 200))):
                ir_c = callgrind_ir([exe, str(steps), "1"], tmp, f"c{steps}", toggle=True)
                ir_x = callgrind_ir([*me, "--one", tag, "--steps", str(steps), "--shim", shim], tmp, tag, toggle=False)
                print(f"callgrind, {steps} steps, instructions of the integrate call: C {ir_c} ({ir_c / steps:.0f} a step), "
                      f"{tag} {ir_x} ({ir_x / steps:.0f} a step), ratio {ir_x / ir_c:.3f}")

if __name__ == "__main__":
    main()
