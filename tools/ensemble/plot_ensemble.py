#!/usr/bin/env python3
"""Plot an ellipse_ensemble file: when each perturbed member's impact sequence leaves the
unperturbed one against the perturbation size (with the fitted Lyapunov exponent), the
distribution of impact counts, and the phase-space separation from the unperturbed member.

    /usr/bin/python3 tools/ensemble/plot_ensemble.py ellipse_ensemble.h5 [out.png]
"""
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(path, out):
    with h5py.File(path, "r") as f:
        m, a = f["members"], f["analysis"]
        size, t_div = a["size"][:], a["divergence_time"][:]
        lam, lam_err, tol = a.attrs["lyapunov"], a.attrs["lyapunov_stderr"], a.attrs["tolerance"]
        status, impacts = m["status"][:], m["impacts"][:]
        T = f.attrs["h"] * (f.attrs["nsteps"] + 0.5)
        traj = "trajectory" in m
        if traj:
            tt, tq, tp = m["trajectory/t"][:], m["trajectory/q"][:], m["trajectory/p"][:]

    fig, ax = plt.subplots(1, 3, figsize=(16, 4.6))
    ok = ~np.isnan(t_div) & (size > 0)
    ax[0].semilogx(size[ok], t_div[ok], "o", ms=3, label="members")
    fit = ok & (size <= 1e-2 * tol)
    if np.isfinite(lam) and fit.sum() >= 2:
        x = np.log(1 / size[fit])
        c = np.mean(t_div[fit] - x / lam)
        s = np.logspace(np.log10(size[fit].min()), np.log10(size[fit].max()), 50)
        ax[0].semilogx(s, c + np.log(1 / s) / lam, "-",
                       label=f"t = c + ln(1/size)/λ,  λ = {lam:.3f} ± {lam_err:.3f} 1/s")
    ax[0].set_xlabel("perturbation size")
    ax[0].set_ylabel("time the impact sequence departs (s)")
    ax[0].set_title(f"departure from the unperturbed impacts (|Δt| > {tol:g} s)")
    ax[0].legend(fontsize=8)

    good = status == 0
    k = impacts[good]
    bins = np.arange(k.min(), k.max() + 2) - 0.5
    ax[1].hist(k, bins=bins, color="tab:orange", edgecolor="k")
    ax[1].axvline(impacts[0], color="k", ls="--", label=f"unperturbed: {impacts[0]}")
    ax[1].set_xlabel(f"impacts in {T:.0f} s")
    ax[1].set_ylabel("members")
    ax[1].set_title(f"impact counts over {good.sum()} members")
    ax[1].legend(fontsize=8)

    if traj:
        ref = np.concatenate([tq[0], tp[0]], axis=1)
        picks = np.unique(np.linspace(1, len(size) - 1, 7).astype(int))
        for j in picks:
            d = np.linalg.norm(np.concatenate([tq[j], tp[j]], axis=1) - ref, axis=1)
            ax[2].semilogy(tt[0], d, lw=1, label=f"size {size[j]:.0e}")
        if np.isfinite(lam):
            t = tt[0]
            ax[2].semilogy(t, 1e-14 * np.exp(lam * (t - t[0])), "k--", lw=1, label=f"e^(λt), λ = {lam:.2f}")
        ax[2].set_ylim(1e-16, 1e2)
        ax[2].set_xlabel("t (s)")
        ax[2].set_ylabel("|(q, p) − unperturbed|")
        ax[2].set_title("separation from the unperturbed member")
        ax[2].legend(fontsize=7)
    else:
        ax[2].set_axis_off()
        ax[2].text(0.5, 0.5, "no trajectories in the file (--stride 0)", ha="center")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        print(__doc__)
        sys.exit(2)
    path = sys.argv[1]
    main(path, sys.argv[2] if len(sys.argv) > 2 else path.rsplit(".", 1)[0] + ".png")
