"""Turning what the user gives for a callback into a C function pointer of the right type.

Accepted for every callback:
  * a Python callable: wrapped by cffi (ffi.callback); an exception inside it is caught and turned
    into a return code (errors.RecoverableError and subclasses: a positive code, a recoverable
    failure; any other exception: a negative code, an unrecoverable one). The code identifies the
    exception, so the integrator can find it again when the library names the code in its message;
  * a numba cfunc (anything with an integer `.address`), a cffi function pointer, a ctypes function
    pointer, or an integer address: used as is, at C speed (the signature must be the one vci.h
    gives: the package cannot check it).
"""
import ctypes
import threading
import traceback

import numpy as np

from ._lib import ffi
from .errors import ArgumentError, RecoverableError

#: kind -> (C typedef, arguments of the Python callable, what it returns)
SIGNATURES = {
    "ld_grad": ("vci_ld_grad_fn", "(q, v, h)", "array (n,)"),
    "ld_dh": ("vci_ld_dh_fn", "(q, v, h)", "float"),
    "hessian": ("vci_hessian_fn", "(q, v, h)", "array (n, n), [i, j] = d2 L_d / dq_i dv_j"),
    "forms": ("vci_forms_fn", "(q)", "array (m, n), row mu = omega^mu"),
    "dconstraint": ("vci_dconstraint_fn", "(base, other, h)", "array (m,)"),
    "dconstraint_jac": ("vci_dconstraint_fn", "(base, other, h)", "array (m, n), [mu, i] = d omega_d^mu / d other_i"),
    "gaps": ("vci_gaps_fn", "(q)", "array (ngaps,)"),
    "gap_grads": ("vci_gap_grads_fn", "(q)", "array (ngaps, n), row j = grad g_j"),
    "energy": ("vci_energy_fn", "(q, p)", "float"),
    "l_value": ("vci_lagrangian_value_fn", "(q, v)", "float"),
    "l_grad": ("vci_lagrangian_grad_fn", "(q, v)", "array (n,)"),
    "l_hessians": ("vci_lagrangian_hessians_fn", "(q, v)", "(lqq, lqv, lvv), each (n, n), [i, j]"),
    "potential": ("vci_potential_fn", "(q)", "float"),
    "potential_grad": ("vci_potential_fn", "(q)", "array (n,)"),
    "potential_hess": ("vci_potential_fn", "(q)", "array (n, n), [i, j] = d2V / dq_i dq_j"),
}


class FailureLog:
    """Exceptions raised by Python callbacks, each under the code its callback returned; per thread
    (integrators made from one model may run in different threads)."""

    _LIMIT = 1000  # codes are 1..LIMIT in absolute value, reused after

    def __init__(self):
        self._local = threading.local()

    def _table(self):
        t = getattr(self._local, "table", None)
        if t is None:
            t = self._local.table = {}
            self._local.next = 1
        return t

    def clear(self):
        self._table().clear()
        self._local.next = 1

    def record(self, name, exc):
        table = self._table()
        k = self._local.next
        self._local.next = k % self._LIMIT + 1
        lines = traceback.format_exception_only(type(exc), exc)
        last = lines[-1].strip() if lines else type(exc).__name__
        recoverable = isinstance(exc, RecoverableError)
        code = k if recoverable else -k
        table[code] = (name, exc, last)
        self._local.last = code
        return code

    def lookup(self, code):
        """(callback name, exception, last traceback line) recorded under code, or None."""
        return self._table().get(code)

    def latest(self):
        table = self._table()
        code = getattr(self._local, "last", None)
        return table.get(code) if code is not None else None

    def interrupt(self):
        """A KeyboardInterrupt or SystemExit recorded since the last clear, to be raised again."""
        for _, exc, _ in self._table().values():
            if isinstance(exc, (KeyboardInterrupt, SystemExit)):
                return exc
        return None


def _view(ptr, count):
    # a copy: the caller's arrays live only during the call
    return np.frombuffer(ffi.buffer(ptr, 8 * count)).copy()


class _Out:
    """An output array of the library, written through cffi (a flat list of numbers: directly) or
    NumPy (anything else)."""
    __slots__ = ("ptr", "count")

    def __init__(self, ptr, count):
        self.ptr, self.count = ptr, count


def _out(ptr, count):
    return _Out(ptr, count)


def _put(name, dest, value, shape, order="C"):
    if len(shape) == 1 and type(value) in (list, tuple) and len(value) == dest.count:
        try:
            dest.ptr[0:dest.count] = value  # the fast path: a flat list of numbers
            return
        except TypeError:
            pass  # not all numbers: NumPy says why below
    _put_numpy(name, np.frombuffer(ffi.buffer(dest.ptr, 8 * dest.count)), value, shape, order)


def _put_numpy(name, dest, value, shape, order):
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != shape and not (arr.size == 1 and int(np.prod(shape)) == 1):
        raise ArgumentError(f"{name} returned an array of shape {arr.shape}, expected {shape}")
    if order == "F" and len(shape) == 2:
        dest[:] = arr.reshape(shape).ravel(order="F")
    else:
        dest[:] = arr.ravel()


def _scalar(name, value):
    if type(value) is float:
        return value
    arr = np.asarray(value, dtype=np.float64)
    if arr.size != 1:
        raise ArgumentError(f"{name} returned an array of shape {arr.shape}, expected a number")
    return float(arr.reshape(()))


def _python_callback(kind, name, fn, log, m, ngaps):
    """A cffi callback around the Python callable fn for a callback of the given kind."""

    def guard(body):
        def cb(*args):
            try:
                body(*args)
                return 0
            except BaseException as exc:  # noqa: B902 -- every exception becomes a return code
                return log.record(name, exc)
        return cb

    if kind == "ld_grad":
        def body(n, q, v, h, out, user):
            _put(name, _out(out, n), fn(_view(q, n), _view(v, n), h), (n,))
    elif kind in ("ld_dh",):
        def body(n, q, v, h, out, user):
            out[0] = _scalar(name, fn(_view(q, n), _view(v, n), h))
    elif kind == "hessian":
        def body(n, q, v, h, out, user):
            _put(name, _out(out, n * n), fn(_view(q, n), _view(v, n), h), (n, n), "F")
    elif kind == "forms":
        def body(n, mm, q, out, user):
            _put(name, _out(out, n * mm), fn(_view(q, n)), (mm, n))
    elif kind == "dconstraint":
        def body(n, mm, base, other, h, out, user):
            _put(name, _out(out, mm), fn(_view(base, n), _view(other, n), h), (mm,))
    elif kind == "dconstraint_jac":
        def body(n, mm, base, other, h, out, user):
            _put(name, _out(out, mm * n), fn(_view(base, n), _view(other, n), h), (mm, n), "F")
    elif kind == "gaps":
        def body(n, ng, q, out, user):
            _put(name, _out(out, ng), fn(_view(q, n)), (ng,))
    elif kind == "gap_grads":
        def body(n, ng, q, out, user):
            _put(name, _out(out, n * ng), fn(_view(q, n)), (ng, n))
    elif kind == "energy":
        def body(n, q, p, out, user):
            out[0] = _scalar(name, fn(_view(q, n), _view(p, n)))
    elif kind == "l_value":
        def body(n, q, v, out, user):
            out[0] = _scalar(name, fn(_view(q, n), _view(v, n)))
    elif kind == "l_grad":
        def body(n, q, v, out, user):
            _put(name, _out(out, n), fn(_view(q, n), _view(v, n)), (n,))
    elif kind == "l_hessians":
        def body(n, q, v, lqq, lqv, lvv, user):
            blocks = fn(_view(q, n), _view(v, n))
            if not isinstance(blocks, (tuple, list)) or len(blocks) != 3:
                raise ArgumentError(f"{name} must return three arrays (lqq, lqv, lvv)")
            for dest, block in zip((lqq, lqv, lvv), blocks):
                _put(name, _out(dest, n * n), block, (n, n), "F")
    elif kind == "potential":
        def body(n, q, out, user):
            out[0] = _scalar(name, fn(_view(q, n)))
    elif kind == "potential_grad":
        def body(n, q, out, user):
            _put(name, _out(out, n), fn(_view(q, n)), (n,))
    elif kind == "potential_hess":
        def body(n, q, out, user):
            _put(name, _out(out, n * n), fn(_view(q, n)), (n, n), "F")
    else:  # pragma: no cover
        raise AssertionError(kind)
    return ffi.callback(SIGNATURES[kind][0], guard(body))


def _address(obj):
    """The address of a compiled function, or None if obj is not one."""
    if isinstance(obj, bool):
        return None
    if isinstance(obj, int):
        return obj
    addr = getattr(obj, "address", None)  # numba cfunc
    if isinstance(addr, int):
        return addr
    if isinstance(obj, ctypes._CFuncPtr):  # noqa: SLF001 -- ctypes' public base has no other name
        return ctypes.cast(obj, ctypes.c_void_p).value
    return None


def to_c(kind, name, obj, log, m=0, ngaps=0):
    """(cdata function pointer, object to keep alive) for the callback `name` given as obj."""
    ctype = SIGNATURES[kind][0]
    if isinstance(obj, ffi.CData):
        t = ffi.typeof(obj)
        if not (t.kind == "function" or (t.kind == "pointer" and t.item.cname == "void")):
            raise ArgumentError(f"{name}: a cffi object of type {t.cname} is not a function pointer "
                                "(give a function pointer, or void * holding one)")
        if obj == ffi.NULL:
            raise ArgumentError(f"{name}: a NULL function pointer")
        return ffi.cast(ctype, obj), obj
    addr = _address(obj)
    if addr is not None:
        if addr == 0:
            raise ArgumentError(f"{name}: a NULL function pointer (address 0)")
        if addr < 0:
            raise ArgumentError(f"{name}: a negative address {addr}")
        return ffi.cast(ctype, addr), obj
    if callable(obj):
        cb = _python_callback(kind, name, obj, log, m, ngaps)
        return cb, cb
    raise ArgumentError(f"{name}: expected a callable {SIGNATURES[kind][1]} -> {SIGNATURES[kind][2]}, "
                        f"a numba cfunc or a C function pointer, got {type(obj).__name__}")
