"""Models: a discrete Lagrangian L_d(q, v, h) (DiscreteModel) or a continuous L(q, qdot)
(LagrangianModel), each a set of callbacks handed to the C ABI.

A model is immutable once created and may be shared by several integrators; each integrator keeps
the library's copy of it and a reference to the Python object (whose callbacks must outlive it).
"""
import operator

from . import _callbacks
from ._lib import ffi, lib
from .errors import ArgumentError, last_error, make_error


def _size(name, value, low):
    try:
        value = operator.index(value)
    except TypeError:
        raise ArgumentError(f"{name} must be an integer, got {type(value).__name__}") from None
    if value < low:
        raise ArgumentError(f"{name} = {value}: must be >= {low}")
    return value


def _user_pointer(user):
    if user is None:
        return ffi.NULL
    if isinstance(user, ffi.CData):
        return ffi.cast("void *", user)
    if isinstance(user, int) and not isinstance(user, bool):
        return ffi.cast("void *", user)
    raise ArgumentError("user must be None, an integer address or a cffi pointer "
                        f"(it is passed to compiled callbacks only), got {type(user).__name__}")


class Model:
    """Common part of the two kinds of model. Attributes n, m, ngaps; `kind` is 'discrete' or
    'lagrangian'."""

    _struct = None
    _create = None
    #: (member of the C struct, kind of callback, required?) in the struct's order
    _members = ()
    kind = None

    def __init__(self, n, m=0, ngaps=0, *, user=None, **callbacks):
        self.n = _size("n", n, 1)
        self.m = _size("m", m, 0)
        self.ngaps = _size("ngaps", ngaps, 0)
        if self.m > self.n:
            raise ArgumentError(f"m = {self.m} > n = {self.n}: more constraints than coordinates")
        known = {name for name, _, _ in self._members}
        unknown = set(callbacks) - known
        if unknown:
            raise ArgumentError(f"unknown callback(s) {sorted(unknown)}; a {type(self).__name__} takes "
                                f"{[name for name, _, _ in self._members]}")
        self._log = _callbacks.FailureLog()
        self._keep = []
        self.callbacks = {}
        cb = ffi.new(self._struct + " *")
        cb.size = ffi.sizeof(self._struct)
        for name, kind, required in self._members:
            obj = callbacks.get(name)
            need = required(self) if callable(required) else required
            if obj is None:
                if need:
                    raise ArgumentError(f"{type(self).__name__}: the callback {name} is required"
                                        + (" (m > 0)" if name in ("constraint_forms", "discrete_constraint") else "")
                                        + (" (ngaps > 0)" if name == "gaps" else ""))
                continue
            ptr, keep = _callbacks.to_c(kind, name, obj, self._log, self.m, self.ngaps)
            setattr(cb, name, ptr)
            self._keep.append(keep)
            self.callbacks[name] = obj
        self._keep.append(user)
        handle = ffi.new("vci_model *")
        status = getattr(lib, self._create)(handle, self.n, self.m, self.ngaps, *self._create_extra(), cb,
                                            _user_pointer(user))
        if status != 0:
            raise make_error(status, last_error(None))
        self._handle = handle

    def _create_extra(self):
        """Arguments of the create function between ngaps and the callbacks (none but for
        SeparableModel's mass matrix)."""
        return ()

    @property
    def handle(self):
        """The library's vci_model handle (cffi pointer)."""
        return self._handle[0]

    def close(self):
        """Release the library's model (integrators made from it keep their own copy)."""
        h = getattr(self, "_handle", None)
        if h is not None and h[0] != ffi.NULL:
            lib.vci_model_destroy(h)

    def __del__(self):
        try:
            self.close()
        except Exception:  # noqa: BLE001 -- interpreter shutdown
            pass

    def __repr__(self):
        given = ", ".join(self.callbacks)
        return f"<vci.{type(self).__name__} n={self.n} m={self.m} ngaps={self.ngaps} callbacks: {given}>"


def _needs_m(model):
    return model.m > 0


def _needs_gaps(model):
    return model.ngaps > 0


class DiscreteModel(Model):
    """A discrete Lagrangian L_d(q, v, h) given by its partials (vci_model_create).

    Callbacks (Python callables with these arguments and results; or compiled C functions of
    vci.h's types):
      d1(q, v, h), d2(q, v, h) -> (n,)    D1 L_d, D2 L_d                      required
      d3(q, v, h) -> float                D3 L_d = dL_d/dh                    required
      mixed_hessian(q, v, h) -> (n, n)    [i, j] = d2 L_d / dq_i dv_j         optional
      constraint_forms(q) -> (m, n)       row mu = omega^mu                   required iff m > 0
      discrete_constraint(base, other, h) -> (m,)                             required iff m > 0
      discrete_constraint_jacobian(base, other, h) -> (m, n)                  optional
      gaps(q) -> (ngaps,)                 admissible where all >= 0           required iff ngaps > 0
      gap_gradients(q) -> (ngaps, n)      row j = grad g_j                    optional
      energy(q, p) -> float               H(q, p)                             optional
    """

    _struct = "vci_callbacks"
    _create = "vci_model_create_v2"
    kind = "discrete"
    _members = (
        ("d1_ld", "ld_grad", True), ("d2_ld", "ld_grad", True), ("d3_ld", "ld_dh", True),
        ("mixed_hessian", "hessian", False), ("constraint_forms", "forms", _needs_m),
        ("discrete_constraint", "dconstraint", _needs_m), ("gaps", "gaps", _needs_gaps),
        ("gap_gradients", "gap_grads", False), ("energy", "energy", False),
        ("discrete_constraint_jacobian", "dconstraint_jac", False),
    )

    def __init__(self, n, m=0, ngaps=0, *, d1, d2, d3, user=None, **optional):
        super().__init__(n, m, ngaps, user=user, d1_ld=d1, d2_ld=d2, d3_ld=d3, **optional)


class LagrangianModel(Model):
    """A continuous Lagrangian L(q, qdot); the integrator discretises it by a scheme
    (vci_model_create_lagrangian).

    Callbacks (Python callables with these arguments and results; or compiled C functions):
      lagrangian(q, v) -> float            L                                   required
      dl_dq(q, v), dl_dv(q, v) -> (n,)     dL/dq, dL/dqdot                      required
      hessians(q, v) -> (lqq, lqv, lvv)    each (n, n), e.g. lqv[i, j] = d2L/dq_i dqdot_j   optional
      constraint_forms(q) -> (m, n)        row mu = omega^mu                    required iff m > 0
      gaps(q) -> (ngaps,)                                                       required iff ngaps > 0
      gap_gradients(q) -> (ngaps, n)       row j = grad g_j                     optional
      energy(q, p) -> float                H(q, p)                              optional

    vci.formula.lagrangian_model builds one from a sympy expression.
    """

    _struct = "vci_lagrangian_callbacks"
    _create = "vci_model_create_lagrangian"
    kind = "lagrangian"
    _members = (
        ("lagrangian", "l_value", True), ("dl_dq", "l_grad", True), ("dl_dv", "l_grad", True),
        ("hessians", "l_hessians", False), ("constraint_forms", "forms", _needs_m),
        ("gaps", "gaps", _needs_gaps), ("gap_gradients", "gap_grads", False), ("energy", "energy", False),
    )

    def __init__(self, n, m=0, ngaps=0, *, lagrangian, dl_dq, dl_dv, user=None, **optional):
        super().__init__(n, m, ngaps, user=user, lagrangian=lagrangian, dl_dq=dl_dq, dl_dv=dl_dv, **optional)


class SeparableModel(LagrangianModel):
    """A separable Lagrangian L = 1/2 qdot^T M qdot - V(q) with a constant mass matrix M
    (vci_model_create_separable). L, its derivatives and H are derived by the library, so every
    scheme of a LagrangianModel runs it, and scheme='composition' (the explicit Verlet
    compositions, order 2 .. 10) needs it. No constraints (m = 0).

    mass: the diagonal of M (n numbers) or M itself (n x n, symmetric positive definite).
    Callbacks (Python callables, or compiled C functions of vci.h's vci_potential_fn and wall types):
      potential(q) -> float                V(q)                                 required
      potential_gradient(q) -> (n,)        grad V                               required
      potential_hessian(q) -> (n, n)       the Hessian of V                     optional
      gaps(q) -> (ngaps,)                                                       required iff ngaps > 0
      gap_gradients(q) -> (ngaps, n)       row j = grad g_j                     required iff ngaps > 0

    vci.formula.lagrangian_model returns one when its L has this form.
    """

    _struct = "vci_separable_callbacks"
    _create = "vci_model_create_separable"
    kind = "separable"
    _members = (
        ("potential", "potential", True), ("potential_gradient", "potential_grad", True),
        ("potential_hessian", "potential_hess", False), ("gaps", "gaps", _needs_gaps),
        ("gap_gradients", "gap_grads", _needs_gaps),
    )

    def __init__(self, n, ngaps=0, *, mass, potential, potential_gradient, user=None, **optional):
        import numpy as np
        nn = _size("n", n, 1)
        arr = np.asarray(mass, dtype=np.float64)
        if arr.shape in ((nn,), ()) and not (arr.shape == () and nn != 1):
            self._mass_kind, flat = 0, arr.reshape(-1)
        elif arr.shape == (nn, nn):
            self._mass_kind, flat = 1, arr.ravel(order="F")
        else:
            raise ArgumentError(f"mass must be the diagonal ({nn},) or the matrix ({nn}, {nn}), got shape {arr.shape}")
        self.mass = arr.copy()
        self._mass_c = ffi.new("double[]", [float(x) for x in flat])
        Model.__init__(self, n, 0, ngaps, user=user, potential=potential, potential_gradient=potential_gradient,
                       **optional)

    def _create_extra(self):
        return (self._mass_kind, self._mass_c)
