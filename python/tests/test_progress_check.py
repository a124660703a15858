"""Progress reports that may stop a run (Integrator.set_progress over vci_set_progress, StoppedError
for VCI_STOPPED), the model checker (vci.check_model over vci_check_model) and the composition
scheme's constant, from Python."""
import math

import numpy as np
import pytest

import vci

import models


def walls_integrator():
    it = vci.Integrator(models.walls_python(), 0.05, scheme="lobatto", stages=2, rtol=1e-14)
    it.init_from_momentum(0.0, [0.0], [4.0])
    return it


def test_progress_reports_every_step_and_the_last():
    it = walls_integrator()
    seen = []
    it.set_progress(seen.append, interval=0.0)
    it.integrate(40)
    assert seen, "no progress report"
    assert all(isinstance(p, vci.Progress) for p in seen)
    assert seen[-1].steps_done == 40 and seen[-1].steps_total == 40
    assert [p.steps_done for p in seen] == sorted(p.steps_done for p in seen)
    assert seen[-1].t == pytest.approx(40 * 0.05, abs=1e-12)
    assert seen[-1].impacts == it.stats.impacts


def test_progress_stops_the_run_and_the_run_goes_on_from_there():
    it = walls_integrator()
    it.set_progress(lambda p: p.steps_done >= 25, interval=0.0)
    with pytest.raises(vci.StoppedError) as info:
        it.integrate(100)
    assert info.value.status == 11 and "stopped by the progress report after 25 of 100" in str(info.value)
    assert it.index == 25
    it.set_progress(None)
    end = it.integrate(75)
    whole = walls_integrator()
    ref = whole.integrate(100)
    # stopping between steps changes nothing of the arithmetic
    assert end.t == ref.t and np.array_equal(end.q, ref.q) and np.array_equal(end.p, ref.p)


def test_progress_exception_is_raised_by_integrate():
    it = walls_integrator()

    def broken(p):
        raise ZeroDivisionError("in the progress callback")

    it.set_progress(broken, interval=0.0)
    with pytest.raises(ZeroDivisionError, match="in the progress callback"):
        it.integrate(10)
    assert 1 <= it.index <= 10  # stopped after a step, the state is usable
    with pytest.raises(vci.ArgumentError, match="callable"):
        it.set_progress(42)


def test_check_model_passes_a_right_model_and_names_a_wrong_derivative():
    rep = vci.check_model(models.walls_python(), [0.3], [1.7])
    assert rep.passed and rep.worst <= 1e-6 and rep.lines
    wrong = vci.LagrangianModel(
        1, 0, 0,
        lagrangian=lambda q, v: 0.5 * v[0] ** 2 + 9.8 * math.cos(q[0]),
        dl_dq=lambda q, v: [+9.8 * math.sin(q[0])],  # wrong sign
        dl_dv=lambda q, v: [v[0]])
    rep = vci.check_model(wrong, [0.3], [1.7])
    assert not rep.passed
    assert rep.worst > 1.0  # dl_dq is -(the truth): relative mismatch 2
    assert any("dl_dq" in line for line in rep.lines)
    # the paper's hand-derived discrete L_d (with its constraint) passes at h > 0
    rep = vci.check_model(models.paper_discrete_python(), models.PAPER_Q0, models.PAPER_Q0 + 0.01, h=0.01)
    assert rep.passed, rep.lines


def test_check_model_bad_input():
    with pytest.raises(vci.ArgumentError):
        vci.check_model(models.walls_python(), [0.3, 0.1], [1.7])
    with pytest.raises(vci.ArgumentError):
        vci.check_model("not a model", [0.3], [1.7])
    with pytest.raises(vci.ArgumentError):  # a discrete model needs h > 0
        vci.check_model(models.paper_discrete_python(), models.PAPER_Q0, models.PAPER_Q0, h=0.0)


def test_composition_reaches_the_library():
    it = vci.Integrator(models.walls_python(), 0.05)
    with pytest.raises(vci.ArgumentError, match="stages"):
        it.set_scheme("composition")
    # the library's composition takes only its own separable models: a Python model is refused
    with pytest.raises(vci.ArgumentError, match="(?i)separable"):
        it.set_scheme("composition", 4)
