#!/usr/bin/python3
"""Independent cross-checks of the Fortran reference solutions (test/support/vci_ref_*.f90).

Scenes and parameters: docs/DESIGN.md section 8. Three independent computations:

* scipy solve_ivp (DOP853, rtol = atol = 1e-12) with terminal events and the impact map applied
  between restarts, for the ellipse and for the pendulum. The pendulum is integrated here as the
  full two-degree-of-freedom Lagrange-d'Alembert system with its multiplier (not the reduced
  1-DOF equation the Fortran code uses), so phi is checked too.
* mpmath, 40 digits: the pendulum's impact times by quadrature of dt = dtheta / |thetadot(theta)|
  from energy conservation (the motion shuttles between the two walls, so the times are
  t1 + k T); the ellipse's impact times event by event on the closed-form flight, both for
  the double-rounded data the Fortran code receives and for the exact data (pi/2, g = 9.8):
  the ellipse is chaotic, and the two part company after a few impacts.
* The Fortran driver tools/reference/print_references.f90 in its "times" mode (built here with
  gfortran unless --exe names a built driver).

Usage:  /usr/bin/python3 tools/reference/references.py [--exe PATH]
The functions are importable for reports: ellipse_scipy, pendulum_scipy, pendulum_quadrature,
ellipse_mp, fortran_results.
"""
import argparse
import math
import os
import subprocess
import tempfile

import mpmath as mp
import numpy as np
from scipy.integrate import solve_ivp

ELLIPSE = dict(m=1.0, g=9.8, a=1.0, b=0.5)
ELLIPSE_Q0 = (math.pi / 2, 0.0, 3.5)
ELLIPSE_V0 = (-3.0, 2.0, 0.0)
PENDULUM = dict(m=1.0, g=9.8, ell=2.0, radius=1.5)
PEND_THETA0 = 0.75 * math.pi
PEND_THETADOT0 = math.pi / 4

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))


# ----------------------------------------------------------------------------- ellipse

def ellipse_scipy(t_final, rtol=1e-12, atol=1e-12, max_step=5e-3, par=ELLIPSE,
                  q0=ELLIPSE_Q0, v0=ELLIPSE_V0):
    """Impact times in (0, t_final] and the state (q, qdot) at t_final, by solve_ivp.

    max_step bounds the steps: the right-hand side is constant, so DOP853 would otherwise take
    steps long enough to jump over a whole excursion below the floor without a sign change.
    """
    m, g, a, b = par["m"], par["g"], par["a"], par["b"]
    inertia = m * (a * a + b * b) / 4

    def phi(th):
        return math.sqrt((a * math.sin(th)) ** 2 + (b * math.cos(th)) ** 2)

    def rhs(t, s):
        return [s[3], s[4], s[5], 0.0, 0.0, -g]

    def gap(t, s):
        return s[2] - phi(s[0])
    gap.terminal = True
    gap.direction = -1

    minv = np.array([1 / inertia, 1 / m, 1 / m])
    t, s, times = 0.0, np.array([*q0, *v0], dtype=float), []
    while True:
        sol = solve_ivp(rhs, (t, t_final), s, method="DOP853", rtol=rtol, atol=atol,
                        max_step=max_step, events=gap)
        if sol.status != 1:
            return times, sol.y[:3, -1], sol.y[3:, -1]
        t, s = sol.t_events[0][0], sol.y_events[0][0].copy()
        # p+ = p- + mu grad g, grad g = (-phi', 0, 1), mu keeps the kinetic energy.
        th = s[0]
        n = np.array([-(a * a - b * b) * math.sin(th) * math.cos(th) / phi(th), 0.0, 1.0])
        mu = -2 * n @ s[3:] / (n @ (minv * n))
        s[3:] += mu * minv * n
        times.append(t)


def ellipse_mp(t_final, dps=40, par=ELLIPSE, q0=ELLIPSE_Q0, v0=ELLIPSE_V0, sample=1e-3):
    """Impact times in (0, t_final] at dps digits, event by event on the closed-form flight.

    The initial data are taken as the exact values of the given doubles (so pi/2 is the double
    nearest to it, as in the Fortran run). Roots are found by sampling the gap every `sample`
    seconds; an interval is cleared when the concave lower bound G + G' u - K u^2/2 stays
    positive on it (|G''| <= K), split in halves while it is neither cleared nor has a sign
    change, and a sign change is polished by bracketed root finding.
    """
    with mp.workdps(dps):
        m, g, a, b = (mp.mpf(par[k]) for k in ("m", "g", "a", "b"))
        inertia = m * (a * a + b * b) / 4
        c = abs(a * a - b * b)
        r = min(a, b)
        curv = (c + (c / (2 * r)) ** 2) / r          # bound on |phi''|
        q = [mp.mpf(x) for x in q0]
        v = [mp.mpf(x) for x in v0]
        t = mp.mpf(0)
        times = []

        def phi(th):
            return mp.sqrt((a * mp.sin(th)) ** 2 + (b * mp.cos(th)) ** 2)

        def dphi(th):
            return (a * a - b * b) * mp.sin(th) * mp.cos(th) / phi(th)

        def gap(s):
            return q[2] + v[2] * s - g * s * s / 2 - phi(q[0] + v[0] * s)

        def dgap(s):
            return v[2] - g * s - dphi(q[0] + v[0] * s) * v[0]

        def first_root(lo, hi, k_bound, depth=0):
            # G(lo) > 0 on entry; returns the first root in (lo, hi] or None.
            g_lo, d_lo, w = gap(lo), dgap(lo), hi - lo
            if g_lo + d_lo * w - k_bound * w * w / 2 > 0:
                return None                       # lower bound positive: no root
            if d_lo + k_bound * w < 0 and gap(hi) <= 0:
                # G' < 0 on the whole interval: the sign change is the only root
                return mp.findroot(gap, (lo, hi), solver="anderson")
            if depth > 100:
                raise RuntimeError(f"ellipse_mp: cannot separate roots near t = {t + lo}")
            mid = (lo + hi) / 2
            left = first_root(lo, mid, k_bound, depth + 1)
            return left if left is not None else first_root(mid, hi, k_bound, depth + 1)

        eps = mp.mpf(10) ** (-dps // 2)
        while True:
            k_bound = g + v[0] ** 2 * curv
            # just after an impact the gap is zero at s = 0: start the search a little later,
            # where the lower bound (with G(0) = 0, G'(0) > 0) is still positive.
            s = min(eps, dgap(0) / k_bound) if times else mp.mpf(0)
            root = None
            while t + s < t_final and root is None:
                hi = min(s + sample, t_final - t)
                root = first_root(s, hi, k_bound)
                s = hi
            if root is None:
                return [float(x) for x in times], times
            # flight to the impact, then the energy-keeping reflection
            q = [q[0] + v[0] * root, q[1] + v[1] * root, q[2] + v[2] * root - g * root ** 2 / 2]
            v = [v[0], v[1], v[2] - g * root]
            t += root
            n = [-dphi(q[0]), mp.mpf(0), mp.mpf(1)]
            minv = [1 / inertia, 1 / m, 1 / m]
            mu = (-2 * sum(n[i] * v[i] for i in range(3))
                  / sum(minv[i] * n[i] ** 2 for i in range(3)))
            v = [v[i] + mu * minv[i] * n[i] for i in range(3)]
            times.append(t)


# ---------------------------------------------------------------------------- pendulum

def _f(th):
    return math.pi + math.cos(th) ** 2


def pendulum_scipy(t_final, rtol=1e-12, atol=1e-12, par=PENDULUM, theta0=PEND_THETA0,
                   thetadot0=PEND_THETADOT0, phi0=0.0):
    """Impact times in (0, t_final] and (theta, phi, thetadot, phidot) at t_final.

    Full system q = (theta, phi) with multiplier lambda for omega = f dtheta - dphi:
        d/dt(M qdot) - dL/dq = lambda omega,   M = m l^2 diag(1, sin^2 theta),
        f thetaddot + f' thetadot^2 - phiddot = 0   (the constraint, differentiated),
    solved as one 3x3 linear system per evaluation (nonsingular also at sin theta = 0).
    At the wall the constraint and the energy leave (thetadot, phidot) -> -(thetadot, phidot).
    """
    m, g, ell, rad = par["m"], par["g"], par["ell"], par["radius"]
    ml2 = m * ell * ell

    def rhs(t, y):
        th, ph, thd, phd = y
        s, c, f = math.sin(th), math.cos(th), _f(th)
        df = -2 * s * c
        mat = np.array([[ml2, 0.0, -f], [0.0, ml2 * s * s, 1.0], [f, -1.0, 0.0]])
        rhs_vec = np.array([ml2 * phd * phd * s * c + m * g * ell * s,
                            -2 * ml2 * s * c * thd * phd,
                            -df * thd * thd])
        thdd, phdd, _ = np.linalg.solve(mat, rhs_vec)
        return [thd, phd, thdd, phdd]

    def gap(t, y):
        return rad * rad - (ell * math.sin(y[0])) ** 2
    gap.terminal = True
    gap.direction = -1

    t = 0.0
    y = np.array([theta0, phi0, thetadot0, _f(theta0) * thetadot0])
    times = []
    while True:
        sol = solve_ivp(rhs, (t, t_final), y, method="DOP853", rtol=rtol, atol=atol, events=gap)
        if sol.status != 1:
            return times, sol.y[:, -1]
        t, y = sol.t_events[0][0], sol.y_events[0][0].copy()
        y[2:] = -y[2:]
        times.append(t)


def pendulum_quadrature(t_final, dps=40, par=PENDULUM, theta0=PEND_THETA0,
                        thetadot0=PEND_THETADOT0, phi0=0.0):
    """Impact times in (0, t_final] and (theta, phi, thetadot) at t_final by quadrature (mpmath).

    Energy E = 1/2 m l^2 A(theta) thetadot^2 + m g l cos(theta), A = 1 + f^2 sin^2 theta, gives
    |thetadot| as a function of theta. Valid when the motion reaches both walls of the well
    around theta = pi (checked): then the walls are hit alternately, t1 is the time to the wall
    ahead and the transit time T between the walls is the same in both directions. The state
    at t_final solves  time from the last wall (or the start) to theta = elapsed time  for
    theta; phi = phi0 + Phi(theta) - Phi(theta0) with Phi = (pi + 1/2) theta + sin(2 theta)/4
    (the constraint integrated in closed form).
    """
    with mp.workdps(dps):
        m, g, ell, rad = (mp.mpf(par[k]) for k in ("m", "g", "ell", "radius"))
        th0, thd0 = mp.mpf(theta0), mp.mpf(thetadot0)

        def area(th):
            return 1 + ((mp.pi + mp.cos(th) ** 2) * mp.sin(th)) ** 2

        energy = m * ell ** 2 * area(th0) * thd0 ** 2 / 2 + m * g * ell * mp.cos(th0)
        w_lo, w_hi = mp.pi - mp.asin(rad / ell), mp.pi + mp.asin(rad / ell)
        if not (w_lo < th0 < w_hi and energy > m * g * ell * mp.cos(w_lo)):
            raise ValueError("quadrature reference needs a start between the walls with "
                             "enough energy to reach them")

        def speed(th):
            return mp.sqrt(2 * (energy - m * g * ell * mp.cos(th)) / (m * ell ** 2 * area(th)))

        def transit(a, b):
            """Time to move from a to b (split at pi, where the integrand has a kink in A)."""
            lo, hi = min(a, b), max(a, b)
            nodes = [lo, mp.pi, hi] if lo < mp.pi < hi else [lo, hi]
            return mp.quad(lambda th: 1 / speed(th), nodes)

        ahead = w_hi if thd0 > 0 else w_lo
        t1 = transit(th0, ahead)
        period = transit(w_lo, w_hi)
        times = []
        while t1 + len(times) * period <= t_final:
            times.append(t1 + len(times) * period)

        # last wall left (or the start), direction of motion since, elapsed time
        if times:
            k = len(times)
            wall = ahead if k % 2 == 1 else (w_lo if ahead == w_hi else w_hi)
            start, sign, elapsed = wall, (-1 if wall == w_hi else 1), t_final - times[-1]
        else:
            start, sign, elapsed = th0, (1 if thd0 > 0 else -1), mp.mpf(t_final)
        theta = mp.findroot(lambda th: transit(start, th) - elapsed,
                            start + sign * speed(start) * elapsed)

        def big_phi(th):
            return (mp.pi + mp.mpf(1) / 2) * th + mp.sin(2 * th) / 4

        phi = phi0 + big_phi(theta) - big_phi(th0)
        state = (float(theta), float(phi), float(sign * speed(theta)))
        return [float(x) for x in times], times, state


# ----------------------------------------------------------------------------- Fortran

def fortran_results(exe=None):
    """Output of the Fortran driver in "times" mode: {name: list of floats}."""
    if exe is None:
        with tempfile.TemporaryDirectory(prefix="vci_refs_") as build:
            exe = os.path.join(build, "print_references")
            sources = [os.path.join(ROOT, "test", "support", f"vci_ref_{n}.f90")
                       for n in ("particle", "ellipse", "pendulum")]
            sources.append(os.path.join(ROOT, "tools", "reference", "print_references.f90"))
            subprocess.run(["gfortran", "-O2", "-J", build, *sources, "-o", exe], check=True)
            return fortran_results(exe)
    out = subprocess.run([exe, "times"], check=True, capture_output=True, text=True).stdout
    results = {}
    for line in out.splitlines():
        name, count, *values = line.split()
        results[name] = [float(x) for x in values]
        assert len(results[name]) == int(count), name
    return results


# -------------------------------------------------------------------------------- main

def _table(title, columns, rows):
    """First column a time (full precision), the others differences."""
    print(title)
    print("   k  " + f"{columns[0]:>24}" + "".join(f"{c:>24}" for c in columns[1:]))
    for k, (time, *diffs) in enumerate(rows, 1):
        print(f"  {k:2d}  {time:24.16e}" + "".join(f"{d:24.2e}" for d in diffs))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--exe", help="a built print_references driver (default: build one)")
    args = parser.parse_args()

    fortran = fortran_results(args.exe)

    f_ell = fortran["ellipse_25"]
    s_ell, _, _ = ellipse_scipy(25.0)
    m_ell, _ = ellipse_mp(25.0)
    with mp.workdps(40):
        exact_scene = dict(ELLIPSE, g=mp.mpf("9.8"))
        x_ell, _ = ellipse_mp(25.0, par=exact_scene, q0=(mp.pi / 2, 0, mp.mpf("3.5")))

    def diff(other, i):
        return other[i] - f_ell[i] if i < len(other) else math.nan

    _table(f"== ellipse, impacts in 25 s: Fortran {len(f_ell)}, scipy {len(s_ell)}, "
           f"mpmath {len(m_ell)}, mpmath with pi/2 and 9.8 exact {len(x_ell)}\n"
           "   (chaotic: differences grow about tenfold per impact, counts over 25 s depend on "
           "the last bit of the data)",
           ["Fortran", "scipy - Fortran", "mpmath(40) - Fortran", "exact data - Fortran"],
           [(f_ell[i], diff(s_ell, i), diff(m_ell, i), diff(x_ell, i))
            for i in range(len(f_ell))])
    print()

    f_pen = fortran["pendulum_100"]
    s_pen, _ = pendulum_scipy(100.0)
    q_pen, _, _ = pendulum_quadrature(100.0)
    n = min(len(f_pen), len(s_pen), len(q_pen))
    _table(f"== pendulum, impacts in 100 s: Fortran {len(f_pen)}, scipy {len(s_pen)}, "
           f"quadrature {len(q_pen)}",
           ["Fortran", "scipy - Fortran", "quadrature - Fortran"],
           [(f_pen[i], s_pen[i] - f_pen[i], q_pen[i] - f_pen[i]) for i in range(n)])
    print(f"  max |scipy - Fortran| = {max(abs(a - b) for a, b in zip(s_pen, f_pen)):.2e}, "
          f"max |quadrature - Fortran| = {max(abs(a - b) for a, b in zip(q_pen, f_pen)):.2e}")

    _, state5 = pendulum_scipy(5.0)
    _, _, q_state5 = pendulum_quadrature(5.0)
    f_state = fortran["pendulum_state_5"]
    print("  state at 5 s (theta, phi, thetadot):")
    print("    Fortran              " + " ".join(f"{x:24.16e}" for x in f_state))
    for label, other in (("scipy - Fortran", state5[:3]), ("quadrature - Fortran", q_state5)):
        print(f"    {label:21s}" + " ".join(f"{a - b:24.2e}" for a, b in zip(other, f_state)))


if __name__ == "__main__":
    main()
