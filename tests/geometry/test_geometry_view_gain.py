"""view_information_gain for many candidate poses equals the per-pose sum over field_of_view, exactly."""

import numpy as np
import pytest

from psgsl_pgm import ViewCache, field_of_view, view_information_gain


def _house_like(rng, h=40, w=50):
    occ = np.zeros((h, w), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    occ[:, 20] = True
    occ[18:22, 20] = False  # a door
    occ[25, 5:15] = True
    occ[rng.integers(1, h - 1, 30), rng.integers(1, w - 1, 30)] = True  # furniture
    return occ


@pytest.mark.parametrize("min_range", [0.0, 0.35])
def test_many_poses_equal_the_per_pose_field_of_view_sums(min_range):
    rng = np.random.default_rng(0)
    occ = _house_like(rng)
    gain = rng.random(occ.shape)
    res = 0.1
    free = np.argwhere(~occ)
    cells = free[rng.choice(len(free), 6, replace=False)]
    # 6 cells × 5 headings, poses anywhere inside their cell, plus 4 poses alone in their cells
    poses = [((c + rng.random()) * res, (r + rng.random()) * res, hd)
             for r, c in cells for hd in rng.uniform(-np.pi, np.pi, 5)]
    lone = free[rng.choice(len(free), 4, replace=False)]
    poses += [((c + 0.5) * res, (r + 0.5) * res, rng.uniform(-np.pi, np.pi)) for r, c in lone]
    poses = np.array(poses)
    fov = dict(max_range=1.5, half_angle=np.deg2rad(35.0), min_range=min_range, resolution=res)
    want = np.array([gain[field_of_view(occ, p, **fov)].sum() for p in poses])
    got = view_information_gain(gain, occ, poses, **fov)
    np.testing.assert_array_equal(got, want)
    assert view_information_gain(gain, occ, poses[3], **fov) == want[3]


def test_full_circle_and_bad_poses():
    rng = np.random.default_rng(1)
    occ = _house_like(rng)
    gain = rng.random(occ.shape)
    poses = np.array([[1.05, 1.05, 0.0], [1.07, 1.02, 2.0], [3.0, 3.1, -1.0]])
    fov = dict(max_range=10.0, half_angle=np.pi, resolution=0.1)
    want = np.array([gain[field_of_view(occ, p, **fov)].sum() for p in poses])
    np.testing.assert_array_equal(view_information_gain(gain, occ, poses, **fov), want)
    with pytest.raises(ValueError, match="outside the map"):
        view_information_gain(gain, occ, np.array([[1.0, 1.0, 0.0], [100.0, 1.0, 0.0]]), **fov)
    with pytest.raises(ValueError, match=r"pose must be \(3,\) or \(P, 3\)"):
        view_information_gain(gain, occ, np.zeros((2, 2)), **fov)


def test_view_cache_equals_field_of_view_for_every_pose_and_stays_within_its_memory_bound():
    rng = np.random.default_rng(2)
    occ = _house_like(rng)
    res = 0.1
    fov = dict(max_range=1.2, half_angle=np.deg2rad(50.0), min_range=0.15, resolution=res)
    views = ViewCache(occ, **fov, max_bytes=40_000)
    free = np.argwhere(~occ)
    for r, c in free[rng.choice(len(free), 40, replace=False)]:
        pose = ((c + rng.random()) * res, (r + rng.random()) * res, rng.uniform(-np.pi, np.pi))
        np.testing.assert_array_equal(views.field_of_view(pose), field_of_view(occ, pose, **fov))
    assert views._bytes <= 40_000 or len(views._sight) == 1
    assert sum(r.size * 8 for r, _ in views._sight.values()) == views._bytes
    assert ViewCache.shared(occ.copy(), **fov) is ViewCache.shared(occ, **fov)
    assert ViewCache.shared(~occ, **fov) is not ViewCache.shared(occ, **fov)


@pytest.mark.parametrize("heading", [0.0, np.pi / 2, np.pi, -np.pi / 2])
def test_cells_exactly_on_the_cone_boundary_are_inside(heading):
    # a 90° camera looking along an axis: the diagonal cells lie exactly on the boundary (closed)
    occ = np.zeros((9, 9), bool)
    seen = field_of_view(occ, (4.5, 4.5, heading), max_range=3.0, half_angle=np.pi / 4)
    d = np.array([np.cos(heading), np.sin(heading)]).round().astype(int)  # forward, (dx, dy) in cells
    side = np.array([-d[1], d[0]])
    for s in (1, -1):
        for k in (1, 2):  # bearing exactly ±45°
            dx, dy = k * d + s * k * side
            assert seen[4 + dy, 4 + dx]
        dx, dy = d + s * 2 * side  # bearing ±63.4°
        assert not seen[4 + dy, 4 + dx]
