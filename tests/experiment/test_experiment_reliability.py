"""The reliability table and diagram of the hit model."""

import numpy as np
import pytest

from psgsl_pgm.experiment import plot_reliability, reliability_table


def _wilson(k, n, z=1.959963984540054):
    p = k / n
    c = (p + z * z / (2 * n)) / (1 + z * z / n)
    h = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (0.0 if k == 0 else c - h), (1.0 if k == n else c + h)


def test_reliability_table_counts_by_hand():
    p = [0.01, 0.015, 0.3, 0.35, 0.39, 0.9, 1.0, 0.2]
    g = np.array([0, 0, 1, 0, 1, 1, 1, 0], bool)
    t = reliability_table(p, g, bins=(0.0, 0.2, 0.4, 1.0))
    assert t["n"].tolist() == [2, 4, 2]  # 0.2 falls in [0.2, 0.4); 1.0 in the closed last bin
    assert t["hits"].tolist() == [0, 2, 2]
    np.testing.assert_allclose(t["mean_predicted"], [0.0125, (0.3 + 0.35 + 0.39 + 0.2) / 4, 0.95], rtol=1e-12)
    np.testing.assert_allclose(t["observed"], [0.0, 0.5, 1.0], rtol=1e-12)
    for i, (k, n) in enumerate(zip(t["hits"], t["n"])):
        lo, hi = _wilson(k, n)
        assert t["lower"][i] == pytest.approx(lo, abs=1e-12) and t["upper"][i] == pytest.approx(hi, abs=1e-12)


def test_reliability_table_empty_bins_and_bad_input():
    t = reliability_table([0.5], [True], bins=(0.0, 0.1, 1.0))
    assert t["n"].tolist() == [0, 1] and np.isnan(t["observed"][0]) and np.isnan(t["lower"][0])
    with pytest.raises(ValueError, match="predicted must be"):
        reliability_table([1.5], [True])
    with pytest.raises(TypeError, match="hits must be booleans"):
        reliability_table([0.5], [1])
    with pytest.raises(ValueError, match="bins must be increasing"):
        reliability_table([0.5], [True], bins=(0.1, 1.0))


def test_plot_reliability_writes_a_png(tmp_path):
    t = reliability_table(np.linspace(0, 1, 50), np.arange(50) % 2 == 0)
    fig = plot_reliability({"a": t, "b": t}, tmp_path / "r.png")
    assert (tmp_path / "r.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    ax = fig.axes[0]
    assert ax.get_xlabel() and ax.get_ylabel()
