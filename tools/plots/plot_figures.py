#!/usr/bin/python3
"""The paper's four figures from vci's HDF5 output (layout: docs/OUTPUT.md).

Usage: /usr/bin/python3 tools/plots/plot_figures.py DIR
Reads DIR/ellipse_2s.h5, DIR/ellipse_25s.h5, DIR/pendulum_5s.h5, DIR/pendulum_100s.h5 (written by
tools/demo.sh) and writes DIR/fig1_ellipse_trajectory.png, DIR/fig2_ellipse_energy.png,
DIR/fig3_pendulum_angles.png, DIR/fig4_pendulum_energy.png. Impacts are marked on each.
Needs Debian's python3-h5py, python3-matplotlib and python3-numpy.
"""
import os
import sys

import h5py
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# The ellipse of the paper (docs/DESIGN.md 8): semi-axes a (along angle theta) and b, floor y = 0.
A, B = 1.0, 0.5


def load(path):
    """Everything the figures need from one run file, as numpy arrays."""
    with h5py.File(path, "r") as f:
        run = {k: f[k][()] for k in ("t", "q", "p", "energy")}
        run["h"] = float(f.attrs["h"])
        run["scene"] = f.attrs["scene"].decode()
        run["status"] = int(f.attrs["status"])
        if "impacts" in f:
            run["impact_t"] = f["impacts/time"][()]
            run["impact_q"] = f["impacts/q"][()]
        else:
            run["impact_t"] = np.zeros(0)
            run["impact_q"] = np.zeros((0, run["q"].shape[1]))
    if run["status"] != 0:
        print(f"warning: {path}: run status {run['status']} (not ok)", file=sys.stderr)
    return run


def mark_impacts(ax, times, label=True):
    for i, ti in enumerate(times):
        ax.axvline(ti, color="tab:red", lw=0.6, alpha=0.45,
                   label=f"impacts ({len(times)})" if (label and i == 0) else None)


def fig1_ellipse_trajectory(run, out):
    t, q = run["t"], run["q"]
    fig, ax = plt.subplots(figsize=(9, 5.2))
    ax.axhline(0.0, color="0.3", lw=1.5)
    ax.plot(q[:, 1], q[:, 2], color="tab:blue", lw=1.2, label="centre (x, y)")
    # the body and its principal axes every 0.2 s
    s = np.linspace(0.0, 2.0 * np.pi, 200)
    every = max(1, int(round(0.2 / run["h"])))
    for k in range(0, len(t), every):
        th, x, y = q[k]
        u = np.array([np.cos(th), np.sin(th)])    # the a-axis
        v = np.array([-np.sin(th), np.cos(th)])   # the b-axis
        ex = x + A * np.cos(s) * u[0] + B * np.sin(s) * v[0]
        ey = y + A * np.cos(s) * u[1] + B * np.sin(s) * v[1]
        ax.plot(ex, ey, color="0.55", lw=0.7)
        ax.plot([x - A * u[0], x + A * u[0]], [y - A * u[1], y + A * u[1]], color="tab:green", lw=0.9)
        ax.plot([x - B * v[0], x + B * v[0]], [y - B * v[1], y + B * v[1]], color="tab:orange", lw=0.9)
    ax.plot([], [], color="0.55", lw=0.7, label="ellipse every 0.2 s")
    ax.plot([], [], color="tab:green", label="major axis")
    ax.plot([], [], color="tab:orange", label="minor axis")
    iq = run["impact_q"]
    if len(iq):
        ax.plot(iq[:, 1], iq[:, 2], "o", color="tab:red", ms=6, label=f"centre at impacts ({len(iq)})")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"Fig. 1: bouncing ellipse, t = {t[0]:.3f} to {t[-1]:.3f} s, h = {run['h']:g}")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def energy_figure(run, out, title):
    t, e = run["t"], run["energy"]
    te = t[1:]   # energy[i] is E_d of the step from t[i] to t[i+1]
    stride = max(1, len(e) // 20000)   # keep the PNG light; every impact is still marked
    fig, ax = plt.subplots(figsize=(9, 4.5))
    ax.plot(te[::stride], e[::stride], color="tab:blue", lw=0.9, label="discrete energy $E_d$")
    mark_impacts(ax, run["impact_t"])
    ax.set_xlabel("t [s]")
    ax.set_ylabel("$E_d$ [J]")
    rel = (e.max() - e.min()) / abs(e[0])
    ax.set_title(f"{title}\nrange of $E_d$: {e.min():.6g} to {e.max():.6g} (relative {rel:.2e})")
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def fig3_pendulum_angles(run, out):
    t, q = run["t"], run["q"]
    fig, ax = plt.subplots(figsize=(9, 4.5))
    ax.plot(t, q[:, 0], color="tab:blue", label=r"$\theta$")
    ax.plot(t, q[:, 1], color="tab:orange", label=r"$\varphi$")
    mark_impacts(ax, run["impact_t"])
    for ti, qi in zip(run["impact_t"], run["impact_q"]):
        ax.plot([ti, ti], [qi[0], qi[1]], "o", color="tab:red", ms=4)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("angle [rad]")
    ax.set_title(f"Fig. 3: nonholonomic pendulum in a cylinder, h = {run['h']:g}")
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    d = sys.argv[1]
    made = []

    def out(name):
        made.append(os.path.join(d, name))
        return made[-1]

    fig1_ellipse_trajectory(load(os.path.join(d, "ellipse_2s.h5")), out("fig1_ellipse_trajectory.png"))
    e25 = load(os.path.join(d, "ellipse_25s.h5"))
    energy_figure(e25, out("fig2_ellipse_energy.png"), f"Fig. 2: bouncing ellipse, energy over 25 s, h = {e25['h']:g}")
    fig3_pendulum_angles(load(os.path.join(d, "pendulum_5s.h5")), out("fig3_pendulum_angles.png"))
    p100 = load(os.path.join(d, "pendulum_100s.h5"))
    energy_figure(p100, out("fig4_pendulum_energy.png"), f"Fig. 4: pendulum, energy over 100 s, h = {p100['h']:g}")
    for m in made:
        print("wrote", m)


if __name__ == "__main__":
    main()
