"""vci_set_bordered_impacts from Python (issue 28 item 4): impact stages by bordering or whole.
The walled pendulum (18 impacts in 10 s) bordered at every stage size (min_unknowns=2) and with the
whole stage matrices: the same impacts and end state to the solver's tolerance (rtol 1e-13: two
runs of 1000 steps through 18 impacts; observed equal to the bit), bordering counted only when on."""
import pytest

import vci

import models


def run(bordered, min_unknowns=0):
    it = vci.Integrator(models.walls_python(), 0.01, rtol=1e-13)
    it.set_bordered_impacts(bordered, min_unknowns)
    it.init_from_momentum(0.0, [0.0], [4.0])
    state = it.integrate(t_final=10.0)
    return state, len(it.impacts), it.bordered_directions


def test_bordered_and_whole_agree():
    sb, nb, db = run(True, 2)
    sw, nw, dw = run(False, 2)
    assert nb == nw == 18
    assert db > 0 and dw == 0
    assert abs(sb.q[0] - sw.q[0]) <= 1e-9 and abs(sb.p[0] - sw.p[0]) <= 1e-9


def test_default_bound_leaves_small_stages_whole():
    # the pendulum's stage systems have 2 unknowns, below the default bound of 16
    _, _, d = run(True)
    assert d == 0


def test_bad_arguments_are_refused():
    it = vci.Integrator(models.walls_python(), 0.01)
    for min_unknowns in (1, -1):
        with pytest.raises(vci.ArgumentError):
            it.set_bordered_impacts(True, min_unknowns)
