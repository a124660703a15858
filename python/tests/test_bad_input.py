"""Bad input from Python: clear exceptions (class, status, message), never a crash or a silent
wrong answer."""
import math

import numpy as np
import pytest
import sympy as sp

import vci
import vci.formula

import models


def simple(**over):
    """The walled pendulum from Python callables, with some callbacks replaced."""
    cbs = dict(lagrangian=lambda q, v: 0.5 * v[0] ** 2 + 9.8 * math.cos(q[0]),
               dl_dq=lambda q, v: [-9.8 * math.sin(q[0])],
               dl_dv=lambda q, v: [v[0]],
               gaps=lambda q: [1.0 - q[0], q[0] + 1.0])
    cbs.update(over)
    return vci.LagrangianModel(1, 0, 2, **cbs)


def started(model, **kw):
    it = vci.Integrator(model, 0.05, **kw)
    it.init_from_momentum(0.0, [0.0], [4.0])
    return it


# ---- arrays ----
@pytest.mark.parametrize("q0, exc, words", [
    ([0.0, 1.0], vci.ArgumentError, "shape (2,), expected (1,)"),
    ([[0.0]], vci.ArgumentError, "shape (1, 1)"),
    (np.array([1j]), vci.DtypeError, "complex128"),
    (["a"], vci.DtypeError, "cannot be read as float64"),
    ([None], vci.DtypeError, "object"),
])
def test_wrong_shapes_and_dtypes(q0, exc, words):
    it = vci.Integrator(simple(), 0.05)
    with pytest.raises(exc) as info:
        it.init_from_momentum(0.0, q0, [4.0])
    assert words in str(info.value)
    assert isinstance(info.value, vci.VciError) and isinstance(info.value, ValueError)


def test_integers_are_accepted_as_floats():
    it = vci.Integrator(simple(), 0.05)
    it.init_from_momentum(0, [0], np.array([4], dtype=np.int32))
    assert it.p.dtype == np.float64 and it.p[0] == 4.0


def test_nan_in_initial_data_is_refused_by_the_library():
    it = vci.Integrator(simple(), 0.05)
    with pytest.raises(vci.ArgumentError) as info:
        it.init_from_momentum(0.0, [float("nan")], [4.0])
    assert info.value.status == 1 and "initial data contain NaN or Inf" in str(info.value)


def test_inadmissible_start():
    it = vci.Integrator(simple(), 0.05)
    with pytest.raises(vci.InadmissibleError, match="admissible"):
        it.init_from_momentum(0.0, [1.5], [0.0])


def test_bad_scalars():
    with pytest.raises(vci.ArgumentError, match="must be positive and finite"):
        vci.Integrator(simple(), 0.0)
    with pytest.raises(vci.DtypeError):
        vci.Integrator(simple(), "0.1")
    it = started(simple())
    with pytest.raises(vci.ArgumentError, match="direction"):
        it.step(2)
    with pytest.raises(vci.ArgumentError, match="nsteps"):
        it.integrate(-1)
    with pytest.raises(vci.ArgumentError, match="nsteps"):
        it.integrate(2.5)
    with pytest.raises(vci.ArgumentError, match="rtol = -1"):
        it.set_tolerances(rtol=-1.0)


# ---- models ----
def test_non_callable_callback():
    with pytest.raises(vci.ArgumentError, match="dl_dq: expected a callable") as info:
        simple(dl_dq="not a function")
    assert "got str" in str(info.value)
    with pytest.raises(vci.ArgumentError, match="NULL"):
        simple(dl_dq=0)


def test_missing_and_unknown_callbacks():
    with pytest.raises(vci.ArgumentError, match="gaps is required"):
        vci.LagrangianModel(1, 0, 2, lagrangian=abs, dl_dq=abs, dl_dv=abs)
    with pytest.raises(vci.ArgumentError, match="unknown callback"):
        simple(hessian=lambda q, v: None)
    with pytest.raises(vci.ArgumentError, match="m = 2 > n = 1"):
        vci.LagrangianModel(1, 2, 0, lagrangian=abs, dl_dq=abs, dl_dv=abs)
    with pytest.raises(vci.ArgumentError, match="n = 0"):
        vci.LagrangianModel(0, 0, 0, lagrangian=abs, dl_dq=abs, dl_dv=abs)


def test_scheme_errors():
    with pytest.raises(vci.ArgumentError, match="unknown scheme"):
        vci.Integrator(simple(), 0.05, scheme="rk4")
    with pytest.raises(vci.ArgumentError, match="stages"):
        vci.Integrator(simple(), 0.05, scheme="lobatto", stages=9)
    # lobatto with constraints: accepted since issue 25 (s out of range is still refused, above)
    vci.Integrator(models.paper_python(), 0.05, scheme="lobatto", stages=2).close()
    # schemes are for continuous models only
    with pytest.raises(vci.ArgumentError, match="schemes discretise a continuous one"):
        vci.Integrator(models.paper_discrete_python(), 0.01, scheme="midpoint")


def test_step_before_init():
    it = vci.Integrator(simple(), 0.05)
    with pytest.raises(vci.StateError):
        it.step()
    with pytest.raises(vci.StateError):
        it.state


def test_closed_integrator():
    it = started(simple())
    it.close()
    with pytest.raises(vci.ArgumentError, match="handle is NULL"):
        it.step()


# ---- callbacks that fail ----
def test_exception_in_callback_is_unrecoverable_and_named():
    calls = [0]

    def dl_dq(q, v):
        calls[0] += 1
        if calls[0] > 60:
            raise ZeroDivisionError("the model divided by zero")
        return [-9.8 * math.sin(q[0])]

    it = started(simple(dl_dq=dl_dq))
    with pytest.raises(vci.CallbackError) as info:
        it.integrate(200)
    err = info.value
    msg = str(err)
    assert "ZeroDivisionError: the model divided by zero" in msg  # the traceback's last line
    assert "dl_dq" in msg and "unrecoverable" in msg
    assert isinstance(err.__cause__, ZeroDivisionError)
    assert err.status == 2 and err.index is not None and err.time == pytest.approx(err.index * 0.05)
    # the state stays at the last accepted step
    assert it.index == err.index and it.t == pytest.approx(err.time)


def test_recoverable_exception_returns_a_positive_code():
    class Outside(vci.RecoverableError):
        pass

    def dl_dq(q, v):
        raise Outside("q outside the chart")

    it = vci.Integrator(simple(dl_dq=dl_dq), 0.05)
    with pytest.raises(vci.CallbackError) as info:
        it.init_from_momentum(0.0, [0.0], [4.0])
        it.step()
    assert "recoverable" in str(info.value) and "unrecoverable" not in str(info.value)
    assert "Outside: q outside the chart" in str(info.value)


def test_nan_from_a_callback():
    it = started(simple(dl_dq=lambda q, v: [float("nan")]))
    with pytest.raises(vci.NonFiniteError, match="NaN"):
        it.step()


def test_wrong_shape_from_a_callback():
    it = started(simple(dl_dq=lambda q, v: [1.0, 2.0]))
    with pytest.raises(vci.CallbackError, match=r"dl_dq returned an array of shape \(2,\), expected \(1,\)"):
        it.step()


def test_failing_impact_callback_keeps_the_step():
    def on_impact(rec):
        raise RuntimeError("stop at the wall")

    it = started(models.walls_python(), on_impact=on_impact)
    with pytest.raises(vci.CallbackError, match="on_impact raised RuntimeError: stop at the wall"):
        it.integrate(200)
    # the step with the impact was accepted: the state is past it
    assert len(it.impacts) == 1 and it.t > it.impacts["t"][0]


def test_reentrant_call_from_a_callback():
    holder = {}

    def dl_dq(q, v):
        if "it" in holder:
            holder["it"].step()  # the integrator is busy: StateError inside the callback
        return [-9.8 * math.sin(q[0])]

    it = vci.Integrator(simple(dl_dq=dl_dq), 0.05)
    it.init_from_momentum(0.0, [0.0], [4.0])
    holder["it"] = it
    with pytest.raises(vci.CallbackError, match="StateError"):
        it.step()


def test_keyboard_interrupt_in_a_callback_is_raised_again():
    def dl_dq(q, v):
        raise KeyboardInterrupt

    it = started(simple(dl_dq=dl_dq))
    with pytest.raises(KeyboardInterrupt):
        it.integrate(10)


# ---- formulas ----
def test_formula_with_a_symbol_that_is_not_a_coordinate():
    th, om, g = sp.symbols("theta omega g")
    with pytest.raises(vci.FormulaError, match="L contains g, which is not a coordinate") as info:
        vci.formula.lagrangian_model(om ** 2 / 2 + g * sp.cos(th), [th], [om])
    assert "params" in str(info.value)
    # given as a parameter it is fine
    vci.formula.lagrangian_model(om ** 2 / 2 + g * sp.cos(th), [th], [om], params={g: 9.8}, backend="python")


def test_formula_other_errors():
    th, om, x = sp.symbols("theta omega x")
    with pytest.raises(vci.FormulaError, match="gaps\\[0\\] contains omega"):
        vci.formula.lagrangian_model(om ** 2 / 2, [th], [om], gaps=[1 - om])
    with pytest.raises(vci.FormulaError, match="forms\\[0\\]\\[0\\] contains x"):
        vci.formula.lagrangian_model(om ** 2 / 2, [th], [om], forms=[[x]])
    with pytest.raises(vci.FormulaError, match="q has 1 symbols but qdot has 2"):
        vci.formula.lagrangian_model(om ** 2 / 2, [th], [om, x])
    with pytest.raises(vci.FormulaError, match="undefined function"):
        vci.formula.lagrangian_model(om ** 2 / 2 + sp.Function("V")(th), [th], [om])
    with pytest.raises(vci.FormulaError, match="Symbols"):
        vci.formula.lagrangian_model(om ** 2 / 2, ["theta"], [om])
    with pytest.raises(vci.FormulaError, match="quadratic"):
        vci.formula.lagrangian_model(om ** 4, [th], [om], energy=True, backend="python")


def test_recorded_run_that_fails_keeps_its_states():
    calls = [0]

    def dl_dq(q, v):
        calls[0] += 1
        if calls[0] > 200:
            raise ValueError("out of model")
        return [-9.8 * math.sin(q[0])]

    it = started(simple(dl_dq=dl_dq))
    with pytest.raises(vci.CallbackError) as info:
        it.integrate(200, record=True)
    traj = info.value.trajectory
    # the states up to the last accepted step, the last one the integrator's current state
    assert 1 < len(traj.t) < 201 and len(traj.energy) == len(traj.t) - 1
    assert traj.t[-1] == it.t and traj.q[-1, 0] == it.q[0] and traj.p[-1, 0] == it.p[0]
    assert np.all(np.diff(traj.t) > 0)


def _fail_once_at(k, exc_type):
    calls = [0]

    def dl_dq(q, v):
        calls[0] += 1
        if calls[0] == k:
            raise exc_type("once")
        return [-9.8 * math.sin(q[0])]

    it = vci.Integrator(simple(dl_dq=dl_dq), 0.05, rtol=1e-15)
    # (creating the integrator probes the callbacks once at q = v = 0 and discards what they return,
    # failures included: src/vci_integrator.f90, create_continuous; count the calls after it)
    calls[0] = 0
    it.init_from_momentum(0.0, [0.0], [4.0])
    return it.integrate(20)


def test_recoverable_failure_is_absorbed_at_trial_points_unrecoverable_never():
    # vci.h: a recoverable failure at a trial point of Newton's line search makes the solver back
    # off (the run goes on to the same solution); anywhere else, and for an unrecoverable failure
    # anywhere, the step fails. Fail once at the k-th call of dl_dq, k = 1..40.
    clean = _fail_once_at(0, RuntimeError)
    absorbed = []
    for k in range(1, 41):
        try:
            state = _fail_once_at(k, vci.RecoverableError)
        except vci.CallbackError as err:
            assert "recoverable" in str(err) and "unrecoverable" not in str(err)
            continue
        absorbed.append(k)
        assert abs(state.q[0] - clean.q[0]) < 1e-12 and abs(state.p[0] - clean.p[0]) < 1e-12
    assert 0 < len(absorbed) < 40  # some calls are trial points, some are not
    for k in absorbed:
        with pytest.raises(vci.CallbackError, match="unrecoverable"):
            _fail_once_at(k, ValueError)


def test_formula_python_backend_failure_is_named_and_silent(capfd):
    # sqrt of a negative number in the generated code (backend "python"): an unrecoverable
    # failure named with the Python error, and nothing printed
    th, om = sp.symbols("theta omega")
    model = vci.formula.lagrangian_model(om ** 2 / 2 - sp.sqrt(th - 0.1), [th], [om], backend="python")
    it = vci.Integrator(model, 0.05)
    with pytest.raises(vci.CallbackError, match="ValueError: math domain error"):
        it.init_from_momentum(0.0, [0.0], [1.0])
        it.step()
    out, err = capfd.readouterr()
    assert out == "" and err == ""
