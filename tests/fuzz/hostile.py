"""Hostile inputs and the contract they are checked against (docs/guide/bad-input.md).

Every public entry point, for every argument:

* **must refuse** garbage — booleans, complex numbers, strings (numeric or not), objects, dicts where arrays or
  lists are expected, NaN/inf, integers too large for a float, ragged lists, wrong kinds of names — with a
  :class:`TypeError` or :class:`ValueError` whose message names the argument;
* **must accept** the same valid value in another valid form — a nested list, a read-only or non-contiguous
  array, float32 (within its tolerance), integers for integral floats, numpy scalars — and give the same result;
* **must stay clean** on extreme but well-typed values (1e300, 5e-324, 10**9, empty axes, ...): either a
  result with finite numbers, or a ValueError/TypeError naming the argument — never another exception type
  (OverflowError, ZeroDivisionError, IndexError, MemoryError, AttributeError, ...) and never a hang
  (:data:`TIMEOUT_S` per case).

The strategies are seeded (``derandomize=True``: every run draws the same cases) and built from
``hypothesis.extra.numpy`` so that a failure shrinks to the smallest array and mutation.
"""

from __future__ import annotations

import collections
import contextlib
import dataclasses
import os
import resource
import signal
from typing import Any, Callable

import numpy as np
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

#: One hostile call may take this long before it counts as a hang, seconds.
TIMEOUT_S = 10.0

#: outcome -> count over the session (printed by conftest.py's terminal summary).
CASES: collections.Counter = collections.Counter()

#: The settings of every fuzz test: seeded (``derandomize``), no per-example deadline (the alarm of :func:`bounded`
#: is the limit); ``PSGSL_FUZZ_EXAMPLES`` examples per test (default 10: the default run stays short) — raise it for a deeper run.
FUZZ = settings(max_examples=int(os.environ.get("PSGSL_FUZZ_EXAMPLES", "10")), deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much,
                                       HealthCheck.function_scoped_fixture])

HUGE = 10**400  # an int no float holds


class Hang(BaseException):
    """A call ran longer than :data:`TIMEOUT_S` (BaseException: library code cannot swallow it)."""


#: Memory one hostile call may add to the process, bytes: beyond it an allocation fails with MemoryError (a
#: finding) instead of the machine's OOM killer ending the whole run.
MEMORY_HEADROOM = 3 * 2**30


@contextlib.contextmanager
def bounded(seconds: float = TIMEOUT_S, memory: int = MEMORY_HEADROOM):
    """Raise :class:`Hang` if the body runs longer than ``seconds`` (SIGALRM; main thread), and cap the address
    space at its current size + ``memory`` meanwhile (RLIMIT_AS; restored afterwards)."""

    def _alarm(signum, frame):
        raise Hang(f"no answer within {seconds} s")

    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    with open("/proc/self/statm") as fh:
        used = int(fh.read().split()[0]) * resource.getpagesize()
    cap = used + memory if hard == resource.RLIM_INFINITY else min(used + memory, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def record(outcome: str) -> None:
    CASES[outcome] += 1


def _names_arg(message: str, names) -> bool:
    return any(n in message for n in names)


def refused(call: Callable[[], Any], names, what: str):
    """``call()`` must raise TypeError/ValueError naming one of ``names``; returns the exception."""
    names = (names,) if isinstance(names, str) else tuple(names)
    try:
        with bounded():
            call()
    except (TypeError, ValueError) as exc:
        msg = str(exc)
        assert _names_arg(msg, names), f"{what}: refused, but the message does not name {names}: {msg!r}"
        assert "Traceback" not in msg
        record("refused")
        return exc
    raise AssertionError(f"{what}: garbage accepted silently")


def clean(call: Callable[[], Any], names, what: str, check: Callable[[Any], None] | None = None):
    """``call()`` returns (then ``check(result)``) or raises TypeError/ValueError naming one of ``names``."""
    names = (names,) if isinstance(names, str) else tuple(names)
    try:
        with bounded():
            out = call()
    except (TypeError, ValueError) as exc:
        assert _names_arg(str(exc), names), f"{what}: the message does not name {names}: {str(exc)!r}"
        record("refused")
        return None
    if check is not None:
        check(out)
    record("accepted")
    return out


def finite(out) -> None:
    """Every number in an output (array, tuple, dict, float) is finite."""
    if isinstance(out, dict):
        for v in out.values():
            finite(v)
    elif isinstance(out, (tuple, list)):
        for v in out:
            finite(v)
    elif isinstance(out, (np.ndarray, float, np.floating)) and np.asarray(out).dtype.kind == "f":
        assert np.all(np.isfinite(out)), f"non-finite output {out!r}"


# ------------------------------------------------------------------------------------------- array hostility
#: Mutations of a real array argument that the contract refuses (TypeError or ValueError).
ARRAY_REFUSE = ("bool", "complex0", "complex", "numeric-str", "object-str", "nested-str", "scalar-str", "dict",
                "nan", "inf", "huge-int", "ragged", "bytes", "none")
#: ... that it must accept with the same result.
ARRAY_ACCEPT = ("list", "readonly", "noncontiguous", "float32")


def refuse_array(v: np.ndarray, how: str, pos: int):
    """``v`` spoilt by mutation ``how`` (``pos`` picks the entry that gets spoilt)."""
    i = np.unravel_index(pos % v.size, v.shape) if v.size else ()
    if how == "bool":
        return v > np.median(v)
    if how == "complex0":
        return v.astype(np.complex128)  # imaginary part 0: still not a real array
    if how == "complex":
        return v + 1e-3j
    if how == "numeric-str":
        return v.astype(str)
    if how == "object-str":
        return v.astype(str).astype(object)
    if how == "nested-str":
        return np.vectorize(repr)(v).tolist()
    if how == "scalar-str":
        return str(float(v.flat[0]))
    if how == "dict":
        return {k: float(x) for k, x in enumerate(v.ravel())}
    if how == "nan":
        w = v.astype(np.float64)
        w[i] = np.nan
        return w
    if how == "inf":
        w = v.astype(np.float64)
        w[i] = np.inf if pos % 2 else -np.inf
        return w
    if how == "huge-int":
        w = v.astype(object)
        w[i] = HUGE
        return w.tolist()
    if how == "ragged":
        rows = v.reshape(v.shape[0], -1).tolist() if v.ndim > 1 else [[x] for x in v.tolist()]
        rows[pos % len(rows)] = rows[pos % len(rows)] + [0.0]
        return rows
    if how == "bytes":
        return v.tobytes()
    if how == "none":
        return None
    raise AssertionError(how)


def accept_array(v: np.ndarray, how: str):
    if how == "list":
        return v.tolist()
    if how == "readonly":
        w = v.copy()
        w.setflags(write=False)
        return w
    if how == "noncontiguous":
        w = np.repeat(v[..., None], 2, axis=-1)[..., 0] if v.ndim else v
        return w
    if how == "float32":
        return v.astype(np.float32)
    raise AssertionError(how)


# ------------------------------------------------------------------------------------------ scalar hostility
#: Mutations of a real scalar argument that the contract refuses.
SCALAR_REFUSE = (True, False, "1.0", "2", 1 + 0j, 0.5 + 1j, None, [1.0], {"x": 1.0}, float("nan"), float("inf"),
                 -float("inf"), HUGE, -HUGE, b"1")
#: Extreme but well-typed values: accepted with a finite result, or refused naming the argument; never a hang.
SCALAR_EXTREME = (0, 0.0, -1.0, 1e-300, 5e-324, 1e300, 1e6, 10**9, 10**18, 2.0**63, -1e6)
#: Mutations of an integer argument (counts, seeds) that the contract refuses.
INT_REFUSE = (True, False, 2.5, "3", None, 3 + 0j, HUGE, [3], float("nan"))
#: Mutations of a boolean flag that the contract refuses (a flag must be a bool).
FLAG_REFUSE = (None, "no", "yes", "", [], 0, 1, 1.0, "False")
#: Mutations of a list of names that the contract refuses.
NAMES_REFUSE = ("ab", b"ab", {"a": 1, "b": 2}, [1, 2], ["a", None], 3, None)
#: Mutations of an argument that must be one object of a class (a GridMap, a problem, a model).
OBJECT_REFUSE = ("grid", 3, 2.5, {}, [], (), True)


def float_arrays(shape, *, low=0.05, high=1.0):
    """Strategy: float64 arrays of ``shape`` with entries in [low, high] (hypothesis.extra.numpy)."""
    return hnp.arrays(np.float64, shape, elements=st.floats(low, high, allow_nan=False, allow_infinity=False,
                                                            allow_subnormal=False))


@dataclasses.dataclass
class Arg:
    """One argument of an entry point and how to spoil it.

    kind : "array" (real array), "dist" (probabilities summing to 1 on the last axis), "prob" (non-negative
    array), "labels" (integer array), "scalar" (real number), "int", "flag", "names", "object"
    names : the words a message may use for it (default: the argument's own name)
    optional : ``None`` is a valid value (so not a mutation)
    extreme : also try :data:`SCALAR_EXTREME` (scalars) with the clean oracle
    float32 : float32 input is accepted (probability arrays within 1e-4)
    """

    kind: str
    names: tuple = ()
    optional: bool = False
    extreme: bool = True
    float32: bool = True
    accept_list: bool = True
