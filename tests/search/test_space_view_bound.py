"""FreeSpace.view_bound against its definition: Σ abs(gain) over the tiles each candidate's view touches."""

import numpy as np


def _brute(space, gain, cells):
    out = []
    for c in cells:
        tiles = np.unique(space.tile[space.view(int(c))[0]])
        out.append(sum(np.abs(gain)[space.tile == t].sum() for t in tiles))
    return np.array(out) * (1.0 + 1e-9)


def test_view_bound_is_the_tile_sum_of_each_view_for_repeated_and_new_candidate_sets(house_space):
    _, space = house_space
    rng = np.random.default_rng(3)
    lattice = np.flatnonzero(space.lattice.ravel())
    cells = lattice[rng.choice(lattice.size, 12, replace=False)]
    for gain, subset in ((rng.normal(size=space.free.size), cells),  # a new set
                         (rng.normal(size=space.free.size), cells),  # the same set (its gather kept), new gains
                         (rng.normal(size=space.free.size), cells[::-1].copy()),  # the same cells, another order
                         (rng.normal(size=space.free.size), cells[:5])):  # a subset
        bound = space.view_bound(gain, subset)
        np.testing.assert_allclose(bound, _brute(space, gain, subset), rtol=1e-12)
        assert (bound[:, None] >= np.abs(space.view_gain(gain, subset))).all()
