#!/usr/bin/python3
"""The SciPy peers on the results scenes: solve_ivp (DOP853, Radau) with a terminal event on the
gap and the elastic impact map applied between restarts, the way a user would write it. The
walled pendulum and the FPU chain have several walls: one terminal event per wall (2 and 2n),
and the impact map of the wall whose event fired. (One event on the smallest gap does not work:
after a reflection that gap starts at zero, and a step that reaches another wall makes SciPy's
root search return the restart time itself.)

    peers_scipy.py sweep REFERENCE.json OUT.csv              tolerance sweep rtol = atol = 1e-3..1e-13
    peers_scipy.py long SCENE OUTDIR METHOD RTOL T_END       long run: |E - E0| per 10 s window

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
PW_L, PW_WALL, PW_OMEGA0 = 1.0, 1.0, 4.0           # walled pendulum (vci_results_common.f90)
FPU_N, FPU_BETA, FPU_W = 32, 1.0, 0.6               # FPU-beta chain between walls
T_FINAL = {"particle": 3.0, "ellipse": 3.0, "pendulum": 5.0, "pendulum_walls": 10.0, "fpu_walls": 2.0}
SCENES = ("particle", "ellipse", "pendulum", "pendulum_walls", "fpu_walls")
# The ellipse's flight is a polynomial: without a bound the steps grow until a short dip of the
# gap (y - phi(theta) oscillates with the spin) could be stepped over unseen. Same bound as CVODE.
MAX_STEP = {"particle": math.inf, "ellipse": 0.05, "pendulum": math.inf, "pendulum_walls": math.inf,
            "fpu_walls": math.inf}


def initial(scene):
    if scene == "particle":
        return np.array([0.0, 1.0, 1.0, 0.0])
    if scene == "ellipse":
        return np.array([math.pi / 2, 0.0, 3.5, -3.0, 2.0, 0.0])
    if scene == "pendulum_walls":
        return np.array([0.0, PW_OMEGA0])
    if scene == "fpu_walls":
        i = np.arange(1, FPU_N + 1)
        x0 = 0.4 * FPU_W * np.sin(2 * math.pi * i / (FPU_N + 1))
        v0 = 1.2 * np.sin(3 * math.pi * i / (FPU_N + 1)) + 0.8 * np.sin(math.pi * i / (FPU_N + 1))
        return np.concatenate([x0, v0])
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


def rhs_pendulum_walls(t, y):
    return [y[1], -(G / PW_L) * math.sin(y[0])]


def fpu_stretches(x):
    """Stretches r_0..r_n of x (n values, or n x k columns of states)."""
    z = np.zeros((1,) + x.shape[1:])
    return np.diff(np.concatenate((z, x, z)), axis=0)


def rhs_fpu(t, y):
    x = y[:FPU_N]
    r = fpu_stretches(x)
    f = r + FPU_BETA * r ** 3
    return np.concatenate([y[FPU_N:], f[1:] - f[:-1]])


def phi(th):
    return math.sqrt((A * math.sin(th)) ** 2 + (B * math.cos(th)) ** 2)


def gap_particle(t, y):
    return y[1]


def gap_ellipse(t, y):
    return y[2] - phi(y[0])


def gap_pendulum(t, y):
    return RAD * RAD - (ELL * math.sin(y[0])) ** 2


def wall_event(i, sign, w):
    """Gap w - sign * x_i of one wall."""
    def gap(t, y):
        return w - sign * y[i]
    return gap


GAPS_PWALLS = [wall_event(0, 1.0, PW_WALL), wall_event(0, -1.0, PW_WALL)]
GAPS_FPU = [wall_event(i, s, FPU_W) for s in (1.0, -1.0) for i in range(FPU_N)]

for _g in [gap_particle, gap_ellipse, gap_pendulum] + GAPS_PWALLS + GAPS_FPU:
    _g.terminal = True
    _g.direction = -1


def impact(scene, y, k=0):
    """Impact map at wall k (the index of the event that fired)."""
    y = y.copy()
    if scene == "particle":
        y[3] = -y[3]
    elif scene == "pendulum_walls":
        y[1] = -y[1]
    elif scene == "fpu_walls":
        i = k % FPU_N
        y[FPU_N + i] = -y[FPU_N + i]     # unit masses, normal e_i: v_i reverses
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
    if scene == "pendulum_walls":
        return 0.5 * M * PW_L ** 2 * y[1] ** 2 - M * G * PW_L * np.cos(y[0])
    if scene == "fpu_walls":
        r = fpu_stretches(y[:FPU_N])
        return 0.5 * np.sum(y[FPU_N:] ** 2, axis=0) + np.sum(0.5 * r ** 2 + 0.25 * FPU_BETA * r ** 4, axis=0)
    th, thd = y[0], y[2]
    f = math.pi + np.cos(th) ** 2
    return 0.5 * ML2 * (1 + (f * np.sin(th)) ** 2) * thd ** 2 + M * G * ELL * np.cos(th)


RHS = {"particle": rhs_particle, "ellipse": rhs_ellipse, "pendulum": rhs_pendulum,
       "pendulum_walls": rhs_pendulum_walls, "fpu_walls": rhs_fpu}
GAP = {"particle": gap_particle, "ellipse": gap_ellipse, "pendulum": gap_pendulum,
       "pendulum_walls": GAPS_PWALLS, "fpu_walls": GAPS_FPU}


def fired(sol):
    """(time, state, wall index) of the terminal event that stopped solve_ivp."""
    k = next(i for i, te in enumerate(sol.t_events) if te.size)
    return sol.t_events[k][0], sol.y_events[k][0], k


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
        t, ye, k = fired(sol)
        y = impact(scene, ye, k)
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
        for scene in SCENES:
            r = ref[scene]
            qref, tref, e0 = np.array(r["q"]), np.array(r["impact_times"]), r["e0"]
            nq = qref.size
            for method in ("DOP853", "Radau"):
                # Radau (implicit, slowest in Python) at every other tolerance: the time budget
                for k in (range(3, 14) if method == "DOP853" else range(3, 14, 2)):
                    tol = 10.0 ** -k
                    (yf, times, chunks, steps, ok), wall, cpu, reps = timed(scene, method, tol)
                    if not ok:
                        w.writerow([scene, "scipy-" + method.lower(), f"{tol:.3e}"] + ["nan"] * 9 + [1])
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


def long_run(scene, outdir, method, tol, t_end):
    """A long run: |E - E0| (largest in each 10 s window) and the run's cost."""
    e0 = float(energy(scene, initial(scene)[:, None])[0])
    w0, c0 = time.perf_counter(), time.process_time()
    t, y = 0.0, initial(scene)
    n_imp, steps, ok = 0, 0, True
    window = 10.0
    nbins = int(math.ceil(t_end / window))
    binmax = np.zeros(nbins)
    while True:
        sol = solve_ivp(RHS[scene], (t, t_end), y, method=method, rtol=tol, atol=tol,
                        max_step=MAX_STEP[scene], events=GAP[scene])
        steps += sol.t.size - 1
        err = np.abs(energy(scene, sol.y) - e0)
        idx = np.minimum((sol.t // window).astype(int), nbins - 1)
        np.maximum.at(binmax, idx, err)
        if sol.status != 1:
            ok = sol.status == 0
            break
        t, ye, k = fired(sol)
        y = impact(scene, ye, k)
        n_imp += 1
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    name = "scipy-" + method.lower()
    tag = f"{tol:.1e}"
    with open(f"{outdir}/long_{scene}_{name}_{tag}.csv", "w") as fh:
        fh.write("t,energy_error\n")
        for i, e in enumerate(binmax):
            fh.write(f"{window * (i + 1):.7e},{e:.5e}\n")
    with open(f"{outdir}/long_{scene}_{name}_{tag}_summary.csv", "w") as fh:
        fh.write("scene,method,param,wall,cpu,max_energy_error,final_energy_error,n_impacts,t_end,status\n")
        fh.write(f"{scene},{name},{tol:.3e},{wall:.5e},{cpu:.5e},{binmax.max():.5e},{binmax[-1]:.5e},"
                 f"{n_imp},{t_end:.7e},{0 if ok else 1}\n")
    print(f"scipy long run: {scene} {name} rtol {tag}: {cpu:.1f} s CPU, {n_imp} impacts, "
          f"max |dE| {binmax.max():.3e}", flush=True)


if __name__ == "__main__":
    if len(sys.argv) >= 4 and sys.argv[1] == "sweep":
        sweep(sys.argv[2], sys.argv[3])
    elif len(sys.argv) >= 7 and sys.argv[1] == "long":
        long_run(sys.argv[2], sys.argv[3], sys.argv[4], float(sys.argv[5]), float(sys.argv[6]))
    else:
        sys.exit(__doc__)
