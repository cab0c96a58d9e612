"""The observation arrays: the downsampled belief keeps the mass; the candidate table ranks by P_f per second."""

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from psgsl_pgm.gym import candidate_table, downsample_belief  # noqa: E402


def test_blocks_hold_the_mass_of_their_cells():
    rng = np.random.default_rng(0)
    p = rng.random((37, 53))
    p /= p.sum()
    b = downsample_belief(p, 8)
    assert b.shape == (8, 8) and b.sum() == pytest.approx(1.0, abs=1e-12)
    # block (0, 0) holds rows 0..4 (⌊r·8/37⌋ = 0 for r < 4.625) and columns 0..6
    assert b[0, 0] == pytest.approx(p[:5, :7].sum(), abs=1e-15)
    small = downsample_belief(np.full((2, 3), 1 / 6), 4)  # fewer cells than blocks: some blocks are empty
    assert small.sum() == pytest.approx(1.0) and (small == 0).sum() == 16 - 6


@pytest.mark.parametrize("bad", [np.ones(4), np.full((2, 2), np.nan), -np.ones((2, 2))])
def test_a_bad_belief_is_refused(bad):
    with pytest.raises(ValueError, match="posterior must be"):
        downsample_belief(bad, 2)


def test_the_table_ranks_by_found_mass_per_second():
    from psgsl_pgm.search._stepper import ClosedLoopEpisode
    from psgsl_pgm.search import SearchConfig

    ep = ClosedLoopEpisode("oven", 0, None, "olfaction", "infotaxis", search=SearchConfig(time_budget=30.0))
    ep.take(ep.first_move())
    sit = ep.situation()
    full = candidate_table(sit, slots=10_000)
    k = int(full.mask.sum())
    rate = full.p_found / (full.drive / sit.speed + sit.sense_time)
    assert np.all(np.diff(rate) <= 0)  # best first
    cells, drive, _ = sit.space.candidates(sit.cell, sit.horizon, sit.far_spacing)
    assert k == len(cells) and set(full.cells) == set(cells.tolist())
    top = candidate_table(sit, slots=5)
    np.testing.assert_array_equal(top.cells, full.cells[:5])
    np.testing.assert_array_equal(top.table, full.table[:5])
    assert np.all(top.table[:, 4] == 1) and np.all(full.table[k:] == 0)
    assert np.all((top.table[:, 3] >= 0) & (top.table[:, 3] <= 1))
