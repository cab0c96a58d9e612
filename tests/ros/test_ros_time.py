"""Time alignment (:mod:`psgsl_pgm.ros._time`): the tolerance on each side, angles along the shorter arc."""

from __future__ import annotations

import numpy as np
import pytest

from psgsl_pgm.ros._time import interpolate

S = 10**9


@pytest.mark.parametrize("before, after", [(0.1, 2.0), (2.0, 0.1)])
def test_the_tolerance_holds_on_each_side(before, after):
    """A reading with a sample 0.1 s on one side and 2 s on the other is not covered at a 0.5 s tolerance,
    whichever side is the far one; at 2.5 s it is."""
    t = np.array([0, round((before + after) * S)], dtype=np.int64)
    q = np.array([round(before * S)], dtype=np.int64)
    with pytest.raises(ValueError, match="no sample within the tolerance 0.5 s on both sides"):
        interpolate(t, [[0.0], [1.0]], q, tolerance=0.5, where="s")
    out = interpolate(t, [[0.0], [1.0]], q, tolerance=2.5, where="s")
    np.testing.assert_allclose(out, [[before / (before + after)]], rtol=1e-12)


def test_yaw_goes_the_short_way_round():
    """From 3.0 rad to -3.0 rad the shorter arc crosses ±π (0.283 rad long), not 0 (6 rad long)."""
    t = np.array([0, 2 * S], dtype=np.int64)
    out = interpolate(t, [[0.0, 3.0], [1.0, -3.0]], np.array([S // 2, S, 3 * S // 2]), tolerance=5.0, where="s",
                      angle_columns=(1,))
    step = (2 * np.pi - 6.0) / 4
    expected = np.array([3.0 + step, np.pi, -3.0 - step])
    assert np.allclose(np.abs(out[1, 1]), np.pi)  # ±π: the same heading
    np.testing.assert_allclose(out[[0, 2], 1], expected[[0, 2]], rtol=1e-12)
    np.testing.assert_allclose(out[:, 0], [0.25, 0.5, 0.75], rtol=1e-12)  # other columns: plain linear
