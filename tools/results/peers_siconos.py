#!/usr/bin/python3
"""The Siconos peer (python3-siconos, Debian 12: 4.4.0): Moreau-Jean time stepping (theta = 1/2,
Newton impact law with restitution e = 1, LCP one-step problem) for the particle (a ball on the
floor: linear time-invariant system and relation) and the ellipse (nonlinear floor relation from
the C plugin siconos_ellipse_plugin.c, built as EllipsePlugin.so).

    peers_siconos.py sweep REFERENCE.json PLUGIN_DIR OUT.csv
    peers_siconos.py long PLUGIN_DIR OUTDIR H            ellipse over 1e4 s: |E - E0| per second

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
T_FINAL = {"particle": 3.0, "ellipse": 3.0}
STEPS = [2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5]


def build(scene, h, t_end, plugin_dir):
    if scene == "particle":
        body = sk.LagrangianLinearTIDS([0.0, 1.0], [1.0, 0.0], np.eye(2))
        body.setFExtPtr(np.array([0.0, -G]))
        rel = sk.LagrangianLinearTIR(np.array([[0.0, 1.0]]))
    else:
        body = sk.LagrangianLinearTIDS([math.pi / 2, 0.0, 3.5], [-3.0, 2.0, 0.0],
                                       np.diag([INERTIA, 1.0, 1.0]))
        body.setFExtPtr(np.array([0.0, 0.0, -G]))
        plugin = f"{plugin_dir}/EllipsePlugin"
        rel = sk.LagrangianScleronomousR(f"{plugin}:h", f"{plugin}:G0")
    inter = sk.Interaction(sk.NewtonImpactNSL(1.0), rel)
    nsds = sk.NonSmoothDynamicalSystem(0.0, t_end)
    nsds.insertDynamicalSystem(body)
    nsds.link(inter, body)
    sim = sk.TimeStepping(nsds, sk.TimeDiscretisation(0.0, h), sk.MoreauJeanOSI(0.5), sk.LCP())
    return body, inter, sim


def energy(scene, q, v):
    if scene == "particle":
        return 0.5 * (v[0] ** 2 + v[1] ** 2) + G * q[1]
    return 0.5 * (INERTIA * v[0] ** 2 + v[1] ** 2 + v[2] ** 2) + G * q[2]


def run(scene, h, t_end, plugin_dir, e0=None, sample=None):
    """Returns final q, impact times, largest |E - E0|, steps (and per-second maxima if sample)."""
    body, inter, sim = build(scene, h, t_end, plugin_dir)
    times, active, steps, emax = [], False, 0, 0.0
    bins = np.zeros(int(math.ceil(t_end))) if sample else None
    while sim.hasNextEvent():
        sim.computeOneStep()
        lam = inter.lambda_(1)[0]
        if lam > 0 and not active:
            times.append(0.5 * (sim.startingTime() + sim.nextTime()))
        active = lam > 0
        if e0 is not None:
            err = abs(energy(scene, body.q(), body.velocity()) - e0)
            emax = max(emax, err)
            if sample:
                k = min(int(sim.nextTime()), bins.size - 1)
                bins[k] = max(bins[k], err)
        steps += 1
        sim.nextStep()
    return np.array(body.q()), times, emax, steps, bins


def sweep(ref_path, plugin_dir, out_path):
    with open(ref_path) as fh:
        ref = json.load(fh)
    with open(out_path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["scene", "method", "param", "wall_median", "cpu_median", "reps", "err_final",
                    "err_energy", "err_impact", "n_impacts", "n_ref_impacts", "steps", "status"])
        for scene in ("particle", "ellipse"):
            r = ref[scene]
            qref, tref, e0 = np.array(r["q"]), np.array(r["impact_times"]), r["e0"]
            for h in STEPS:
                # accuracy run (energy evaluated per step), then timed runs without it
                qf, times, emax, steps, _ = run(scene, h, T_FINAL[scene], plugin_dir, e0=e0)
                walls, cpus = [], []
                while True:
                    w0, c0 = time.perf_counter(), time.process_time()
                    run(scene, h, T_FINAL[scene], plugin_dir)
                    walls.append(time.perf_counter() - w0)
                    cpus.append(time.process_time() - c0)
                    n, tot = len(walls), sum(walls)
                    if (n >= 3 and tot > 2.0) or (n >= 5 and tot > 0.5) or n >= 9:
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


def long_run(plugin_dir, outdir, h, t_end=1.0e4):
    scene = "ellipse"
    e0 = energy(scene, [math.pi / 2, 0.0, 3.5], [-3.0, 2.0, 0.0])
    w0, c0 = time.perf_counter(), time.process_time()
    _, times, emax, steps, bins = run(scene, h, t_end, plugin_dir, e0=e0, sample=True)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    tag = f"{h:.1e}"
    with open(f"{outdir}/long_siconos-moreau-jean_{tag}.csv", "w") as fh:
        fh.write("t,energy_error\n")
        for i, e in enumerate(bins):
            fh.write(f"{i + 1:.7e},{e:.5e}\n")
    with open(f"{outdir}/long_siconos-moreau-jean_{tag}_summary.csv", "w") as fh:
        fh.write("method,param,wall,cpu,max_energy_error,final_energy_error,n_impacts,t_end,status\n")
        fh.write(f"siconos-moreau-jean,{h:.3e},{wall:.5e},{cpu:.5e},{emax:.5e},{bins[-1]:.5e},"
                 f"{len(times)},{t_end:.7e},0\n")
    print(f"siconos long run: h {tag}: {wall:.1f} s (energy evaluated every step), "
          f"max |dE| {emax:.3e}", flush=True)


if __name__ == "__main__":
    if len(sys.argv) >= 5 and sys.argv[1] == "sweep":
        sweep(sys.argv[2], sys.argv[3], sys.argv[4])
    elif len(sys.argv) >= 5 and sys.argv[1] == "long":
        long_run(sys.argv[2], sys.argv[3], float(sys.argv[4]))
    else:
        sys.exit(__doc__)
