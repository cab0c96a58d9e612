"""survey and candidate_poses on the default house."""

from __future__ import annotations

import numpy as np
import pytest

from psgsl_pgm import field_of_view
from psgsl_pgm.sim import Camera, SemanticMap
from psgsl_pgm.teaching import candidate_poses, survey


def test_survey_updates_only_the_cells_in_view(house):
    k = len(house.classes)
    prior = np.full(k, 1.0 / k)
    pose = (7.5, 3.0, -1.5)
    a = survey(house, [pose], SemanticMap.from_prior(house.shape, prior, house.classes), seed=4)
    b = survey(house, [pose], SemanticMap.from_prior(house.shape, prior, house.classes), seed=4)
    np.testing.assert_array_equal(a.probs, b.probs)  # seeded
    changed = np.any(a.probs != prior, axis=-1)
    cam = Camera()
    seen = field_of_view(house.grid.occupancy, pose, max_range=cam.max_range, half_angle=cam.half_angle,
                         min_range=cam.min_range, resolution=house.grid.resolution) & house.grid.free
    assert changed.any() and not np.any(changed & ~seen)
    with pytest.raises(ValueError, match=r"\(P, 3\)"):
        survey(house, pose, a, seed=0)


def test_survey_voxels(house):
    k = len(house.classes)
    edges = [0.0, 0.5, 1.0, 1.5]
    m = survey(house, [(7.5, 3.0, -1.5), (8.0, 3.0, 0.0)],
               SemanticMap.from_prior(house.shape + (3,), np.full(k, 1.0 / k), house.classes), seed=1,
               layer_edges=edges)
    assert m.n_frames == 2 and m.probs.shape == house.shape + (3, k)
    np.testing.assert_allclose(m.probs.sum(axis=-1), 1.0, rtol=1e-12)


def test_candidate_poses_keep_clear_of_obstacles(house):
    poses = candidate_poses(house, spacing=0.7, n_headings=6, clearance=0.35)
    q = poses.reshape(-1, 6, 3)
    np.testing.assert_array_equal(q[:, :, :2], np.repeat(q[:, :1, :2], 6, axis=1))  # position-major
    np.testing.assert_allclose(q[0, :, 2], 2 * np.pi * np.arange(6) / 6)
    obstacles = house.grid.cell_centres()[house.robot_obstacles]  # (N, 2) centres of blocked cells
    xy = q[:, 0, :2]
    nearest = np.min(np.linalg.norm(xy[:, None, :] - obstacles[None, :, :], axis=-1), axis=1)
    assert nearest.min() > 0.35 - 1e-9  # clearance measured between cell centres
    assert xy.shape[0] > 30  # the lattice covers the rooms
    for kwargs in ({"spacing": 0.0}, {"spacing": 1.0, "n_headings": 0}, {"spacing": 1.0, "clearance": -1.0}):
        with pytest.raises(ValueError):
            candidate_poses(house, **kwargs)
