"""vci from Python: variational collision integrators over the C ABI of libvci (cffi, ABI mode).

    import vci
    model = vci.LagrangianModel(1, 0, 2, lagrangian=..., dl_dq=..., dl_dv=..., gaps=...)
    integ = vci.Integrator(model, 0.05, scheme="lobatto", stages=4)
    integ.init_from_momentum(0.0, [0.0], [4.0])
    integ.integrate(200)

or, with L as a sympy formula, vci.formula.lagrangian_model(L, q, qdot, gaps=[...]). docs/PYTHON.md.
"""
from ._lib import library_path, lib as _clib
from .errors import (ArgumentError, CallbackError, DtypeError, FormulaError, ImpactError, InadmissibleError,
                     MemoryError_, NewtonError, NonFiniteError, OutputError, RecoverableError, StateError,
                     StoppedError, TooManyImpactsError, VciError, status_string)
from .ensemble import Ensemble, EnsembleResult
from .integrator import CheckReport, Integrator, Progress, State, Stats, Trajectory, check_model, impact_dtype
from .model import DiscreteModel, LagrangianModel, Model, SeparableModel


def library_version():
    """The loaded libvci's version as (major, minor, patch)."""
    v = _clib.vci_version()
    return (v // 10000, v // 100 % 100, v % 100)


__version__ = "0.2.0"


def __getattr__(name):
    # the symbolic path imports sympy and numba, which take a second or two: only when asked for
    if name == "formula":
        import importlib
        return importlib.import_module(".formula", __name__)
    if name == "read_output":
        from .output import read_output
        return read_output
    raise AttributeError(f"module 'vci' has no attribute {name!r}")
