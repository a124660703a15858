"""Integrator.set_poke_samples (docs/BACKWARD.md, "A wall poked within one sub-step"): a parabola
under a ceiling y <= 1 (gravity 9.8, h = 1e-2) whose apex, at t = 0.205 half-way between two grid
points, is g h^2 / 16 = 6.1e-5 above the ceiling, so both grid points next to it are below the
ceiling and only the screen inside the step meets the touch (the midpoint rule is exact on a
parabola). The same scene as test/api/poke_test.c."""
import vci

G, H, T_APEX = 9.8, 1.0e-2, 0.205


def ceiling():
    return vci.LagrangianModel(
        1, 0, 1,
        lagrangian=lambda q, v: 0.5 * v[0] ** 2 - G * q[0],
        dl_dq=lambda q, v: [-G],
        dl_dv=lambda q, v: [v[0]],
        hessians=lambda q, v: ([[0.0]], [[0.0]], [[1.0]]),
        gaps=lambda q: [1.0 - q[0]],
        gap_gradients=lambda q: [[-1.0]])


def impacts(poke=None):
    it = vci.Integrator(ceiling(), H)
    if poke is not None:
        it.set_poke_samples(poke)
    depth = G * H ** 2 / 16.0
    it.init_from_momentum(0.0, [1.0 + depth - 0.5 * G * T_APEX ** 2], [G * T_APEX])
    state = it.integrate(t_final=0.6)
    assert abs(state.t - 0.6) < 1e-12
    return len(it.impacts)


def test_poke_screen_default_on_and_settable():
    assert impacts() == 1            # on by default: the touch between grid points is an impact
    assert impacts(False) == 0       # off: the gaps at the grid points only, both positive
    assert impacts(True) == 1
