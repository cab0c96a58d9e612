"""The content-keyed caches: equal content, one entry; other content, another; bounded; bad sizes refused."""

import numpy as np
import pytest

from psgsl_pgm._shared._memo import ContentCache, content_digest


def test_digest_is_of_content_not_identity():
    a = np.arange(6.0).reshape(2, 3)
    assert content_digest(a, 1.0) == content_digest(a.copy(), 1.0)
    assert content_digest(a, 1.0) != content_digest(a.T.copy(), 1.0)  # same bytes sorted otherwise: shape counts
    assert content_digest(a) != content_digest(a.astype(np.float32))  # and dtype
    assert content_digest(a, 1.0) != content_digest(a, 1.5)
    assert content_digest(np.zeros(2, bool), 0) != content_digest(np.zeros(2, bool), False)  # the type is named


def test_cache_fills_once_keeps_the_last_used_and_stores_no_failure():
    calls = []
    cache = ContentCache(maxsize=2)

    def make(v):
        def f():
            calls.append(v)
            return v
        return f

    assert [cache.get(k, make(k)) for k in ("a", "b", "a", "c", "a", "b")] == ["a", "b", "a", "c", "a", "b"]
    assert calls == ["a", "b", "c", "b"]  # "b" was the least recently used when "c" came
    assert len(cache) == 2

    def boom():
        raise ValueError("no")

    with pytest.raises(ValueError, match="no"):
        cache.get("d", boom)
    assert len(cache) == 2
    cache.clear()
    assert len(cache) == 0


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2"])
def test_bad_sizes_are_refused(bad):
    with pytest.raises(ValueError, match="maxsize must be a positive integer"):
        ContentCache(maxsize=bad)
