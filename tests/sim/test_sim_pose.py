"""The robot's localisation error: the Ornstein-Uhlenbeck offset against its theory, seeding, a world without
error bit for bit today's, and a world with error that senses at the true pose and reports in the believed one."""

import numpy as np
import pytest

from psgsl_pgm.sim import Anemometer, GasSensor, LocalisationError, make_world


def _acf(x, lag):
    x = x - x.mean()
    return float(np.dot(x[:-lag], x[lag:]) / np.dot(x, x))


def test_offset_has_the_stationary_std_and_the_autocorrelation_of_the_theory():
    """AR(1) with a = exp(-dt/τ): std σ, corr at lag m a^m. Tolerances are 4 standard errors from the theory of
    an AR(1) sample: var(s²)/σ⁴ ≈ 2/n (1 + a²)/(1 − a²), and Bartlett's var(r_m) ≈ [(1 + a²)(1 − a^{2m})/(1 − a²)
    − 2m a^{2m}] / n."""
    err = LocalisationError(sigma=0.1, heading_sigma=0.05, tau=10.0)
    dt, n = 1.0, 200_000
    e = err.sample(n, dt, rng=np.random.default_rng(11))
    assert e.shape == (n, 3)
    a = np.exp(-dt / err.tau)
    rel_var = np.sqrt(2.0 / n * (1 + a * a) / (1 - a * a))  # relative standard error of s²
    for j, sd in enumerate((0.1, 0.1, 0.05)):
        x = e[:, j]
        assert abs(x.mean()) < 4 * sd * np.sqrt((1 + a) / (1 - a) / n)
        assert abs(x.var() / sd**2 - 1) < 4 * rel_var
        for m in (1, 10, 30):  # 10 = one correlation time: exp(-1)
            se = np.sqrt(((1 + a * a) * (1 - a ** (2 * m)) / (1 - a * a) - 2 * m * a ** (2 * m)) / n)
            assert abs(_acf(x, m) - a**m) < 4 * se, (j, m, _acf(x, m), a**m, se)
    # the axes are independent
    assert abs(np.corrcoef(e[:, 0], e[:, 1])[0, 1]) < 4 * np.sqrt((1 + a * a) / (1 - a * a) / n)


def test_offset_steps_draw_in_order_and_zero_std_is_zero():
    err = LocalisationError(sigma=0.2, heading_sigma=0.03, tau=5.0)
    s = np.array([0.1, -0.2, 0.01])
    whole = err.advance(s, 30, 0.1, rng=np.random.default_rng(4))
    rng = np.random.default_rng(4)
    first = err.advance(s, 12, 0.1, rng=rng)
    parts = np.concatenate([first, err.advance(first[-1], 18, 0.1, rng=rng)])
    np.testing.assert_allclose(parts, whole, rtol=0, atol=1e-15)
    # one step by hand: e_1 = a e_0 + sqrt(1 - a²) σ n
    n0 = np.random.default_rng(4).standard_normal(3)
    a = np.exp(-0.1 / 5.0)
    np.testing.assert_allclose(whole[0], a * s + np.sqrt(1 - a * a) * err.std * n0, rtol=1e-12)
    assert not LocalisationError(sigma=0.0, heading_sigma=0.0).sample(50, 0.1, rng=np.random.default_rng(0)).any()
    assert err.advance(s, 0, 0.1, rng=rng).shape == (0, 3)


def test_bad_inputs_name_what_was_expected():
    with pytest.raises(ValueError, match="sigma must be a non-negative finite number in metres"):
        LocalisationError(sigma=-0.1)
    with pytest.raises(TypeError, match="sigma must be a non-negative number"):
        LocalisationError(sigma="0.1")
    with pytest.raises(ValueError, match="tau must be a positive finite number in seconds"):
        LocalisationError(tau=0.0)
    with pytest.raises(ValueError, match="heading_sigma must be below π/4"):
        LocalisationError(heading_sigma=1.0)
    with pytest.raises(ValueError, match="heading_sigma must be a non-negative finite number in radians"):
        LocalisationError(heading_sigma=float("nan"))
    err = LocalisationError()
    with pytest.raises(ValueError, match="dt must be a positive"):
        err.advance(np.zeros(3), 3, 0.0, rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="state must be a finite"):
        err.advance(np.zeros(2), 3, 0.1, rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="n must be an int >= 1"):
        err.sample(0, 0.1, rng=np.random.default_rng(0))
    with pytest.raises(TypeError, match="localisation must be a LocalisationError or None, got dict"):
        make_world(seed=0, warm_up=0.0, localisation={"sigma": 0.1})
    w = make_world(seed=0, warm_up=0.0, localisation=err)
    with pytest.raises(ValueError, match=r"points must be finite positions of shape \(\.\.\., 2\)"):
        w.true_positions([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="times must be finite"):
        w.true_positions([1.0, 2.0], times=float("inf"))
    with pytest.raises(ValueError, match=r"pose must be a finite \(x, y, heading\)"):
        w.camera_frame((1.0, 2.0))


def _episode(w):
    """A few readings and frames of a world, everything they return."""
    out = []
    for p in ((3.0, 6.0), (7.0, 1.5), (5.0, 4.0)):
        r = w.sense_gas(p)
        out += [r.value, r.state, w.sense_wind(p)]
        f = w.camera_frame((p[0], p[1], 0.7))
        out += [f.pose, f.cells, f.distance, f.labels, f.likelihood]
        w.advance(2.0)
    return out + [w.gas.positions.copy(), w.time]


def _same(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        x, y = np.asarray(x), np.asarray(y)
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()


def test_no_error_and_zero_error_are_todays_world_bit_for_bit():
    base = _episode(make_world(seed=5, warm_up=10.0))
    _same(base, _episode(make_world(seed=5, warm_up=10.0, localisation=None)))
    _same(base, _episode(make_world(seed=5, warm_up=10.0,
                                    localisation=LocalisationError(sigma=0.0, heading_sigma=0.0))))
    w = make_world(seed=5, warm_up=0.0)
    p = np.array([[1.0, 2.0], [3.5, 4.25]])
    np.testing.assert_array_equal(w.true_positions(p), p)


def test_offset_is_seeded_and_independent_of_when_it_is_asked():
    err = LocalisationError(sigma=0.2, heading_sigma=0.04, tau=20.0)
    a = make_world(seed=7, warm_up=0.0, localisation=err)
    b = make_world(seed=7, warm_up=0.0, localisation=err)
    c = make_world(seed=8, warm_up=0.0, localisation=err)
    p = (3.0, 6.0)
    for t in (10.0, 50.0, 400.0):  # a asks at three times, b only at the last
        ta = a.true_positions(p, times=t)
    tb = b.true_positions(p, times=400.0)
    np.testing.assert_array_equal(ta, tb)
    assert not np.array_equal(ta, c.true_positions(p, times=400.0))
    assert np.linalg.norm(ta - p) > 0
    # the offset drifts: close over a tenth of τ, unrelated over 10 τ
    e = np.array([p]) - a.true_positions(np.tile(p, (3, 1)), times=[100.0, 102.0, 300.0])
    assert np.linalg.norm(e[0] - e[1]) < np.linalg.norm(e[0] - e[2])
    # the other streams draw as without the error: the same filaments after the same calls
    plain = make_world(seed=7, warm_up=0.0)
    for w in (a, plain):
        w.sense_gas(p), w.sense_wind(p), w.camera_frame((*p, 0.0))
    np.testing.assert_array_equal(a.gas.positions, plain.gas.positions)


def _pair(err, seed=2, **kw):
    """(world with ``err``, the same world without): the gas, wind and detector streams are the same."""
    return (make_world(seed=seed, warm_up=30.0, localisation=err, **kw),
            make_world(seed=seed, warm_up=30.0, **kw))


def test_sensing_happens_at_the_true_pose():
    ideal = dict(gas_sensor=GasSensor(window=0.1), anemometer=Anemometer(noise_std=0.0))
    err = LocalisationError(sigma=0.3, heading_sigma=0.2, tau=1e4)
    w, plain = _pair(err, **ideal)
    other = make_world(seed=2, warm_up=30.0, **ideal)
    p = w.source + np.array([0.6, 0.3])  # downwind of the oven, where the plume's edge is steep
    true = w.true_positions(p)
    e = w._offset_at(w.time)  # the test may read the truth
    np.testing.assert_allclose(true, p - e[:2], rtol=0, atol=1e-12)
    g = w.sense_gas(p)
    assert g.value == plain.sense_gas(true).value  # one window, one sample, at the true position
    assert g.value != other.sense_gas(p).value  # ... not at the believed one
    e = w._offset_at(w.time)  # one sensor window later: the offset has moved on
    u = plain.wind_now().at(p - e[:2])
    c, s = np.cos(e[2]), np.sin(e[2])
    np.testing.assert_allclose(w.sense_wind(p), [c * u[0] - s * u[1], s * u[0] + c * u[1]], rtol=1e-12)


def test_a_frame_is_seen_from_the_true_pose_and_placed_from_the_believed_one():
    err = LocalisationError(sigma=0.3, heading_sigma=0.0, tau=1e4)
    w, plain = _pair(err)
    pose = np.array([3.0, 6.0, 0.3])
    e = w._offset_at(w.time)
    assert np.linalg.norm(e[:2]) > 0.1  # a displacement of a cell or more
    f = w.camera_frame(pose)
    truth = plain.camera_frame((*(pose[:2] - e[:2]), pose[2]))
    np.testing.assert_array_equal(f.pose, pose)  # the pose the robot believes
    g = w.house.grid
    inside = g.contains(g.world_to_cell(g.cell_to_world(truth.cells) + e[:2]))
    assert inside.sum() == len(f.cells) > 100
    np.testing.assert_array_equal(f.labels, truth.labels[inside])  # the same detections ...
    np.testing.assert_array_equal(f.distance, truth.distance[inside])
    shift = g.cell_to_world(f.cells) - g.cell_to_world(truth.cells[inside])  # ... shifted by the offset
    assert (np.abs(shift - e[:2]) <= g.resolution / 2 + 1e-9).all()
    # with a heading error the cells turn about the robot: each keeps the range and the bearing relative to
    # the heading that the robot measured from its true pose (to the snapping of a cell centre)
    w2, plain2 = _pair(LocalisationError(sigma=0.2, heading_sigma=0.15, tau=1e4), seed=3)
    e2 = w2._offset_at(w2.time)
    assert abs(e2[2]) > 0.02
    f2 = w2.camera_frame(pose)
    t2 = plain2.camera_frame((*(pose[:2] - e2[:2]), pose[2] - e2[2]))
    assert len(f2.cells) > 100 and np.isin(f2.distance, t2.distance).all()
    rel = g.cell_to_world(f2.cells) - pose[:2]
    d = np.linalg.norm(rel, axis=-1)
    assert (np.abs(d - f2.distance) <= g.resolution / np.sqrt(2) + 1e-9).all()
    bearing = np.angle(np.exp(1j * (np.arctan2(rel[:, 1], rel[:, 0]) - pose[2])))
    far = f2.distance > 1.0
    q = np.array([(t2.distance == x).argmax() for x in f2.distance[far]])  # distances are distinct enough
    rel_t = g.cell_to_world(t2.cells[q]) - (pose[:2] - e2[:2])
    measured = np.angle(np.exp(1j * (np.arctan2(rel_t[:, 1], rel_t[:, 0]) - (pose[2] - e2[2]))))
    gap = np.abs(np.angle(np.exp(1j * (bearing[far] - measured))))
    assert np.median(gap) < 0.02 < abs(e2[2])  # the placement turned with the heading error


def test_a_true_position_never_lies_in_a_wall():
    w = make_world(seed=1, warm_up=0.0, localisation=LocalisationError(sigma=0.5, heading_sigma=0.0, tau=5.0))
    g = w.house.grid
    walls = g.occupancy
    # believed positions beside a wall: every free cell with a wall cell two cells away
    near = np.argwhere(~walls[2:-2, 2:-2] & walls[:-4, 2:-2]) + 2
    pts = g.cell_to_world(near[:200])
    times = np.linspace(0.0, 300.0, 40)
    true = w.true_positions(np.broadcast_to(pts[None], (40,) + pts.shape), times=times[:, None])
    rc = g.world_to_cell(true)
    assert g.contains(rc).all() and not walls[rc[..., 0], rc[..., 1]].any()
    # nor behind one: the straight way from the believed position crosses no wall
    f = np.linspace(0.0, 1.0, 41)[:, None, None, None]
    way = g.world_to_cell(pts[None, None] + f * (true[None] - pts[None, None]))
    assert not walls[way[..., 0], way[..., 1]].any()
    e = w._offset_at(times)[:, None, :2]
    moved = np.linalg.norm(true - (pts[None] - e), axis=-1) > 1e-12
    assert 0 < moved.mean() < 1  # pulled back where the offset crosses a wall, else believed − offset
    # a pulled-back point lies on the segment between the believed and the offset point
    along = true - pts[None]
    cross = along[..., 0] * -e[..., 1] - along[..., 1] * -e[..., 0]
    assert np.abs(cross[moved]).max() < 1e-9


def test_the_pose_component_of_a_world_model_and_a_realistic_camera():
    """``model="ideal+pose"`` gives the world the default error; with the occluding camera and the realistic
    detector as well, a frame placed from the believed pose keeps one bearing and one distance per cell."""
    from psgsl_pgm.sim import default_world

    w = default_world().make_world(4, "oven", warm_up=5.0, model="ideal+pose")
    assert w.localisation == LocalisationError()
    assert default_world().make_world(4, "oven", warm_up=5.0).localisation is None
    w = default_world().make_world(4, "oven", warm_up=5.0, model="ideal+camera+pose")
    f = w.camera_frame((3.0, 6.0, 0.3))
    assert f.bearing is not None and len(f.cells) > 50
    assert len(f.bearing) == len(f.distance) == len(f.labels) == len(f.likelihood) == len(f.cells)
    np.testing.assert_array_equal(f.pose, (3.0, 6.0, 0.3))
