#!/usr/bin/python3
"""The Siconos peer (python3-siconos, Debian 12: 4.4.0): Moreau-Jean time stepping (theta = 1/2,
Newton impact law with restitution e = 1, LCP one-step problem) for the particle (a ball on the
floor: linear time-invariant system and relation), the ellipse (nonlinear floor relation from
the C plugin siconos_ellipse_plugin.c, built as EllipsePlugin.so), the walled pendulum and the
FPU chain between walls (nonlinear internal forces from siconos_walls_plugin.c, WallsPlugin.so;
one linear relation per wall). Not the nonholonomic pendulum (not a Siconos relation).

    peers_siconos.py sweep REFERENCE.json PLUGIN_DIR OUT.csv
    peers_siconos.py long SCENE PLUGIN_DIR OUTDIR H T_END    |E - E0| per 10 s window

Impact times: Moreau-Jean applies the impulse over a whole step and does not locate the impact;
a step whose contact impulse is positive (after one that was not) counts as one impact at the
step's midpoint. Errors, timing: as peers_scipy.py.
"""
import csv
import json
import math
import statistics
import sys
import time

import numpy as np
import siconos.kernel as sk

G = 9.8
A, B = 1.0, 0.5
INERTIA = (A * A + B * B) / 4
PW_L, PW_WALL, PW_OMEGA0 = 1.0, 1.0, 4.0           # as vci_results_common.f90
FPU_N, FPU_BETA, FPU_W = 32, 1.0, 0.6
T_FINAL = {"particle": 3.0, "ellipse": 3.0, "pendulum_walls": 10.0, "fpu_walls": 2.0}
STEPS = [1e-1, 5e-2, 2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5]
# first order: the smallest steps cost seconds per run for a decade of error; cut for the time
# budget (the FPU chain has 64 relations, one LCP of that size per step)
# h >= 5e-5 (first order: the smallest steps cost seconds each for little; the time budget)
STEPS_OF = {"particle": [s for s in STEPS if s >= 5e-5], "ellipse": [s for s in STEPS if s >= 5e-5],
            "pendulum_walls": [s for s in STEPS if s >= 5e-5], "fpu_walls": [s for s in STEPS if s >= 5e-4]}


def initial(scene):
    if scene == "pendulum_walls":
        return np.array([0.0]), np.array([PW_OMEGA0])
    i = np.arange(1, FPU_N + 1)
    x0 = 0.4 * FPU_W * np.sin(2 * math.pi * i / (FPU_N + 1))
    v0 = 1.2 * np.sin(3 * math.pi * i / (FPU_N + 1)) + 0.8 * np.sin(math.pi * i / (FPU_N + 1))
    return x0, v0


def build(scene, h, t_end, plugin_dir):
    """Returns the body, its interactions (one per wall) and the simulation."""
    rels = []
    if scene in ("pendulum_walls", "fpu_walls"):
        q0, v0 = initial(scene)
        n = q0.size
        body = sk.LagrangianDS(q0, v0, np.eye(n))   # m l^2 = 1 (pendulum), unit masses (chain)
        plugin = f"{plugin_dir}/WallsPlugin"
        stem = "pendulum" if scene == "pendulum_walls" else "fpu"
        body.setComputeFIntFunction(plugin, f"{stem}_fint")
        body.setComputeJacobianFIntqFunction(plugin, f"{stem}_jacq")
        body.setComputeJacobianFIntqDotFunction(plugin, "zero_jac")
        wall = PW_WALL if scene == "pendulum_walls" else FPU_W
        for i in range(n):
            for sgn in (-1.0, 1.0):             # w - x_i >= 0 and w + x_i >= 0
                row = np.zeros((1, n))
                row[0, i] = sgn
                rels.append(sk.LagrangianLinearTIR(row, np.array([wall])))
    elif scene == "particle":
        body = sk.LagrangianLinearTIDS([0.0, 1.0], [1.0, 0.0], np.eye(2))
        body.setFExtPtr(np.array([0.0, -G]))
        rels.append(sk.LagrangianLinearTIR(np.array([[0.0, 1.0]])))
    else:
        body = sk.LagrangianLinearTIDS([math.pi / 2, 0.0, 3.5], [-3.0, 2.0, 0.0],
                                       np.diag([INERTIA, 1.0, 1.0]))
        body.setFExtPtr(np.array([0.0, 0.0, -G]))
        plugin = f"{plugin_dir}/EllipsePlugin"
        rels.append(sk.LagrangianScleronomousR(f"{plugin}:h", f"{plugin}:G0"))
    nsds = sk.NonSmoothDynamicalSystem(0.0, t_end)
    nsds.insertDynamicalSystem(body)
    inters = []
    for rel in rels:
        inter = sk.Interaction(sk.NewtonImpactNSL(1.0), rel)
        nsds.link(inter, body)
        inters.append(inter)
    sim = sk.TimeStepping(nsds, sk.TimeDiscretisation(0.0, h), sk.MoreauJeanOSI(0.5), sk.LCP())
    return body, inters, sim


def energy(scene, q, v):
    q, v = np.asarray(q), np.asarray(v)
    if scene == "particle":
        return 0.5 * (v[0] ** 2 + v[1] ** 2) + G * q[1]
    if scene == "pendulum_walls":
        return 0.5 * PW_L ** 2 * v[0] ** 2 - G * PW_L * math.cos(q[0])
    if scene == "fpu_walls":
        r = np.diff(np.concatenate(([0.0], q, [0.0])))
        return 0.5 * float(v @ v) + float(np.sum(0.5 * r ** 2 + 0.25 * FPU_BETA * r ** 4))
    return 0.5 * (INERTIA * v[0] ** 2 + v[1] ** 2 + v[2] ** 2) + G * q[2]


def run(scene, h, t_end, plugin_dir, e0=None, sample=None):
    """Returns final q, impact times, largest |E - E0|, steps (and per-second maxima if sample)."""
    body, inters, sim = build(scene, h, t_end, plugin_dir)
    times, steps, emax = [], 0, 0.0
    active = [False] * len(inters)
    window = 10.0
    bins = np.zeros(int(math.ceil(t_end / window))) if sample else None
    while sim.hasNextEvent():
        sim.computeOneStep()
        for j, inter in enumerate(inters):
            lam = inter.lambda_(1)[0]
            if lam > 0 and not active[j]:
                times.append(0.5 * (sim.startingTime() + sim.nextTime()))
            active[j] = lam > 0
        if e0 is not None:
            err = abs(energy(scene, body.q(), body.velocity()) - e0)
            emax = max(emax, err)
            if sample:
                k = min(int(sim.nextTime() / window), bins.size - 1)
                bins[k] = max(bins[k], err)
        steps += 1
        sim.nextStep()
    return np.array(body.q()), sorted(times), emax, steps, bins


def sweep(ref_path, plugin_dir, out_path):
    with open(ref_path) as fh:
        ref = json.load(fh)
    with open(out_path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["scene", "method", "param", "wall_median", "cpu_median", "reps", "err_final",
                    "err_energy", "err_impact", "n_impacts", "n_ref_impacts", "steps", "status"])
        for scene in ("particle", "ellipse", "pendulum_walls", "fpu_walls"):
            r = ref[scene]
            qref, tref, e0 = np.array(r["q"]), np.array(r["impact_times"]), r["e0"]
            for h in STEPS_OF.get(scene, STEPS):
                # accuracy run (energy evaluated per step), then timed runs without it
                qf, times, emax, steps, _ = run(scene, h, T_FINAL[scene], plugin_dir, e0=e0)
                walls, cpus = [], []
                while True:
                    w0, c0 = time.perf_counter(), time.process_time()
                    run(scene, h, T_FINAL[scene], plugin_dir)
                    walls.append(time.perf_counter() - w0)
                    cpus.append(time.process_time() - c0)
                    n, tot = len(walls), sum(walls)
                    if tot > 1.0 or (n >= 3 and tot > 0.5) or n >= 9:
                        break
                got = np.array(times)
                err_imp = max(float(np.min(np.abs(got - ti))) for ti in tref) if got.size else math.inf
                # the final time is the last grid point, T exactly (t_k = k h)
                w.writerow([scene, "siconos-moreau-jean", f"{h:.3e}", f"{statistics.median(walls):.5e}",
                            f"{statistics.median(cpus):.5e}", len(walls),
                            f"{float(np.max(np.abs(qf - qref))):.5e}", f"{emax:.5e}", f"{err_imp:.5e}",
                            len(times), tref.size, steps, 0])
                fh.flush()
            print(f"siconos sweep: {scene} done", flush=True)


def long_run(scene, plugin_dir, outdir, h, t_end):
    if scene == "ellipse":
        e0 = energy(scene, [math.pi / 2, 0.0, 3.5], [-3.0, 2.0, 0.0])
    else:
        e0 = energy(scene, *initial(scene))
    w0, c0 = time.perf_counter(), time.process_time()
    _, times, emax, steps, bins = run(scene, h, t_end, plugin_dir, e0=e0, sample=True)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    tag = f"{h:.1e}"
    with open(f"{outdir}/long_{scene}_siconos-moreau-jean_{tag}.csv", "w") as fh:
        fh.write("t,energy_error\n")
        for i, e in enumerate(bins):
            fh.write(f"{10.0 * (i + 1):.7e},{e:.5e}\n")
    with open(f"{outdir}/long_{scene}_siconos-moreau-jean_{tag}_summary.csv", "w") as fh:
        fh.write("scene,method,param,wall,cpu,max_energy_error,final_energy_error,n_impacts,t_end,status\n")
        fh.write(f"{scene},siconos-moreau-jean,{h:.3e},{wall:.5e},{cpu:.5e},{emax:.5e},{bins[-1]:.5e},"
                 f"{len(times)},{t_end:.7e},0\n")
    print(f"siconos long run: {scene} h {tag}: {cpu:.1f} s CPU (energy evaluated every step), "
          f"{len(times)} impacts, max |dE| {emax:.3e}", flush=True)


if __name__ == "__main__":
    if len(sys.argv) >= 5 and sys.argv[1] == "sweep":
        sweep(sys.argv[2], sys.argv[3], sys.argv[4])
    elif len(sys.argv) >= 7 and sys.argv[1] == "long":
        long_run(sys.argv[2], sys.argv[3], sys.argv[4], float(sys.argv[5]), float(sys.argv[6]))
    else:
        sys.exit(__doc__)
