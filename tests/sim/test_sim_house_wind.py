"""The default house (layout, determinism, rooms, objects) and the wind (potential flow against an independent
dense solve, divergence-free, no flux through walls; the perturbation; the CFD CSV reader)."""

import numpy as np
import pytest

from psgsl_pgm.sim import (
    HOUSE_CLASSES,
    HOUSE_ROOMS,
    OTHER,
    GridMap,
    WindField,
    default_house,
    make_wind,
    potential_flow,
    read_gaden_wind_csv,
)


# ---- house ---------------------------------------------------------------------------------------------------
def test_default_house_layout(house):
    h = house
    g = h.grid
    assert g.shape == (120, 100) and g.resolution == 0.1 and g.origin == (0.0, 0.0)
    assert h.room_names == HOUSE_ROOMS
    # every free cell has a room, walls have none
    assert (h.room_labels[g.free] >= 0).all() and (h.room_labels[g.occupancy] == -1).all()
    for i in range(len(HOUSE_ROOMS)):
        assert (h.room_labels == i).sum() > 100
    # the outer wall is closed except for the two windows
    border = np.zeros(g.shape, bool)
    border[[0, -1], :] = True
    border[:, [0, -1]] = True
    assert (g.occupancy | h.inlet | h.outlet)[border].all()
    assert h.inlet.any() and h.outlet.any() and not (h.inlet & h.outlet).any()
    assert (h.inlet & border).any() and (h.outlet & border).any()
    # every class of the house appears, each object in free cells of one room
    present = {o.class_name for o in h.objects}
    assert present == set(HOUSE_CLASSES) - {OTHER}
    for o, m in zip(h.objects, h.object_masks):
        assert m.any() and not (m & g.occupancy).any()
        assert len(np.unique(h.room_labels[m])) == 1
    kitchen = HOUSE_ROOMS.index("Kitchen")
    for cls in ("oven", "microwave", "toaster", "refrigerator"):
        assert all(h.room_of(o.center) == kitchen for o in h.objects_of_class(cls))
    assert h.room_of(h.objects_of_class("toilet")[0].center) == HOUSE_ROOMS.index("Bathroom")
    # robot obstacles = walls + furniture + windows
    np.testing.assert_array_equal(h.robot_obstacles, g.occupancy | h.furniture | h.inlet | h.outlet)


def test_default_house_is_deterministic_per_seed():
    a, b, c = default_house(3), default_house(3), default_house(4)
    np.testing.assert_array_equal(a.class_map, b.class_map)
    np.testing.assert_array_equal(a.grid.occupancy, c.grid.occupancy)  # walls do not move
    moved = [not np.allclose(x.footprint, y.footprint) for x, y in zip(a.objects, c.objects)]
    assert any(moved)
    for seed in range(20):  # the jitter never breaks the layout (checked inside default_house)
        default_house(seed)
    with pytest.raises(TypeError, match="seed"):
        default_house(1.5)


def test_class_maps(house):
    h = house
    cm = h.class_map
    other = HOUSE_CLASSES.index(OTHER)
    assert (cm[~h.furniture] == other).all() and (cm[h.furniture] != other).all()
    oven = h.objects_of_class("oven")[0]
    assert HOUSE_CLASSES[cm[tuple(h.grid.world_to_cell(oven.center))]] == "oven"
    # the microwave sits on the countertop: counter below 0.9 m, microwave above, "other" above 1.2 m
    vox = h.voxel_class_map([0.0, 0.5, 1.0, 1.5, 2.0])
    mw = h.grid.world_to_cell(h.objects_of_class("microwave")[0].center)
    assert [HOUSE_CLASSES[i] for i in vox[mw[0], mw[1]]] == ["countertop", "microwave", "microwave", OTHER]
    fridge = h.grid.world_to_cell(h.objects_of_class("refrigerator")[0].center)
    assert [HOUSE_CLASSES[i] for i in vox[fridge[0], fridge[1]]] == ["refrigerator"] * 4
    np.testing.assert_array_equal(vox[~h.furniture], other)


def test_plot_house_runs(house):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from psgsl_pgm.sim import plot_house

    h = house
    conc = np.full(h.shape, np.nan)
    conc[::2, ::2] = 1.0
    ax = plot_house(h, wind=potential_flow(h.grid, h.inlet, h.outlet), concentration=conc, source=(7.5, 0.5))
    assert ax.get_xlim() == (0.0, 10.0) and ax.get_ylim() == (0.0, 12.0)
    assert len(ax.images) >= 5  # rooms, objects, gas, walls, inlet, outlet
    plt.close("all")


# ---- potential flow ------------------------------------------------------------------------------------------
def _dense_potential(occ, inlet, outlet):
    """Independent reference: φ from a dense linear system assembled cell by cell (loops)."""
    h, w = occ.shape
    free = ~occ | inlet | outlet
    unknown = [(r, c) for r in range(h) for c in range(w) if free[r, c] and not inlet[r, c] and not outlet[r, c]]
    index = {rc: i for i, rc in enumerate(unknown)}
    a = np.zeros((len(unknown), len(unknown)))
    b = np.zeros(len(unknown))
    for (r, c), i in index.items():
        for rr, cc in ((r + 1, c), (r - 1, c), (r, c + 1), (r, c - 1)):
            if 0 <= rr < h and 0 <= cc < w and free[rr, cc]:
                a[i, i] += 1.0
                if (rr, cc) in index:
                    a[i, index[(rr, cc)]] -= 1.0
                else:
                    b[i] += 1.0 if inlet[rr, cc] else 0.0
    phi = np.where(inlet, 1.0, 0.0)
    sol = np.linalg.solve(a, b)
    for (r, c), i in index.items():
        phi[r, c] = sol[i]
    return phi, free


def _small_world():
    occ = np.zeros((9, 12), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    occ[1:6, 5] = True  # an internal wall with a gap
    occ[5, 8:11] = True
    inlet = np.zeros_like(occ)
    outlet = np.zeros_like(occ)
    inlet[2:5, 0] = True
    outlet[0, 9:11] = True
    return GridMap(occ & ~inlet & ~outlet, 0.2, (1.0, -2.0)), inlet, outlet


def test_potential_flow_matches_dense_reference():
    g, inlet, outlet = _small_world()
    field = potential_flow(g, inlet, outlet, mean_speed=0.25)
    phi, free = _dense_potential(g.occupancy, inlet, outlet)
    h, w = g.shape
    u = np.zeros((h, w + 1))
    v = np.zeros((h + 1, w))
    for r in range(h):
        for c in range(1, w):
            if free[r, c] and free[r, c - 1]:
                u[r, c] = -(phi[r, c] - phi[r, c - 1]) / 0.2
    for r in range(1, h):
        for c in range(w):
            if free[r, c] and free[r - 1, c]:
                v[r, c] = -(phi[r, c] - phi[r - 1, c]) / 0.2
    cell_speed = np.hypot((u[:, 1:] + u[:, :-1]) / 2, (v[1:] + v[:-1]) / 2)
    inner = free & ~inlet & ~outlet
    scale = 0.25 / cell_speed[inner].mean()
    np.testing.assert_allclose(field.u_faces, u * scale, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(field.v_faces, v * scale, rtol=1e-10, atol=1e-12)
    assert field.speed()[inner].mean() == pytest.approx(0.25, rel=1e-12)


def test_house_flow_divergence_free_and_no_flux_through_walls(house):
    h = house
    g = h.grid
    field = potential_flow(g, h.inlet, h.outlet, mean_speed=0.2)
    inner = g.free & ~h.inlet & ~h.outlet
    typical = np.abs(field.u_faces).max() / g.resolution
    assert np.abs(field.divergence()[inner]).max() <= 1e-10 * typical
    # faces touching a wall, and the map border, carry no flow
    wall = g.occupancy
    assert (field.u_faces[:, 1:-1][wall[:, 1:] | wall[:, :-1]] == 0).all()
    assert (field.v_faces[1:-1, :][wall[1:, :] | wall[:-1, :]] == 0).all()
    assert (field.u_faces[:, [0, -1]] == 0).all() and (field.v_faces[[0, -1], :] == 0).all()
    # what enters by the inlet leaves by the outlet: net outflow of the windows is ± the same
    div = field.divergence() * g.resolution**2
    assert div[h.inlet].sum() > 0
    assert div[h.inlet].sum() == pytest.approx(-div[h.outlet].sum(), rel=1e-9)
    assert (field.velocity[g.occupancy] == 0).all()
    assert field.speed()[inner].mean() == pytest.approx(0.2, rel=1e-12)


def test_uniform_channel_is_uniform_flow():
    occ = np.zeros((6, 20), bool)
    occ[0, :] = occ[-1, :] = True
    inlet = np.zeros_like(occ)
    outlet = np.zeros_like(occ)
    inlet[1:-1, 0] = True
    outlet[1:-1, -1] = True
    field = potential_flow(GridMap(occ, 0.1), inlet, outlet, mean_speed=0.3)
    interior = field.velocity[1:-1, 1:-1]
    np.testing.assert_allclose(interior[..., 0], 0.3, rtol=1e-12)
    np.testing.assert_allclose(interior[..., 1], 0.0, atol=1e-13)


def test_potential_flow_errors():
    g = GridMap(np.zeros((4, 4), bool), 0.1)
    m = np.zeros((4, 4), bool)
    with pytest.raises(ValueError, match="at least one cell"):
        potential_flow(g, m, m)
    a = m.copy(); a[0, 0] = True
    b = m.copy(); b[3, 3] = True
    occ = np.zeros((4, 4), bool); occ[:, 2] = True
    with pytest.raises(ValueError, match="no free path"):
        potential_flow(GridMap(occ, 0.1), a, b)
    with pytest.raises(ValueError, match="disjoint"):
        potential_flow(g, a, a)
    with pytest.raises(ValueError, match="mean_speed"):
        potential_flow(g, a, b, mean_speed=-1)


def test_perturbed_wind_sequence(house):
    h = house
    g = h.grid
    from psgsl_pgm.sim import _wind

    seq = make_wind(g, h.inlet, h.outlet, mean_speed=0.2, perturbation=0.3, period=10.0, duration=100.0, seed=5)
    # kept for the next run of the episode (immutable); made again without the cache, the same numbers
    assert make_wind(g, h.inlet, h.outlet, mean_speed=0.2, perturbation=0.3, period=10.0, duration=100.0,
                     seed=5) is seq
    _wind._WIND_SEQUENCES.clear()
    again = make_wind(g, h.inlet, h.outlet, mean_speed=0.2, perturbation=0.3, period=10.0, duration=100.0, seed=5)
    assert again is not seq
    other = make_wind(g, h.inlet, h.outlet, mean_speed=0.2, perturbation=0.3, period=10.0, duration=100.0, seed=6)
    assert not np.array_equal(other.velocities, seq.velocities)
    base = potential_flow(g, h.inlet, h.outlet, mean_speed=0.2)
    assert len(seq.snapshots) == 10
    np.testing.assert_array_equal(seq.velocities, again.velocities)
    inner = g.free & ~h.inlet & ~h.outlet
    wall = g.occupancy | h.inlet | h.outlet
    bath = h.room_labels == HOUSE_ROOMS.index("Bathroom")
    for snap in seq.snapshots:
        pu, pv = snap.u_faces - base.u_faces, snap.v_faces - base.v_faces
        pert = WindField.from_faces(g, pu, pv)
        assert np.abs(pert.divergence()[inner]).max() <= 1e-10 * np.abs(pu).max() / g.resolution
        # no flux through walls, windows or the border
        assert (pu[:, 1:-1][wall[:, 1:] | wall[:, :-1]] == 0).all()
        assert (pv[1:-1, :][wall[1:, :] | wall[:-1, :]] == 0).all()
        assert (pu[:, [0, -1]] == 0).all() and (pv[[0, -1], :] == 0).all()
        # the dead-end bathroom is not still, and the perturbation is of the requested size (same order)
        assert pert.speed()[bath].mean() > 0.01
        assert 0.3 * 0.2 / 3 < pert.speed()[inner].mean() < 0.3 * 0.2 * 3
    # piecewise constant in time, slowly changing, looping
    assert seq.at_time(0.0) is seq.at_time(9.99) and seq.at_time(10.0) is seq.snapshots[1]
    assert seq.at_time(100.0) is seq.snapshots[0]
    d01 = np.abs(seq.velocities[1] - seq.velocities[0])[inner].mean()
    d09 = np.abs(seq.velocities[9] - seq.velocities[0])[inner].mean()
    assert 0 < d01 < d09
    still = make_wind(g, h.inlet, h.outlet, perturbation=0.0, duration=30.0)
    np.testing.assert_array_equal(still.velocities[2], still.velocities[0])


# ---- CFD CSV -------------------------------------------------------------------------------------------------
def test_gaden_csv_reader(tmp_path):
    g = GridMap(np.zeros((3, 4), bool), 1.0, (0.0, 0.0))
    rng = np.random.default_rng(0)
    rows = []
    for z in (0.2, 0.5, 1.5):
        for r in range(3):
            for c in range(4):
                u = rng.normal(size=3)
                rows.append((u, (c + 0.5 + 0.1, r + 0.5 - 0.1, z)))
    header = '"p","Points:2","U:1","Points:0","U:0","Points:1","U:2"'
    lines = [header] + [f"1.0,{p[2]},{u[1]},{p[0]},{u[0]},{p[1]},{u[2]}" for u, p in rows]
    (tmp_path / "w.csv").write_text("\n".join(lines) + "\n")
    field = read_gaden_wind_csv(tmp_path / "w.csv", like=g, height=0.5, slab=0.2)
    at = {(round(p[0] - 0.6), round(p[1] - 0.4)): u for u, p in rows if p[2] == 0.5}
    for r in range(3):
        for c in range(4):
            np.testing.assert_array_equal(field.velocity[r, c], at[(c, r)][:2])
    with pytest.raises(ValueError, match="face velocities"):
        field.divergence()


def test_gaden_csv_errors(tmp_path):
    g = GridMap(np.zeros((3, 4), bool), 1.0)
    (tmp_path / "a.csv").write_text('"U:0","U:1","Points:0","Points:1","Points:2"\n0,0,0,0,0\n')
    with pytest.raises(ValueError, match=r"a\.csv: missing column\(s\) \['U:2'\]"):
        read_gaden_wind_csv(tmp_path / "a.csv", like=g, height=0.0)
    (tmp_path / "b.csv").write_text('U:0,U:1,U:2,Points:0,Points:1,Points:2\n0,0,0,0,0,0\n1,x,0,0,0,0\n')
    with pytest.raises(ValueError, match=r"b\.csv: line 3, column 'U:1': not a number"):
        read_gaden_wind_csv(tmp_path / "b.csv", like=g, height=0.0)
    (tmp_path / "c.csv").write_text('U:0,U:1,U:2,Points:0,Points:1,Points:2\n0,0,0,0,0,3\n')
    with pytest.raises(ValueError, match=r"c\.csv: no point within .* of height 0"):
        read_gaden_wind_csv(tmp_path / "c.csv", like=g, height=0.0)
    with pytest.raises(FileNotFoundError, match="none.csv"):
        read_gaden_wind_csv(tmp_path / "none.csv", like=g, height=0.0)
