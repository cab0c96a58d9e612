"""Line of sight, the filament model (physics sanity and the concentration formula against a direct sum) and the
gas sensor / anemometer."""

import numpy as np
import pytest
import yaml

from psgsl_pgm.sim import (
    Anemometer,
    FilamentModel,
    FilamentParams,
    GasSensor,
    GridMap,
    LineOfSightCache,
    WindField,
    cells_clear,
    read_gaden_config,
)

from ..core.brute_force import touches


# ---- line of sight -------------------------------------------------------------------------------------------
def test_cells_clear_matches_exact_geometry():
    rng = np.random.default_rng(0)
    for trial in range(4):
        occ = rng.random((9, 11)) < 0.15
        a = rng.integers(0, [9, 11], size=(150, 2))
        b = rng.integers(0, [9, 11], size=(150, 2))
        b[:20] = a[:20] + rng.integers(-3, 4, size=(20, 1)) * np.array([1, 1])  # many exact diagonals
        b = np.clip(b, 0, [8, 10])
        got = cells_clear(occ, a, b)
        for i in range(len(a)):
            rs = range(min(a[i, 0], b[i, 0]), max(a[i, 0], b[i, 0]) + 1)
            cs = range(min(a[i, 1], b[i, 1]), max(a[i, 1], b[i, 1]) + 1)
            blocked = any(occ[r, c] and touches(a[i], b[i], r, c) for r in rs for c in cs)
            assert got[i] == (not blocked), (trial, a[i], b[i])


def test_line_of_sight_cache_agrees_and_no_diagonal_leak():
    occ = np.zeros((6, 6), bool)
    occ[[0, 1, 2, 3, 4, 5], [5, 4, 3, 2, 1, 0]] = True  # a wall of cells touching only at corners
    cache = LineOfSightCache(occ, capacity=2)
    targets = np.argwhere(~occ)
    for origin in ([0, 0], [5, 5], [0, 0]):
        np.testing.assert_array_equal(cache.clear_from(origin, targets),
                                      cells_clear(occ, np.broadcast_to(origin, targets.shape), targets))
    below = targets[targets.sum(axis=1) < 5]
    above = targets[targets.sum(axis=1) > 5]
    assert not cells_clear(occ, np.broadcast_to([0, 0], above.shape), above).any()
    assert cells_clear(occ, np.broadcast_to([0, 0], below.shape), below).all()


# ---- filaments -----------------------------------------------------------------------------------------------
def _box(h=30, w=60, res=0.1):
    occ = np.zeros((h, w), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    return occ


def test_concentration_matches_direct_sum_with_cutoff_and_walls():
    occ = _box(20, 40)
    occ[1:19, 25] = True  # a closed wall at x = 2.5..2.6
    g = GridMap(occ, 0.1)
    p = FilamentParams(sigma0=0.1, gamma=2e-3, ppm_center=7.0)
    gas = FilamentModel(g, WindField(g, np.zeros((20, 40, 2))), (1.0, 1.0), params=p)
    rng = np.random.default_rng(3)
    gas.positions = np.column_stack([rng.uniform(0.15, 3.85, 400), rng.uniform(0.15, 1.85, 400)])
    gas._cells = g.world_to_cell(gas.positions)
    keep = ~occ[gas._cells[:, 0], gas._cells[:, 1]]
    gas.positions, gas._cells = gas.positions[keep], gas._cells[keep]
    gas.births = rng.uniform(0.0, 50.0, len(gas.positions))
    gas.time = 60.0
    queries = np.array([[0.55, 0.95], [2.35, 1.05], [2.85, 1.0], [3.6, 1.7]])
    got = gas.concentration(queries)
    for q, val in zip(queries, got):
        total = 0.0
        qc = g.world_to_cell(q)
        for x, b, fc in zip(gas.positions, gas.births, gas._cells):
            sigma = np.sqrt(0.1**2 + 2e-3 * (60.0 - b))
            d = np.hypot(*(x - q))
            left_q, left_f = qc[1] < 25, fc[1] < 25  # line of sight = same side of the wall
            if d < 5 * sigma and left_q == left_f:
                total += 7.0 * (0.1 / sigma) ** 3 * np.exp(-(d**2) / (2 * sigma**2))
        assert val == pytest.approx(total, rel=1e-12, abs=1e-300)
    assert got[1] > 0 and got[2] > 0


def test_release_count_and_sigma_growth():
    g = GridMap(_box(), 0.1)
    p = FilamentParams(release_rate=7.0)  # not a multiple of 1/dt
    gas = FilamentModel(g, WindField(g, np.zeros((30, 60, 2))), (3.0, 1.5), params=p, seed=1)
    for t in (0.1, 1.0, 3.3, 10.0):
        gas.run(t - gas.time)
        assert gas.n_released == int(np.floor(t * 7.0 + 1e-9))
    np.testing.assert_allclose(gas.sigma() ** 2, 0.1**2 + 15e-4 * (gas.time - gas.births), rtol=1e-12)
    assert gas.n_filaments == gas.n_released  # a closed box with no outlet keeps everything


@pytest.mark.parametrize("thickness, speed", [(2, 0.8), (1, 0.8), (1, 1.9)])
def test_no_gas_crosses_a_wall(thickness, speed):
    """Interior and border walls one or two cells thick; at 1.9 m/s a step moves ~2 cells (split moves)."""
    occ = _box(30, 60)
    occ[:, 30 : 30 + thickness] = True  # a solid wall at x = 3.0
    g = GridMap(occ, 0.1)
    wind = np.zeros((30, 60, 2))
    wind[..., 0] = speed  # pushes every filament against the wall
    wind[..., 1] = -0.3 * speed  # and against the bottom border wall
    p = FilamentParams(noise_std=0.05, release_rate=20.0)
    gas = FilamentModel(g, WindField(g, wind), (2.5, 1.5), params=p, seed=2)
    for _ in range(300):
        gas.step()
        rc = g.world_to_cell(gas.positions)
        assert (rc[:, 1] < 30).all() and not occ[rc[:, 0], rc[:, 1]].any()
    assert gas.n_removed == 0  # nothing leaks out of the closed box either
    # right behind the wall, within 5 σ of hundreds of filaments, the concentration is exactly zero
    x = 3.05 + 0.1 * thickness
    assert gas.concentration([[x, 1.5], [x, 0.5]]).tolist() == [0.0, 0.0]
    assert gas.concentration(np.median(gas.positions, axis=0)) > 1.0  # in the pile against the wall


def test_no_gas_through_diagonal_gaps():
    occ = np.zeros((40, 40), bool)
    idx = np.arange(40)
    occ[idx, 39 - idx] = True  # cells touching only at corners: the diagonal r + c = 39
    g = GridMap(occ, 0.1)
    wind = np.zeros((40, 40, 2))
    wind[..., :] = 0.5  # along +x +y: straight at the diagonal
    gas = FilamentModel(g, WindField(g, wind), (1.0, 1.0), params=FilamentParams(noise_std=0.05), seed=3)
    for _ in range(200):
        gas.step()
        rc = g.world_to_cell(gas.positions)
        assert (rc.sum(axis=1) < 39).all()
    assert gas.n_filaments == gas.n_released  # pinned against the diagonal, none lost


def test_outlets_remove_filaments():
    occ = _box(20, 60)
    outlet = np.zeros_like(occ)
    outlet[1:-1, -1] = True
    g = GridMap(occ & ~outlet, 0.1)
    wind = np.zeros((20, 60, 2))
    wind[1:-1, :, 0] = 0.5
    gas = FilamentModel(g, WindField(g, wind), (0.5, 1.0), outlet=outlet, seed=4)
    gas.run(30.0)
    assert gas.n_removed > 0 and gas.n_removed + gas.n_filaments == gas.n_released
    rc = g.world_to_cell(gas.positions)
    assert not outlet[rc[:, 0], rc[:, 1]].any()
    # transit of 5.5 m at 0.5 m/s takes ~11 s: what was released before ~15 s has left
    assert gas.births.min() > 30.0 - 15.0
    shut = GridMap(occ, 0.1)  # the same channel with the outlet walled up
    closed = FilamentModel(shut, WindField(shut, wind), (0.5, 1.0), outlet=None, seed=4)
    closed.run(30.0)
    assert closed.n_removed == 0 and closed.n_filaments == closed.n_released


def test_plume_decays_downwind_and_is_higher_downwind_than_upwind():
    occ = _box(40, 100)
    inlet, outlet = np.zeros_like(occ), np.zeros_like(occ)
    inlet[1:-1, 0] = True
    outlet[1:-1, -1] = True
    g = GridMap(occ & ~inlet & ~outlet, 0.1)
    wind = np.zeros((40, 100, 2))
    wind[1:-1, :, 0] = 0.3
    gas = FilamentModel(g, WindField(g, wind), (3.0, 2.0), outlet=outlet, seed=5)
    gas.run(40.0)  # warm-up: the plume reaches the outlet
    xs = [2.5, 3.5, 4.0, 5.0, 6.5]  # upwind 0.5 m, downwind 0.5, 1, 2, 3.5 m
    total = np.zeros(len(xs))
    for _ in range(1500):
        gas.step()
        total += gas.concentration(np.column_stack([xs, np.full(len(xs), 2.0)]))
    mean = total / 1500
    up, down = mean[0], mean[1:]
    assert np.all(np.diff(down) < 0)  # decays with distance downwind
    assert down[0] > 10 * up  # and is far higher than at the same distance upwind
    assert up >= 0


def test_filament_params_and_gaden_yaml(tmp_path):
    with pytest.raises(ValueError, match="dt"):
        FilamentParams(dt=0.0)
    with pytest.raises(TypeError, match="gamma"):
        FilamentParams(gamma="fast")
    (tmp_path / "s.yaml").write_text(yaml.safe_dump({
        "source_x": 1.5, "source_y": -2.0, "source_z": 0.4, "time_step": 0.05, "num_filaments_sec": 20,
        "ppm_filament_center": 5.0, "filament_initial_std": 8.0, "filament_growth_gamma": 10.0,
        "filament_noise_std": 0.01, "models": ["whatever.stl"]}))
    p, src = read_gaden_config(tmp_path / "s.yaml")
    assert p == FilamentParams(dt=0.05, release_rate=20, ppm_center=5.0, sigma0=0.08, gamma=1e-3, noise_std=0.01)
    np.testing.assert_array_equal(src, [1.5, -2.0, 0.4])
    (tmp_path / "t.yaml").write_text(yaml.safe_dump({"source_x": 1.5, "source_y": "here"}))
    with pytest.raises(ValueError, match=r"t\.yaml.*'source_y' must be a number"):
        read_gaden_config(tmp_path / "t.yaml")
    cases = (("time_step", 0, "key 'time_step' must"),  # a zero step; a radius that is 0 m once converted from cm
             ("filament_initial_std", 1e-323, r"key 'filament_initial_std' \(in SI units\) must"))
    for key, value, shown in cases:
        (tmp_path / "u.yaml").write_text(yaml.safe_dump({"source_x": 1.5, "source_y": 2.0, key: value}))
        with pytest.raises(ValueError, match=rf"u\.yaml: {shown} be a positive finite number"):
            read_gaden_config(tmp_path / "u.yaml")


def test_filament_model_input_errors():
    g = GridMap(_box(), 0.1)
    w = WindField(g, np.zeros((30, 60, 2)))
    with pytest.raises(ValueError, match="occupied cell"):
        FilamentModel(g, w, (0.05, 0.05))
    with pytest.raises(ValueError, match="inside the map"):
        FilamentModel(g, w, (1.0, 1.0)).concentration([[10.0, 1.0]])
    with pytest.raises(TypeError, match="wind"):
        FilamentModel(g, np.zeros((30, 60, 2)), (1.0, 1.0))


# ---- sensors -------------------------------------------------------------------------------------------------
def test_gas_sensor_response_and_threshold():
    x = np.array([0.0, 4.0, 4.0, 1.0, 0.0, 0.0, 3.0])
    s = GasSensor(threshold=1.5, window=0.7, response_time=0.3)
    y = s.response(x, 0.1, initial=2.0)
    a = 1 - np.exp(-0.1 / 0.3)
    ref, prev = [], 2.0
    for xk in x:  # y_k = y_{k-1} + a (x_k - y_{k-1})
        prev = prev + a * (xk - prev)
        ref.append(prev)
    np.testing.assert_allclose(y, ref, rtol=1e-12)
    r = s.read(x, 0.1, initial=2.0)
    assert r.value == pytest.approx(np.mean(ref), rel=1e-12) and r.state == pytest.approx(ref[-1], rel=1e-12)
    assert r.hit == (np.mean(ref) >= 1.5)
    assert s.samples(0.1) == 7
    ideal = GasSensor(threshold=1.0)
    assert ideal.read([0.99], 0.1).hit is False and ideal.read([1.0], 0.1).hit is True
    with pytest.raises(ValueError, match="rng"):
        GasSensor(noise_std=0.1).read([1.0], 0.1)
    with pytest.raises(ValueError, match="threshold"):
        GasSensor(threshold=0.0)


def test_noisy_sensors_statistics():
    rng = np.random.default_rng(0)
    n = 200_000
    y = GasSensor(noise_std=0.5).response(np.full(n, 10.0), 0.1, rng=rng)
    assert abs(y.mean() - 10.0) < 5 * 0.5 / np.sqrt(n) and abs(y.std() - 0.5) < 0.01
    w = Anemometer(noise_std=0.05).read(np.broadcast_to([0.2, -0.1], (n, 2)), rng=rng)
    np.testing.assert_allclose(w.mean(axis=0), [0.2, -0.1], atol=5 * 0.05 / np.sqrt(n))
    np.testing.assert_allclose(w.std(axis=0), [0.05, 0.05], rtol=0.01)
