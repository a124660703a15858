"""L as a formula: a sympy expression of q and qdot becomes a compiled LagrangianModel.

    import sympy as sp, vci.formula
    th, om = sp.symbols("theta omega")
    model = vci.formula.lagrangian_model(om**2 / 2 + 9.8 * sp.cos(th), [th], [om],
                                         gaps=[1 - th, th + 1])

The package derives dL/dq, dL/dqdot, the Hessian blocks d2L/dq dq, d2L/dq dqdot, d2L/dqdot dqdot
and the gap gradients with sympy, writes each callback as Python source (common subexpressions
shared), compiles it with numba's cfunc into a C function of vci.h's type, and hands the pointers to
vci_model_create_lagrangian: no Python runs while the library integrates.
"""
import math
import os
import sys

import numpy as np

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.printing.pycode import PythonCodePrinter

from ._lib import ffi
from .errors import FormulaError
from .model import LagrangianModel, SeparableModel

# the C types of the callbacks: kind -> (C typedef, argument names)
_KINDS = {
    "lagrangian": ("vci_lagrangian_value_fn", ("n", "q", "v", "out", "user")),
    "dl_dq": ("vci_lagrangian_grad_fn", ("n", "q", "v", "out", "user")),
    "dl_dv": ("vci_lagrangian_grad_fn", ("n", "q", "v", "out", "user")),
    "hessians": ("vci_lagrangian_hessians_fn", ("n", "q", "v", "lqq", "lqv", "lvv", "user")),
    "constraint_forms": ("vci_forms_fn", ("n", "m", "q", "out", "user")),
    "gaps": ("vci_gaps_fn", ("n", "ng", "q", "out", "user")),
    "gap_gradients": ("vci_gap_grads_fn", ("n", "ng", "q", "out", "user")),
    "energy": ("vci_energy_fn", ("n", "q", "p", "out", "user")),
    "potential": ("vci_potential_fn", ("n", "q", "out", "user")),
    "potential_gradient": ("vci_potential_fn", ("n", "q", "out", "user")),
    "potential_hessian": ("vci_potential_fn", ("n", "q", "out", "user")),
}


def _symbols(name, syms):
    if isinstance(syms, sp.Symbol):
        syms = [syms]
    try:
        syms = list(syms)
    except TypeError:
        raise FormulaError(f"{name} must be a sympy Symbol or a sequence of them, got {type(syms).__name__}") from None
    for s in syms:
        if not isinstance(s, sp.Symbol):
            raise FormulaError(f"{name} must hold sympy Symbols; {s!r} is a {type(s).__name__}")
    if len(set(syms)) != len(syms):
        raise FormulaError(f"{name} has a repeated symbol: {syms}")
    return syms


def _expr(what, e, params):
    try:
        e = sp.sympify(e)
    except (sp.SympifyError, TypeError) as exc:
        raise FormulaError(f"{what}: not a sympy expression ({exc})") from None
    if not isinstance(e, sp.Expr):
        raise FormulaError(f"{what}: {e!r} is not a scalar expression")
    undefined = e.atoms(AppliedUndef)
    if undefined:
        raise FormulaError(f"{what} contains undefined function(s) {sorted(map(str, undefined))}: "
                           "write them out as expressions")
    return e.xreplace(params) if params else e


def _check_symbols(what, e, allowed, kinds):
    extra = e.free_symbols - allowed
    if extra:
        names = ", ".join(sorted(str(s) for s in extra))
        raise FormulaError(f"{what} contains {names}, which is not {kinds}; give a number for a parameter "
                           f"with params={{{sorted(extra, key=str)[0]}: ...}}")


class _Printer(PythonCodePrinter):
    """Python source that numba compiles: math.* functions, floats."""

    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "standard": "python3"})


def _source(fname, kind, outputs, qs, vs, extra_in=None):
    """Source of def fname(...): outputs is a list of (target, expression) in the placeholders
    _q0.., _v0.. (or _p0..)."""
    args = _KINDS[kind][1]
    printer = _Printer()
    exprs = [e for _, e in outputs]
    repl, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("_c"), optimizations="basic")
    lines = [f"def {fname}({', '.join(args)}):"]
    used = set()
    for e in exprs:
        used |= e.free_symbols
    for i, s in enumerate(qs):
        if s in used:
            lines.append(f"    {s} = q[{i}]")
    second = "p" if kind == "energy" else "v"
    for i, s in enumerate(vs or []):
        if s in used:
            lines.append(f"    {s} = {second}[{i}]")
    for sym, e in repl:
        lines.append(f"    {sym} = {printer.doprint(e)}")
    for (target, _), e in zip(outputs, reduced):
        lines.append(f"    {target} = {printer.doprint(e)}")
    lines.append("    return 0")
    return "\n".join(lines) + "\n"


class Formula:
    """The derived expressions of a model given by a formula (in the user's symbols), and the
    generated source of its callbacks."""

    def __init__(self, **kw):
        self.__dict__.update(kw)

    def __repr__(self):
        return f"<vci.formula.Formula L = {self.L}, n = {len(self.q)}, m = {len(self.forms)}, ngaps = {len(self.gaps)}>"


def _numba_compile(kind, func):
    from numba import cfunc, types
    dp = types.CPointer(types.float64)
    i = types.int32
    v = types.voidptr
    sigs = {
        "vci_lagrangian_value_fn": types.int32(i, dp, dp, dp, v),
        "vci_lagrangian_grad_fn": types.int32(i, dp, dp, dp, v),
        "vci_lagrangian_hessians_fn": types.int32(i, dp, dp, dp, dp, dp, v),
        "vci_forms_fn": types.int32(i, i, dp, dp, v),
        "vci_gaps_fn": types.int32(i, i, dp, dp, v),
        "vci_gap_grads_fn": types.int32(i, i, dp, dp, v),
        "vci_energy_fn": types.int32(i, dp, dp, dp, v),
        "vci_potential_fn": types.int32(i, dp, dp, v),
    }
    return cfunc(sigs[_KINDS[kind][0]], nopython=True, error_model="numpy")(func)


_SIG_NAMES = {
    "vci_lagrangian_value_fn": "(i, dp, dp, dp, v)",
    "vci_lagrangian_grad_fn": "(i, dp, dp, dp, v)",
    "vci_lagrangian_hessians_fn": "(i, dp, dp, dp, dp, dp, v)",
    "vci_forms_fn": "(i, i, dp, dp, v)",
    "vci_gaps_fn": "(i, i, dp, dp, v)",
    "vci_gap_grads_fn": "(i, i, dp, dp, v)",
    "vci_energy_fn": "(i, dp, dp, dp, v)",
    "vci_potential_fn": "(i, dp, dp, v)",
}


def _cached_module(cache, sources):
    """The callbacks compiled through a module file in the directory cache, with numba's on-disk
    cache (cache=True): a later model with the same generated source loads them instead of
    compiling. The file's name is the hash of its text."""
    import hashlib
    import importlib.util
    lines = ["# generated by vci.formula: the callbacks of one model; compiled by numba, cached",
             "import math", "from numba import cfunc, types",
             "dp = types.CPointer(types.float64)", "i = types.int32", "v = types.voidptr", ""]
    for kind, src in sources.items():
        sig = _SIG_NAMES[_KINDS[kind][0]]
        lines.append(f"@cfunc(types.int32{sig}, nopython=True, error_model='numpy', cache=True)")
        lines.append(src)
    text = "\n".join(lines)
    digest = hashlib.sha256(text.encode()).hexdigest()[:20]
    os.makedirs(cache, exist_ok=True)
    path = os.path.join(cache, f"vci_formula_{digest}.py")
    if not os.path.exists(path):
        tmp = f"{path}.{os.getpid()}.tmp"
        with open(tmp, "w") as f:
            f.write(text)
        os.replace(tmp, path)  # whole or absent, also with concurrent writers
    spec = importlib.util.spec_from_file_location(f"vci_formula_{digest}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # numba's cache finds the module's globals by its name
    spec.loader.exec_module(module)
    return {kind: getattr(module, f"vci_{kind}") for kind in sources}


def lagrangian_model(L, q, qdot, *, forms=None, gaps=None, params=None, energy=False, hessians=True,
                     gap_gradients=True, backend="numba", cache=None, separable=None):
    """A LagrangianModel from the sympy expression L of the coordinates q and velocities qdot.

    forms: the constraint one-forms, m rows of n expressions of q (row mu: omega^mu = sum_i
    forms[mu][i] dq_i); gaps: expressions g_j(q), the admissible set is g_j >= 0; params: values
    of other symbols in the expressions. energy=True also derives H(q, p) (L must be quadratic in
    qdot); else the library inverts dL/dqdot where it needs H. hessians, gap_gradients: derive
    these (else the library differences them). backend: 'numba' (compiled; C speed) or 'python'
    (the same generated code run by the interpreter through cffi: no compile time, slow).
    cache: a directory in which the numba backend keeps the generated module and numba's compiled
    code, so that building the same model again loads instead of compiling (default: the
    environment variable VCI_FORMULA_CACHE, else no cache: nothing is written).

    separable: None (default) returns a SeparableModel when L = 1/2 qdot^T M qdot - V(q) with a
    constant, positive definite M and there are no constraints (its V, grad V, Hessian of V and gap
    gradients derived here; H is then the library's, `energy` and `gap_gradients` are not used), so
    that scheme='composition' runs it; else a LagrangianModel. True: the SeparableModel or
    FormulaError saying why L is not separable; False: always a LagrangianModel.

    The returned model has the attribute `formula` (the derived expressions and the source).
    A symbol that is neither a coordinate, a velocity nor in params raises FormulaError.
    """
    if backend not in ("numba", "python"):
        raise FormulaError(f"backend must be 'numba' or 'python', got {backend!r}")
    qs = _symbols("q", q)
    vs = _symbols("qdot", qdot)
    n = len(qs)
    if n == 0:
        raise FormulaError("q is empty")
    if len(vs) != n:
        raise FormulaError(f"q has {n} symbols but qdot has {len(vs)}")
    if set(qs) & set(vs):
        raise FormulaError(f"a symbol is both a coordinate and a velocity: {sorted(map(str, set(qs) & set(vs)))}")
    subs = {}
    for k, val in (params or {}).items():
        key = sp.Symbol(k) if isinstance(k, str) else k
        if key in qs or key in vs:
            raise FormulaError(f"params gives a value for {key}, which is a coordinate or velocity")
        try:
            subs[key] = sp.Float(float(val)) if not isinstance(val, sp.Basic) else val
        except (TypeError, ValueError):
            raise FormulaError(f"params[{key}] = {val!r} is not a number") from None
    allowed_l = set(qs) | set(vs)
    allowed_q = set(qs)
    L = _expr("L", L, subs)
    _check_symbols("L", L, allowed_l, "a coordinate (q) or a velocity (qdot)")

    if forms is None:
        form_rows = []
    else:
        mat = sp.Matrix(forms) if not isinstance(forms, sp.MatrixBase) else forms
        if mat.shape[1] != n and mat.shape == (n, 1) and n > 1:
            mat = mat.T  # a single form given as a flat list
        if mat.shape[1] != n:
            raise FormulaError(f"forms must be m rows of n = {n} expressions, got shape {mat.shape}")
        form_rows = [[_expr(f"forms[{mu}][{i}]", mat[mu, i], subs) for i in range(n)] for mu in range(mat.shape[0])]
        for mu, row in enumerate(form_rows):
            for i, e in enumerate(row):
                _check_symbols(f"forms[{mu}][{i}]", e, allowed_q, "a coordinate (one-forms depend on q only)")
    m = len(form_rows)
    if m > n:
        raise FormulaError(f"{m} constraint one-forms for n = {n} coordinates")

    if gaps is None:
        gap_list = []
    else:
        if isinstance(gaps, sp.Expr) or not hasattr(gaps, "__iter__"):
            gaps = [gaps]
        gap_list = [_expr(f"gaps[{j}]", g, subs) for j, g in enumerate(gaps)]
        for j, g in enumerate(gap_list):
            _check_symbols(f"gaps[{j}]", g, allowed_q, "a coordinate (gap functions depend on q only)")
    ngaps = len(gap_list)

    # placeholders with fixed names, so that the source never depends on the user's names
    pq = sp.symbols(f"_q0:{n}", real=True)
    pv = sp.symbols(f"_v0:{n}", real=True)
    pp = sp.symbols(f"_p0:{n}", real=True)
    to_ph = dict(zip(qs, pq)) | dict(zip(vs, pv))
    Lp = L.xreplace(to_ph)
    if separable not in (None, True, False):
        raise FormulaError(f"separable must be None, True or False, got {separable!r}")
    if separable is not False:
        mass, pot, why = _separable_parts(Lp, pq, pv, m)
        if why is None:
            return _separable_model(L, qs, vs, gap_list, pq, pv, to_ph, mass, pot, hessians, backend, cache)
        if separable:
            raise FormulaError(f"separable=True but L is not 1/2 qdot^T M qdot - V(q) with M constant: {why}")
    dl_dq = [sp.diff(Lp, a) for a in pq]
    dl_dv = [sp.diff(Lp, a) for a in pv]
    outputs = {
        "lagrangian": [("out[0]", Lp)],
        "dl_dq": [(f"out[{i}]", e) for i, e in enumerate(dl_dq)],
        "dl_dv": [(f"out[{i}]", e) for i, e in enumerate(dl_dv)],
    }
    derived = dict(dl_dq=dl_dq, dl_dv=dl_dv)
    if hessians:
        lqq = [[sp.diff(dl_dq[i], pq[j]) for j in range(n)] for i in range(n)]
        lqv = [[sp.diff(dl_dq[i], pv[j]) for j in range(n)] for i in range(n)]
        lvv = [[sp.diff(dl_dv[i], pv[j]) for j in range(n)] for i in range(n)]
        # column-major: block[i + n*j]
        outputs["hessians"] = [(f"{name}[{i + n * j}]", blk[i][j]) for name, blk in (("lqq", lqq), ("lqv", lqv),
                                                                                        ("lvv", lvv))
                               for j in range(n) for i in range(n)]
        derived.update(lqq=lqq, lqv=lqv, lvv=lvv)
    if m:
        fp = [[e.xreplace(to_ph) for e in row] for row in form_rows]
        outputs["constraint_forms"] = [(f"out[{i + n * mu}]", fp[mu][i]) for mu in range(m) for i in range(n)]
    if ngaps:
        gp = [g.xreplace(to_ph) for g in gap_list]
        outputs["gaps"] = [(f"out[{j}]", g) for j, g in enumerate(gp)]
        if gap_gradients:
            dg = [[sp.diff(g, pq[i]) for i in range(n)] for g in gp]
            outputs["gap_gradients"] = [(f"out[{i + n * j}]", dg[j][i]) for j in range(ngaps) for i in range(n)]
            derived["gap_gradients"] = dg
    if energy:
        H = _hamiltonian(Lp, pq, pv, pp)
        outputs["energy"] = [("out[0]", H.xreplace(dict(zip(pq, pq))))]
        derived["energy"] = H

    sources = {}
    holder = {}
    for kind, outs in outputs.items():
        sources[kind] = _source(f"vci_{kind}", kind, outs, pq, pp if kind == "energy" else pv)
    pointers = _compile_sources(sources, backend, cache, holder)

    model = LagrangianModel(n, m, ngaps, **pointers)
    holder["log"] = model._log
    back = {v: k for k, v in to_ph.items()} | {p: sp.Symbol(f"p_{s}") for p, s in zip(pp, qs)}
    model.formula = Formula(L=L, q=qs, qdot=vs, forms=form_rows, gaps=gap_list, backend=backend,
                            derived={k: _back(v, back) for k, v in derived.items()}, sources=sources)
    return model


def _recorder(holder, name):
    def onerror(exc_type, exc, tb):
        log = holder.get("log")
        return log.record(name, exc) if log is not None else -1
    return onerror


def _back(x, back):
    if isinstance(x, list):
        return [_back(e, back) for e in x]
    return x.xreplace(back)


def _hamiltonian(Lp, pq, pv, pp):
    """H(q, p) = p.v - L with v solving p = dL/dv, for L quadratic in v (dL/dv = M(q) v + b(q))."""
    n = len(pq)
    zero_v = {a: 0 for a in pv}
    dl_dv = sp.Matrix([sp.diff(Lp, a) for a in pv])
    M = dl_dv.jacobian(pv)
    if M.free_symbols & set(pv):
        raise FormulaError("energy=True needs L quadratic in qdot (d2L/dqdot2 depends on qdot); "
                           "leave energy=False and the library inverts dL/dqdot")
    b = dl_dv.xreplace(zero_v)
    v = M.LUsolve(sp.Matrix(pp) - b)
    vsub = dict(zip(pv, list(v)))
    H = sum(pp[i] * v[i] for i in range(n)) - Lp.xreplace(vsub)
    return H


def _separable_parts(Lp, pq, pv, m):
    """(M as floats, V, None) when Lp = 1/2 v^T M v - V(q) with M constant and positive definite and
    m = 0; else (None, None, the reason)."""
    import numpy as np
    if m:
        return None, None, "it has constraints (m > 0)"
    n = len(pq)
    dl_dv = sp.Matrix([sp.diff(Lp, a) for a in pv])
    M = dl_dv.jacobian(pv)
    if M.free_symbols:
        return None, None, "d2L/dqdot2 depends on " + ", ".join(sorted(map(str, M.free_symbols)))
    zero_v = {a: 0 for a in pv}
    if any(sp.simplify(e) != 0 for e in dl_dv.xreplace(zero_v)):
        return None, None, "dL/dqdot at qdot = 0 is not zero (terms linear in qdot)"
    v = sp.Matrix(pv)
    pot = sp.simplify(-(Lp - (v.T * M * v)[0, 0] / 2))
    if pot.free_symbols & set(pv):
        return None, None, "L - 1/2 qdot^T M qdot still depends on qdot"
    try:
        mass = np.array([[float(M[i, j]) for j in range(n)] for i in range(n)])
    except TypeError:
        return None, None, "M is not numeric"
    if not np.all(np.isfinite(mass)) or np.any(np.linalg.eigvalsh(mass) <= 0.0):
        return None, None, "M is not positive definite"
    return mass, pot, None


def _separable_model(L, qs, vs, gap_list, pq, pv, to_ph, mass, pot, hessians, backend, cache):
    """The SeparableModel of L = 1/2 v^T M v - pot(q): V, grad V, its Hessian, the gaps and their
    gradients derived and compiled as lagrangian_model compiles its callbacks."""
    n = len(pq)
    grad = [sp.diff(pot, a) for a in pq]
    outputs = {"potential": [("out[0]", pot)],
               "potential_gradient": [(f"out[{i}]", e) for i, e in enumerate(grad)]}
    derived = dict(potential=pot, potential_gradient=grad)
    if hessians:
        hv = [[sp.diff(grad[i], pq[j]) for j in range(n)] for i in range(n)]
        outputs["potential_hessian"] = [(f"out[{i + n * j}]", hv[i][j]) for j in range(n) for i in range(n)]
        derived["potential_hessian"] = hv
    ngaps = len(gap_list)
    if ngaps:
        gp = [g.xreplace(to_ph) for g in gap_list]
        dg = [[sp.diff(g, pq[i]) for i in range(n)] for g in gp]
        outputs["gaps"] = [(f"out[{j}]", g) for j, g in enumerate(gp)]
        outputs["gap_gradients"] = [(f"out[{i + n * j}]", dg[j][i]) for j in range(ngaps) for i in range(n)]
        derived["gap_gradients"] = dg
    sources = {kind: _source(f"vci_{kind}", kind, outs, pq, None) for kind, outs in outputs.items()}
    holder = {}
    pointers = _compile_sources(sources, backend, cache, holder)
    diag = np.diag(np.diag(mass))
    given = np.diag(mass).copy() if np.array_equal(mass, diag) else mass
    model = SeparableModel(n, ngaps, mass=given, **pointers)
    holder["log"] = model._log
    back = {v: k for k, v in to_ph.items()}
    model.formula = Formula(L=L, q=qs, qdot=vs, forms=[], gaps=gap_list, backend=backend, mass=mass,
                            derived={k: _back(v, back) for k, v in derived.items()}, sources=sources)
    return model


def _compile_sources(sources, backend, cache, holder):
    """The C function pointers of the generated sources: loaded from the cache directory (numba,
    cache or VCI_FORMULA_CACHE), else compiled with numba's cfunc, or (backend "python") cffi
    callbacks whose exceptions go to holder's log through _recorder."""
    pointers = {}
    if cache is None:
        cache = os.environ.get("VCI_FORMULA_CACHE") or None
    if backend == "numba" and cache:
        pointers.update(_cached_module(os.fspath(cache), sources))
    for kind, src in sources.items():
        if kind in pointers:
            continue
        namespace = {"math": math}
        exec(compile(src, f"<vci.formula {kind}>", "exec"), namespace)  # noqa: S102 -- our own generated code
        func = namespace[f"vci_{kind}"]
        if backend == "numba":
            pointers[kind] = _numba_compile(kind, func)
        else:
            # an exception (math domain error, division by zero) becomes an unrecoverable failure
            # whose message the integrator finds, as for any Python callable; cffi prints nothing
            pointers[kind] = ffi.callback(_KINDS[kind][0], func, error=-1, onerror=_recorder(holder, kind))
    return pointers
