"""Time alignment: a reading at time t gets the pose (or wind) interpolated between the samples around t.

The rule (stated once, used for every stream):

* a sample whose stamp equals t exactly (to the nanosecond) is taken as it is — no arithmetic, so a recorded
  episode replays bit for bit;
* otherwise the value is interpolated linearly between the last sample before t and the first after t, provided
  both lie within ``tolerance`` seconds of t (angles along the shorter arc);
* a reading with no such pair — before the first sample, after the last, or inside a gap longer than
  ``tolerance`` on either side — is an error naming the stream and the time (never extrapolated, never held).

Times are integer nanoseconds (ROS stamps), so "equal" is exact.
"""

from __future__ import annotations

import numpy as np

__all__ = ["DEFAULT_TOLERANCE", "check_increasing", "interpolate", "wrap_angle"]

#: Default alignment tolerance, s: a 10 Hz pose with a dropped message still covers every reading.
DEFAULT_TOLERANCE = 0.5


def wrap_angle(a):
    """Angles wrapped to [-π, π)."""
    return (np.asarray(a, dtype=np.float64) + np.pi) % (2 * np.pi) - np.pi


def check_increasing(t_ns: np.ndarray, where: str, *, strict: bool = False, describe=None) -> None:
    """ValueError naming ``where`` and the time when the stamps ``t_ns`` go backwards (or repeat, ``strict``)."""
    t_ns = np.asarray(t_ns, dtype=np.int64)
    step = np.diff(t_ns)
    bad = np.flatnonzero(step <= 0 if strict else step < 0)
    if len(bad):
        i = int(bad[0])
        when = describe(int(t_ns[i + 1])) if describe else f"{t_ns[i + 1] * 1e-9:.9f} s"
        raise ValueError(f"{where}: time goes backwards at {when} (after a stamp "
                         f"{(t_ns[i] - t_ns[i + 1]) * 1e-9:.9f} s later)")


def interpolate(t_ns, values, query_ns, *, tolerance: float, where: str, angle_columns=(), describe=None):
    """Values of a stream at the query times (see the module docstring).

    Parameters
    ----------
    t_ns : (n,) int64 array
        Sample stamps, non-decreasing (checked by the reader).
    values : (n, d) ndarray
    query_ns : (m,) int64 array
    tolerance : float, keyword-only
        Seconds.
    where : str, keyword-only
        The stream, for the error message ("bag.db3: topic /tf (map -> base_link)").
    angle_columns : sequence of int, keyword-only
        Columns that are angles (interpolated along the shorter arc, wrapped to [-π, π)).
    describe : callable, optional, keyword-only
        ``describe(t_ns) -> str`` for times in messages.

    Returns
    -------
    (m, d) ndarray
    """
    t_ns = np.asarray(t_ns, dtype=np.int64)
    values = np.asarray(values, dtype=np.float64)
    q = np.asarray(query_ns, dtype=np.int64)
    tol = round(float(tolerance) * 1e9)
    out = np.empty((len(q), values.shape[1]))
    if len(t_ns) == 0:
        if len(q):
            raise ValueError(f"{where}: no sample at all, needed at {_when(q[0], describe)}")
        return out
    right = np.searchsorted(t_ns, q, side="left")  # first sample at or after each query
    exact = (right < len(t_ns)) & (t_ns[np.minimum(right, len(t_ns) - 1)] == q)
    out[exact] = values[right[exact]]
    rest = np.flatnonzero(~exact)
    if len(rest) == 0:
        return out
    lo, hi = right[rest] - 1, right[rest]
    inside = (lo >= 0) & (hi < len(t_ns))
    lo_c, hi_c = np.clip(lo, 0, len(t_ns) - 1), np.clip(hi, 0, len(t_ns) - 1)
    ok = inside & (q[rest] - t_ns[lo_c] <= tol) & (t_ns[hi_c] - q[rest] <= tol)
    if not ok.all():
        i = int(np.flatnonzero(~ok)[0])
        t = q[rest][i]
        if not inside[i]:
            span = f"samples cover {_when(t_ns[0], describe)} to {_when(t_ns[-1], describe)}"
        else:
            span = (f"the samples around it are {(t - t_ns[lo_c[i]]) * 1e-9:.3f} s before and "
                    f"{(t_ns[hi_c[i]] - t) * 1e-9:.3f} s after")
        raise ValueError(f"{where}: no sample within the tolerance {tolerance:g} s on both sides of "
                         f"{_when(t, describe)} ({span})")
    frac = ((q[rest] - t_ns[lo_c]) / (t_ns[hi_c] - t_ns[lo_c]).astype(np.float64))[:, None]
    a, b = values[lo_c], values[hi_c]
    diff = b - a
    cols = list(angle_columns)
    if cols:
        diff[:, cols] = wrap_angle(diff[:, cols])
    res = a + frac * diff
    if cols:
        res[:, cols] = wrap_angle(res[:, cols])
    out[rest] = res
    return out


def _when(t_ns, describe) -> str:
    return describe(int(t_ns)) if describe else f"{int(t_ns) * 1e-9:.9f} s"
