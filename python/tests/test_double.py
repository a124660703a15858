"""A double pendulum (unit masses and rods) whose lower bob meets a wall x <= 1.5: from a formula
and from hand-derived Python callables. No closed form exists: the checks are agreement of the two
derivations, self-convergence at the scheme's order, the energy H(q, p) kept through the impacts
(hamiltonian condition), and admissibility along the run."""
import math

import numpy as np
import pytest

import vci
from vci._lib import ffi

import models
from conftest import slope

Q0 = [0.3, 0.2]
V0 = [1.5, 2.5]


def momentum(q, v):
    c = math.cos(q[0] - q[1])
    return [2 * v[0] + v[1] * c, v[1] + v[0] * c]


def hamiltonian(q, p):
    """H by solving p = M(q) v numerically (independent of the symbolic inversion)."""
    c = math.cos(q[0] - q[1])
    mass = np.array([[2.0, c], [c, 1.0]])
    v = np.linalg.solve(mass, p)
    return 0.5 * v @ mass @ v - 9.8 * (2 * math.cos(q[0]) + math.cos(q[1]))


def run(model, h, stages, t_final=3.0):
    it = vci.Integrator(model, h, scheme="lobatto", stages=stages, rtol=1e-15, impact_energy="hamiltonian")
    it.init_from_momentum(0.0, Q0, momentum(Q0, V0))
    return it.integrate(round(t_final / h), record=True)


@pytest.fixture(scope="module")
def formula_model():
    return models.double_formula(energy=True)


def test_formula_and_python_agree(formula_model):
    # the same L derived by sympy and by hand, the same scheme: equal to round-off over 3 s
    # (2 impacts); the run is not chaotic enough in 3 s to amplify rounding beyond ~1e-11
    a = run(formula_model, 0.01, 2)
    b = run(models.double_python(), 0.01, 2)
    assert len(a.impacts) == len(b.impacts) == 2
    assert np.max(np.abs(a.q - b.q)) < 1e-10 and np.max(np.abs(a.p - b.p)) < 1e-10
    assert np.max(np.abs(a.impacts["t"] - b.impacts["t"])) < 1e-10


def test_self_convergence_order_4(formula_model):
    # lobatto s = 2 at h = 0.04, 0.02, 0.01 against s = 4 at h = 0.0025 (error ~1e-13, far below):
    # order 4 (errors 1e-5 .. 5e-8)
    ref = run(formula_model, 0.0025, 4)
    hs = [0.04, 0.02, 0.01]
    errs = []
    for h in hs:
        tr = run(formula_model, h, 2)
        assert len(tr.impacts) == len(ref.impacts) == 2
        errs.append(np.max(np.abs(tr.q[-1] - ref.q[-1])))
    assert slope(hs, errs) == pytest.approx(4.0, abs=0.4)


def test_energy_kept_through_impacts(formula_model):
    # H along the run: the scheme's error only (order 2s = 8 at h = 0.01: measured 1e-12), and the
    # impacts keep it (hamiltonian condition); an impact that lost energy would show as a jump
    tr = run(formula_model, 0.01, 4)
    e = np.array([hamiltonian(q, p) for q, p in zip(tr.q, tr.p)])
    assert len(tr.impacts) == 2
    assert np.max(np.abs(e - e[0])) < 1e-9
    gap = 1.5 - np.sin(tr.q[:, 0]) - np.sin(tr.q[:, 1])
    assert gap.min() >= -1e-12
    # the lower bob is on the wall at each impact
    q = tr.impacts["q"]
    assert np.allclose(np.sin(q[:, 0]) + np.sin(q[:, 1]), 1.5, atol=1e-10)


def test_symbolic_energy_is_the_legendre_transform(formula_model):
    # energy=True derives H(q, p) symbolically; the compiled callback against a numerical solve
    fn = ffi.cast("vci_energy_fn", formula_model.callbacks["energy"].address)
    rng = np.random.default_rng(7)
    out = ffi.new("double[1]")
    for _ in range(20):
        q, p = rng.uniform(-2, 2, 2), rng.uniform(-5, 5, 2)
        assert fn(2, ffi.from_buffer("double[]", q), ffi.from_buffer("double[]", p), out, ffi.NULL) == 0
        assert out[0] == pytest.approx(hamiltonian(q, p), rel=1e-12, abs=1e-12)
