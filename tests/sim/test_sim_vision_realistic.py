"""The opt-in camera realism: furniture occlusion by height, detection falling with range and bearing, errors that
persist per object instance, recurring false-positive sites — and the defaults unchanged."""

import numpy as np
import pytest

from psgsl_pgm.geometry._grid import GridMap
from psgsl_pgm.geometry._sight import rays_clear_above
from psgsl_pgm.sim import (
    HOUSE_CLASSES,
    OTHER,
    Camera,
    DetectorErrors,
    DetectorModel,
    Frame,
    House,
    SceneObject,
    box_footprint,
    default_house,
    make_world,
    take_frame,
)

ROW, COL = 10, 5  # the camera's cell in the corridor: pose (0.55, 1.05), looking along +x
POSE = (0.55, 1.05, 0.0)


def _corridor(objects=(), *, wall_col=None, shape=(21, 60)):
    """A 6 m x 2.1 m corridor (0.1 m cells) with walls around it (and across it at ``wall_col``)."""
    occ = np.zeros(shape, bool)
    occ[0] = occ[-1] = True
    occ[:, 0] = occ[:, -1] = True
    if wall_col is not None:
        occ[:, wall_col] = True
    none = np.zeros(shape, bool)
    return House(GridMap(occ, 0.1), np.where(occ, -1, 0), ("Kitchen",), tuple(objects), none, none.copy())


def _box(cls, x, size, z):
    return SceneObject(cls, box_footprint((x, 1.05), size), z)


def _reference_row(house, eye):
    """Visibility of the cells of the camera's row by the stated rule, computed independently of the kernel: a
    cell c is hidden when a cell cb between holds the ray's height y = eye + (z_t − eye) t at t = (cb − c0) /
    (c − c0) within [z_low, z_high), z_t the top of c's objects (0 for floor)."""
    w = house.shape[1]
    lo = np.full(w, np.inf)
    hi = np.full(w, -np.inf)
    for o, m in zip(house.objects, house.object_masks):
        lo[m[ROW]] = np.minimum(lo[m[ROW]], o.z_range[0])
        hi[m[ROW]] = np.maximum(hi[m[ROW]], o.z_range[1])
    seen = np.zeros(w, bool)
    for c in range(COL + 1, w - 1):
        zt = hi[c] if np.isfinite(hi[c]) else 0.0
        t = (np.arange(COL + 1, c) - COL) / (c - COL)
        y = eye + (zt - eye) * t
        seen[c] = not np.any((lo[COL + 1:c] <= y) & (y < hi[COL + 1:c]))
    return seen


# ---- occlusion -----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("eye", [1.0, 0.3, 2.2])
@pytest.mark.parametrize("blocker", [(0.0, 1.8), (0.0, 0.5), (0.6, 1.4)])
def test_furniture_occlusion_follows_the_stated_rule_on_the_axis(eye, blocker):
    house = _corridor([_box("refrigerator", 2.05, (0.3, 0.5), blocker), _box("oven", 3.55, (0.3, 0.3), (0.0, 0.9))])
    cam = Camera(max_range=9.0, occlusion="furniture", height=eye)
    seen = cam.visible(house.grid, POSE, house=house)[ROW]
    ref = _reference_row(house, eye)
    beyond = slice(COL + 3, -1)  # past the 0.2 m minimum range
    np.testing.assert_array_equal(seen[beyond], ref[beyond])
    assert Camera(max_range=9.0).visible(house.grid, POSE)[ROW, beyond].all()  # walls only: all of the row
    assert not ref[beyond].all()  # every case hides something


def test_an_object_behind_a_taller_one_is_hidden_behind_a_lower_one_seen():
    oven = _box("oven", 3.55, (0.3, 0.3), (0.0, 0.9))
    cam = Camera(max_range=9.0, occlusion="furniture")  # eye at 1.0 m
    for top, hidden in ((1.8, True), (0.5, False)):
        house = _corridor([_box("refrigerator", 2.05, (0.3, 0.5), (0.0, top)), oven])
        seen = cam.visible(house.grid, POSE, house=house)
        oven_cells = house.object_masks[1]
        assert seen[oven_cells].any() != hidden, top
        assert Camera(max_range=9.0).visible(house.grid, POSE)[oven_cells].all()
    # the floor right behind a 0.5 m box is below the ray's reach (y = 1 − t < 0.5 for t > 0.5), far floor is seen
    house = _corridor([_box("refrigerator", 2.05, (0.3, 0.5), (0.0, 0.5))])
    seen = cam.visible(house.grid, POSE, house=house)[ROW]
    assert not seen[22:36].any() and seen[40:59].all()


def test_a_wall_still_hides_everything():
    house = _corridor([_box("refrigerator", 2.05, (0.3, 0.5), (0.0, 0.4))], wall_col=30)
    for eye in (0.5, 1.0, 3.0):
        seen = Camera(max_range=9.0, half_angle=np.pi, occlusion="furniture", height=eye).visible(
            house.grid, POSE, house=house)
        assert not seen[:, 30:].any() and seen[:, 6:19].any()
    h = default_house(0)
    rng = np.random.default_rng(0)
    free = np.argwhere(~h.robot_obstacles)
    for rc in free[rng.choice(len(free), 8, replace=False)]:
        pose = (*h.grid.cell_to_world(rc), rng.uniform(-np.pi, np.pi))
        both = Camera(occlusion="furniture").visible(h.grid, pose, house=h)
        assert not (both & ~Camera().visible(h.grid, pose)).any()  # a subset of the walls-only view


def test_rays_clear_above_marks_walls_and_empty_cells():
    lo = np.full((1, 6), np.inf)
    hi = np.full((1, 6), -np.inf)
    assert rays_clear_above(lo, hi, (0, 0), [[0, 5]], eye=1.0, tops=[0.0]).all()
    lo[0, 3], hi[0, 3] = -np.inf, np.inf  # a wall
    assert not rays_clear_above(lo, hi, (0, 0), [[0, 5]], eye=50.0, tops=[50.0]).any()
    assert rays_clear_above(lo, hi, (0, 0), [[0, 3], [0, 2]], eye=1.0, tops=[0.0, 0.0]).all()  # end cells untested
    with pytest.raises(ValueError, match="one shape"):
        rays_clear_above(lo, hi[:, :3], (0, 0), [[0, 1]], eye=1.0, tops=[0.0])
    with pytest.raises(ValueError, match="one height per target"):
        rays_clear_above(lo, hi, (0, 0), [[0, 1]], eye=1.0, tops=[0.0, 1.0])
    with pytest.raises(ValueError, match="inside"):
        rays_clear_above(lo, hi, (0, 0), [[0, 6]], eye=1.0, tops=[0.0])
    with pytest.raises(ValueError, match="NaN"):
        rays_clear_above(lo * np.nan, hi, (0, 0), [[0, 1]], eye=1.0, tops=[0.0])
    with pytest.raises(ValueError, match="finite"):
        rays_clear_above(lo, hi, (0, 0), [[0, 1]], eye=np.nan, tops=[0.0])


# ---- detection probability -----------------------------------------------------------------------------------
def test_detection_rate_follows_the_logistic_range_and_cos4_bearing_curves():
    """Detections among n draws per (d, β) against p_d = 0.9 / (1 + exp((d − 4) / 0.8)) · cos⁴β: within 4 binomial
    standard deviations (each of the 12 cells fails by chance with probability 6e-5)."""
    det = DetectorModel.realistic()
    rng = np.random.default_rng(0)
    oven = HOUSE_CLASSES.index("oven")
    n = 20_000
    for d in (0.5, 2.0, 3.5, 4.0, 5.0, 6.5):
        for beta in (0.0, np.deg2rad(30)):
            p = 0.9 / (1 + np.exp((d - 4.0) / 0.8)) * np.cos(beta) ** 4
            labels = det.sample(np.full(n, oven), np.full(n, d), rng, bearing=np.full(n, beta))
            rate = np.mean(labels != det.nothing)
            assert abs(rate - p) <= 4 * np.sqrt(p * (1 - p) / n), (d, beta, rate, p)
    # the likelihood is the same curve: p(nothing | oven, d, β) = 1 − p_d
    lik = det.likelihood(np.array([det.nothing]), np.array([4.0]), np.array([0.3]))
    assert lik[0, oven] == pytest.approx(1 - 0.45 * np.cos(0.3) ** 4, rel=1e-12)


def test_frames_carry_the_bearing_off_the_optical_axis():
    house = _corridor([_box("oven", 3.55, (0.3, 0.3), (0.0, 0.9))])
    det = DetectorModel.realistic(persistence=0.0, distractors=0)
    f = take_frame(house, (0.55, 1.05, 0.2), camera=Camera(max_range=9.0), detector=det,
                   rng=np.random.default_rng(0))
    xy = house.grid.cell_to_world(f.cells)
    expect = np.arctan2(xy[:, 1] - 1.05, xy[:, 0] - 0.55) - 0.2
    np.testing.assert_allclose(f.bearing, expect, atol=1e-12)
    assert np.abs(f.bearing).max() <= Camera().half_angle + 1e-9
    np.testing.assert_allclose(f.likelihood, det.likelihood(f.labels, f.distance, f.bearing), rtol=0)


# ---- persistent instance errors ------------------------------------------------------------------------------
def test_a_mislabelled_instance_stays_mislabelled_at_the_stated_rate():
    """An oven whose persistent label is "microwave": in each frame, all its detections read "microwave" with
    probability ρ + (1 − ρ) C^n (n its detected cells); over 600 frames the count is within 4 binomial standard
    deviations of the sum, and frames with fresh labels read "oven" at C[oven, oven] per detection."""
    house = _corridor([_box("oven", 2.05, (0.3, 0.5), (0.0, 0.9))])
    det = DetectorModel.realistic(persistence=0.6, distractors=0)
    micro = det.labels.index("microwave")
    oven = HOUSE_CLASSES.index("oven")
    errors = DetectorErrors(np.array([micro]), np.full(house.shape, -1))
    cam = Camera(max_range=9.0)
    rng = np.random.default_rng(1)
    c_m = det.confusion[oven, micro]
    all_m, expect, fresh_oven, fresh_n = 0, [], 0, 0
    for _ in range(600):
        f = take_frame(house, POSE, camera=cam, detector=det, rng=rng, errors=errors)
        on = house.object_masks[0][f.cells[:, 0], f.cells[:, 1]]
        lab = f.labels[on & (f.labels != det.nothing)]
        if lab.size == 0:
            continue
        expect.append(0.6 + 0.4 * c_m ** lab.size)
        if (lab == micro).all():
            all_m += 1
        else:
            fresh_oven += int((lab == det.labels.index("oven")).sum())
            fresh_n += lab.size
    p = np.array(expect)
    assert abs(all_m - p.sum()) <= 4 * np.sqrt((p * (1 - p)).sum())
    assert len(p) > 500
    # frames with fresh labels: the confusion row, cell by cell (conditioning on "not all microwave" shifts it by
    # less than C^n ≈ 1e-4 here)
    q = det.confusion[oven, det.labels.index("oven")]
    assert abs(fresh_oven / fresh_n - q) <= 4 * np.sqrt(q * (1 - q) / fresh_n)  # fresh labels: independent cells


def test_instance_labels_are_drawn_from_the_confusion_row():
    """Over 3000 worlds' draws, the persistent label of an oven is distributed as C[oven, ·] (5 standard
    errors), so the label distribution over worlds and frames is the confusion row."""
    house = _corridor([_box("oven", 2.05, (0.3, 0.5), (0.0, 0.9))])
    det = DetectorModel.realistic(distractors=0)
    rng = np.random.default_rng(2)
    n = 3000
    drawn = np.array([DetectorErrors.draw(det, house, rng).instance_label[0] for _ in range(n)])
    freq = np.bincount(drawn, minlength=len(det.labels) - 1)[: len(det.labels) - 1] / n
    row = det.confusion[HOUSE_CLASSES.index("oven")]
    assert np.all(np.abs(freq - row) <= 5 * np.sqrt(row * (1 - row) / n) + 1e-12)


# ---- recurring false positives -------------------------------------------------------------------------------
def test_distractor_sites_recur_where_they_are():
    """With no per-cell false positives, the only object labels on an empty corridor are the sites': each site
    cell in view reads its label with probability p_d(d, β) (4 binomial standard deviations over 300 frames), and
    no other cell ever reads anything."""
    house = _corridor()
    det = DetectorModel.realistic(false_positive=0.0, distractors=4, distractor_radius=0.2)
    world_errors = DetectorErrors.draw(det, house, np.random.default_rng(5))
    sites = world_errors.site_map
    assert (sites >= 0).sum() >= 13  # 4 discs of 0.2 m radius: 13 cells each, fewer where they overlap a wall
    cam = Camera(max_range=9.0, half_angle=np.pi)
    rng = np.random.default_rng(3)
    hits = np.zeros(house.shape)
    n = 300
    for _ in range(n):
        f = take_frame(house, (3.05, 1.05, 0.0), camera=cam, detector=det, rng=rng, errors=world_errors)
        shown = f.labels != det.nothing
        assert (f.labels[shown] == sites[f.cells[shown, 0], f.cells[shown, 1]]).all()
        np.add.at(hits, (f.cells[shown, 0], f.cells[shown, 1]), 1)
    f = take_frame(house, (3.05, 1.05, 0.0), camera=cam, detector=det, rng=rng, errors=world_errors)
    on = sites[f.cells[:, 0], f.cells[:, 1]] >= 0
    p = det.detection_probability(f.distance[on], f.bearing[on])
    rate = hits[f.cells[on, 0], f.cells[on, 1]] / n
    assert np.all(np.abs(rate - p) <= 4 * np.sqrt(p * (1 - p) / n) + 1e-12)
    assert (hits[sites < 0] == 0).all()


def test_world_draws_its_errors_from_its_seed():
    det = DetectorModel.realistic()
    cam = Camera(occlusion="furniture")
    a = make_world(seed=3, warm_up=0.0, camera=cam, detector=det)
    b = make_world(seed=3, warm_up=0.0, camera=cam, detector=det)
    c = make_world(seed=4, warm_up=0.0, camera=cam, detector=det)
    np.testing.assert_array_equal(a.detector_errors.instance_label, b.detector_errors.instance_label)
    np.testing.assert_array_equal(a.detector_errors.site_map, b.detector_errors.site_map)
    assert not np.array_equal(a.detector_errors.site_map, c.detector_errors.site_map)
    pose = (7.0, 2.0, 0.3)
    for _ in range(3):
        fa, fb = a.camera_frame(pose), b.camera_frame(pose)
        np.testing.assert_array_equal(fa.labels, fb.labels)
        np.testing.assert_array_equal(fa.cells, fb.cells)
    # the errors stream is a fourth child of the seed: gas, anemometer and camera streams are those of the default
    d = make_world(seed=3, warm_up=0.0)
    assert d.detector_errors is None
    e = make_world(seed=3, warm_up=0.0, detector=det)
    assert e._rng_camera.bit_generator.state == d._rng_camera.bit_generator.state
    assert e._rng_gas_sensor.bit_generator.state == d._rng_gas_sensor.bit_generator.state


# ---- defaults unchanged --------------------------------------------------------------------------------------
def test_defaults_are_todays_frames():
    """Camera() and DetectorModel.default: no bearing, no world errors, and a realistic-capable detector with every
    option off gives the same labels and likelihoods bit for bit."""
    house = default_house(0)
    assert Camera().occlusion == "walls"
    plain = DetectorModel.default(house.classes)
    off = DetectorModel(plain.classes, plain.confusion, half_range=None, angle_power=0.0, persistence=0.0,
                        distractors=0)
    assert not plain.correlated and plain.half_range is None and plain.angle_power == 0
    pose = (7.6, 3.5, -np.pi / 2)
    f1 = take_frame(house, pose, camera=Camera(), detector=plain, rng=np.random.default_rng(9))
    f2 = take_frame(house, pose, camera=Camera(), detector=off, rng=np.random.default_rng(9))
    assert f1.bearing is None
    for name in ("cells", "distance", "labels", "likelihood"):
        np.testing.assert_array_equal(getattr(f1, name), getattr(f2, name))
    assert make_world(seed=0, warm_up=0.0).detector_errors is None
    legacy = Frame(f1.pose, f1.cells, None, f1.distance, f1.labels, f1.likelihood, f1.classes)  # 7 fields still
    assert legacy.bearing is None


# ---- bad inputs ----------------------------------------------------------------------------------------------
def test_bad_inputs_name_what_was_expected():
    house = _corridor([_box("oven", 2.05, (0.3, 0.5), (0.0, 0.9))])
    with pytest.raises(ValueError, match="occlusion must be one of"):
        Camera(occlusion="floor")
    with pytest.raises(TypeError, match="needs the house"):
        Camera(occlusion="furniture").visible(house.grid, POSE)
    with pytest.raises(ValueError, match="whose grid"):
        Camera(occlusion="furniture").visible(_corridor().grid, POSE, house=house)
    for kw, match in (({"persistence": 1.5}, "persistence"), ({"distractors": -1}, "distractors"),
                      ({"distractors": 2.5}, "distractors"), ({"half_range": 0.0}, "half_range"),
                      ({"range_width": 0.0}, "range_width"), ({"angle_power": -1.0}, "angle_power"),
                      ({"distractor_radius": np.inf}, "distractor_radius")):
        with pytest.raises(ValueError, match=match):
            DetectorModel.realistic(**kw)
    det = DetectorModel.realistic()
    with pytest.raises(ValueError, match="needs the world's errors"):
        take_frame(house, POSE, camera=Camera(), detector=det, rng=np.random.default_rng(0))
    other = DetectorErrors.draw(det, default_house(0), np.random.default_rng(0))
    with pytest.raises(ValueError, match="objects"):
        take_frame(house, POSE, camera=Camera(), detector=det, rng=np.random.default_rng(0), errors=other)
    with pytest.raises(TypeError, match="DetectorErrors"):
        take_frame(house, POSE, camera=Camera(), detector=det, rng=np.random.default_rng(0), errors="none")
    with pytest.raises(ValueError, match="bearing must have the shape"):
        det.detection_probability([1.0, 2.0], bearing=[0.0])
    with pytest.raises(TypeError, match="House"):
        DetectorErrors.draw(det, house.grid, np.random.default_rng(0))
    assert OTHER in det.classes


def test_voxel_frames_with_persistent_errors():
    """In a voxel frame an instance's persistent label applies to the voxels of its height range only."""
    house = _corridor([_box("microwave", 2.05, (0.3, 0.5), (0.9, 1.2))])
    det = DetectorModel.realistic(persistence=1.0, distractors=0, false_positive=0.0)
    tv = det.labels.index("tv")
    errors = DetectorErrors(np.array([tv]), np.full(house.shape, -1))
    edges = np.array([0.0, 0.5, 1.0, 1.5])
    f = take_frame(house, POSE, camera=Camera(max_range=9.0, vertical_half_angle=np.deg2rad(60)), detector=det,
                   rng=np.random.default_rng(0), errors=errors, layer_edges=edges)
    on = house.object_masks[0][f.cells[:, 0], f.cells[:, 1]]
    shown = f.labels != det.nothing
    assert (f.labels[shown] == tv).all() and shown.any()  # ρ = 1: every detection reads the persistent label
    assert set(f.layers[shown].tolist()) <= {1, 2} and (on[shown]).all()  # the microwave spans layers 1 and 2
