"""The one grid (psgsl_pgm.GridMap) and the one line of sight: the camera and the gas agree on every wall."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import psgsl_pgm
import psgsl_pgm.olfaction
import psgsl_pgm.sim
from psgsl_pgm import GridMap, field_of_view
from psgsl_pgm.geometry._grid import free_space_graph
from psgsl_pgm.sim import Camera, LineOfSightCache, cells_clear

from ..core.brute_force import touches


def _brute_force_view(occ, pose, max_range, half_angle):
    """field_of_view by its definition: cone from the pose, occlusion from the camera cell's centre."""
    h, w = occ.shape
    r0, c0 = int(pose[1]), int(pose[0])
    out = np.zeros_like(occ)
    for r in range(h):
        for c in range(w):
            dx, dy = c + 0.5 - pose[0], r + 0.5 - pose[1]
            d = np.hypot(dx, dy)
            bearing = np.angle(np.exp(1j * (np.arctan2(dy, dx) - pose[2])))
            if d > max_range or not (abs(bearing) <= half_angle or d < 1e-12):
                continue
            out[r, c] = not any(
                occ[rr, cc] and (rr, cc) not in ((r, c), (r0, c0)) and touches((r0, c0), (r, c), rr, cc)
                for rr in range(min(r, r0), max(r, r0) + 1)
                for cc in range(min(c, c0), max(c, c0) + 1)
            )
    return out


def test_one_grid_object_everywhere():
    assert psgsl_pgm.sim.GridMap is GridMap
    assert not hasattr(psgsl_pgm.olfaction, "GridGeometry")  # the olfactory estimators use GridMap too
    g = GridMap(np.zeros((3, 4), int), 0.5, (-1, 2))
    assert g.origin == (-1.0, 2.0) and g.occupancy.dtype == bool and not g.occupancy.flags.writeable
    np.testing.assert_array_equal(g.world_to_cell(g.cell_centres()), np.stack(np.indices((3, 4)), axis=-1))
    assert g.cell_of((0.9, 3.4)) == (2, 3) and g.centre_of((2, 3)) == (0.75, 3.25)


def test_coarsen_any_keeps_thin_walls():
    occ = np.zeros((4, 6), bool)
    occ[0, 0] = True
    g = GridMap(occ, 0.01).coarsen(2, occupied_fraction="any")
    np.testing.assert_array_equal(g.occupancy, [[True, False, False], [False, False, False]])
    with pytest.raises(ValueError, match="occupied_fraction must be a number in \\(0, 1\\] or 'any'"):
        GridMap(occ, 0.01).coarsen(2, occupied_fraction="all")


def test_free_space_graph_has_no_corner_cutting_and_true_lengths():
    free = np.ones((3, 3), bool)
    free[0, 1] = False  # the diagonal (0, 0) - (1, 2)... and (0, 0)-(1, 1) passes beside (0, 1)
    g = free_space_graph(free, 0.5).toarray()
    assert g[0 * 3 + 0, 1 * 3 + 1] == 0  # (0,0) -> (1,1) would cut the corner of (0,1)
    assert g[1 * 3 + 0, 2 * 3 + 1] == pytest.approx(0.5 * np.sqrt(2), rel=1e-15)
    assert g[1 * 3 + 0, 1 * 3 + 1] == 0.5 and np.array_equal(g, g.T)
    assert not g[1].any()  # the occupied cell has no edges
    np.testing.assert_array_equal(GridMap(~free, 0.5).free_space_graph().toarray(), g)


@settings(max_examples=60, deadline=None)
@given(
    occ=arrays(bool, st.tuples(st.integers(2, 10), st.integers(2, 10)), elements=st.booleans()),
    cam=st.tuples(st.floats(0, 1, exclude_max=True), st.floats(0, 1, exclude_max=True)),
    heading=st.floats(-4, 4),
    half_angle=st.sampled_from([np.pi, 2.0, 0.6]),
    max_range=st.floats(0.5, 14),
)
def test_field_of_view_is_exactly_the_supercover_rule(occ, cam, heading, half_angle, max_range):
    h, w = occ.shape
    pose = (cam[0] * w, cam[1] * h, heading)
    got = field_of_view(occ, pose, max_range=max_range, half_angle=half_angle)
    np.testing.assert_array_equal(got, _brute_force_view(occ, pose, max_range, half_angle))


@settings(max_examples=40, deadline=None)
@given(occ=arrays(bool, (7, 9), elements=st.booleans()), data=st.data())
def test_camera_and_gas_agree_on_every_wall(occ, data):
    """Seen free cell ⟺ gas line of sight, from every free camera cell."""
    free = np.argwhere(~occ)
    if len(free) == 0:
        return
    r0, c0 = free[data.draw(st.integers(0, len(free) - 1))]
    seen = field_of_view(occ, (c0 + 0.5, r0 + 0.5, 0.0), max_range=20, half_angle=np.pi) & ~occ
    clear = cells_clear(occ, np.broadcast_to([r0, c0], free.shape), free)
    np.testing.assert_array_equal(seen[free[:, 0], free[:, 1]], clear)


@pytest.mark.parametrize("camera_cell", [(15, 4), (12, 2), (19, 0), (10, 9)])
def test_a_diagonal_wall_hides_everything_behind_it_for_camera_and_gas(camera_cell):
    n = 20
    occ = np.zeros((n, n), bool)
    occ[np.arange(n), np.arange(n)] = True  # cells (i, i): they touch only at their corners
    rows, cols = np.indices((n, n))
    behind = rows < cols  # the other side of the wall (the camera is at row > col)
    grid = GridMap(occ, 0.1)
    r0, c0 = camera_cell
    pose = ((c0 + 0.5) * 0.1, (r0 + 0.5) * 0.1, 0.0)
    # the camera: the core function and the simulator's Camera
    seen = field_of_view(occ, pose, max_range=10.0, half_angle=np.pi, resolution=0.1)
    assert not (seen & behind).any()
    assert (seen & ~occ & ~behind).sum() >= 20  # its own side is seen
    cam = Camera(max_range=10.0, half_angle=np.pi, min_range=0.0)
    assert not (cam.visible(grid, np.array(pose)) & behind).any()
    # the gas: cells_clear, the cached form the filament model uses, and GridMap.line_of_sight
    targets = np.argwhere(behind)
    origin = np.broadcast_to([r0, c0], targets.shape)
    assert not cells_clear(occ, origin, targets).any()
    assert not LineOfSightCache(occ).clear_from((r0, c0), targets).any()
    assert not grid.line_of_sight(origin, targets).any()


def test_field_of_view_on_a_fine_map_is_bounded_in_memory_and_time():
    """1 cm, 1140 × 870 cells, 4 m range, full circle: used to need ~3.7 GB (MemoryError)."""
    occ = np.zeros((870, 1140), bool)
    occ[[0, -1], :] = occ[:, [0, -1]] = True
    occ[200:700, 300] = occ[200:700, 900] = occ[200, 300:901] = occ[700, 300:901] = True  # a 6 × 5 m room
    occ[450, 300:901] = True  # splits the room in two
    tracemalloc.start()
    seen = field_of_view(occ, (6.005, 4.005, 0.0), max_range=4.0, half_angle=np.pi, resolution=0.01)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    open_seen = field_of_view(occ, (1.005, 1.005, 0.0), max_range=4.0, half_angle=np.pi, resolution=0.01)
    assert peak < 40e6, peak  # the (H, W) result is 1 MB; one ring and the shadows are small
    rows, cols = np.indices(occ.shape)
    in_room = (rows > 200) & (rows < 450) & (cols > 300) & (cols < 900)  # the camera's half of the room
    assert seen[in_room].all() and not seen[(rows > 450) & (rows < 700) & (cols > 300) & (cols < 900)].any()
    assert open_seen.sum() > 0.6 * np.pi * 400**2 / 4  # a quarter disc of 4 m, outside the room


def test_huge_range_costs_no_more_than_the_map():
    occ = np.zeros((5, 5), bool)
    assert field_of_view(occ, (2.5, 2.5, 0.0), max_range=1e6, half_angle=np.pi).all()
