"""The metal-oxide and photo-ionisation gas sensors (step responses against the exact formula, noise and drift
statistics, seeding, bad inputs), their state in the world, and the anemometer's offset, direction error and
datasheet preset."""

import numpy as np
import pytest

from psgsl_pgm.sim import Anemometer, GasSensor, MOXSensor, MOXState, PIDSensor, make_world

DT = 0.1


def _fit_tau(t, frac):
    """τ from a least-squares line through log(frac) = −t / τ."""
    return -1.0 / np.polyfit(t, np.log(frac), 1)[0]


# ---- dynamics -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("sensor", [MOXSensor.tgs2620(), MOXSensor.tgs2600(), MOXSensor.tgs2611()],
                         ids=["tgs2620", "tgs2600", "tgs2611"])
def test_step_response_recovers_the_rise_and_recovery_time_constants(sensor):
    s = MOXSensor(**{f: getattr(sensor, f) for f in ("rise_time", "recovery_time", "sensitivity", "knee")},
                  noise_std=0.0, drift_std=0.0)
    c = 20.0
    y_ss = float(s.steady_state(c))
    n = 1000  # 100 s: past the slowest sensor's 90 % recovery (TGS2600: 18.75 s × ln 10 = 43 s)
    t = DT * np.arange(1, n + 1)
    up = s.response(np.full(n, c), DT) - 1.0  # from clean air: y(t) = y_ss (1 − e^(−t/τ_r))
    np.testing.assert_allclose(up, y_ss * -np.expm1(-t / s.rise_time), rtol=1e-12, atol=1e-15)
    early = t < 3 * s.rise_time
    tau_r = _fit_tau(t[early], 1.0 - up[early] / y_ss)
    assert tau_r == pytest.approx(s.rise_time, rel=1e-9)
    y0 = 0.5 * y_ss
    down = s.response(np.zeros(n), DT, initial=MOXState(y0, 0.0)) - 1.0  # gas removed: y(t) = y_0 e^(−t/τ_d)
    # the output is G / G_0 ≈ 1: y read back from it carries float64's absolute rounding of ~1e-16
    np.testing.assert_allclose(down, y0 * np.exp(-t / s.recovery_time), rtol=1e-12, atol=1e-15)
    late = t < 3 * s.recovery_time
    tau_d = _fit_tau(t[late], down[late] / y0)
    assert tau_d == pytest.approx(s.recovery_time, rel=1e-9)
    assert tau_d > tau_r  # recovery slower than rise
    # the 90 % times, as read off a recorded trace, in the same ratio
    t90_up = t[np.argmax(up >= 0.9 * y_ss)]
    t90_down = t[np.argmax(down <= 0.1 * y0)]
    assert t90_up == pytest.approx(s.rise_time * np.log(10), abs=DT)
    assert t90_down == pytest.approx(s.recovery_time * np.log(10), abs=DT)


def test_default_is_the_tgs2620_and_its_curve_is_the_datasheet_line_above_the_knee():
    s = MOXSensor()
    assert s == MOXSensor.tgs2620()
    assert (s.rise_time, s.recovery_time) == (2.96, 15.71)
    assert s.knee == pytest.approx(4.574, abs=1e-3)
    c = np.array([300.0, 1000.0, 5000.0])
    rs_r0 = 21.0 / (1.0 + s.steady_state(c))  # R_s / R_0 = (R_air / R_0) / (G / G_air)
    np.testing.assert_allclose(rs_r0, 62.32 * c**-0.7155, rtol=0.012)
    assert s.steady_state(0.0) == 0.0
    assert np.all(np.diff(s.steady_state(np.linspace(0, 50, 101))) > 0)


def test_the_lag_switches_constant_with_the_direction_of_change():
    """A falling then rising concentration: each sample's step uses τ_d while the target is below the response,
    τ_r above it (the sample-by-sample recursion)."""
    s = MOXSensor(noise_std=0.0, drift_std=0.0)
    x = np.r_[np.full(30, 10.0), np.full(30, 0.5), np.full(30, 10.0)]
    got = s.response(x, DT) - 1.0
    y, want = 0.0, []
    for u in s.steady_state(x):
        tau = s.rise_time if u > y else s.recovery_time
        y = u + (y - u) * np.exp(-DT / tau)
        want.append(y)
    np.testing.assert_allclose(got, want, rtol=1e-12)


def test_pid_t90_is_the_datasheet_two_seconds():
    s = PIDSensor(noise_std=0.0)
    dt = 0.01
    y = s.response(np.full(500, 5.0), dt)
    t90 = dt * (1 + np.argmax(y >= 0.9 * 5.0))
    assert t90 == pytest.approx(2.0, abs=dt)
    down = s.response(np.zeros(500), dt, initial=MOXState(5.0, 0.0))
    assert dt * (1 + np.argmax(down <= 0.5)) == pytest.approx(2.0, abs=dt)  # symmetric


# ---- noise and drift -------------------------------------------------------------------------------------------
def test_noise_is_white_with_the_stated_std():
    s = MOXSensor(drift_std=0.0)
    v = s.response(np.zeros(40_000), DT, rng=np.random.default_rng(1))
    assert v.mean() == pytest.approx(1.0, abs=4 * s.noise_std / 200)
    assert v.std() == pytest.approx(s.noise_std, rel=0.03)
    e = v - 1.0
    assert abs(np.corrcoef(e[:-1], e[1:])[0, 1]) < 0.02


def test_drift_is_a_random_walk_of_the_stated_diffusion_plus_its_rate():
    s = MOXSensor(noise_std=0.0, drift_std=2e-3, drift_rate=1e-4)
    T, n_runs = 50.0, 2000
    n = int(T / DT)
    ends = np.array([s.response(np.zeros(n), DT, rng=np.random.default_rng(k))[-1] - 1.0 for k in range(n_runs)])
    assert ends.mean() == pytest.approx(1e-4 * T, abs=4 * 2e-3 * np.sqrt(T / n_runs))
    assert ends.var() == pytest.approx(2e-3**2 * T, rel=0.1)  # 2000 runs: the variance to ~3 %
    one = s.response(np.zeros(20_000), DT, rng=np.random.default_rng(5)) - 1.0
    steps = np.diff(one)
    assert steps.std() == pytest.approx(2e-3 * np.sqrt(DT), rel=0.03)
    assert steps.mean() == pytest.approx(1e-4 * DT, abs=4 * 2e-3 * np.sqrt(DT) / np.sqrt(steps.size))


def test_idle_recovers_in_clean_air_and_drifts():
    s = MOXSensor(drift_std=1e-3, drift_rate=-2e-4)
    st = MOXState(0.4, 0.01)
    quiet = MOXSensor(drift_std=0.0, drift_rate=-2e-4).idle(st, 20.0)
    assert quiet.level == pytest.approx(0.4 * np.exp(-20.0 / s.recovery_time), rel=1e-12)
    assert quiet.drift == pytest.approx(0.01 - 2e-4 * 20.0, rel=1e-12)
    d = np.array([s.idle(st, 20.0, rng=np.random.default_rng(k)).drift for k in range(3000)])
    assert d.mean() == pytest.approx(0.01 - 4e-3, abs=4 * 1e-3 * np.sqrt(20.0 / 3000))
    assert d.std() == pytest.approx(1e-3 * np.sqrt(20.0), rel=0.06)
    assert s.idle(st, 0.0, rng=np.random.default_rng(0)) == st


# ---- seeding, the reading, the world ---------------------------------------------------------------------------
def test_readings_are_reproducible_from_the_seed():
    x = np.linspace(0, 8, 25)
    for s in (MOXSensor(), PIDSensor()):
        a = s.read(x, DT, rng=np.random.default_rng(3))
        b = s.read(x, DT, rng=np.random.default_rng(3))
        c = s.read(x, DT, rng=np.random.default_rng(4))
        assert a.value == b.value and a.state == b.state and np.array_equal(a.trace, b.trace)
        assert not np.array_equal(a.trace, c.trace)
        assert a.hit is None and a.value == pytest.approx(a.trace.mean(), rel=1e-15)
    runs = []
    for _ in range(2):
        w = make_world(seed=4, warm_up=10.0, gas_sensor=MOXSensor())
        traces = [w.sense_gas((2.0, 6.0)).trace for _ in range(3)]
        w.advance(12.0)  # the sensor idles: recovery and drift drawn from the world's sensor stream
        runs.append(traces + [w.sense_gas((2.5, 6.0)).trace])
    np.testing.assert_array_equal(np.concatenate(runs[0]), np.concatenate(runs[1]))


def test_the_world_carries_the_mox_state_and_lets_it_recover_between_readings():
    w = make_world(seed=0, warm_up=30.0, gas_sensor=MOXSensor(noise_std=0.0, drift_std=0.0))
    near = w.source + np.array([0.3, 0.0])
    first = w.sense_gas(near)
    assert isinstance(first.state, MOXState) and first.state.level > 0.05
    w.advance(10.0)
    t_end = w.time
    nxt = w.sense_gas(near, duration=w.dt)  # one sample after 10 s away: recovered, then one step of the lag
    level = first.state.level * np.exp(-(t_end - (t_end - 10.0)) / w.gas_sensor.recovery_time)
    u = float(w.gas_sensor.steady_state(w.concentration(near)))
    tau = w.gas_sensor.rise_time if u > level else w.gas_sensor.recovery_time
    assert nxt.state.level == pytest.approx(u + (level - u) * np.exp(-w.dt / tau), rel=1e-9)


def test_the_ideal_sensor_is_untouched():
    s = GasSensor()
    r = s.read([0.0, 2.0, 2.0, 2.0], dt=0.25)
    assert (r.value, r.hit, r.state, r.trace) == (1.5, True, 2.0, None)
    assert s.idle(0.7, 30.0, rng=None) == 0.7


# ---- bad inputs ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, err, match", [
    ({"rise_time": -1.0}, ValueError, "MOXSensor.rise_time"),
    ({"window": 0.0}, ValueError, "MOXSensor.window"),
    ({"knee": 0.0}, ValueError, "MOXSensor.knee"),
    ({"sensitivity": float("nan")}, ValueError, "MOXSensor.sensitivity"),
    ({"noise_std": "0.1"}, TypeError, "MOXSensor.noise_std"),
    ({"drift_rate": float("inf")}, ValueError, "MOXSensor.drift_rate"),
])
def test_bad_mox_parameters_are_named(kwargs, err, match):
    with pytest.raises(err, match=match):
        MOXSensor(**kwargs)


def test_bad_readings_are_refused():
    s = MOXSensor()
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="needs rng"):
        s.read([1.0, 2.0], DT)
    with pytest.raises(TypeError, match="numpy Generator"):
        s.read([1.0, 2.0], DT, rng=np.random.RandomState(0))
    with pytest.raises(ValueError, match="non-negative"):
        s.read([1.0, -2.0], DT, rng=rng)
    with pytest.raises(ValueError, match="finite"):
        s.read([1.0, np.nan], DT, rng=rng)
    with pytest.raises(ValueError, match="dt must be"):
        s.read([1.0], 0.0, rng=rng)
    with pytest.raises(ValueError, match="at least one"):
        s.read([], DT, rng=rng)
    with pytest.raises(ValueError, match="non-negative response level"):
        s.read([1.0], DT, initial=-0.5, rng=rng)
    with pytest.raises(TypeError, match="MOXState"):
        s.read([1.0], DT, initial="warm", rng=rng)
    with pytest.raises(ValueError, match="seconds"):
        s.idle(MOXState(), -1.0, rng=rng)
    with pytest.raises(ValueError, match="PIDSensor.response_time"):
        PIDSensor(response_time=-0.1)
    with pytest.raises(TypeError, match="gas_sensor must be"):
        make_world(seed=0, warm_up=0.0, gas_sensor="TGS2620")


# ---- anemometer ------------------------------------------------------------------------------------------------
def test_anemometer_defaults_are_the_ideal_instrument_with_noise():
    w = np.array([[0.2, -0.1], [0.05, 0.3]])
    got = Anemometer().read(w, rng=np.random.default_rng(7))
    np.testing.assert_array_equal(got, w + np.random.default_rng(7).normal(0.0, 0.02, size=w.shape))


def test_anemometer_offset_and_direction_error():
    a = Anemometer(noise_std=0.0, bias=(0.01, -0.02), direction_error=30.0)
    got = a.read([[0.3, 0.0], [0.0, 0.1]], rng=None)
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    np.testing.assert_allclose(got, [[0.3 * c + 0.01, 0.3 * s - 0.02], [-0.1 * s + 0.01, 0.1 * c - 0.02]], rtol=1e-12)


def test_windsonic_preset_statistics():
    a = Anemometer.datasheet()
    w = np.array([0.3, 0.1])
    r = a.read(np.tile(w, (20_000, 1)), rng=np.random.default_rng(2))
    np.testing.assert_allclose(r / 0.01, np.round(r / 0.01), atol=1e-9)  # 0.01 m/s resolution
    th = np.deg2rad(3.0)
    want = np.array([np.cos(th) * w[0] - np.sin(th) * w[1], np.sin(th) * w[0] + np.cos(th) * w[1]]) + 0.01
    np.testing.assert_allclose(r.mean(axis=0), want, atol=5e-4)  # rounding of N(μ, 0.01²) is unbiased to ~1e-5
    assert r.std(axis=0) == pytest.approx([np.sqrt(0.01**2 + 0.01**2 / 12)] * 2, rel=0.03)  # noise + rounding


@pytest.mark.parametrize("kwargs, err, match", [
    ({"bias": (0.1,)}, ValueError, "Anemometer.bias"),
    ({"bias": "none"}, (TypeError, ValueError), "Anemometer.bias"),
    ({"direction_error": float("nan")}, ValueError, "Anemometer.direction_error"),
    ({"resolution": -0.01}, ValueError, "Anemometer.resolution"),
    ({"noise_std": -1.0}, ValueError, "Anemometer.noise_std"),
])
def test_bad_anemometer_parameters_are_named(kwargs, err, match):
    with pytest.raises(err, match=match):
        Anemometer(**kwargs)
