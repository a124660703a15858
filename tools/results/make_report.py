#!/usr/bin/python3
"""Turn the CSV output of the results drivers into docs/RESULTS.md and docs/figures/*.png.

    make_report.py OUTDIR REPO_ROOT

OUTDIR holds what run_results.sh produced (sweep CSVs, long/ CSVs, richardson.csv, reference.json,
meta.json, driver stderr). Every number in the generated page comes from those files. Method names
come from the CSVs: a new vci scheme added as rows of vci_results_driver (its EXTENSION POINT)
appears in the plots and tables without changes here (style: VCI_ORDER / STYLE, else automatic).
"""
import csv
import glob
import json
import math
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# the large chain (fpu_walls_1024, issue 28) joins the scenes when its rows exist (main)
SCENES = ("particle", "ellipse", "pendulum", "pendulum_walls", "fpu_walls")
LARGE_CHAIN = "fpu_walls_1024"
TITLE = {"particle": "Particle on the floor", "ellipse": "Ellipse on the floor (the paper's)",
         "pendulum": "Nonholonomic pendulum in the cylinder (the paper's)",
         "pendulum_walls": "Walled planar pendulum", "fpu_walls": "FPU-β chain between walls (n = 32)",
         LARGE_CHAIN: "FPU-β chain between walls (n = 1024)"}
PEERS = ["dop853", "cvode-adams", "cvode-bdf", "scipy-dop853", "scipy-radau", "siconos-moreau-jean"]
# names as the tables and plots show them: SciPy is interpreted (Python per step and per restart)
DISPLAY = {"scipy-dop853": "scipy-dop853 (interpreted)", "scipy-radau": "scipy-radau (interpreted)",
           "dop853": "dop853 (compiled)"}
STYLE = {
    "vci-ld-discrete": dict(color="tab:blue", marker="o", ls="-"),
    "vci-ld-hamiltonian": dict(color="navy", marker="s", ls="-"),
    "vci-ld-pair-discrete": dict(color="lightsteelblue", marker="o", ls=":"),
    "vci-ld-pair-hamiltonian": dict(color="cornflowerblue", marker="s", ls=":"),
    "dop853": dict(color="black", marker="h", ls="--"),
    "cvode-adams": dict(color="tab:red", marker="^", ls="--"),
    "cvode-bdf": dict(color="tab:orange", marker="v", ls="--"),
    "scipy-dop853": dict(color="tab:green", marker="D", ls="-."),
    "scipy-radau": dict(color="olive", marker="P", ls="-."),
    "siconos-moreau-jean": dict(color="tab:purple", marker="X", ls="-."),
    # the schemes from the continuous L: colour per scheme, dotted = the paper's impact condition
    "vci-left-discrete": dict(color="gray", marker="<", ls=":"),
    "vci-midpoint-discrete": dict(color="tab:cyan", marker="o", ls=":"),
    "vci-midpoint-hamiltonian": dict(color="tab:cyan", marker="s", ls="-"),
    "vci-lobatto2-discrete": dict(color="tab:brown", marker="o", ls=":"),
    "vci-lobatto2-hamiltonian": dict(color="tab:brown", marker="s", ls="-"),
    "vci-lobatto3-discrete": dict(color="goldenrod", marker="o", ls=":"),
    "vci-lobatto3-hamiltonian": dict(color="goldenrod", marker="s", ls="-"),
    "vci-lobatto4-discrete": dict(color="deeppink", marker="o", ls=":"),
    "vci-lobatto4-hamiltonian": dict(color="deeppink", marker="s", ls="-"),
    "vci-lobatto4-hamiltonian-r8": dict(color="deeppink", marker="^", ls="-."),
    "vci-lobatto4-hamiltonian-r6": dict(color="deeppink", marker="v", ls="--"),
    "vci-lobatto1-discrete": dict(color="darkseagreen", marker="o", ls=":"),
    "vci-lobatto1-hamiltonian": dict(color="darkseagreen", marker="s", ls="-"),
    # the explicit compositions (separable scenes): one colour ramp, solid, triangles
    "vci-composition2-hamiltonian": dict(color="#9ecae1", marker=">", ls="-"),
    "vci-composition4-hamiltonian": dict(color="#6baed6", marker=">", ls="-"),
    "vci-composition6-hamiltonian": dict(color="#3182bd", marker=">", ls="-"),
    "vci-composition8-hamiltonian": dict(color="#08519c", marker=">", ls="-"),
    "vci-composition10-hamiltonian": dict(color="#08306b", marker=">", ls="-"),
}
AUTO = ["tab:cyan", "tab:brown", "tab:pink", "tab:gray", "teal", "darkgoldenrod", "slateblue"]
FLOOR = 1e-16   # errors below this are plotted at this value (exact to rounding)
LEVELS = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
GOAL_LEVELS = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
T_FINAL = {"particle": 3.0, "ellipse": 3.0, "pendulum": 5.0, "pendulum_walls": 10.0, "fpu_walls": 2.0,
           LARGE_CHAIN: 0.5}


def style(m):
    if m not in STYLE:
        STYLE[m] = dict(color=AUTO[len(STYLE) % len(AUTO)], marker="*", ls="-")
    return STYLE[m]


def is_vci(m):
    return m.startswith("vci")


def shown_name(m):
    return DISPLAY.get(m, m)


def is_pair(m):
    return "-pair" in m


def param_name(m):
    return "h" if is_vci(m) or m.startswith("siconos") else "tol"


def read_csv(path):
    if not os.path.exists(path):
        return []
    with open(path) as fh:
        return list(csv.DictReader(fh))


def num(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def fmt(x, digits=2):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "—"
    if x == 0:
        return "0"
    return f"{x:.{digits}e}".replace("e-0", "e-").replace("e+0", "e+")


def ms(x):
    return f"{1e3 * x:.3g} ms"


def load_sweeps(outdir):
    rows = []
    for name in ("vci_sweep.csv", "dop853_sweep.csv", "cvode_sweep.csv", "scipy_sweep.csv", "siconos_sweep.csv",
                 "vci_chain1024.csv", "cvode_chain1024.csv"):
        rows += read_csv(os.path.join(outdir, name))
    for r in rows:
        r["method"] = r["method"].strip()
        for k in ("param", "wall_median", "cpu_median", "err_final", "err_energy", "err_impact"):
            r[k] = num(r[k])
        r["err_constraint"] = num(r.get("err_constraint"))   # absent in the Python peers' CSVs
        try:
            r["status"] = int(r["status"])
        except ValueError:   # a failed run written with one 'nan' too many (first edition's drivers)
            extra = r.get(None) or ["1"]
            r["status"] = int(extra[-1])
    return rows


def methods_of(rows, scene=None):
    seen = []
    for r in rows:
        if (scene is None or r["scene"] == scene) and r["method"] not in seen:
            seen.append(r["method"])
    vci = [m for m in seen if is_vci(m)]
    return vci + [m for m in PEERS if m in seen] + [m for m in seen if not is_vci(m) and m not in PEERS]


def plot_scene(rows, scene, figdir):
    fig, axes = plt.subplots(1, 3, figsize=(17, 5.6))
    measures = [("err_final", f"error of q at T = {T_FINAL[scene]:g} s (max-norm)"),
                ("err_impact", "impact-time error (matched impacts, max)"),
                ("err_energy", "largest |E − E0| over the run")]
    for ax, (key, label) in zip(axes, measures):
        for m in methods_of(rows, scene):
            pts = sorted((r["cpu_median"], max(r[key], FLOOR)) for r in rows
                         if r["scene"] == scene and r["method"] == m and r["status"] == 0)
            if not pts:
                continue
            st = style(m)
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], label=shown_name(m), ms=4 if is_pair(m) else 5,
                      lw=0.9 if is_pair(m) else 1.4, **st)
        ax.set_xlabel("CPU time per run [s] (median of repeats)")
        ax.set_ylabel(label)
        ax.grid(True, which="major", alpha=0.4)
        ax.set_title(label, fontsize=10)
    axes[0].legend(fontsize=7, loc="best", ncol=2)
    fig.suptitle(f"{TITLE[scene]}: error against CPU time, every method from the exact (q(0), q̇(0)) "
                 f"(-pair: vci from the paper's initial pair); errors below {FLOOR:g} drawn at {FLOOR:g}",
                 fontsize=11)
    fig.tight_layout()
    path = os.path.join(figdir, f"results_{scene}.png")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def best_at(rows, scene, method, level):
    ok = [r for r in rows if r["scene"] == scene and r["method"] == method and r["status"] == 0
          and r["err_final"] <= level]
    return min(ok, key=lambda r: r["cpu_median"]) if ok else None


def best_at_kept(rows, scene, method, level):
    """The cheapest run of method reaching level whose finer settings (every smaller h or tolerance
    of the same method) all reach it too: a level a user can count on when tightening the setting,
    not one a run reaches by a cancellation of its errors."""
    mine = [r for r in rows if r["scene"] == scene and r["method"] == method]
    ok = [r for r in mine if r["status"] == 0 and r["err_final"] <= level
          and all(f["status"] == 0 and f["err_final"] <= level for f in mine if f["param"] < r["param"])]
    return min(ok, key=lambda r: r["cpu_median"]) if ok else None


def best_vci(rows, scene, level, pair=False):
    cands = [best_at(rows, scene, m, level) for m in methods_of(rows, scene)
             if is_vci(m) and is_pair(m) == pair]
    cands = [c for c in cands if c]
    return min(cands, key=lambda r: r["cpu_median"]) if cands else None


def cheapest_table(rows, scene):
    methods = methods_of(rows, scene)
    lines = ["| error ≤ | cheapest | " + " | ".join(shown_name(m) for m in methods) + " |",
             "|" + "---|" * (len(methods) + 2)]
    for lev in LEVELS:
        best = {m: best_at(rows, scene, m, lev) for m in methods}
        best = {m: r for m, r in best.items() if r}
        wins = f"**{min(best, key=lambda m: best[m]['cpu_median'])}**" if best else "none"
        cells = [f"{ms(best[m]['cpu_median'])} ({param_name(m)} {fmt(best[m]['param'], 0)})" if m in best
                 else "—" for m in methods]
        lines.append(f"| {fmt(lev, 0)} | {wins} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def full_table(rows, scene):
    cons = scene == "pendulum"   # the constraint residual, sin²θ |f θ̇ − φ̇| (largest over the steps)
    lines = ["| method | h or tol | CPU | wall | reps | final error | max energy error | "
             "impact-time error | impacts (ref) | steps | status |" + (" constraint residual |" if cons else ""),
             "|" + "---|" * (12 if cons else 11)]
    for m in methods_of(rows, scene):
        for r in rows:
            if r["scene"] != scene or r["method"] != m:
                continue
            ok = r["status"] == 0
            lines.append(f"| {m} | {fmt(r['param'], 3 if is_vci(m) else 0)} | {ms(r['cpu_median']) if ok else '—'} | "
                         f"{ms(r['wall_median']) if ok else '—'} | {r['reps']} | "
                         f"{fmt(r['err_final'])} | {fmt(r['err_energy'])} | {fmt(r['err_impact'])} | "
                         f"{r['n_impacts']} ({r['n_ref_impacts']}) | {r['steps']} | {r['status']} |"
                         + (f" {fmt(r['err_constraint'])} |" if cons else ""))
    return "\n".join(lines)


def lsq(xs, ys):
    n = len(xs)
    if n < 3:
        return math.nan
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else math.nan


def order_fit(rows, scene, method, hmin=1e-3, hmax=2.1e-2):
    """Least-squares slope of log(final error) against log(h) over hmin <= h <= hmax, errors above
    1e-10 (Lobatto rows: h <= 0.2, whose asymptotic range lies at large steps, and errors above 1e-9,
    two decades above their round-off floor, which their small steps reach)."""
    floor = 1e-10
    if "lobatto" in method:
        hmin, hmax, floor = 0.0, 0.21, 1e-9
    pts = [(math.log(r["param"]), math.log(r["err_final"])) for r in rows
           if r["scene"] == scene and r["method"] == method and r["status"] == 0
           and hmin * 0.9 <= r["param"] <= hmax and r["err_final"] > floor]
    return lsq([p[0] for p in pts], [p[1] for p in pts]), len(pts)


# ---- long runs --------------------------------------------------------------------------------

def load_long(outdir):
    out = []
    for f in sorted(glob.glob(os.path.join(outdir, "long", "long_*_vci.csv")) +
                    glob.glob(os.path.join(outdir, "long", "long_*_cvode_*.csv")) +
                    glob.glob(os.path.join(outdir, "long", "*_summary.csv"))):
        out += read_csv(f)
    for s in out:
        s["method"] = s["method"].strip()
        for k in ("param", "wall", "cpu", "max_energy_error", "final_energy_error", "t_end"):
            s[k] = num(s[k])
        s["n_impacts"] = int(s["n_impacts"])
    return out


def series_path(outdir, s):
    base = os.path.join(outdir, "long", f"long_{s['scene']}_{s['method']}")
    if is_vci(s["method"]):
        return base + ".csv"
    tag = f"{s['param']:.1e}"
    if s["method"].startswith("cvode") or s["method"] == "dop853":
        tag = tag.upper()
    return base + f"_{tag}.csv"


def series(outdir, s):
    data = read_csv(series_path(outdir, s))
    return [num(d["t"]) for d in data], [num(d["energy_error"]) for d in data]


def drift_fit(t, e):
    """Slope of log(window max |E - E0|) against log t over the last two decades of the run
    (1: linear drift, 1/2: random walk, 0: bounded), and the rate of a linear fit e = a + b t."""
    if not t:
        return math.nan, math.nan
    tmax = t[-1]
    pts = [(math.log(x), math.log(y)) for x, y in zip(t, e) if x >= tmax / 100 and y > 0]
    slope = lsq([p[0] for p in pts], [p[1] for p in pts])
    rate = lsq(t, e)
    return slope, rate


def matched(summaries, scene, ref_cpu):
    """Per peer, its best run (smallest largest |E - E0|) among those costing at most 1.1x the
    reference CPU time; if none is that cheap, its cheapest run."""
    out = {}
    for s in summaries:
        m = s["method"]
        if s["scene"] != scene or is_vci(m) or int(s["status"]) != 0:
            continue
        within = s["cpu"] <= 1.1 * ref_cpu
        key = (0, s["max_energy_error"]) if within else (1, s["cpu"])
        if m not in out or key < out[m][0]:
            out[m] = (key, s)
    return {m: v[1] for m, v in out.items()}


def plot_long(outdir, scene, shown, figdir):
    fig, ax = plt.subplots(figsize=(11, 6))
    for s in shown:
        t, e = series(outdir, s)
        if not t:
            continue
        run, cur = [], 0.0
        for v in e:
            cur = max(cur, v)
            run.append(max(cur, FLOOR))
        st = style(s["method"])
        ax.loglog(t, run, lw=1.6, color=st["color"], ls=st["ls"],
                  label=f"{shown_name(s['method'])} ({param_name(s['method'])} {fmt(s['param'], 0)}, CPU {s['cpu']:.2g} s, "
                        f"{s['n_impacts']} impacts)")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("largest |E − E0| up to t")
    ax.set_title(f"{TITLE[scene]}: energy error over a long run, vci (ld rows h = 1e-2, Lobatto h = 0.1) and "
                 "each peer's best run costing ≤ 1.1× vci-ld-hamiltonian's CPU time (else its cheapest)", fontsize=9)
    ax.grid(True, which="major", alpha=0.4)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    path = os.path.join(figdir, f"results_long_{scene}.png")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


# ---- the page ---------------------------------------------------------------------------------

def main(outdir, root):
    figdir = os.path.join(root, "docs", "figures")
    os.makedirs(figdir, exist_ok=True)
    for old in glob.glob(os.path.join(figdir, "results_long_energy.png")):
        os.remove(old)   # the first edition's single long-run figure
    global SCENES
    rows = load_sweeps(outdir)
    meta = json.load(open(os.path.join(outdir, "meta.json")))
    refs = json.load(open(os.path.join(outdir, "reference.json")))
    large = os.path.join(outdir, "reference_chain1024.json")
    if os.path.exists(large) and any(r["scene"] == LARGE_CHAIN for r in rows):
        refs.update(json.load(open(large)))
        SCENES = SCENES + (LARGE_CHAIN,)
    rich = read_csv(os.path.join(outdir, "richardson.csv"))
    summaries = load_long(outdir)
    failures = [r for r in rows if r["status"] != 0]
    errlog = ""
    p = os.path.join(outdir, "vci_sweep.stderr")
    if os.path.exists(p):
        errlog = open(p).read().strip()
    for scene in SCENES:
        plot_scene(rows, scene, figdir)

    out = []
    w = out.append
    w("# Results: error against run time (third edition: the compiled DOP853 peer, the explicit compositions)\n")
    w("<!-- Generated by tools/results/make_report.py from the output of tools/results/run_results.sh. "
      "Do not edit by hand: rerun the command below. -->\n")
    w("Regenerate (installs missing Debian packages, builds, runs every method, rewrites this page and "
      "`docs/figures/results_*.png`; not run by CI):\n")
    w("```sh\ntools/results/run_results.sh\n```\n")
    w(f"Last run: {meta['date']} on {meta['nproc']} cores ({meta['cpu']}); the whole command took "
      f"**{meta['elapsed_s'] / 60:.1f} min**; vci at commit {meta.get('commit', '?')}. "
      f"Versions: {meta['versions']}.\n")
    if meta.get("note"):
        w(f"Note on this run: {meta['note']}\n")
    if meta.get("refreshed"):
        parts = [f"**{e['scene']}** {e['date']} (commit {e['commit']}, {e['elapsed_s']} s"
                 + (f", load average {e['load']}" if e.get("load") else "") + ")" for e in meta["refreshed"]]
        w("Rows rerun since by `tools/results/run_results.sh --scene SCENE` (vci, the compiled DOP853 and "
          "CVODE of that scene, timed the same way in one run): " + "; ".join(parts) + ". The interpreted "
          "peers' rows and the long runs are from the full run above; the profile is rerun with pendulum_walls.\n")
    w("vci's poke screen (a wall crossed and left within one sub-step, docs/BACKWARD.md) is on by default "
      "since merge e6aced0 (2026-11-27) and costs 11–29 % more instructions a step of the midpoint "
      "schemes; Lobatto's screen reads its own stage polynomial since merge b8e5b3f and costs +2–7 % a "
      "regular step, +1–2 % an impact step (docs/bench/poke.md): a scene whose rows come from an "
      "earlier commit ran with the screen off or with the older screen.\n")
    w("> **vci rows.** `vci-ld-*`: the scene's own hand-written discrete Lagrangian (the midpoint rule, "
      "second order; the nonholonomic pendulum's is the paper's first-order left-point rule). "
      "`vci-left-*`, `vci-midpoint-*`, `vci-lobattoS-*`: the library's schemes built from the scene's "
      "continuous L (docs/SCHEMES.md; `integ%set_scheme`), orders 1, 2 and 2s. The suffix is the impact "
      "condition: `discrete` the paper's E_d(αh) = E_d((1−α)h), `hamiltonian` H(q̃, p⁺) = H(q̃, p⁻). "
      "`left` runs only with `discrete` (with `hamiltonian` its first-order momenta make the energy at the "
      "wall drift, docs/SCHEMES.md). Lobatto s = 1 … 4 runs the nonholonomic pendulum (constraints at the "
      "nodes, issue 25), s = 2 … 4 the holonomic scenes; on the FPU chain midpoint and Lobatto s = 2, 4 with "
      "`hamiltonian` (time budget). `vci-compositionP-hamiltonian`: the explicit Störmer–Verlet (P = 2) and "
      "its symmetric compositions of order P = 4 … 10 (`VCI_SCHEME_COMPOSITION`, issue 32) on every scene "
      "with a separable Lagrangian (all but the nonholonomic pendulum), which always reflect with the "
      "Hamiltonian condition.\n\n"
      "> **Peers.** `dop853 (compiled)`: Hairer's DOP853 written for these tools in Fortran "
      "(`tools/results/results_dop853.f90`, checked by `dop853_results_driver check` at the start of the "
      "command: order 8, the dense output's order, exact event times), events located on its 7th-order "
      "dense output — what a user with a smooth, non-stiff scene and events picks. `cvode-*`: SUNDIALS "
      "CVODE, compiled. `scipy-*` are **interpreted**: the same algorithms in Python, which pays "
      "~0.1–0.2 ms per step and ~1 ms per restart, so their CPU times measure the interpreter, not the "
      "method.\n")

    # --- summary
    w("## Summary\n")
    w(summary_text(rows, summaries, outdir))

    prof = os.path.join(outdir, "profile.md")
    if os.path.exists(prof):
        w("### Where the time goes: vci against the compiled DOP853 on the walled pendulum\n")
        w(open(prof).read().strip() + "\n")
    # --- what is measured
    w("## What is measured\n")
    w(MEASURED.format(sundials=meta.get("sundials", ""), fpu_check=fmt(refs["fpu_walls"].get("self_check", math.nan)),
                      n_pw=len(refs["pendulum_walls"]["impact_times"]), n_fpu=len(refs["fpu_walls"]["impact_times"])))
    chk = os.path.join(outdir, "dop853_check.txt")
    if os.path.exists(chk):
        w("<details><summary>The compiled DOP853's checks in this run (<code>dop853_results_driver check</code>)"
          "</summary>\n")
        w("```\n" + open(chk).read().strip() + "\n```\n")
        w("</details>\n")

    # --- per scene
    for scene in SCENES:
        w(f"## {TITLE[scene]}\n")
        w(f"![{scene}: error against CPU time](figures/results_{scene}.png)\n")
        fits = []
        for m in methods_of(rows, scene):
            if is_vci(m):
                o, n = order_fit(rows, scene, m)
                if n >= 3:
                    fits.append(f"{m} {o:.2f}")
                else:
                    fits.append(f"{m} — (error at round-off at every h: no order)")
        if fits:
            w("Least-squares order of vci's final error in h (h = 2e-2 … 1e-3, errors above 1e-10; Lobatto "
              "rows: h ≤ 0.2, errors above 1e-9): " + "; ".join(fits) + ".\n")
        w("Cheapest run (CPU time, with its step size or tolerance) of each method that reaches each "
          "level of final error at T; **bold**: the cheapest overall.\n")
        w(cheapest_table(rows, scene) + "\n")
        w("<details><summary>All runs</summary>\n")
        w(full_table(rows, scene) + "\n")
        w("</details>\n")
        if scene == LARGE_CHAIN:
            rf = refs[LARGE_CHAIN]
            w(LARGE_CHAIN_TEXT.format(n_imp=len(rf["impact_times"]), check=fmt(rf.get("self_check", math.nan)),
                                      e0=rf["e0"]))
        if scene == "pendulum" and rich:
            w("**Reference cross-check (pendulum).** The paper's pendulum L_d is first order, so "
              "R(h) = 2 q(h/2) − q(h) is an O(h²) estimate of the exact solution built from vci alone "
              "(paper's pair, discrete impact condition). Its distance to the reduced-ODE reference "
              "shrinks like h², an order faster than vci's own error — the two independent computations agree:\n")
            w("| h | vci error at h/2 (q) | Richardson error (q) | vci error at h/2 (impact times) | "
              "Richardson error (impact times) |\n|---|---|---|---|---|")
            for r in rich:
                w(f"| {fmt(num(r['h']), 3)} | {fmt(num(r['err_q_vci_h2']))} | {fmt(num(r['err_q_richardson']))} | "
                  f"{fmt(num(r['err_t_vci_h2']))} | {fmt(num(r['err_t_richardson']))} |")
            w("")

    # --- long runs
    w("## Long runs: energy over ≥ 10⁵ impacts\n")
    w(LONG_INTRO)
    for scene in ("pendulum_walls", "ellipse"):
        ss = [s for s in summaries if s["scene"] == scene]
        if not ss:
            continue
        vl = [s for s in ss if is_vci(s["method"])]
        ref = next((s for s in vl if s["method"] == "vci-ld-hamiltonian"), vl[0] if vl else None)
        ref_cpu = ref["cpu"] if ref else 1.0
        chosen = matched(summaries, scene, ref_cpu)
        shown = vl + list(chosen.values())
        plot_long(outdir, scene, shown, figdir)
        w(f"### {TITLE[scene]}\n")
        w(f"![{scene}: energy error over a long run](figures/results_long_{scene}.png)\n")
        w("| method | h or tol | horizon [s] | impacts | CPU [s] | CPU / vci-ld-hamiltonian | largest \\|E − E0\\| | "
          "\\|E − E0\\| in the last window | drift slope (log-log, last 2 decades) | linear rate [1/s] | in plot |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|")
        shown_ids = {id(s) for s in shown}
        for s in ss:
            t, e = series(outdir, s)
            slope, rate = drift_fit(t, e)
            w(f"| {s['method']} | {fmt(s['param'], 0)} | {s['t_end']:.3g} | {s['n_impacts']} | {s['cpu']:.3g} | "
              f"{s['cpu'] / ref_cpu:.2g} | {fmt(s['max_energy_error'])} | {fmt(s['final_energy_error'])} | "
              f"{slope:.2f} | {fmt(rate)} | {'yes' if id(s) in shown_ids else 'no'} |")
        w("")

    w("## Reading\n")
    w(READING)
    if failures or errlog:
        w("### Runs that failed\n")
        for r in failures:
            w(f"- {r['scene']} {r['method']} {param_name(r['method'])} = {fmt(r['param'], 3)}: status {r['status']}")
        if errlog:
            w("\nvci's messages (stderr of the driver):\n")
            w("```\n" + errlog + "\n```\n")
    w("## Throughput\n")
    summary = os.path.join(root, "docs", "bench", "summary.md")
    if os.path.exists(summary):
        w(open(summary).read())
    else:
        w("see docs/bench/throughput.md\n")
    # Sections that other commands regenerate (the schemes' orders, ensemble scaling) live after
    # KEEP_MARKER in docs/RESULTS.md and are carried over unchanged.
    path = os.path.join(root, "docs", "RESULTS.md")
    kept = ""
    if os.path.exists(path):
        old = open(path).read()
        if KEEP_MARKER in old:
            kept = old[old.index(KEEP_MARKER):]
    with open(path, "w") as fh:
        fh.write("\n".join(out) + "\n")
        if kept:
            fh.write("\n" + kept)


KEEP_MARKER = "<!-- sections below are regenerated by their own commands; make_report.py keeps them -->"


def summary_text(rows, summaries, outdir):
    """The measured facts of the summary: cheapest method per level, vci against CVODE-Adams on the
    goal scenes, long-run drift."""
    lines = []
    lines.append("Cheapest method (CPU time) to reach each final error at T, from the same exact start; "
                 "vci's best non-pair variant and its cost relative to the winner:\n")
    lines.append("| scene | 1e-2 | 1e-4 | 1e-6 | 1e-8 | 1e-10 |\n|---|---|---|---|---|---|")
    for scene in SCENES:
        cells = []
        for lev in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10):
            b = {m: best_at(rows, scene, m, lev) for m in methods_of(rows, scene) if not is_pair(m)}
            b = {m: r for m, r in b.items() if r}
            if not b:
                cells.append("none")
                continue
            win = min(b, key=lambda m: b[m]["cpu_median"])
            v = best_vci(rows, scene, lev)
            if is_vci(win):
                second = [m for m in b if not is_vci(m)]
                if second:
                    ps = min(second, key=lambda m: b[m]["cpu_median"])
                    cells.append(f"**{win}** {ms(b[win]['cpu_median'])} ({b[ps]['cpu_median'] / b[win]['cpu_median']:.2g}× "
                                 f"cheaper than {ps})")
                else:
                    cells.append(f"**{win}** {ms(b[win]['cpu_median'])} (no peer reaches it)")
            elif v:
                cells.append(f"**{win}** {ms(b[win]['cpu_median'])}; vci {v['cpu_median'] / b[win]['cpu_median']:.2g}×")
            else:
                cells.append(f"**{win}** {ms(b[win]['cpu_median'])}; vci does not reach it")
        lines.append(f"| {scene} | " + " | ".join(cells) + " |")
    lines.append("")
    lines.append(peers_text(rows))
    lines.append("Long runs (vci-ld rows at h = 1e-2, the Lobatto row at h = 0.1; drift slope = log-log slope of the windowed |E − E0| over "
                 "the last two decades of time; 0 bounded, ½ random walk, 1 linear drift):\n")
    for scene in ("pendulum_walls", "ellipse"):
        parts = []
        for s in summaries:
            if s["scene"] != scene:
                continue
            t, e = series(outdir, s)
            slope, _ = drift_fit(t, e)
            parts.append(f"{s['method']} {param_name(s['method'])} {fmt(s['param'], 0)}: "
                         f"max {fmt(s['max_energy_error'])}, slope {slope:.2f}, CPU {s['cpu']:.2g} s, "
                         f"{s['n_impacts']} impacts")
        lines.append(f"- **{scene}**: " + "; ".join(parts) + ".")
    lines.append("")
    lines.append(SUMMARY_READING.format(**reading_figures(rows, summaries, outdir)))
    return "\n".join(lines) + "\n"


def best_vci_where(rows, scene, level, pred):
    """vci's cheapest non-pair run reaching level among the methods pred accepts."""
    cands = [best_at(rows, scene, m, level) for m in methods_of(rows, scene)
             if is_vci(m) and not is_pair(m) and pred(m)]
    cands = [c for c in cands if c]
    return min(cands, key=lambda r: r["cpu_median"]) if cands else None


def is_explicit(m):
    return "composition" in m


def versus(rows, scene, level, peer, pred=lambda m: True):
    """(ratio vci / peer CPU, vci row, peer row); ratio None when one of them does not reach level."""
    v = best_vci_where(rows, scene, level, pred)
    c = best_at(rows, scene, peer, level)
    return (v["cpu_median"] / c["cpu_median"] if v and c else None), v, c


def ratio_cell(rows, scene, level, peer, pred=lambda m: True):
    r, v, c = versus(rows, scene, level, peer, pred)
    if r is not None:
        return f"{r:.2g} ({v['method'].replace('vci-', '')}, h {fmt(v['param'], 1)})"
    if v:
        return "vci only"
    if c:
        return "peer only"
    return "neither"


def target_line(rows, what, scene, peer, limits, pred=lambda m: True):
    """One target: vci (methods pred accepts) at most limits[level] × the peer's CPU at each level."""
    missed, worst = [], []
    for lev, lim in limits:
        r, v, c = versus(rows, scene, lev, peer, pred)
        if r is None:
            if not v and c:
                missed.append(f"{fmt(lev, 0)}: vci does not reach it")
            continue        # the peer does not reach it (or neither): nothing to beat
        worst.append(r / lim)
        if r > lim:
            missed.append(f"{fmt(lev, 0)}: {r:.2g}× ({'limit ' + f'{lim:g}×'})")
    verdict = "**met**" if not missed else "**missed** at " + "; ".join(missed)
    return f"- {what}: {verdict}."


def peers_text(rows):
    """vci's best against the compiled DOP853 and against CVODE-Adams on every scene, level by level,
    and the issues' targets, met or missed (computed from this run's rows)."""
    out = []
    levels = GOAL_LEVELS
    for peer, name in (("dop853", "the compiled DOP853"), ("cvode-adams", "CVODE-Adams")):
        out.append(f"**vci against {name}**: CPU time of vci's cheapest run reaching each final error / "
                   f"{name}'s cheapest (< 1: vci cheaper; the vci method and step in brackets):\n")
        out.append("| scene | " + " | ".join(fmt(l, 0) for l in levels) + " |\n|---|" + "---|" * len(levels))
        for scene in SCENES:
            out.append(f"| {scene} | " + " | ".join(ratio_cell(rows, scene, l, peer) for l in levels) + " |")
        out.append("")
    sep = [sc for sc in SCENES if any(is_explicit(m) for m in methods_of(rows, sc))]
    if sep:
        out.append("**vci's explicit compositions alone** (separable scenes) against the compiled DOP853 and "
                   "CVODE-Adams, same measure:\n")
        out.append("| scene | peer | " + " | ".join(fmt(l, 0) for l in levels) + " |\n|---|---|" + "---|" * len(levels))
        for scene in sep:
            for peer in ("dop853", "cvode-adams"):
                out.append(f"| {scene} | {peer} | " + " | ".join(ratio_cell(rows, scene, l, peer, is_explicit)
                                                               for l in levels) + " |")
        out.append("")
    out.append("**Targets** (same run; a level neither reaches is skipped, a level only the peer reaches is "
               "missed):\n")
    out.append(target_line(rows, "issue 26 item 6, walled pendulum, vci's best scheme vs the compiled DOP853 "
                           "(≤ 1× at 1e-8 and 1e-10, ≤ 2× at 1e-4 … 1e-6)", "pendulum_walls", "dop853",
                           [(1e-4, 2.0), (1e-5, 2.0), (1e-6, 2.0), (1e-8, 1.0), (1e-10, 1.0)]))
    out.append(target_line(rows, "issue 32 item 5, walled pendulum, vci's best explicit composition vs the "
                           "compiled DOP853 (< 1× at 1e-8 and 1e-10, ≤ 1.2× at 1e-4 … 1e-6)", "pendulum_walls",
                           "dop853", [(1e-4, 1.2), (1e-5, 1.2), (1e-6, 1.2), (1e-8, 1.0), (1e-10, 1.0)], is_explicit))
    every = [(l, 1.0) for l in levels]
    out.append(target_line(rows, "issue 28 item 4 / issue 32 item 5, FPU chain (n = 32), vci's best vs "
                           "CVODE-Adams (< 1× at every level 1e-4 … 1e-10)", "fpu_walls", "cvode-adams", every))
    out.append(target_line(rows, "the same with the explicit compositions only", "fpu_walls", "cvode-adams",
                           every, is_explicit))
    if LARGE_CHAIN in SCENES:
        out.append(target_line(rows, "issue 28 item 4, FPU chain (n = 1024), vci's best vs CVODE-Adams (< 1× at "
                               "every level 1e-4 … 1e-10)", LARGE_CHAIN, "cvode-adams", every))
    out.append(target_line(rows, "issue 25 item 5, nonholonomic pendulum, vci's best vs CVODE-Adams (< 1× at "
                           "every level 1e-4 … 1e-10)", "pendulum", "cvode-adams", every))
    out.append(kept_text(rows, "pendulum", "cvode-adams", levels))
    out.append("")
    out.append("Ratios near 1 move with the machine's load between the vci and the peer sweeps (they run one "
               "after the other). docs/bench/lobatto.md times CVODE-Adams before and after vci on the "
               "nonholonomic pendulum and is the steadier reading of the issue-25 line at 1e-4 … 1e-6; "
               "read the two together.")
    out.append("")
    return "\n".join(out)


def kept_text(rows, scene, peer, levels):
    """The issue-25 comparison again with best_at_kept on both sides, and the peer's runs whose error
    is below a level that a tighter tolerance of the same peer misses."""
    cells = []
    for lev in levels:
        v = [best_at_kept(rows, scene, m, lev) for m in methods_of(rows, scene) if is_vci(m) and not is_pair(m)]
        v = [r for r in v if r]
        v = min(v, key=lambda r: r["cpu_median"]) if v else None
        c = best_at_kept(rows, scene, peer, lev)
        if v and c:
            cells.append(f"{v['cpu_median'] / c['cpu_median']:.2g} ({v['method'].replace('vci-', '')}, "
                         f"h {fmt(v['param'], 1)}; {peer} tol {fmt(c['param'], 0)})")
        else:
            cells.append("vci only" if v else ("peer only" if c else "neither"))
    mine = sorted((r for r in rows if r["scene"] == scene and r["method"] == peer and r["status"] == 0),
                  key=lambda r: -r["param"])
    flukes = []
    for r in mine:
        worse = [f for f in mine if f["param"] < r["param"] and f["err_final"] > r["err_final"] * 4]
        if worse:
            f = max(worse, key=lambda f: f["err_final"])
            flukes.append(f"tol {fmt(r['param'], 0)} ends {fmt(r['err_final'])} where tol {fmt(f['param'], 0)} "
                          f"ends {fmt(f['err_final'])}")
    out = [f"\nThe errors of {peer} on the {scene} scene are not monotone in its tolerance"
           + (" (" + "; ".join(flukes) + ")" if flukes else "")
           + ": its cheapest run at a level can be one whose errors happen to cancel. The same ratios, each "
           "side's cheapest run whose every finer setting (smaller h, smaller tolerance) also reaches the level:\n",
           "| scene | " + " | ".join(fmt(l, 0) for l in levels) + " |\n|---|" + "---|" * len(levels),
           f"| {scene} | " + " | ".join(cells) + " |"]
    return "\n".join(out)


def profile_figures(outdir):
    """From profile.md (profile_peers.sh): the composition runs' instructions over the cheapest
    DOP853 run at least as accurate, their share locating impacts, vci's set-up, DOP853 at 1e-8."""
    out = {"prof_ratio": "n/a", "prof_share": "n/a", "prof_setup": "n/a", "prof_dop8": "n/a"}
    path = os.path.join(outdir, "profile.md")
    if not os.path.exists(path):
        return out
    runs = []
    for line in open(path):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 5 and (cells[0].startswith("dop853") or cells[0].startswith("vci")):
            try:
                runs.append((cells[0], float(cells[1]), float(cells[2]), float(cells[3]),
                             float(cells[4].rstrip(" %"))))
            except ValueError:
                continue
    dop = [r for r in runs if r[0].startswith("dop853")]
    comp = [r for r in runs if "composition" in r[0]]
    ratios = []
    for c in comp:
        better = [d for d in dop if d[1] <= c[1]]
        if better:
            ratios.append(c[2] / min(d[2] for d in better))
    if ratios:
        out["prof_ratio"] = f"{min(ratios):.2g}–{max(ratios):.2g}×"
    if comp:
        out["prof_share"] = f"{min(c[4] for c in comp):.0f}–{max(c[4] for c in comp):.0f} %"
        setup = sorted(c[2] - c[3] for c in comp)[len(comp) // 2]
        out["prof_setup"] = f"about {setup / 1e6:.2g} M instructions"
    d8 = [d for d in dop if d[0].endswith("1e-8")]
    if d8:
        out["prof_dop8"] = f"{d8[0][2] / 1e6:.2g} M"
    return out


def reading_figures(rows, summaries, outdir):
    """The numbers that the summary's reading quotes, from this run's data (CPU ratios move by tens
    of percent between runs on a shared machine; the text must quote the run it sits beside)."""
    def ratio(scene, peers, lev):
        """cheapest of `peers` reaching lev / vci's best reaching it (> 1: vci cheaper), or None"""
        v = best_vci(rows, scene, lev)
        c = [best_at(rows, scene, m, lev) for m in peers]
        c = [r for r in c if r]
        if not (v and c):
            return None
        return min(r["cpu_median"] for r in c) / v["cpu_median"]

    def g2(x):
        return f"{x:.0f}" if x >= 100 else f"{x:.2g}"

    def rng(vals, invert=False):
        vals = [1.0 / x if invert else x for x in vals if x]
        if not vals:
            return "n/a"
        lo, hi = min(vals), max(vals)
        return f"{g2(lo)}×" if g2(lo) == g2(hi) else f"{g2(lo)}–{g2(hi)}×"

    def one(x, invert=False):
        return "n/a" if not x else f"{g2(1.0 / x if invert else x)}×"

    def long_max(scene, method, param=None):
        for r in summaries:
            if r["scene"] == scene and r["method"] == method and (param is None or abs(r["param"] - param) <= 1e-3 * param):
                return r
        return None

    def e(r):
        if not r:
            return "n/a"
        return f"{r['max_energy_error']:.1e}".replace("e-0", "e-").replace("e+0", "e+")

    lev7 = GOAL_LEVELS

    def vs(scene, peer, pred=lambda m: True, levels=lev7):
        """range of vci / peer CPU over the levels both reach (> 1: vci dearer)"""
        return rng([versus(rows, scene, l, peer, pred)[0] for l in levels])

    def cons(scene, method):
        """range of the largest constraint residual over a method's successful runs"""
        vals = [r["err_constraint"] for r in rows if r["scene"] == scene and r["method"] == method
                and r["status"] == 0 and not math.isnan(r["err_constraint"])]
        if not vals:
            return "n/a"
        return f"{fmt(min(vals), 1)} … {fmt(max(vals), 1)}"

    def cons_vci_lobatto(scene):
        vals = [r["err_constraint"] for r in rows if r["scene"] == scene and "lobatto" in r["method"]
                and r["status"] == 0 and not math.isnan(r["err_constraint"])]
        return fmt(max(vals), 1) if vals else "n/a"

    def long_e(scene, method, param=None):
        return e(long_max(scene, method, param))

    lob4 = long_max("pendulum_walls", "vci-lobatto4-hamiltonian")
    a12 = long_max("pendulum_walls", "cvode-adams", 1e-12)
    prof = profile_figures(outdir)
    return {
        **prof,
        "pw_dop": vs("pendulum_walls", "dop853"),
        "pw_dop_exp": vs("pendulum_walls", "dop853", is_explicit),
        "pw_dop_lob": vs("pendulum_walls", "dop853", lambda m: "lobatto" in m),
        "pw_cv": vs("pendulum_walls", "cvode-adams"),
        "fpu_dop": vs("fpu_walls", "dop853"),
        "fpu_cv": vs("fpu_walls", "cvode-adams"),
        "pa_dop": vs("particle", "dop853"),
        "pa_cv": vs("particle", "cvode-adams"),
        "el_dop": vs("ellipse", "dop853"),
        "el_cv": vs("ellipse", "cvode-adams"),
        "pe_dop": vs("pendulum", "dop853"),
        "pe_cv": vs("pendulum", "cvode-adams"),
        "pe_cons_lob": cons_vci_lobatto("pendulum"),
        "pe_cons_cv": cons("pendulum", "cvode-adams"),
        "pe_cons_dop": cons("pendulum", "dop853"),
        "pe_cons_mid": cons("pendulum", "vci-midpoint-hamiltonian"),
        "pe_cons_ld": cons("pendulum", "vci-ld-discrete"),
        "lob4_max": e(lob4), "lob4_cpu": "n/a" if not lob4 else f"{lob4['cpu']:.2g}",
        "pw_ld_h": long_e("pendulum_walls", "vci-ld-hamiltonian"),
        "pw_a8": long_e("pendulum_walls", "cvode-adams", 1e-8),
        "pw_a10": long_e("pendulum_walls", "cvode-adams", 1e-10),
        "pw_a12": e(a12),
        "pw_a12_cpu": "n/a" if not (a12 and lob4) else f"{a12['cpu'] / lob4['cpu']:.2g}",
        "pw_d8": long_e("pendulum_walls", "dop853", 1e-8),
        "pw_d12": long_e("pendulum_walls", "dop853", 1e-12),
        "el_d8": long_e("ellipse", "dop853", 1e-8),
        "el_d12": long_e("ellipse", "dop853", 1e-12),
        "el_lob2": long_e("ellipse", "vci-lobatto2-hamiltonian"),
        "el_ld_h": long_e("ellipse", "vci-ld-hamiltonian"),
        "el_a12": long_e("ellipse", "cvode-adams", 1e-12),
    }


MEASURED = """\
- **Same start for every method.** Every method starts from the exact (q(0), q̇(0)) at t = 0:
  the ODE peers and Siconos directly, vci through `init_from_momentum` with p(0) = M(q(0)) q̇(0).
  vci's step is h = T/N (N the integer nearest to T/h_nominal), so T is a grid point, and every
  method's final error is taken at the same T. The paper's initial pair q(0) ∓ (h/2) q̇(0) (the
  pendulum: q(0), q(0) + h q̇(0)) stays as the separate rows `vci-ld-pair-*` on the paper's three
  scenes, with h = T/(N + ½) so that T is again a grid point.
- **Scenes.** The paper's three (docs/DESIGN.md §8): particle on the floor (T = 3 s, 3 impacts),
  ellipse on the floor (T = 3 s, 3 impacts; chaotic, so only over a horizon where every method
  still follows the exact impact sequence), nonholonomic pendulum in the cylinder (T = 5 s,
  3 impacts). Two scenes whose free flight is not polynomial: the **walled planar pendulum**
  θ̈ = −(g/ℓ) sin θ, g = 9.8, ℓ = 1, walls at ±1 rad, θ(0) = 0, θ̇(0) = 4 (T = 10 s, {n_pw} impacts),
  and the **FPU-β chain between walls**: n = 32 unit masses, fixed ends, V(r) = r²/2 + r⁴/4,
  every particle confined to |x_i| ≤ 0.6 (64 walls), x_i(0) = 0.24 sin(2πi/33), ẋ_i(0) =
  1.2 sin(3πi/33) + 0.8 sin(πi/33) (T = 2 s, {n_fpu} impacts).
- **References**, independent of every method (`test/support/vci_ref_*.f90`): the particle's
  closed form; the exact event-driven ellipse (quad precision); the pendulum's reduced 1-DOF ODE
  (cross-checked below by Richardson extrapolation of vci); the walled pendulum in closed form
  (Jacobi elliptic functions in quad precision, checked in its tests against a Taylor integrator
  to ~1e-30); the FPU chain by a quad-precision order-30 Taylor event-driven integration, checked
  here two ways: step 0.01 against step 0.005 differ by {fpu_check} in the double results (state
  and impact times at T), and in its tests against normal modes and closed forms.
- **Constraint residual** (the nonholonomic pendulum only, column of its full table):
  sin²θ |f(θ) θ̇ − φ̇|, largest over the states the method reports (vci from the momenta,
  (f sin²θ p_θ − p_φ)/(mℓ²); the ODE peers from their velocities): the constraint in momentum form,
  finite through θ = π.
- **Final error**: max-norm of the configuration error at T. **Energy error**: largest |E − E0|
  over the run, E0 the exact energy; vci's energy is H(q_k, p_k) (the pendulum: the reduced
  energy with θ̇ = p_θ/(mℓ²)), the peers' E(q, q̇) at every step they take. **Impact-time error**:
  for each reference impact, the distance to the nearest impact the method reports; the largest.
  Siconos's Moreau–Jean does not locate impacts: the midpoint of the step that carries the
  impulse is used.
- **Cost**: process CPU time of one run, the median of its timed repeats (compiled methods: repeated until
  the repeats sum to 0.1 s, at least 9 and at most 2001 times, or to 1 s, at least 3 times — runs of
  microseconds are timed hundreds of times; the `reps` column; wall time in the full tables).
  vci and CVODE are Fortran, timed in-process; SciPy and Siconos are timed from Python around the
  integration loop (interpreter overhead is part of what a user of them pays). The machine may be
  shared: CPU time is the measure.
- **Methods.** `dop853`: the explicit Runge–Kutta pair of order 8(5,3) of Dormand and Prince with
  its 7th-order continuous extension, as in Hairer, Nørsett & Wanner, *Solving ODEs I* (§II.5,
  §II.6; coefficients from their published table), written here in Fortran
  (`tools/results/results_dop853.f90`): Hairer's error norm, step-size factor 0.9·err^(−1/8) clipped
  to [0.333, 6], his initial-step heuristic; after each accepted step the gaps, a decreasing
  crossing located by a safeguarded Illinois iteration on the gap of the dense output, the state
  taken at the bracket's outer end, the elastic impact map, a restart with the step size proposed
  before the impact (a one-step method keeps no history); after a reflection the return to the same
  wall is bracketed away from the restart point (samples of the dense output). Same equations,
  gaps, impact maps and tolerance sweep as CVODE (`tools/results/results_scene_ode.f90`). Checked at
  every run (`dop853_results_driver check`, a failure stops the command; its output is at the end
  of this section): the order with fixed steps on the wall-free pendulum (8 ± 0.3), the local order
  of the dense output (8 ± 0.5), impact times and final states of the particle and the ellipse
  (polynomial flight, which the method reproduces) within 1e-12 of the exact ones, the walled
  pendulum's within 1e-9 at rtol 1e-12, the ellipse over 600 s without a stall of impacts; each
  check was seen to fail with a perturbed coefficient, a root finder stopped early or a wrong
  impact map. `vci-compositionP-hamiltonian`: `set_scheme(VCI_SCHEME_COMPOSITION, P)` on the scene as a
  `vci_separable_t` (`tools/results/results_separable_scenes.f90`; the walled pendulum's
  `examples/scenes/vci_scene_pendulum_walls_sep.f90`), steps 1e-1 … 1e-4 (P = 2) and 0.4 … 1e-3.
  `vci-ld-discrete`: vci on the scene's hand-written L_d with the paper's impact
  condition (E_d(αh) = E_d((1−α)h)); `vci-ld-hamiltonian`: the same with H(q̃, p⁺) = H(q̃, p⁻) at
  the wall; Newton rtol 1e-12; nominal steps 1e-1 … 1e-5 (FPU: 5e-2 … 1e-4). The schemes from the
  scenes' continuous L (`examples/scenes/`, analytic Hessian blocks): `vci-left-discrete`,
  `vci-midpoint-*` (rtol 1e-12, steps 1e-1 … 1e-4; the ld rows cover the smaller ones) and
  `vci-lobattoS-*` (rtol 1e-14, steps 0.4 … 1e-3; FPU 0.2 … 2e-3, s = 4 down to 5e-2 only; larger
  steps fail, listed at the end; on the nonholonomic pendulum also `vci-lobatto4-hamiltonian-r8` and
  `-r6`, the same at rtol 1e-8 and 1e-6, as a user matches the solver tolerance to the accuracy
  wanted while the ODE peers' tolerance is swept). The OpenBLAS used by vci's Newton, CVODE-BDF and SciPy runs
  single-threaded (`OPENBLAS_NUM_THREADS=1`). `cvode-adams` (Adams, fixed point), `cvode-bdf` (BDF,
  Newton, dense difference-quotient Jacobian): SUNDIALS CVODE {sundials} through its Fortran 2003
  interface, root finding on every gap (decreasing crossings), elastic impact map and CVodeReInit
  at each root. `scipy-dop853`, `scipy-radau`: `solve_ivp` with a terminal event per wall and the
  impact map between restarts. The ODE peers sweep rtol = atol = 1e-3 … 1e-13 (SciPy's Radau at
  every other power of ten); on the ellipse
  they get max_step = 0.05 s so that a short dip of the gap cannot be stepped over unseen.
  `siconos-moreau-jean`: Siconos Moreau–Jean (θ = ½, Newton impact law e = 1, LCP), steps
  1e-1 … 5e-5 (FPU: … 5e-4), one relation per wall, nonlinear forces and the ellipse's floor as C plugins; not on the nonholonomic
  pendulum (not a Siconos relation). The pendulum's ODE peers integrate the Lagrange–d'Alembert
  system in (θ, φ) with the multiplier eliminated.
"""

LARGE_CHAIN_TEXT = """\
The same chain with **n = 1024** particles (2048 walls) over T = 0.5 s ({n_imp} impacts; E0 = {e0:.6g}):
x_i(0) = 0.24 sin(2πi/1025), ẋ_i(0) = 1.2 sin(3πi/1025) + 0.8 sin(πi/1025), same springs and walls.
Reference: the quad-precision order-30 Taylor event-driven integration, step 0.01 against step 0.005:
they differ by {check} in the double results (state and impact times at T). Run by
`vci_results_driver sweep FILE "" fpu_walls_1024` and the peers' drivers with the scene
`fpu_walls_1024`. vci runs `midpoint` from L with the chain's tridiagonal Hessians declared
(`declare_bandwidth(1)`, LAPACK band LU), and the explicit compositions of order 2 … 10 with the
Hamiltonian condition (their stage 1 searches first the wall estimated to be crossed first, and keeps
every wall's gap at the accepted point: 0.2–0.7 ms an impact here, where searching the walls in index
order cost ~0.07 s; docs/bench/composition.md). Its dense rows (the hand-written
L_d with an n × n mixed Hessian, Lobatto's stage systems) and CVODE-BDF (a dense 2n × 2n Newton
matrix) are left out: each would spend the time budget on dense LU, and a user with this chain would
not pick them. So is the compiled DOP853: its event location (written for the small scenes)
evaluates the whole dense output and all 2048 gaps at every root iteration, 1.3–3 s CPU a run
here at every tolerance — a cost of these tools, not of the method
(`dop853_results_driver sweep FILE fpu_walls_1024` runs it).
"""

LONG_INTRO = """\
The walled pendulum over 6·10⁴ s and the ellipse over 1.1·10⁵ s (each ≥ 10⁵ impacts) from the same
exact start. vci's hand-written L_d at h = 1e-2 with both impact conditions, and the best Lobatto
row of the scene's sweep with the Hamiltonian condition at h = 0.1 (s = 4 on the walled pendulum,
s = 2 on the ellipse: a cost near CVODE-Adams's), each timed with its energy observer (the peers
also evaluate the energy at every step); vci's long runs allow up to 64 impacts per step (the
ellipse's chaotic run has bursts of chatter that a 0.1 s step would otherwise refuse).
CVODE-Adams at rtol 1e-6 … 1e-12 and CVODE-BDF at 1e-6 and 1e-10 over the same horizon.
SciPy (DOP853, rtol 1e-10) and Siconos (h = 1e-2) pay about a millisecond of Python per impact
or per few steps, so they run over a tenth of the horizon (~10⁴ impacts) to keep the page under
15 minutes; their drift slope is over that shorter run. Each peer is plotted at its best run
(smallest energy error) among those costing at most 1.1× vci-ld-hamiltonian's CPU time, or at its
cheapest if none is that cheap. Energies are stored as the largest |E − E0| of each 10 s window;
the plot shows the running maximum, the drift slope is fitted to the window maxima (log |ΔE|
against log t, t in the last two decades of the run), the linear rate is a least-squares line
through them.
"""

SUMMARY_READING = """\
**In short** (the ratios are vci's CPU time over the peer's, over the levels 1e-4 … 1e-10 that both
reach, from the tables above; runs of microseconds are timed as the median of hundreds of repeats,
yet on a shared machine ratios within ~20 % of 1 are ties, not wins):

- **Against the compiled DOP853** — what a user with a smooth, non-stiff scene and events picks —
  the walled pendulum {pw_dop} (vci's best there are the explicit compositions; Lobatto
  {pw_dop_lob}), the FPU chain {fpu_dop}, the nonholonomic pendulum {pe_dop} (vci: Lobatto with
  the constraint at the nodes; DOP853 integrates the ODE with the multiplier eliminated), the
  particle {pa_dop} (runs of ~0.01 ms, set-up dominated), the ellipse ({el_dop}: vci's
  `hamiltonian` schemes are exact there at any step — uniform gravity, exact reflection — so the
  coarsest run wins). The instruction profile below (callgrind, run and set-up
  only) on the walled pendulum: a composition run executes {prof_ratio} the instructions of the cheapest DOP853 run that is at
  least as accurate; {prof_share} of them locate the impacts (the composed map evaluated again
  along the root iteration, where DOP853 evaluates its dense-output polynomial), and {prof_setup}
  are vci's set-up (create, set_scheme, init_from_momentum; a whole DOP853 run at rtol 1e-8 is
  {prof_dop8}).
- **Against CVODE-Adams** vci's best is cheaper on the walled pendulum ({pw_cv}), the FPU chain
  ({fpu_cv}, the explicit compositions: CVODE restarts at order 1 after each of the 41 impacts),
  the ellipse ({el_cv}) and the particle ({pa_cv}). On the nonholonomic pendulum Lobatto s = 3, 4
  (constraints at the nodes) cost {pe_cv} CVODE-Adams's. Constraint residuals there
  (sin²θ |f θ̇ − φ̇|, largest over a run): every Lobatto run ≤ {pe_cons_lob} (the end momentum is
  projected onto the constraint), CVODE-Adams {pe_cons_cv} and DOP853 {pe_cons_dop} (they keep
  the constraint only as an invariant of the ODE, to their tolerance), `midpoint` from L
  {pe_cons_mid}, the paper's L_d {pe_cons_ld}.
- **Long runs (≥ 10⁵ impacts).** *Walled pendulum*: vci-lobatto4-hamiltonian (h = 0.1,
  {lob4_cpu} s CPU) keeps |E − E0| below {lob4_max}; vci-ld-hamiltonian (h = 1e-2) is bounded at
  {pw_ld_h}. CVODE-Adams drifts linearly to {pw_a8}, {pw_a10} and {pw_a12} (rtol 1e-8, 1e-10,
  1e-12; the last at {pw_a12_cpu}× the Lobatto run's CPU); the compiled DOP853 reaches {pw_d8}
  and {pw_d12} (rtol 1e-8, 1e-12). *Ellipse*: vci-lobatto2-hamiltonian (h = 0.1) stays below
  {el_lob2} and vci-ld-hamiltonian (h = 1e-2) below {el_ld_h}; CVODE-Adams at rtol 1e-12 reaches
  {el_a12}, DOP853 {el_d8} and {el_d12} (rtol 1e-8, 1e-12). The drift slopes are in the long-run
  tables below.
"""

READING = """\
- **Same start.** From `init_from_momentum` the particle and the ellipse are integrated exactly
  by every `-hamiltonian` row at every h (errors 1e-14 … 1e-10 at h ≥ 5e-3). Below that the
  hand-written L_d's error grows with the number of steps (round-off: ~1e-7 at h = 1e-4 and 2e-5
  at h = 1e-5 on the ellipse — the negative "order" in the ellipse's fits is that, not
  truncation); `midpoint` from L, which solves for the increment and carries the rounding of the
  positions over (docs/SCHEMES.md), stays below 4e-11 down to h = 1e-4. From the paper's initial
  pair (rows `-pair`) the same model is second order, because the pair is O(h²) off the exact
  trajectory.
- **Orders through impacts** (walled pendulum, fits in its section): midpoint 2, Lobatto
  s = 2, 3, 4: 3.9–4.1, 5.7–6.3, 7.1–8.0 (the paper's condition first, then the Hamiltonian
  one), down to a round-off floor of ~1e-11 … 1e-12 that lobatto4 reaches at h = 0.05. The
  `midpoint` rows from L give the hand-written midpoint L_d's trajectory (the same numbers to the
  printed digits on the walled pendulum and the FPU chain) at about the same cost.
- **The paper's impact condition** (E_d(αh) = E_d((1−α)h)) is second order at best even where the
  flight is exact, and not monotone in h (docs/DESIGN.md §8); with Lobatto it keeps the scheme's
  order on average but scatters with α; over 10⁵ impacts its energy random-walks, while the
  Hamiltonian condition's does not drift.
- **`left`** (the paper's retraction) is first order on every scene; on the chaotic ellipse it
  leaves the exact impact sequence (final errors ~0.1–1) at every step tried.
- **Pendulum energy column.** For the nonholonomic pendulum vci's energy is computed from the
  discrete momentum p_θ as m ℓ² θ̇; for the paper's L_d, `left` and `midpoint` that column
  converges with order 1 (`midpoint`'s positions with order 2); for Lobatto it follows the
  scheme's order down to ~1e-9 (the full table).
- **Siconos Moreau–Jean** is first order on every scene (its impacts are smeared over a step)
  and the most expensive per accuracy everywhere; on the walled pendulum its energy stays bounded
  (θ = ½ scheme) but its positions carry an O(h) error.
- **SciPy** reaches small errors on the nonlinear scenes (DOP853, order 8) but pays Python per
  step and per restart: ~1 ms per impact. On the ellipse's long run its event detection missed an
  impact and the body flew on below the floor (40 impacts in 1.1·10⁴ s instead of ~10⁴), so that
  run is not a valid trajectory.
- **Failures** (listed below with the messages). The nonholonomic pendulum at h = 0.1 with the
  first-order L_d (the scene's and `left`): Newton fails at θ near π, the step is too long for it.
  (`left` on the ellipse at h = 0.05 failed at an impact in earlier editions; it runs in this one,
  with the impact steps' new starts and fallback, docs/DESIGN.md §2.) The Lobatto rows with the
  `hamiltonian` condition on the walled pendulum at h = 0.4 (0.7 of the ~0.55 s between impacts)
  failed in stage 2 in earlier editions and run since issue 27 (docs/STABILITY.md). On the FPU chain Lobatto at h ≥ 0.25 exceeds the 8 impacts allowed per
  step, so its sweep starts at 0.2.
- **Missed impacts** (the "impacts (ref)" column): the order-4 composition at its longest steps
  (walled pendulum h = 0.2, 0.3; FPU chain h = 0.1, 0.2) finds one or two impacts fewer than the
  reference — a dip into a wall and out again between the composition's internal samples, which
  docs/SCHEMES.md says the sampling can miss; those runs are far off (errors 0.03 … 0.4) and reach
  none of the tables' levels. The compiled DOP853, like CVODE, looks for crossings at its step
  ends only; it found every impact in this run.
"""


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
