"""Argument validation at the public boundary: the one vocabulary every part of the package uses.

Every public function converts and checks its inputs here, once, and raises :class:`ValueError` or
:class:`TypeError` with a message that names the argument, what was expected and what arrived. Internal code
may then assume finite, non-negative, correctly shaped floating arrays.

The type contract
-----------------
* Arrays of numbers must be *real numeric*: boolean, complex, object (other than Python numbers) and string
  arrays are refused with :class:`TypeError` (a boolean grid is a mask, see :func:`bool_mask`).
* Python integers are converted safely: one too large for a float64 (``10**400``) is a :class:`ValueError`
  naming the argument, never an :class:`OverflowError`.
* Flags must be :class:`bool` (:func:`flag`); ``None``, ``"no"`` or ``0`` are refused.
* Distributions must sum to 1 within :data:`SUM_RTOL` for their dtype: 1e-6 in float64, 1e-4 in float32.
* Messages name the argument (or the file and field), the expected kind of value and the value received;
  never an internal quantity.

Vocabulary
----------
:func:`real_number`, :func:`positive`, :func:`unit_interval`, :func:`index` (scalars); :func:`real_pair`;
:func:`flag`; :func:`names` (a list of names); :func:`bool_mask`; :func:`as_float_array`, :func:`check_nonnegative`, :func:`check_last_axis`,
:func:`check_distribution` / :func:`distribution`, :func:`check_sums`, :func:`as_array` (arrays); :func:`file_field` (a number
read from a file, named by file and field), :func:`check_keys` (the keys of a mapping read from a file).
"""

from __future__ import annotations

import math
import numbers
import re

import numpy as np

__all__ = [
    "did_you_mean",
    "one_of",
    "SUM_RTOL",
    "as_array",
    "as_float_array",
    "bool_mask",
    "cell_distribution",
    "check_distribution",
    "check_keys",
    "check_last_axis",
    "check_nonnegative",
    "check_sums",
    "describe",
    "distribution",
    "file_field",
    "flag",
    "identifier",
    "index",
    "names",
    "positive",
    "real_number",
    "real_pair",
    "unit_interval",
]

#: Tolerance on ``|sum - 1|`` for arrays that must be normalised, per floating dtype. Probabilities written
#: to disk with 7 significant digits, or computed in float32, are accepted; anything further off is refused.
SUM_RTOL = {np.dtype(np.float64): 1e-6, np.dtype(np.float32): 1e-4}


def describe(x) -> str:
    """Short description of an array-like for error messages: type, shape and dtype."""
    if isinstance(x, np.ndarray):
        return f"ndarray of shape {x.shape} and dtype {x.dtype}"
    return f"{type(x).__name__} {x!r}" if np.ndim(x) == 0 else f"{type(x).__name__} of shape {np.shape(x)}"


def as_array(x, name: str, what: str = "an array") -> np.ndarray:
    """``np.asarray(x)``, with a ragged nested list (or anything numpy cannot make an array of) a
    :class:`TypeError` naming the argument instead of numpy's "inhomogeneous shape" ValueError."""
    try:
        return np.asarray(x)
    except (TypeError, ValueError) as err:
        raise TypeError(f"{name} must be {what}, got {type(x).__name__} ({' '.join(str(err).split())})") from None


def _real_array(x, name: str, what: str) -> np.ndarray:
    """``np.asarray(x)`` for a real numeric array; TypeError/ValueError by the type contract otherwise."""
    if isinstance(x, (str, bytes)) or x is None:
        raise TypeError(f"{name} must be {what}, got {type(x).__name__} {x!r}")
    try:
        arr = np.asarray(x)
    except (TypeError, ValueError) as err:  # ragged nested sequences
        raise TypeError(f"{name} must be {what}, got {type(x).__name__} ({err})") from None
    if arr.dtype == object:
        arr = _object_to_float(arr, name, what)
    if arr.dtype == bool or np.issubdtype(arr.dtype, np.bool_):
        raise TypeError(f"{name} must be {what}, got booleans ({describe(arr)})")
    if np.iscomplexobj(arr):
        raise TypeError(f"{name} must be real, got complex dtype {arr.dtype}")
    if not np.issubdtype(arr.dtype, np.number):
        raise TypeError(f"{name} must be {what}, got {describe(arr)}")
    return arr


def _object_to_float(arr: np.ndarray, name: str, what: str) -> np.ndarray:
    """Float64 array from an object array of Python real numbers (e.g. integers beyond int64)."""
    flat = arr.ravel().tolist()
    for v in flat:  # loop over an object array: only reached for Python ints beyond int64 or mixed objects
        if isinstance(v, bool) or not isinstance(v, numbers.Real):
            raise TypeError(f"{name} must be {what}, got an entry {type(v).__name__} {v!r}")
    try:
        return np.array([float(v) for v in flat], dtype=np.float64).reshape(arr.shape)
    except OverflowError:
        big = next(v for v in flat if isinstance(v, int) and abs(v) > 2**1024)
        raise ValueError(
            f"{name} must hold finite numbers, got an integer too large for a float64 ({_short(big)})"
        ) from None


def _short(v) -> str:
    """An integer written briefly for messages (``10**400`` has 401 digits)."""
    text = str(v)
    return text if len(text) <= 24 else f"{text[:6]}…({len(text.lstrip('-'))} digits)"


def as_float_array(x, name: str, *, dtype=None, min_ndim: int = 0, ndim: int | None = None) -> np.ndarray:
    """Convert ``x`` to a floating array (float64 unless ``x`` is already float32, or ``dtype`` is given).

    Raises
    ------
    TypeError
        If ``x`` is not a real numeric array (strings, objects, booleans, complex numbers).
    ValueError
        If the number of dimensions is wrong, or an integer is too large for a float64. NaN and inf are
        *not* checked here (see :func:`check_nonnegative`).
    """
    arr = _real_array(x, name, "a real numeric array")
    if dtype is None:
        dtype = np.float32 if arr.dtype == np.float32 else np.float64
    arr = np.asarray(arr, dtype=dtype)
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} must have {ndim} dimension(s), got {describe(arr)}")
    if arr.ndim < min_ndim:
        raise ValueError(f"{name} must have at least {min_ndim} dimension(s), got {describe(arr)}")
    return arr


def check_nonnegative(arr: np.ndarray, name: str) -> np.ndarray:
    """Refuse NaN, infinite or negative entries (one pass: ``min`` propagates NaN, ``max`` finds +inf)."""
    if arr.size == 0:
        raise ValueError(f"{name} must not be empty, got {describe(arr)}")
    lo, hi = np.min(arr), np.max(arr)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise ValueError(f"{name} must be finite, got {arr[tuple(bad)]} at index {tuple(int(i) for i in bad)}")
    if lo < 0:
        bad = np.argwhere(arr < 0)[0]
        raise ValueError(
            f"{name} must be non-negative (probabilities), got {arr[tuple(bad)]} at index "
            f"{tuple(int(i) for i in bad)}"
        )
    return arr


def check_last_axis(arr: np.ndarray, name: str, k: int, what: str = "classes") -> None:
    """Require the last axis of ``arr`` to have length ``k``."""
    if arr.ndim == 0 or arr.shape[-1] != k:
        raise ValueError(f"{name} must have {k} {what} on its last axis, got {describe(arr)}")


def check_distribution(arr: np.ndarray, name: str, *, axis: int = -1, sums=None) -> np.ndarray:
    """Refuse entries that are negative/NaN/inf, or slices along ``axis`` that do not sum to 1.

    ``sums`` may pass precomputed sums along ``axis`` (e.g. from a fused matrix product) to save a pass.
    The tolerance is :data:`SUM_RTOL` for the array's dtype.
    """
    check_nonnegative(arr, name)
    if sums is None:
        sums = np.sum(arr, axis=axis, dtype=np.float64)
    check_sums(sums, name, arr.dtype)
    return arr


def check_sums(sums: np.ndarray, name: str, dtype, *, over: str = "along its last axis") -> None:
    """Refuse normalising sums further than :data:`SUM_RTOL` from 1 (NaN sums are refused too); ``over`` says
    what was summed (e.g. ``"over all cells"`` for a map's total)."""
    tol = SUM_RTOL.get(np.dtype(dtype), 1e-6)
    dev = np.abs(np.asarray(sums, dtype=np.float64) - 1.0)
    worst = np.nanargmax(dev) if np.ndim(dev) else None
    worst_dev = dev.flat[worst] if worst is not None else dev
    if not np.all(dev <= tol):
        where = ""
        if worst is not None:  # plain ints: no numpy reprs in messages
            at = tuple(int(i) for i in np.unravel_index(worst, np.shape(sums)))
            where = f" at cell {at}" + (" (row, col)" if len(at) == 2 else "")
        value = np.asarray(sums).flat[worst] if worst is not None else sums
        raise ValueError(
            f"{name} must sum to 1 {over} (tolerance {tol:g}), got a sum of {float(value)!r}{where}"
            + ("" if np.isfinite(worst_dev) else " (NaN or inf entries)")
        )


def distribution(x, name: str, *, ndim: int | None = None, min_ndim: int = 1, axis: int = -1) -> np.ndarray:
    """A probability array: real, finite, non-negative, summing to 1 along ``axis`` within :data:`SUM_RTOL`.

    float32 input stays float32 (tolerance 1e-4), anything else becomes float64 (tolerance 1e-6).

    Examples
    --------
    >>> distribution(np.array([0.5, 0.5 + 1e-8]), "p").dtype
    dtype('float64')
    >>> distribution([0.5, 0.6], "p")
    Traceback (most recent call last):
    ...
    ValueError: p must sum to 1 along its last axis (tolerance 1e-06), got a sum of 1.1
    """
    arr = as_float_array(x, name, ndim=ndim, min_ndim=min_ndim)
    return check_distribution(arr, name, axis=axis)


def real_number(value, name: str, *, unit: str = "", what: str = "a real number", finite: str = "a finite number") -> float:
    """A finite real scalar as a Python float (bools, strings, arrays and complex numbers refused).

    Python integers too large for a float64 are a :class:`ValueError`, never an :class:`OverflowError`.
    """
    where = f" in {unit}" if unit else ""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.integer, np.floating)):
        raise TypeError(f"{name} must be {what}{where}, got {type(value).__name__} {value!r}")
    try:
        v = float(value)
    except OverflowError:
        raise ValueError(f"{name} must be {what}{where}, got an integer too large for a float64 ({_short(value)})") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be {finite}{where}, got {value!r}")
    return v


def positive(value, name: str, unit: str = "", *, allow_zero: bool = False) -> float:
    """A positive (or, with ``allow_zero``, non-negative) finite number; ``unit`` is named in the messages.

    Examples
    --------
    >>> positive(0.1, "resolution", "metres")
    0.1
    >>> positive(0, "resolution", "metres")
    Traceback (most recent call last):
    ...
    ValueError: resolution must be a positive finite number in metres, got 0
    """
    kind = "non-negative" if allow_zero else "positive"
    v = real_number(value, name, unit=unit, what=f"a {kind} number", finite=f"a {kind} finite number")
    if v < 0 or (v == 0 and not allow_zero):
        where = f" in {unit}" if unit else ""
        raise ValueError(f"{name} must be a {kind} finite number{where}, got {value!r}")
    return v


def unit_interval(value, name: str, *, low_open: bool = False, high_open: bool = False) -> float:
    """A number in [0, 1] (ends excluded with ``low_open`` / ``high_open``)."""
    v = real_number(value, name, what="a number", finite="a finite number in [0, 1]")
    lo_ok = v > 0 if low_open else v >= 0
    hi_ok = v < 1 if high_open else v <= 1
    if not (lo_ok and hi_ok):
        interval = f"{'(' if low_open else '['}0, 1{')' if high_open else ']'}"
        raise ValueError(f"{name} must lie in {interval}, got {value!r}")
    return v


def index(value, name: str, *, minimum: int = 0, maximum: int | None = None) -> int:
    """An integer (Python or numpy) with ``minimum <= value`` (``<= maximum``).

    Booleans and non-numbers are a :class:`TypeError`; other numbers that are not ints (``2.5``, ``2.0``) a
    :class:`ValueError` (a count is never silently truncated).
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.integer, np.floating)):
        raise TypeError(f"{name} must be an int >= {minimum}, got {type(value).__name__} {value!r}")
    if not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an int >= {minimum}, got {type(value).__name__} {value!r}")
    v = int(value)
    if v < minimum or (maximum is not None and v > maximum):
        bound = f">= {minimum}" if maximum is None else f"in [{minimum}, {maximum}]"
        raise ValueError(f"{name} must be an int {bound}, got {_short(v)}")
    return v


def flag(value, name: str) -> bool:
    """A boolean flag: ``True`` or ``False`` (numpy booleans too); anything else is a TypeError."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {type(value).__name__} {value!r}")
    return bool(value)


def names(values, name: str, *, allow_empty: bool = False, unique: bool = True) -> tuple:
    """A sequence of non-empty strings as a tuple (a list, tuple or array of str; refused: one str — ``"ab"``
    is not ``('a', 'b')`` —, bytes, a mapping, a set, a number, non-str entries).

    Examples
    --------
    >>> names(["oven", "sink"], "classes")
    ('oven', 'sink')
    >>> names("ab", "classes")
    Traceback (most recent call last):
    ...
    TypeError: classes must be a list of names (str), got the str 'ab'
    """
    if isinstance(values, (str, bytes)):
        raise TypeError(f"{name} must be a list of names (str), got the {type(values).__name__} {values!r}")
    if isinstance(values, (dict, set, frozenset)) or not isinstance(values, (list, tuple, np.ndarray)):
        import collections.abc as abc

        if isinstance(values, (abc.Mapping, abc.Set)) or not isinstance(values, abc.Sequence):
            raise TypeError(f"{name} must be a list of names (str), got {type(values).__name__} {values!r}")
    out = tuple(values.tolist() if isinstance(values, np.ndarray) else values)
    for v in out:
        if not isinstance(v, str) or not v.strip():
            raise TypeError(f"{name} must hold non-empty strings, got {type(v).__name__} {v!r}")
    if not out and not allow_empty:
        raise ValueError(f"{name} must not be empty")
    if unique and len(set(out)) != len(out):
        dup = sorted({v for v in out if out.count(v) > 1})
        raise ValueError(f"{name} has duplicate names {dup}")
    return out


def real_pair(value, name: str, what: str = "an (x, y)", unit: str = "metres") -> np.ndarray:
    """A finite pair of real numbers, e.g. a position (x, y) or a wind vector; (2,) float64.

    Examples
    --------
    >>> real_pair((1, 2.5), "origin").tolist()
    [1.0, 2.5]
    """
    p = _real_array(value, name, f"{what} pair of real numbers in {unit}")
    if isinstance(value, (list, tuple)) and any(isinstance(v, (bool, np.bool_)) for v in value):
        raise TypeError(f"{name} must be {what} pair of real numbers in {unit}, got {value!r}")  # (True, 2.0) is a float array
    if p.shape != (2,):
        raise ValueError(f"{name} must be {what} pair in {unit}, got shape {p.shape}")
    p = p.astype(np.float64)
    if not np.isfinite(p).all():
        raise ValueError(f"{name} must be finite (a finite {what.split(' ', 1)[-1]} pair in {unit}), got {tuple(p.tolist())}")
    return p


def bool_mask(x, name: str, shape=None, *, ndim: int = 2) -> np.ndarray:
    """A boolean mask (own, read-only copy) from a bool array or an integer array of 0/1.

    Parameters
    ----------
    x : array_like
    name : str
    shape : tuple of int, optional
        Required shape (e.g. the map's (H, W)).
    ndim : int, default 2
        Required number of dimensions (every axis non-empty).
    """
    if x is None or isinstance(x, (str, bytes)):
        raise TypeError(f"{name} must be a boolean array (True/False or 0/1), got {type(x).__name__} {x!r}")
    arr = as_array(x, name, "a boolean array (True/False or 0/1)")
    if arr.dtype != bool:
        if not np.issubdtype(arr.dtype, np.integer) or not np.isin(arr, (0, 1)).all():
            raise TypeError(f"{name} must be a boolean array (True/False or integers 0/1), got {describe(arr)}")
    if arr.ndim != ndim or 0 in arr.shape:
        axes = "(H, W)" if ndim == 2 else f"{ndim}-D"
        raise ValueError(f"{name} must be a non-empty {axes} array, got shape {arr.shape}")
    if shape is not None and arr.shape != tuple(shape):
        raise ValueError(f"{name} must have the map's shape {tuple(shape)}, got {arr.shape}")
    out = np.array(arr, dtype=bool)
    out.flags.writeable = False
    return out


def check_keys(where: str, data: dict, *, required=(), optional=()) -> None:
    """Refuse unknown and missing keys of a mapping read from ``where`` (a file, or a file and key).

    Examples
    --------
    >>> check_keys("w.yaml", {"mapp": 1}, required=("map",))
    Traceback (most recent call last):
    ...
    ValueError: w.yaml: unknown key(s) ['mapp']; allowed keys are ['map']
    """
    if not isinstance(data, dict):
        raise ValueError(f"{where}: expected a mapping, got {type(data).__name__} {data!r}")
    unknown = sorted(str(k) for k in data if k not in required and k not in optional)
    if unknown:
        raise ValueError(
            f"{where}: unknown key(s) {unknown}; allowed keys are {sorted(set(required) | set(optional))}"
        )
    missing = [k for k in required if k not in data]
    if missing:
        raise ValueError(f"{where}: missing required key(s) {missing}")


def file_field(where: str, field: str, value, *, positive: bool = False, nonnegative: bool = False,
               integer: bool = False) -> float:
    """A finite real number read from field ``field`` of file ``where`` (bools and strings refused).

    Every failure is a :class:`ValueError` naming the file and the field, so that a user with a hand-edited
    file knows what to fix.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{where}: field '{field}' must be a number, got {type(value).__name__} {value!r}")
    try:
        v = float(value)
    except OverflowError:
        raise ValueError(f"{where}: field '{field}' must be a finite number, got an integer too large for a "
                         f"float64 ({_short(value)})") from None
    if not math.isfinite(v):
        raise ValueError(f"{where}: field '{field}' must be finite, got {value!r}")
    if positive and v <= 0:
        raise ValueError(f"{where}: field '{field}' must be > 0, got {value!r}")
    if nonnegative and v < 0:
        raise ValueError(f"{where}: field '{field}' must be >= 0, got {value!r}")
    if integer and v != round(v):
        raise ValueError(f"{where}: field '{field}' must be an integer, got {value!r}")
    return v


_IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")


def identifier(name: object, what: str) -> str:
    """Return ``name`` if it is a valid XMLBIF/BIF identifier, else raise.

    Parameters
    ----------
    name : object
        Candidate name.
    what : str
        What the name is for, used in the error message.

    Returns
    -------
    str
        ``name`` unchanged.

    Examples
    --------
    >>> identifier("oven", "class name")
    'oven'
    """
    if not isinstance(name, str):
        raise TypeError(f"{what} must be a str, got {type(name).__name__} {name!r}")
    if not _IDENTIFIER.match(name):
        raise ValueError(
            f"{what} must start with a letter and contain only letters, digits and underscores "
            f"(XMLBIF/BIF identifiers), got {name!r}"
        )
    return name


def cell_distribution(x, name: str, cell_shape: tuple, *, like: str) -> np.ndarray:
    """Validate a distribution over cells (non-negative, finite, sums to 1) of shape ``cell_shape``, the cells of
    argument ``like`` (named in the message, as the other side of a mismatch)."""
    arr = as_float_array(x, name)
    if arr.shape != tuple(cell_shape):
        raise ValueError(f"{name} must have the cells' shape {tuple(cell_shape)} (the cells of {like}), got "
                         f"{describe(arr)}")
    check_distribution(arr.reshape(-1), name, sums=np.sum(arr, dtype=np.float64))
    return arr


def one_of(value, name: str, allowed: tuple) -> str:
    """``value`` if it is one of the names ``allowed``; TypeError for a non-string, ValueError (with the closest
    names) for an unknown one, both naming ``allowed``.

    Examples
    --------
    >>> one_of("dev", "split", ("dev", "test"))
    'dev'
    """
    if not isinstance(value, str):
        raise TypeError(f"{name} must be one of {allowed}, got {type(value).__name__} {value!r}")
    if value not in allowed:
        raise ValueError(f"{name} must be one of {allowed}, got {value!r}{did_you_mean(value, allowed)}")
    return value


def did_you_mean(name: str, known) -> str:
    """``" — did you mean 'oven'?"`` for the closest of ``known`` (difflib), or ""."""
    import difflib

    close = difflib.get_close_matches(str(name), [str(k) for k in known], n=2, cutoff=0.6)
    return f" — did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
