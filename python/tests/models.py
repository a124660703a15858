"""The test scenes, each written the three ways a user can give a model. The formulas are written
out by hand here (not derived by sympy), so the formula path is checked against an independent
derivation."""
import ctypes
import math
import os
import subprocess

import numpy as np
import sympy as sp

import vci
import vci.formula

from conftest import c_compiler

G = 9.8


# ---- walled pendulum: L = thetadot^2 / 2 + 9.8 cos theta, walls at +-1 rad ----
def walls_python(hessians=True):
    """Python callables."""
    opt = {}
    if hessians:
        opt["hessians"] = lambda q, v: ([[-G * math.cos(q[0])]], [[0.0]], [[1.0]])
    return vci.LagrangianModel(
        1, 0, 2,
        lagrangian=lambda q, v: 0.5 * v[0] ** 2 + G * math.cos(q[0]),
        dl_dq=lambda q, v: [-G * math.sin(q[0])],
        dl_dv=lambda q, v: [v[0]],
        gaps=lambda q: [1.0 - q[0], q[0] + 1.0],
        gap_gradients=lambda q: [[-1.0], [1.0]], **opt)


def walls_numba():
    """Hand-written numba cfuncs (the compiled-callback path without sympy)."""
    from numba import carray, cfunc, types
    dp = types.CPointer(types.float64)
    i4 = types.int32
    vp = types.voidptr

    @cfunc(types.int32(i4, dp, dp, dp, vp))
    def lagrangian(n, q, v, out, user):
        out[0] = 0.5 * v[0] * v[0] + 9.8 * math.cos(q[0])
        return 0

    @cfunc(types.int32(i4, dp, dp, dp, vp))
    def dl_dq(n, q, v, out, user):
        out[0] = -9.8 * math.sin(q[0])
        return 0

    @cfunc(types.int32(i4, dp, dp, dp, vp))
    def dl_dv(n, q, v, out, user):
        out[0] = v[0]
        return 0

    @cfunc(types.int32(i4, dp, dp, dp, dp, dp, vp))
    def hessians(n, q, v, lqq, lqv, lvv, user):
        lqq[0] = -9.8 * math.cos(q[0])
        lqv[0] = 0.0
        lvv[0] = 1.0
        return 0

    @cfunc(types.int32(i4, i4, dp, dp, vp))
    def gaps(n, ng, q, g, user):
        g_ = carray(g, (ng,))
        g_[0] = 1.0 - q[0]
        g_[1] = q[0] + 1.0
        return 0

    @cfunc(types.int32(i4, i4, dp, dp, vp))
    def gap_gradients(n, ng, q, dg, user):
        dg[0] = -1.0
        dg[1] = 1.0
        return 0

    return vci.LagrangianModel(1, 0, 2, lagrangian=lagrangian, dl_dq=dl_dq, dl_dv=dl_dv, hessians=hessians,
                               gaps=gaps, gap_gradients=gap_gradients)


WALLS_C = r"""
#include <math.h>
int l_value(int n, const double *q, const double *v, double *l, void *u) { l[0] = 0.5*v[0]*v[0] + 9.8*cos(q[0]); return 0; }
int l_dq(int n, const double *q, const double *v, double *o, void *u) { o[0] = -9.8*sin(q[0]); return 0; }
int l_dv(int n, const double *q, const double *v, double *o, void *u) { o[0] = v[0]; return 0; }
int l_hess(int n, const double *q, const double *v, double *a, double *b, double *c, void *u) {
  a[0] = -9.8*cos(q[0]); b[0] = 0.0; c[0] = 1.0; return 0; }
int walls(int n, int ng, const double *q, double *g, void *u) { g[0] = 1.0 - q[0]; g[1] = q[0] + 1.0; return 0; }
int wall_grads(int n, int ng, const double *q, double *dg, void *u) { dg[0] = -1.0; dg[1] = 1.0; return 0; }
/* a callback that counts its calls through the user pointer */
int l_dq_counting(int n, const double *q, const double *v, double *o, void *u) { ++*(long *)u; o[0] = -9.8*sin(q[0]); return 0; }
"""


def walls_c_library(tmp_path):
    """The walled pendulum's callbacks compiled by the C compiler into a shared library (ctypes)."""
    src = tmp_path / "walls.c"
    src.write_text(WALLS_C)
    so = tmp_path / "libwalls.so"
    subprocess.run([c_compiler(), "-O2", "-shared", "-fPIC", str(src), "-o", str(so), "-lm"], check=True)
    return ctypes.CDLL(os.fspath(so))


def walls_c(tmp_path, user=None, counting=False):
    lib = walls_c_library(tmp_path)
    model = vci.LagrangianModel(1, 0, 2, lagrangian=lib.l_value, dl_dq=lib.l_dq_counting if counting else lib.l_dq,
                                dl_dv=lib.l_dv, hessians=lib.l_hess, gaps=lib.walls, gap_gradients=lib.wall_grads,
                                user=user)
    model._test_lib = lib  # keep the shared library loaded
    return model


def walls_formula(**kw):
    th, om = sp.symbols("theta omega")
    return vci.formula.lagrangian_model(om ** 2 / 2 + G * sp.cos(th), [th], [om], gaps=[1 - th, th + 1], **kw)


# ---- the paper's nonholonomic pendulum in a cylinder (m = 1, l = 2, R = 1.5) ----
PAPER_Q0 = np.array([0.75 * math.pi, 0.0])
PAPER_QDOT0 = np.array([math.pi / 4, (math.pi + 0.5) * math.pi / 4])


def paper_p0():
    """p = dL/dqdot = m l^2 (thetadot, sin^2 theta phidot) at the paper's start."""
    return np.array([4.0 * PAPER_QDOT0[0], 4.0 * math.sin(PAPER_Q0[0]) ** 2 * PAPER_QDOT0[1]])


def paper_formula(**kw):
    th, ph, thd, phd = sp.symbols("theta phi thetadot phidot")
    m, g, l, R = sp.symbols("m g l R")
    L = m * l ** 2 / 2 * (thd ** 2 + sp.sin(th) ** 2 * phd ** 2) - m * g * l * sp.cos(th)
    return vci.formula.lagrangian_model(L, [th, ph], [thd, phd], forms=[[sp.pi + sp.cos(th) ** 2, -1]],
                                        gaps=[R ** 2 - l ** 2 * sp.sin(th) ** 2],
                                        params={m: 1.0, g: G, l: 2.0, R: 1.5}, **kw)


def paper_python():
    ml2, mgl = 4.0, 2.0 * G

    def hessians(q, v):
        s, c = math.sin(q[0]), math.cos(q[0])
        lqq = [[ml2 * v[1] ** 2 * (c * c - s * s) + mgl * c, 0.0], [0.0, 0.0]]
        lqv = [[0.0, 2 * ml2 * s * c * v[1]], [0.0, 0.0]]
        lvv = [[ml2, 0.0], [0.0, ml2 * s * s]]
        return lqq, lqv, lvv

    return vci.LagrangianModel(
        2, 1, 1,
        lagrangian=lambda q, v: 0.5 * ml2 * (v[0] ** 2 + math.sin(q[0]) ** 2 * v[1] ** 2) - mgl * math.cos(q[0]),
        dl_dq=lambda q, v: [ml2 * math.sin(q[0]) * math.cos(q[0]) * v[1] ** 2 + mgl * math.sin(q[0]), 0.0],
        dl_dv=lambda q, v: [ml2 * v[0], ml2 * math.sin(q[0]) ** 2 * v[1]],
        hessians=hessians,
        constraint_forms=lambda q: [[math.pi + math.cos(q[0]) ** 2, -1.0]],
        gaps=lambda q: [1.5 ** 2 - 4.0 * math.sin(q[0]) ** 2],
        gap_gradients=lambda q: [[-8.0 * math.sin(q[0]) * math.cos(q[0]), 0.0]])


def paper_discrete_python():
    """The paper's hand-derived discrete L_d (examples/c/scenes.h), as Python callables."""
    ml2, mgl = 4.0, 2.0 * G
    f = lambda th: math.pi + math.cos(th) ** 2  # noqa: E731

    def d1(q, v, h):
        s, c = math.sin(q[0]), math.cos(q[0])
        return [-ml2 * (v[0] - q[0]) / h + ml2 * (v[1] - q[1]) ** 2 * s * c / h + h * mgl * s,
                -ml2 * (v[1] - q[1]) * s * s / h]

    def d2(q, v, h):
        return [ml2 * (v[0] - q[0]) / h, ml2 * (v[1] - q[1]) * math.sin(q[0]) ** 2 / h]

    def d3(q, v, h):
        s = math.sin(q[0])
        return -0.5 * ml2 * ((v[0] - q[0]) ** 2 + (v[1] - q[1]) ** 2 * s * s) / h ** 2 - mgl * math.cos(q[0])

    return vci.DiscreteModel(
        2, 1, 1, d1=d1, d2=d2, d3=d3,
        constraint_forms=lambda q: [[f(q[0]), -1.0]],
        discrete_constraint=lambda b, o, h: [(f(b[0]) * (o[0] - b[0]) - (o[1] - b[1])) / h],
        gaps=lambda q: [1.5 ** 2 - 4.0 * math.sin(q[0]) ** 2])


# ---- a double pendulum (unit masses and lengths) against a wall x <= 1.5 at the lower bob ----
def double_formula(**kw):
    a, b, ad, bd = sp.symbols("a b adot bdot")
    x2 = sp.sin(a) + sp.sin(b)
    y2 = -sp.cos(a) - sp.cos(b)
    # kinetic energy of two unit point masses on unit rods, potential of both
    T = (ad ** 2 + (ad ** 2 + bd ** 2 + 2 * ad * bd * sp.cos(a - b))) / 2
    V = G * (-sp.cos(a)) + G * y2
    return vci.formula.lagrangian_model(T - V, [a, b], [ad, bd], gaps=[sp.Rational(3, 2) - x2], **kw)


def double_python():
    def lagrangian(q, v):
        a, b = q
        return 0.5 * (2 * v[0] ** 2 + v[1] ** 2 + 2 * v[0] * v[1] * math.cos(a - b)) + G * (2 * math.cos(a) + math.cos(b))

    def dl_dq(q, v):
        a, b = q
        w = v[0] * v[1] * math.sin(a - b)
        return [-w - 2 * G * math.sin(a), w - G * math.sin(b)]

    def dl_dv(q, v):
        c = math.cos(q[0] - q[1])
        return [2 * v[0] + v[1] * c, v[1] + v[0] * c]

    return vci.LagrangianModel(2, 0, 1, lagrangian=lagrangian, dl_dq=dl_dq, dl_dv=dl_dv,
                               gaps=lambda q: [1.5 - math.sin(q[0]) - math.sin(q[1])],
                               gap_gradients=lambda q: [[-math.cos(q[0]), -math.cos(q[1])]])
