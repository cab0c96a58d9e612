"""Bounded in-process caches keyed by content.

What depends only on a house (its arrays and a few numbers) is computed once per worker process and shared by
every run, policy and condition of that house: the key is a digest of the content itself, never an object's
identity, so two equal houses built apart share an entry and a changed house never meets a stale one. The values
are returned as stored; callers keep them read-only.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict

import numpy as np

__all__ = ["ContentCache", "content_digest"]


def content_digest(*parts) -> str:
    """SHA-1 (hex) of arrays (dtype, shape and bytes) and plain values (their ``repr``), in order.

    Examples
    --------
    >>> import numpy as np
    >>> content_digest(np.zeros(3), 0.5) == content_digest(np.zeros(3), 0.5) != content_digest(np.ones(3), 0.5)
    True
    """
    h = hashlib.sha1()
    for p in parts:
        if isinstance(p, np.ndarray):
            a = np.ascontiguousarray(p)
            h.update(f"ndarray{a.dtype.str}{a.shape}".encode())
            h.update(a.tobytes())
        else:
            h.update(f"{type(p).__name__}:{p!r}|".encode())
    return h.hexdigest()


class ContentCache:
    """A least-recently-used mapping of at most ``maxsize`` entries, filled on a miss by a given function.

    Parameters
    ----------
    maxsize : int, keyword-only
        Entries kept (≥ 1); the least recently used one is dropped beyond it.

    Examples
    --------
    >>> cache = ContentCache(maxsize=2)
    >>> cache.get("a", lambda: 1), cache.get("a", lambda: 2), len(cache)
    (1, 1, 1)
    """

    def __init__(self, *, maxsize: int):
        if isinstance(maxsize, bool) or not isinstance(maxsize, int) or maxsize < 1:
            raise ValueError(f"maxsize must be a positive integer, got {maxsize!r}")
        self.maxsize = maxsize
        self._data: OrderedDict = OrderedDict()

    def get(self, key, make):
        """The value stored under ``key``, or ``make()`` stored under it (an exception stores nothing)."""
        try:
            value = self._data[key]
        except KeyError:
            value = make()
            self._data[key] = value
            while len(self._data) > self.maxsize:
                self._data.popitem(last=False)
            return value
        self._data.move_to_end(key)
        return value

    def clear(self) -> None:
        """Drop every entry."""
        self._data.clear()

    def __len__(self) -> int:
        return len(self._data)
