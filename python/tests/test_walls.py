"""The walled pendulum (theta'' = -9.8 sin theta, walls at +-1 rad, theta(0) = 0, theta'(0) = 4,
18 impacts in 10 s) given the three ways -- Python callables, compiled callbacks (hand-written
numba cfuncs, and C functions compiled by the C compiler, through ctypes), L as a sympy formula --
against the exact solution (Jacobi elliptic functions in quad precision,
test/support/vci_ref_pendulum_walls.f90, through test/python/vci_python_ref)."""
import math

import numpy as np
import pytest

import vci
from vci._lib import ffi

import models
from conftest import slope, walls_exact

T_FINAL = 10.0


@pytest.fixture(scope="module")
def exact():
    return walls_exact(0.0, 4.0, 1.0, T_FINAL)


def run(model, h, **kw):
    it = vci.Integrator(model, h, rtol=1e-15, **kw)
    it.init_from_momentum(0.0, [0.0], [4.0])
    state = it.integrate(t_final=T_FINAL)
    assert state.t == pytest.approx(T_FINAL, abs=1e-9)
    return state, it.impacts


def errors(state, impacts, exact):
    theta, omega, times = exact
    assert len(impacts) == len(times) == 18
    return max(abs(state.q[0] - theta), abs(state.p[0] - omega)), float(np.max(np.abs(impacts["t"] - times)))


PATHS = {
    "python": lambda tmp: models.walls_python(),
    "numba": lambda tmp: models.walls_numba(),
    "c": lambda tmp: models.walls_c(tmp),
    "formula": lambda tmp: models.walls_formula(),
}


@pytest.mark.parametrize("path", sorted(PATHS))
def test_lobatto4_matches_exact(path, tmp_path, exact):
    # order 8 (2s): measured 2.5e-11 (theta) and 6.2e-11 (theta') from the exact state, as the
    # C client (test/api/lagrangian_test.c) finds; 1e-9 leaves room for round-off but not for a
    # lower order (h^6 at h = 0.05 is 1.6e-8) nor for a missed or extra impact
    state, impacts = run(PATHS[path](tmp_path), 0.05, scheme="lobatto", stages=4)
    e_state, e_times = errors(state, impacts, exact)
    assert e_state <= 1e-9
    assert e_times <= 1e-9
    # the impacts alternate between the walls, each with g(q) = 0 on the wall
    assert list(impacts["gap"]) == [0, 1] * 9
    assert np.allclose(np.abs(impacts["q"][:, 0]), 1.0, atol=1e-12)
    assert np.all((impacts["alpha"] >= 0) & (impacts["alpha"] <= 1))


def test_paths_agree_to_roundoff(tmp_path):
    # the same scheme on the same L: only rounding may differ between the ways of giving it
    finals = {}
    for path, make in PATHS.items():
        state, impacts = run(make(tmp_path), 0.05, scheme="lobatto", stages=4, impact_energy="hamiltonian")
        finals[path] = np.concatenate([state.q, state.p, impacts["t"]])
    ref = finals.pop("c")
    for path, x in finals.items():
        assert np.max(np.abs(x - ref)) <= 1e-12, path


def test_formula_order_lobatto2(exact):
    # s = 2: order 4 through the 18 impacts (hamiltonian condition: docs/SCHEMES.md); errors from
    # 2e-3 to 5e-7 over h = 0.1 .. 0.0125, far above round-off
    model = models.walls_formula()
    hs = [0.1, 0.05, 0.025, 0.0125]
    errs = [errors(*run(model, h, scheme="lobatto", stages=2, impact_energy="hamiltonian"), exact) for h in hs]
    assert slope(hs, [e[0] for e in errs]) == pytest.approx(4.0, abs=0.4)
    assert slope(hs, [e[1] for e in errs]) == pytest.approx(4.0, abs=0.4)


def test_numba_order_lobatto3(exact):
    # s = 3: order 6; errors 5e-6 .. 1e-9 over h = 0.1 .. 0.025
    model = models.walls_numba()
    hs = [0.1, 0.05, 0.025]
    errs = [errors(*run(model, h, scheme="lobatto", stages=3, impact_energy="hamiltonian"), exact) for h in hs]
    assert slope(hs, [e[0] for e in errs]) == pytest.approx(6.0, abs=0.5)
    assert slope(hs, [e[1] for e in errs]) == pytest.approx(6.0, abs=0.5)


def test_python_order_midpoint(exact):
    # midpoint: order 2; errors 2e-2 .. 1.4e-3 over h = 0.02 .. 0.005
    model = models.walls_python(hessians=False)  # the library differences the Hessian blocks
    hs = [0.02, 0.01, 0.005]
    errs = [errors(*run(model, h, scheme="midpoint", impact_energy="hamiltonian"), exact) for h in hs]
    assert slope(hs, [e[0] for e in errs]) == pytest.approx(2.0, abs=0.3)
    assert slope(hs, [e[1] for e in errs]) == pytest.approx(2.0, abs=0.3)


def test_c_pointer_receives_user(tmp_path):
    # compiled callbacks get the model's user pointer: a C callback counts its calls through it
    counter = ffi.new("long *")
    model = models.walls_c(tmp_path, user=counter, counting=True)
    run(model, 0.05, scheme="lobatto", stages=2)
    assert counter[0] > 200


def test_record_matches_integrate(exact):
    # step-by-step recording gives the same run as one library call
    model = models.walls_formula()
    it = vci.Integrator(model, 0.05, scheme="lobatto", stages=4, rtol=1e-15)
    it.init_from_momentum(0.0, [0.0], [4.0])
    traj = it.integrate(200, record=True)
    state, _ = run(model, 0.05, scheme="lobatto", stages=4)
    assert traj.t.shape == (201,) and traj.q.shape == (201, 1) and traj.energy.shape == (200,)
    assert traj.q[-1, 0] == state.q[0] and traj.p[-1, 0] == state.p[0]
    assert len(traj.impacts) == 18
    # E_d stays within the scheme's error of the exact energy 8 - 9.8 = -1.8 (E = v^2/2 - 9.8 cos)
    assert np.max(np.abs(traj.energy - (0.5 * 16 - 9.8))) < 1e-6
    assert it.stats.steps == 200 and it.stats.impacts == 18 and it.index == 200


def test_backward_returns(exact):
    model = models.walls_formula()
    it = vci.Integrator(model, 0.05, scheme="lobatto", stages=4, rtol=1e-15)
    it.init_from_momentum(0.0, [0.0], [4.0])
    it.integrate(100)
    it.integrate(100, direction="backward")
    st = it.state
    assert st.t == pytest.approx(0.0, abs=1e-12)
    assert abs(st.q[0]) < 1e-10 and abs(st.p[0] - 4.0) < 1e-10


def test_cffi_function_pointers(exact):
    # a cffi function pointer, or a void * holding one, is passed through; other pointers are refused
    numba_model = models.walls_numba()
    cbs = dict(numba_model.callbacks)
    cbs["dl_dq"] = ffi.cast("void *", cbs["dl_dq"].address)
    cbs["dl_dv"] = ffi.cast("vci_lagrangian_grad_fn", cbs["dl_dv"].address)
    state, impacts = run(vci.LagrangianModel(1, 0, 2, **cbs), 0.05, scheme="lobatto", stages=4)
    assert errors(state, impacts, exact)[0] <= 1e-9
    with pytest.raises(vci.ArgumentError, match="double \\* is not a function pointer"):
        vci.LagrangianModel(1, 0, 2, **dict(cbs, dl_dq=ffi.new("double *")))


def test_untied_impact_counted():
    # a ball under gravity g = 10 leaving the floor early in a step of 0.2 and only just reaching a
    # ceiling at 0.04 within it (midpoint: E_d = H - g^2 tau^2 / 8 on a sub-step of length tau): no
    # impulse holds the floor impact's energy condition on the sub-step up to the ceiling, so it
    # keeps it on the rest of the step and the integrator counts it (core_reversal's
    # test_untied_impact_is_counted, the same scene in the box; docs/BACKWARD.md)
    g, c, tau1, e_minus = 10.0, 0.04, 0.02, 0.1975
    model = vci.LagrangianModel(
        1, 0, 2,
        lagrangian=lambda q, v: 0.5 * v[0] ** 2 - g * q[0],
        dl_dq=lambda q, v: [-g],
        dl_dv=lambda q, v: [v[0]],
        gaps=lambda q: [q[0], c - q[0]],
        gap_gradients=lambda q: [[1.0], [-1.0]])
    va = math.sqrt(2.0 * (e_minus + g ** 2 * tau1 ** 2 / 8.0))
    it = vci.Integrator(model, 0.2, scheme="midpoint")
    it.init_from_momentum(0.0, [va * tau1 - 0.5 * g * tau1 ** 2], [-(va - g * tau1)])
    assert it.irreversible_impacts == 0
    it.step()
    assert list(it.impacts["gap"][:2]) == [0, 1]
    assert it.irreversible_impacts == 1
