#!/usr/bin/python3
"""The SciPy peers on the three scenes: solve_ivp (DOP853, Radau) with a terminal event on the
gap and the elastic impact map applied between restarts, the way a user would write it.

    peers_scipy.py sweep REFERENCE.json OUT.csv        tolerance sweep rtol = atol = 1e-3..1e-12
    peers_scipy.py long OUTDIR METHOD RTOL [T_END]     ellipse over 1e4 s: |E - E0| per second

Error measures as in vci_results_common.f90: max-norm configuration error at the final time
against the reference (written by vci_results_driver), largest |E - E0| over the solver's steps
(E0 exact), largest distance from a reference impact time to the nearest impact time found.
Timing: the integration loop only (wall: perf_counter, CPU: process_time), median of repeats;
energies are evaluated afterwards from the stored steps.
"""
import csv
import json
import math
import statistics
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

G, M = 9.8, 1.0
A, B = 1.0, 0.5
INERTIA = M * (A * A + B * B) / 4
ELL, RAD = 2.0, 1.5
ML2 = M * ELL * ELL
T_FINAL = {"particle": 3.0, "ellipse": 3.0, "pendulum": 5.0}
# The ellipse's flight is a polynomial: without a bound the steps grow until a short dip of the
# gap (y - phi(theta) oscillates with the spin) could be stepped over unseen. Same bound as CVODE.
MAX_STEP = {"particle": math.inf, "ellipse": 0.05, "pendulum": math.inf}


def initial(scene):
    if scene == "particle":
        return np.array([0.0, 1.0, 1.0, 0.0])
    if scene == "ellipse":
        return np.array([math.pi / 2, 0.0, 3.5, -3.0, 2.0, 0.0])
    th0, thd0 = 0.75 * math.pi, math.pi / 4
    return np.array([th0, 0.0, thd0, (math.pi + math.cos(th0) ** 2) * thd0])


def rhs_particle(t, y):
    return [y[2], y[3], 0.0, -G]


def rhs_ellipse(t, y):
    return [y[3], y[4], y[5], 0.0, 0.0, -G]


def rhs_pendulum(t, y):
    # Lagrange-d'Alembert with the multiplier of omega = f dtheta - dphi eliminated (closed form of
    # the 3x3 system in tools/reference/references.py; same as the CVODE peer).
    th, _, thd, phd = y
    s, c = math.sin(th), math.cos(th)
    f = math.pi + c * c
    df = -2 * s * c
    r1 = ML2 * phd * phd * s * c + M * G * ELL * s
    r2 = -2 * ML2 * s * c * thd * phd
    thdd = (r2 - ML2 * s * s * df * thd * thd + r1 / f) / (ML2 * (s * s * f + 1 / f))
    return [thd, phd, thdd, f * thdd + df * thd * thd]


def phi(th):
    return math.sqrt((A * math.sin(th)) ** 2 + (B * math.cos(th)) ** 2)


def gap_particle(t, y):
    return y[1]


def gap_ellipse(t, y):
    return y[2] - phi(y[0])


def gap_pendulum(t, y):
    return RAD * RAD - (ELL * math.sin(y[0])) ** 2


for _g in (gap_particle, gap_ellipse, gap_pendulum):
    _g.terminal = True
    _g.direction = -1


def impact(scene, y):
    y = y.copy()
    if scene == "particle":
        y[3] = -y[3]
    elif scene == "ellipse":
        th = y[0]
        n = np.array([-(A * A - B * B) * math.sin(th) * math.cos(th) / phi(th), 0.0, 1.0])
        minv = np.array([1 / INERTIA, 1 / M, 1 / M])
        mu = -2 * (n @ y[3:]) / (n @ (minv * n))
        y[3:] += mu * minv * n
    else:
        y[2:] = -y[2:]      # the velocity on the constraint that keeps the energy
    return y


def energy(scene, y):
    """Energy along an array of states (columns)."""
    if scene == "particle":
        return 0.5 * M * (y[2] ** 2 + y[3] ** 2) + M * G * y[1]
    if scene == "ellipse":
        return 0.5 * (INERTIA * y[3] ** 2 + M * (y[4] ** 2 + y[5] ** 2)) + M * G * y[2]
    th, thd = y[0], y[2]
    f = math.pi + np.cos(th) ** 2
    return 0.5 * ML2 * (1 + (f * np.sin(th)) ** 2) * thd ** 2 + M * G * ELL * np.cos(th)


RHS = {"particle": rhs_particle, "ellipse": rhs_ellipse, "pendulum": rhs_pendulum}
GAP = {"particle": gap_particle, "ellipse": gap_ellipse, "pendulum": gap_pendulum}


def run(scene, method, tol, t_end):
    """One event-driven run. Returns (final state, impact times, list of step arrays, steps, ok)."""
    t, y = 0.0, initial(scene)
    times, chunks, steps = [], [], 0
    while True:
        sol = solve_ivp(RHS[scene], (t, t_end), y, method=method, rtol=tol, atol=tol,
                        max_step=MAX_STEP[scene], events=GAP[scene])
        chunks.append(sol.y)
        steps += sol.t.size - 1
        if sol.status == -1:
            return sol.y[:, -1], times, chunks, steps, False
        if sol.status != 1:
            return sol.y[:, -1], times, chunks, steps, True
        t = sol.t_events[0][0]
        y = impact(scene, sol.y_events[0][0])
        times.append(t)


def timed(scene, method, tol):
    walls, cpus = [], []
    while True:
        w0, c0 = time.perf_counter(), time.process_time()
        out = run(scene, method, tol, T_FINAL[scene])
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
        n, total = len(walls), sum(walls)
        if not out[4] or (n >= 3 and total > 2.0) or (n >= 5 and total > 0.5) or n >= 9:
            return out, statistics.median(walls), statistics.median(cpus), n


def sweep(ref_path, out_path):
    with open(ref_path) as fh:
        ref = json.load(fh)
    fields = ["scene", "method", "param", "wall_median", "cpu_median", "reps", "err_final",
              "err_energy", "err_impact", "n_impacts", "n_ref_impacts", "steps", "status"]
    with open(out_path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(fields)
        for scene in ("particle", "ellipse", "pendulum"):
            r = ref[scene]
            qref, tref, e0 = np.array(r["q"]), np.array(r["impact_times"]), r["e0"]
            nq = qref.size
            for method in ("DOP853", "Radau"):
                for k in range(3, 13):
                    tol = 10.0 ** -k
                    (yf, times, chunks, steps, ok), wall, cpu, reps = timed(scene, method, tol)
                    if not ok:
                        w.writerow([scene, "scipy-" + method.lower(), f"{tol:.3e}"] + ["nan"] * 10 + [1])
                        continue
                    err_final = float(np.max(np.abs(yf[:nq] - qref)))
                    err_energy = max(float(np.max(np.abs(energy(scene, c) - e0))) for c in chunks)
                    got = np.array(times)
                    err_imp = (max(float(np.min(np.abs(got - ti))) for ti in tref)
                               if got.size else math.inf) if tref.size else 0.0
                    w.writerow([scene, "scipy-" + method.lower(), f"{tol:.3e}", f"{wall:.5e}",
                                f"{cpu:.5e}", reps, f"{err_final:.5e}", f"{err_energy:.5e}",
                                f"{err_imp:.5e}", len(times), tref.size, steps, 0])
                    fh.flush()
            print(f"scipy sweep: {scene} done", flush=True)


def long_run(outdir, method, tol, t_end=1.0e4):
    """The ellipse over t_end: |E - E0| (largest in each second) and the run's cost."""
    scene = "ellipse"
    e0 = float(energy(scene, initial(scene)[:, None])[0])
    w0, c0 = time.perf_counter(), time.process_time()
    t, y = 0.0, initial(scene)
    n_imp, steps, ok = 0, 0, True
    nbins = int(math.ceil(t_end))
    binmax = np.zeros(nbins)
    while True:
        sol = solve_ivp(RHS[scene], (t, t_end), y, method=method, rtol=tol, atol=tol,
                        max_step=MAX_STEP[scene], events=GAP[scene])
        steps += sol.t.size - 1
        err = np.abs(energy(scene, sol.y) - e0)
        idx = np.minimum((sol.t // 1.0).astype(int), nbins - 1)
        np.maximum.at(binmax, idx, err)
        if sol.status != 1:
            ok = sol.status == 0
            break
        t = sol.t_events[0][0]
        y = impact(scene, sol.y_events[0][0])
        n_imp += 1
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    name = "scipy-" + method.lower()
    tag = f"{tol:.1e}"
    with open(f"{outdir}/long_{name}_{tag}.csv", "w") as fh:
        fh.write("t,energy_error\n")
        for i, e in enumerate(binmax):
            fh.write(f"{i + 1:.7e},{e:.5e}\n")
    with open(f"{outdir}/long_{name}_{tag}_summary.csv", "w") as fh:
        fh.write("method,param,wall,cpu,max_energy_error,final_energy_error,n_impacts,t_end,status\n")
        fh.write(f"{name},{tol:.3e},{wall:.5e},{cpu:.5e},{binmax.max():.5e},{binmax[-1]:.5e},"
                 f"{n_imp},{t:.7e},{0 if ok else 1}\n")
    print(f"scipy long run: {name} rtol {tag}: {wall:.1f} s, max |dE| {binmax.max():.3e}", flush=True)


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "sweep":
        sweep(sys.argv[2], sys.argv[3])
    elif len(sys.argv) >= 5 and sys.argv[1] == "long":
        long_run(sys.argv[2], sys.argv[3], float(sys.argv[4]),
                 float(sys.argv[5]) if len(sys.argv) > 5 else 1.0e4)
    else:
        sys.exit(__doc__)
