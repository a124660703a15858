"""The paper's nonholonomic pendulum in a cylinder (q = (theta, phi), constraint
(pi + cos^2 theta) dtheta - dphi = 0, wall R^2 - l^2 sin^2 theta >= 0; 3 impacts in 5 s) from a
formula, from Python callables, and as the paper's hand-derived discrete L_d, against the
event-driven reference test/support/vci_ref_pendulum.f90 (impact times within 1e-13 of quadrature)."""
import math

import numpy as np
import pytest

import vci

import models
from conftest import paper_exact, slope

T_FINAL = 5.0


@pytest.fixture(scope="module")
def exact():
    return paper_exact(models.PAPER_Q0[0], models.PAPER_QDOT0[0], models.PAPER_Q0[1], T_FINAL)


def run(model, h, **kw):
    it = vci.Integrator(model, h, rtol=1e-15, **kw)
    it.init_from_momentum(0.0, models.PAPER_Q0, models.paper_p0())
    state = it.integrate(round(T_FINAL / h))
    return state, it.impacts


def errors(state, impacts, exact):
    theta, phi, _, times = exact
    assert len(times) == 3 and len(impacts) == 3
    return max(abs(state.q[0] - theta), abs(state.q[1] - phi)), float(np.max(np.abs(impacts["t"] - times)))


STEPS = [T_FINAL / round(T_FINAL / (1e-2 / 1.65 ** k)) for k in range(8)]


@pytest.mark.parametrize("mode", ["discrete", "hamiltonian"])
def test_formula_midpoint_order_2_through_impacts(mode, exact):
    # midpoint: order 2 through the 3 impacts (final configuration and impact times), 8 step
    # sizes over 1.5 decades, errors 2e-3 .. 3e-7, far above round-off
    model = models.paper_formula()
    errs = [errors(*run(model, h, scheme="midpoint", impact_energy=mode), exact) for h in STEPS]
    assert slope(STEPS, [e[0] for e in errs]) == pytest.approx(2.0, abs=0.3)
    assert slope(STEPS, [e[1] for e in errs]) == pytest.approx(2.0, abs=0.3)


def test_python_midpoint_order_2(exact):
    # the same with Python callables (4 step sizes: Python callbacks are slow)
    model = models.paper_python()
    hs = STEPS[:4]
    errs = [errors(*run(model, h, scheme="midpoint"), exact) for h in hs]
    assert slope(hs, [e[0] for e in errs]) == pytest.approx(2.0, abs=0.3)
    assert slope(hs, [e[1] for e in errs]) == pytest.approx(2.0, abs=0.3)


def test_constraint_holds_on_the_trajectory():
    # midpoint imposes Omega(midpoint) . (q_k+1 - q_k) = 0 every step, to the solver's tolerance
    model = models.paper_formula()
    it = vci.Integrator(model, 0.01, rtol=1e-15)
    it.init_from_momentum(0.0, models.PAPER_Q0, models.paper_p0())
    traj = it.integrate(500, record=True)
    mid = 0.5 * (traj.q[1:] + traj.q[:-1])
    dq = np.diff(traj.q, axis=0)
    residual = (math.pi + np.cos(mid[:, 0]) ** 2) * dq[:, 0] - dq[:, 1]
    # (a step with an impact is two sub-steps, each with its own midpoint: left out)
    regular = np.ones(len(dq), bool)
    for t in traj.impacts["t"]:
        regular[np.searchsorted(traj.t, t) - 1] = False
    assert np.count_nonzero(~regular) == 3
    assert np.max(np.abs(residual[regular])) < 1e-12
    assert traj.multipliers.shape == (500, 1) and np.all(np.isfinite(traj.multipliers))
    assert len(traj.impacts) == 3


def test_discrete_model_is_the_left_scheme(exact):
    # the paper's hand-derived L_d (a DiscreteModel of Python callables) is the `left` scheme of
    # the formula's L: the two runs agree to the rounding of their different arrangements
    # (docs/SCHEMES.md: ~1e-11 after 5 s), and the impacts are the exact ones to first order
    h = 1e-3
    q0 = models.PAPER_Q0
    q1 = q0 + h * models.PAPER_QDOT0
    a = vci.Integrator(models.paper_discrete_python(), h)
    a.init_from_pair(0.0, q0, q1)
    sa = a.integrate(round(T_FINAL / h) - 1)
    b = vci.Integrator(models.paper_formula(), h, scheme="left")
    b.init_from_pair(0.0, q0, q1)
    sb = b.integrate(round(T_FINAL / h) - 1)
    assert sa.t == sb.t == pytest.approx(T_FINAL)
    assert np.max(np.abs(sa.q - sb.q)) < 1e-9 and np.max(np.abs(sa.p - sb.p)) < 1e-9
    assert len(a.impacts) == 3
    # order 1 at h = 1e-3: a few h
    assert np.max(np.abs(a.impacts["t"] - exact[3])) < 5 * h
    assert a.multipliers.shape == (1,)
