"""Exceptions: one class per status code of vci.h, all derived from VciError.

Every exception carries the library's status code (`status`), its message (`message`: for a failed
step it names the step index, the time and the cause), and, when the message says so, the step
index (`index`) and time (`time`) of the failure. When a Python callback raised, the exception
that it raised is the `__cause__` and its last traceback line ends the message.
"""
import re

from ._lib import ffi, lib


class VciError(Exception):
    """Base of every vci exception. status: the library's status code (0 for Python-side checks
    that have no library status)."""

    status = None

    def __init__(self, message, status=None):
        super().__init__(message)
        self.message = message
        if status is not None:
            self.status = status
        self.index = None
        self.time = None
        m = re.search(r"index (-?\d+) \(t =\s*([^,)\s]+)", message)
        if m:
            self.index = int(m.group(1))
            try:
                self.time = float(m.group(2))
            except ValueError:
                pass


class ArgumentError(VciError, ValueError):
    """VCI_ERR_ARGUMENT: bad input (a dead handle, a bad size or value, a wrong shape or dtype)."""
    status = 1


class CallbackError(VciError):
    """VCI_ERR_CALLBACK: a callback failed (a Python callback raised, or returned a nonzero code)."""
    status = 2


class NonFiniteError(VciError, FloatingPointError):
    """VCI_ERR_NONFINITE: NaN or Inf from a callback or a solve."""
    status = 3


class NewtonError(VciError):
    """VCI_ERR_NEWTON: Newton's iteration did not converge."""
    status = 4


class ImpactError(VciError):
    """VCI_ERR_IMPACT: the impact stages had no admissible solution."""
    status = 5


class TooManyImpactsError(VciError):
    """VCI_ERR_TOO_MANY_IMPACTS: more impacts in one step than allowed."""
    status = 6


class InadmissibleError(VciError):
    """VCI_ERR_INADMISSIBLE: a state outside the admissible set (some gap < 0)."""
    status = 7


class OutputError(VciError, OSError):
    """VCI_ERR_IO: the output file could not be written, or HDF5 was not built in."""
    status = 8


class StateError(VciError):
    """VCI_ERR_STATE: a call out of order (step before init), or the integrator is busy."""
    status = 9


class MemoryError_(VciError, MemoryError):
    """VCI_ERR_MEMORY: an allocation failed."""
    status = 10


class StoppedError(VciError):
    """VCI_STOPPED: the run was stopped by the progress callback (Integrator.set_progress); the
    state is that of the last step done, and the integrator may go on from it."""
    status = 11


class FormulaError(ArgumentError):
    """A formula the symbolic path cannot use (a free symbol that is neither a coordinate, a
    velocity nor a given parameter; wrong sizes)."""


class DtypeError(ArgumentError, TypeError):
    """An array of a type that cannot be read as float64 (complex, object, strings)."""


class RecoverableError(Exception):
    """Raise this (or a subclass) inside a Python callback for a recoverable failure: at a trial
    point of Newton's line search the solver backs off to a shorter step. Any other exception is
    an unrecoverable failure (the step fails at once)."""


BY_STATUS = {cls.status: cls for cls in (ArgumentError, CallbackError, NonFiniteError, NewtonError, ImpactError,
                                         TooManyImpactsError, InadmissibleError, OutputError, StateError,
                                         MemoryError_, StoppedError)}


def status_string(status):
    """The library's description of a status code."""
    return ffi.string(lib.vci_status_string(status)).decode("utf-8", "replace")


def last_error(handle=None):
    """The library's message of the last call on handle (None: the thread's last handle-less failure)."""
    buf = ffi.new("char[]", 2048)
    lib.vci_last_error(handle if handle is not None else ffi.NULL, buf, 2048)
    return ffi.string(buf).decode("utf-8", "replace")


def make_error(status, message):
    cls = BY_STATUS.get(status, VciError)
    err = cls(f"{status_string(status)}: {message}" if message else status_string(status), status)
    err.message = message
    return err
