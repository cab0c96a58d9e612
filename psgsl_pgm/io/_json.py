"""Strict JSON for the result files (``summary.json``, ``paired.json``, ...): no ``NaN`` or ``Infinity`` tokens.

A statistic with nothing to estimate it from (an interval from one run, a median survival never reached) is NaN;
:func:`json.dumps` would write the non-standard token ``NaN`` that strict readers (``jq``, JavaScript) refuse.
:func:`json_safe` turns such numbers into ``None`` (JSON ``null``) so that ``json.dumps(json_safe(obj),
allow_nan=False)`` always succeeds on the summaries the package writes.
"""

from __future__ import annotations

import math

__all__ = ["json_safe"]


def json_safe(obj):
    """A copy of ``obj`` with every non-finite float (NaN, ±inf) replaced by ``None``.

    Dicts keep their keys, lists and tuples become lists, floats (also ``numpy.float64``, a subclass of
    :class:`float`) that are not finite become ``None``; everything else is returned as it is.

    Examples
    --------
    >>> json_safe({"ci95": (float("nan"), 2.0), "n": 1, "median": float("inf")})
    {'ci95': [None, 2.0], 'n': 1, 'median': None}
    """
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj
