"""Grid map frame conversions and the loaders (ROS maps, room maps, object lists): round trips, the real
house of ../shared, and clear errors for bad files."""

import numpy as np
import pytest
import yaml
from PIL import Image

from psgsl_pgm.sim import (
    GridMap,
    SceneObject,
    box_footprint,
    load_objects,
    load_ros_map,
    load_room_map,
    save_objects,
    save_ros_map,
    save_room_map,
)

from tests.sim.house_b import house_b_folder

SHARED = house_b_folder()


# ---- GridMap -------------------------------------------------------------------------------------------------
def test_world_to_cell_matches_definition_and_inverts_cell_to_world():
    rng = np.random.default_rng(0)
    g = GridMap(rng.random((7, 11)) < 0.3, 0.05, (-1.3, 2.7))
    rc = np.stack(np.meshgrid(np.arange(7), np.arange(11), indexing="ij"), axis=-1)  # (7, 11, 2)
    xy = g.cell_to_world(rc)
    # centre of (r, c) = origin + ((c + 0.5) res, (r + 0.5) res)
    np.testing.assert_allclose(xy[..., 0], -1.3 + (rc[..., 1] + 0.5) * 0.05, rtol=0, atol=1e-12)
    np.testing.assert_allclose(xy[..., 1], 2.7 + (rc[..., 0] + 0.5) * 0.05, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(g.world_to_cell(xy), rc)
    # any point strictly inside a cell maps to it; shapes (..., 2) are preserved
    off = rng.uniform(-0.49, 0.49, size=rc.shape) * 0.05
    np.testing.assert_array_equal(g.world_to_cell(xy + off), rc)
    assert g.world_to_cell([-1.3, 2.7]).tolist() == [0, 0]
    assert g.world_to_cell([-1.31, 2.69]).tolist() == [-1, -1]
    assert not g.contains(g.world_to_cell([-1.31, 2.69]))


def test_gridmap_rejects_bad_input():
    with pytest.raises(ValueError, match="resolution"):
        GridMap(np.zeros((2, 2), bool), 0.0)
    with pytest.raises(TypeError, match="occupancy"):
        GridMap(np.full((2, 2), 0.5), 0.1)
    with pytest.raises(ValueError, match=r"\(\.\.\., 2\)"):
        GridMap(np.zeros((2, 2), bool), 0.1).world_to_cell([1.0, 2.0, 3.0])
    with pytest.raises(TypeError, match="integer"):
        GridMap(np.zeros((2, 2), bool), 0.1).cell_to_world([0.5, 1.0])


def test_coarsen_blocks():
    occ = np.zeros((4, 6), bool)
    occ[0, 0] = True  # 1 of 4 fine cells
    occ[2:4, 2:4] = True  # 4 of 4
    occ[0:2, 4] = True  # 2 of 4
    g = GridMap(occ, 0.01, (1.0, 2.0)).coarsen(2)
    assert g.resolution == 0.02 and g.origin == (1.0, 2.0)
    np.testing.assert_array_equal(g.occupancy, [[False, False, True], [False, True, False]])
    np.testing.assert_array_equal(GridMap(occ, 0.01).coarsen(2, occupied_fraction=0.25).occupancy,
                                  [[True, False, True], [False, True, False]])


# ---- ROS maps ------------------------------------------------------------------------------------------------
def test_ros_map_round_trip(tmp_path):
    rng = np.random.default_rng(1)
    g = GridMap(rng.random((23, 17)) < 0.4, 0.05, (-3.25, 1.5))
    y = save_ros_map(g, tmp_path / "m.yaml")
    back = load_ros_map(y)
    np.testing.assert_array_equal(back.occupancy, g.occupancy)
    assert back.resolution == g.resolution and back.origin == g.origin


def test_ros_map_thresholds_negate_and_row_flip(tmp_path):
    # image row 0 is the top of the map (highest y): it must become grid row H - 1
    grey = np.array([[0, 255, 128, 30], [250, 100, 200, 255]], dtype=np.uint8)
    Image.fromarray(grey).save(tmp_path / "g.pgm")
    meta = {"image": "g.pgm", "resolution": 0.5, "origin": [0.0, 0.0, 0.0], "negate": 0,
            "occupied_thresh": 0.65, "free_thresh": 0.196}
    (tmp_path / "a.yaml").write_text(yaml.safe_dump(meta))
    p = (255 - grey.astype(float)) / 255  # map_server: p = (255 - v) / 255
    occ, free = p > 0.65, p < 0.196
    g = load_ros_map(tmp_path / "a.yaml")
    np.testing.assert_array_equal(g.occupancy, (occ | ~free)[::-1])  # unknown counts as occupied
    g = load_ros_map(tmp_path / "a.yaml", unknown="free")
    np.testing.assert_array_equal(g.occupancy, occ[::-1])
    meta["negate"] = 1
    (tmp_path / "b.yaml").write_text(yaml.safe_dump(meta))
    p = grey.astype(float) / 255
    np.testing.assert_array_equal(load_ros_map(tmp_path / "b.yaml", unknown="free").occupancy, (p > 0.65)[::-1])
    # a point in the top-left pixel (v = 0, occupied) is at the lowest x and the highest y
    g = load_ros_map(tmp_path / "a.yaml")
    rc = g.world_to_cell([0.1, 0.9])
    assert tuple(rc) == (1, 0) and g.occupancy[1, 0]


@pytest.mark.parametrize(
    "change, message",
    [
        ({"image": "missing.pgm"}, r"a\.yaml.*'image'.*does not exist"),
        ({"resolution": "fine"}, r"a\.yaml.*'resolution' must be a number"),
        ({"resolution": -0.1}, r"a\.yaml.*'resolution' must be > 0"),
        ({"origin": [0.0, "x", 0.0]}, r"a\.yaml.*'origin\[1\]' must be a number"),
        ({"origin": [0.0, 0.0, 0.5]}, r"a\.yaml.*'origin'.*rotated"),
        ({"occupied_thresh": 0.1, "free_thresh": 0.5}, r"a\.yaml.*'free_thresh'"),
        ({"negate": 2}, r"a\.yaml.*'negate'"),
        ({"colour": "blue"}, r"a\.yaml.*unknown key.*colour"),
    ],
)
def test_ros_map_bad_files_name_file_and_field(tmp_path, change, message):
    Image.fromarray(np.zeros((3, 3), np.uint8)).save(tmp_path / "g.pgm")
    meta = {"image": "g.pgm", "resolution": 0.1, "origin": [0.0, 0.0, 0.0], "negate": 0,
            "occupied_thresh": 0.65, "free_thresh": 0.196}
    meta.update(change)
    (tmp_path / "a.yaml").write_text(yaml.safe_dump(meta))
    with pytest.raises((ValueError, FileNotFoundError), match=message):
        load_ros_map(tmp_path / "a.yaml")


def test_ros_map_missing_key_and_missing_yaml(tmp_path):
    (tmp_path / "a.yaml").write_text(yaml.safe_dump({"image": "g.pgm", "resolution": 0.1}))
    with pytest.raises(ValueError, match=r"a\.yaml.*missing required key.*origin"):
        load_ros_map(tmp_path / "a.yaml")
    with pytest.raises(FileNotFoundError, match="nope.yaml"):
        load_ros_map(tmp_path / "nope.yaml")


# ---- room maps -----------------------------------------------------------------------------------------------
def _grid(h=6, w=8):
    return GridMap(np.zeros((h, w), bool), 0.1, (0.0, 0.0))


def test_room_masks_round_trip(tmp_path):
    rng = np.random.default_rng(2)
    labels = rng.integers(-1, 3, size=(6, 8))
    names = ["Kitchen", "Living Room", "Bath"]
    save_room_map(labels, names, tmp_path / "rooms.yaml")
    back, back_names = load_room_map(tmp_path / "rooms.yaml", like=_grid())
    assert back_names == names
    np.testing.assert_array_equal(back, labels)


def test_room_segmented_image(tmp_path):
    grey = np.array([[0, 50, 50, 91], [137, 137, 0, 91], [50, 91, 255, 255]], dtype=np.uint8)
    Image.fromarray(grey).save(tmp_path / "seg.pgm")
    (tmp_path / "seg.yaml").write_text(yaml.safe_dump(
        {"image": "seg.pgm", "rooms": {50: "LivingRoom", 91: "Kitchen", 137: "Bathroom", 255: "Kitchen"}}))
    labels, names = load_room_map(tmp_path / "seg.yaml", like=_grid(3, 4))
    assert names == ["LivingRoom", "Kitchen", "Bathroom"]
    lut = {0: -1, 50: 0, 91: 1, 137: 2, 255: 1}
    np.testing.assert_array_equal(labels, np.vectorize(lut.get)(grey)[::-1])


def test_room_map_errors(tmp_path):
    Image.fromarray(np.zeros((5, 5), np.uint8)).save(tmp_path / "small.png")
    (tmp_path / "a.yaml").write_text(yaml.safe_dump({"categories": [{"name": "Kitchen", "mask": "small.png"}]}))
    with pytest.raises(ValueError, match=r"a\.yaml.*'categories\[0\]\.mask'.*5 x 5 pixels.*8 x 6"):
        load_room_map(tmp_path / "a.yaml", like=_grid())
    (tmp_path / "b.yaml").write_text(yaml.safe_dump({"categories": [{"name": "Kitchen", "mask": "none.png"}]}))
    with pytest.raises(FileNotFoundError, match=r"b\.yaml.*'categories\[0\]\.mask'.*none\.png"):
        load_room_map(tmp_path / "b.yaml", like=_grid())
    (tmp_path / "c.yaml").write_text(yaml.safe_dump({"categories": [{"name": "K", "mask": "small.png", "tint": 3}]}))
    with pytest.raises(ValueError, match=r"c\.yaml.*categories\[0\].*unknown key.*tint"):
        load_room_map(tmp_path / "c.yaml", like=_grid())
    full = np.full((6, 8), 255, np.uint8)
    Image.fromarray(full).save(tmp_path / "full.png")
    (tmp_path / "d.yaml").write_text(yaml.safe_dump(
        {"categories": [{"name": "A", "mask": "full.png"}, {"name": "B", "mask": "full.png"}]}))
    with pytest.raises(ValueError, match=r"d\.yaml.*'categories\[1\]\.mask'.*'B' overlaps room 'A'"):
        load_room_map(tmp_path / "d.yaml", like=_grid())
    Image.fromarray(np.full((6, 8), 77, np.uint8)).save(tmp_path / "seg.png")
    (tmp_path / "e.yaml").write_text(yaml.safe_dump({"image": "seg.png", "rooms": {50: "A"}}))
    with pytest.raises(ValueError, match=r"e\.yaml.*'rooms'.*grey levels \[77\]"):
        load_room_map(tmp_path / "e.yaml", like=_grid())
    (tmp_path / "f.yaml").write_text(yaml.safe_dump({"image": "seg.png", "rooms": {"fifty": "A"}}))
    with pytest.raises(ValueError, match=r"f\.yaml.*'rooms\.fifty' must be a number"):
        load_room_map(tmp_path / "f.yaml", like=_grid())
    (tmp_path / "g.yaml").write_text(yaml.safe_dump({"rooms_list": []}))
    with pytest.raises(ValueError, match=r"g\.yaml.*expected either"):
        load_room_map(tmp_path / "g.yaml", like=_grid())


# ---- object lists --------------------------------------------------------------------------------------------
def test_objects_round_trip_and_masks(tmp_path):
    g = GridMap(np.zeros((20, 30), bool), 0.1, (0.0, 0.0))
    (tmp_path / "o.yaml").write_text(yaml.safe_dump({"objects": [
        {"class": "oven", "position": [1.0, 0.5], "size": [0.6, 0.4], "height": [0.0, 0.9]},
        {"class": "couch", "footprint": [[2.0, 1.0], [2.8, 1.0], [2.8, 1.4], [2.0, 1.4]], "name": "sofa"},
        {"class": "tv", "position": [0.25, 1.85, 1.2], "yaw": 0.3},
    ]}))
    objs = load_objects(tmp_path / "o.yaml", like=g, classes=["oven", "couch", "tv", "other"])
    assert [o.class_name for o in objs] == ["oven", "couch", "tv"]
    assert objs[1].name == "sofa" and objs[0].z_range == (0.0, 0.9)
    m = objs[0].mask(g)  # cells with centres in x [0.7, 1.3), y [0.3, 0.7)
    assert m.sum() == 6 * 4 and m[3:7, 7:13].all()
    assert objs[2].mask(g).sum() == 1  # a one-cell box (default size = one cell)
    save_objects(objs, tmp_path / "o2.yaml")
    back = load_objects(tmp_path / "o2.yaml", like=g)
    for a, b in zip(objs, back):
        assert (a.class_name, a.name, a.z_range) == (b.class_name, b.name, b.z_range)
        np.testing.assert_allclose(a.footprint, b.footprint, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(a.mask(g), b.mask(g))


@pytest.mark.parametrize(
    "item, message",
    [
        ({"class": "dragon", "position": [1, 1]}, r"'objects\[0\]\.class': unknown class 'dragon'"),
        ({"class": "oven", "position": [1, "a"]}, r"'objects\[0\]\.position\[1\]' must be a number"),
        ({"class": "oven", "position": [99, 1]}, r"'objects\[0\]'.*outside the map"),
        ({"class": "oven", "position": [1, 1], "colour": 2}, r"objects\[0\].*unknown key.*colour"),
        ({"class": "oven"}, r"'objects\[0\]': needs 'position'"),
        ({"class": "oven", "position": [1, 1], "height": [1, 0.5]}, r"'objects\[0\]\.height'"),
    ],
)
def test_objects_bad_files(tmp_path, item, message):
    g = GridMap(np.zeros((20, 30), bool), 0.1)
    (tmp_path / "o.yaml").write_text(yaml.safe_dump({"objects": [item]}))
    with pytest.raises(ValueError, match=r"o\.yaml.*" + message):
        load_objects(tmp_path / "o.yaml", like=g, classes=["oven", "other"])


def test_box_footprint_rotation():
    fp = box_footprint((1.0, 2.0), (2.0, 1.0), np.pi / 2)
    np.testing.assert_allclose(np.sort(fp[:, 0]), [0.5, 0.5, 1.5, 1.5], atol=1e-12)
    np.testing.assert_allclose(np.sort(fp[:, 1]), [1.0, 1.0, 3.0, 3.0], atol=1e-12)
    with pytest.raises(ValueError, match="z_range"):
        SceneObject("oven", fp, (1.0, 1.0))


# ---- the real house of ../shared -----------------------------------------------------------------------------
needs_shared = pytest.mark.skipif(not SHARED.is_dir(), reason="../shared/data/mapir_house_B is absent")


@pytest.mark.shared_data
@needs_shared
def test_real_house_loads(tmp_path):
    g = load_ros_map(SHARED / "_occupancy.yaml")
    assert g.shape == (1140, 870) and g.resolution == 0.01 and g.origin == (-7.55, -7.88)
    labels, names = load_room_map(SHARED / "room_categories" / "roomMasks.yaml", like=g)
    assert sorted(names) == ["Bathroom", "Bedroom", "Hallway", "Kitchen", "LivingRoom"]
    # the segmented image (grey levels from the README) gives the same room map
    (tmp_path / "seg.yaml").write_text(yaml.safe_dump({
        "image": str(SHARED / "segmented.pgm"),
        "rooms": {50: "LivingRoom", 91: "Kitchen", 137: "Bathroom", 191: "Bedroom", 255: "Hallway"}}))
    seg, seg_names = load_room_map(tmp_path / "seg.yaml", like=g)
    np.testing.assert_array_equal(np.array(names + ["-"])[labels], np.array(seg_names + ["-"])[seg])
    # the lab's scenario files: B1's source is in the kitchen, B2's in the bathroom, the robot starts in the hallway
    def room_at(xy):
        rc = g.world_to_cell(xy)
        return names[labels[rc[0], rc[1]]]

    b1 = yaml.safe_load((SHARED / "simulations" / "B1.yaml").read_text())
    b2 = yaml.safe_load((SHARED / "simulations" / "B2.yaml").read_text())
    start = yaml.safe_load((SHARED / "basicSim" / "B1.yaml").read_text())["robots"][0]["position"]
    assert room_at([b1["source_x"], b1["source_y"]]) == "Kitchen"
    assert room_at([b2["source_x"], b2["source_y"]]) == "Bathroom"
    assert room_at(start[:2]) == "Hallway"
    # rooms lie on free space of the walls-only map (same frame; flipped the other way they would not)
    (tmp_path / "walls.yaml").write_text(yaml.safe_dump({
        "image": str(SHARED / "_occupancy_walls.pgm"), "resolution": 0.01, "origin": [-7.55, -7.88, 0.0],
        "negate": 0, "occupied_thresh": 0.9, "free_thresh": 0.1}))
    walls = load_ros_map(tmp_path / "walls.yaml")
    in_room = labels >= 0
    assert (walls.occupancy & in_room).sum() < 0.01 * in_room.sum()
    assert (walls.occupancy & in_room[::-1]).sum() > 0.1 * in_room.sum()
    assert not g.occupancy[g.world_to_cell(start[:2])[0], g.world_to_cell(start[:2])[1]]


@pytest.mark.shared_data
@needs_shared
def test_real_house_wind_and_gas(tmp_path):
    """The lab's walls map at 0.1 m, its rooms and windows (README): the flow is divergence-free and the gas
    from B1's source stays in free space and leaves by the outlets."""
    from psgsl_pgm.sim import FilamentModel, FilamentParams, House, make_wind, read_gaden_config

    (tmp_path / "walls.yaml").write_text(yaml.safe_dump({
        "image": str(SHARED / "_occupancy_walls.pgm"), "resolution": 0.01, "origin": [-7.55, -7.88, 0.0],
        "negate": 0, "occupied_thresh": 0.9, "free_thresh": 0.1}))
    fine = load_ros_map(tmp_path / "walls.yaml")
    labels, names = load_room_map(SHARED / "room_categories" / "roomMasks.yaml", like=fine)
    grid = fine.coarsen(10)
    house = House.from_maps(
        grid, labels[5::10, 5::10], names,
        inlets=[((-7.15, 3.42), (-5.65, 3.42)), ((-2.65, 3.42), (-1.10, 3.42))],
        outlets=[((-1.70, -7.88), (-0.25, -7.88)), ((-6.45, -7.88), (-4.95, -7.88))],
    )
    wind = make_wind(house.grid, house.inlet, house.outlet, mean_speed=0.2, duration=100.0, seed=0)
    inner = house.grid.free & ~house.inlet & ~house.outlet
    for snap in wind.snapshots[:3]:
        div = snap.divergence()[inner]
        assert np.abs(div).max() <= 1e-10 * np.abs(snap.u_faces).max() / grid.resolution
    params, src = read_gaden_config(SHARED / "simulations" / "B1.yaml")
    assert params == FilamentParams(dt=0.1, release_rate=10, ppm_center=10, sigma0=0.1, gamma=15e-4, noise_std=0.02)
    gas = FilamentModel(house.grid, wind, src[:2], params=params, outlet=house.outlet, seed=0)
    for _ in range(10):
        gas.run(10.0)
        rc = house.grid.world_to_cell(gas.positions)
        assert not house.grid.occupancy[rc[:, 0], rc[:, 1]].any()
    assert gas.n_released == 1000 and gas.n_filaments + gas.n_removed == 1000
    assert names[house.room_labels[tuple(house.grid.world_to_cell(src[:2]))]] == "Kitchen"
