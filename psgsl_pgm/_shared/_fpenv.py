"""The processor's floating-point environment, kept IEEE 754 across foreign compiled code.

A shared library built with gcc's ``-Ofast`` or ``-ffast-math`` carries ``crtfastmath.o``, whose constructor sets
the x86 MXCSR flags FTZ (flush results that would be subnormal to zero) and DAZ (read subnormal inputs as zero)
when the library is loaded — for the whole thread, and for every thread it creates later. pystencils compiles
lbmpy's kernels that way (the CFD wind, :mod:`psgsl_pgm.sim._lbm`), so without a guard one CFD solve silently
changes every later floating-point result of the process that goes through subnormals: e.g. ``exp`` of a very
negative log-probability gives 0 instead of 1e-310, and an episode that solved its wind would not compute the
same numbers as one that loaded it from the cache. :func:`preserved_float_environment` saves the calling
thread's environment (rounding mode, exception masks, FTZ/DAZ) and puts it back on exit; :func:`subnormals_work`
checks the result.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import functools
import warnings

import numpy as np

__all__ = ["preserved_float_environment", "subnormals_work"]

#: Bytes reserved for a C ``fenv_t``: 32 on x86-64 glibc, 8 on aarch64; generous for any platform.
_FENV_BYTES = 256


@functools.cache
def _libm():
    """The C math library's ``fegetenv``/``fesetenv``, or None where they cannot be found."""
    name = ctypes.util.find_library("m")
    if name is None:
        return None
    try:
        lib = ctypes.CDLL(name)
        get, put = lib.fegetenv, lib.fesetenv
    except (OSError, AttributeError):
        return None
    get.argtypes = put.argtypes = [ctypes.c_void_p]
    get.restype = put.restype = ctypes.c_int
    return get, put


def subnormals_work() -> bool:
    """True when this thread computes with IEEE subnormals: neither read as zero (DAZ) nor flushed to zero (FTZ).

    Examples
    --------
    >>> subnormals_work()
    True
    """
    smallest = np.array([np.finfo(np.float64).smallest_subnormal])
    tiny = np.array([np.finfo(np.float64).tiny])  # the smallest normal number
    return bool((smallest * 1.0)[0] != 0.0) and bool((tiny * 0.5)[0] != 0.0)


@contextlib.contextmanager
def preserved_float_environment():
    """Restore the calling thread's floating-point environment on leaving the block, whatever the block loaded.

    On a platform whose C library offers no ``fegetenv`` the environment cannot be saved; if the block then leaves
    subnormals flushed, a :class:`RuntimeWarning` says so (the results that follow are not IEEE 754).

    Examples
    --------
    >>> with preserved_float_environment():
    ...     pass
    >>> subnormals_work()
    True
    """
    calls = _libm()
    saved = None
    if calls is not None:
        saved = ctypes.create_string_buffer(_FENV_BYTES)
        if calls[0](saved) != 0:
            saved = None
    try:
        yield
    finally:
        if saved is not None:
            calls[1](saved)
        if not subnormals_work():
            warnings.warn("compiled code loaded in this process switched the processor to flush subnormal numbers to "
                          "zero (FTZ/DAZ) and the floating-point environment could not be restored: later results "
                          "are not IEEE 754", RuntimeWarning, stacklevel=3)
