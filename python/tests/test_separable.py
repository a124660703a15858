"""The separable kind from Python (issue 32): vci.formula detects L = 1/2 qdot^T M qdot - V(q) with
M constant and builds a SeparableModel, so scheme='composition' (the explicit Verlet
compositions) runs a formula; SeparableModel from Python callables; refusals."""
import math

import numpy as np
import pytest
import sympy as sp

import vci
import vci.formula
from conftest import slope, walls_exact
from models import G, walls_formula


def _walled_run(model, order, h, t=10.0):
    integ = vci.Integrator(model, h, scheme="composition", stages=order)
    integ.init_from_momentum(0.0, [0.0], [4.0])
    integ.integrate(int(round(t / h)))
    return integ


def test_formula_detects_separable():
    model = walls_formula(backend="python")
    assert isinstance(model, vci.SeparableModel) and model.kind == "separable"
    np.testing.assert_array_equal(model.formula.mass, [[1.0]])
    th = model.formula.q[0]
    assert sp.simplify(model.formula.derived["potential"] + G * sp.cos(th)) == 0
    # not separable: a velocity-dependent mass, a term linear in qdot, constraints; and forced off
    th, om, x, xd = sp.symbols("theta omega x xd")
    for L, q, v, kw in ((om ** 2 * (2 + sp.cos(th)) / 2, [th], [om], {}),
                        (om ** 2 / 2 + th * om, [th], [om], {}),
                        (om ** 2 / 2 + xd ** 2 / 2, [th, x], [om, xd], {"forms": [[1, -1]]}),
                        (om ** 2 / 2 + G * sp.cos(th), [th], [om], {"separable": False})):
        m = vci.formula.lagrangian_model(L, q, v, backend="python", **kw)
        assert type(m) is vci.LagrangianModel
    with pytest.raises(vci.FormulaError, match="not 1/2 qdot"):
        vci.formula.lagrangian_model(om ** 2 * (2 + sp.cos(th)) / 2, [th], [om], backend="python", separable=True)


def test_formula_composition_orders_through_impacts():
    # The walled pendulum from a formula (numba backend), 10 s, 18 impacts, against the exact
    # state: orders 4 and 6 of the compositions over one decade of h each (the same spans as
    # test/core/test_composition.pf: errors 1e-3 .. 1e-9, far above the round-off floor ~3e-14),
    # least-squares slopes within 0.3 of the order.
    theta, omega, times = walls_exact(0.0, 4.0, 1.0, 10.0)
    assert len(times) == 18
    model = walls_formula()
    assert isinstance(model, vci.SeparableModel)
    for order, hmax, hmin in ((4, 0.1, 0.01), (6, 0.2, 0.02)):
        hs, errs = [], []
        for k in range(8):
            h = 10.0 / round(10.0 / (hmax * (hmin / hmax) ** (k / 7)))
            integ = _walled_run(model, order, h)
            assert integ.stats.impacts == 18
            q, p = integ.q, integ.p
            hs.append(h)
            errs.append(max(abs(q[0] - theta), abs(p[0] - omega)))
        s = slope(hs, errs)
        print(f"formula, composition order {order}: slope {s:.2f}, errors {errs[0]:.2e} .. {errs[-1]:.2e}")
        assert min(errs) > 1e-12
        assert abs(s - order) <= 0.3


def test_formula_matches_python_callables():
    # The formula's compiled V, grad V against the same model from Python callables: the same
    # arithmetic (9.8 sin theta), so the same bits through 18 impacts (order 6, h = 0.05).
    model_f = walls_formula()
    model_p = vci.SeparableModel(1, 2, mass=[1.0], potential=lambda q: -G * math.cos(q[0]),
                                 potential_gradient=lambda q: [G * math.sin(q[0])],
                                 gaps=lambda q: [1.0 - q[0], q[0] + 1.0],
                                 gap_gradients=lambda q: [[-1.0], [1.0]])
    a = _walled_run(model_f, 6, 0.05)
    b = _walled_run(model_p, 6, 0.05)
    print("formula vs callables:", a.q - b.q, a.p - b.p)
    assert np.array_equal(a.q, b.q) and np.array_equal(a.p, b.p)


def test_separable_refusals():
    with pytest.raises(vci.ArgumentError, match="mass"):
        vci.SeparableModel(2, 0, mass=[1.0, 2.0, 3.0], potential=lambda q: 0.0, potential_gradient=lambda q: [0, 0])
    with pytest.raises(vci.VciError, match="positive"):
        vci.SeparableModel(2, 0, mass=[1.0, -2.0], potential=lambda q: 0.0, potential_gradient=lambda q: [0, 0])
    with pytest.raises(vci.VciError, match="symmetric positive definite"):
        vci.SeparableModel(2, 0, mass=[[1.0, 2.0], [2.0, 1.0]], potential=lambda q: 0.0,
                           potential_gradient=lambda q: [0, 0])
    with pytest.raises(vci.ArgumentError, match="gap_gradients"):
        vci.SeparableModel(1, 2, mass=[1.0], potential=lambda q: 0.0, potential_gradient=lambda q: [0.0],
                           gaps=lambda q: [1.0, 1.0])
    # composition on a model that is not separable: the library's refusal
    th, om = sp.symbols("theta omega")
    lag = vci.formula.lagrangian_model(om ** 2 / 2 + G * sp.cos(th), [th], [om], backend="python", separable=False)
    with pytest.raises(vci.ArgumentError, match="separable"):
        vci.Integrator(lag, 0.05, scheme="composition", stages=4)
