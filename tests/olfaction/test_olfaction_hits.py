"""The robot's hit rule: plume passages found in noisy, drifting MOX and PID traces, no hit on drift or noise
alone, noise and baseline estimated online, and the argued choice (a level rule on a MOX keeps firing while the
sensor recovers; the rise rule does not)."""

import numpy as np
import pytest

from psgsl_pgm.olfaction import HIT_RULE_KINDS, HitRule
from psgsl_pgm.sim import MOXSensor, PIDSensor

DT = 0.1
GAP = 7.0  # s between readings (driving to the next stop); a reading takes 1 s


def _stops(sensor, concentrations, seed):
    """The traces of one reading per stop, the sensor idling in clean air for GAP s in between (as in World)."""
    rng = np.random.default_rng(seed)
    state, traces = 0.0, []
    for j, c in enumerate(concentrations):
        if j:
            state = sensor.idle(state, GAP, rng=rng)
        r = sensor.read(np.full(sensor.samples(DT), float(c)), DT, initial=state, rng=rng)
        state = r.state
        traces.append(r.trace)
    return traces


def _decide(rule, traces):
    return np.array([rule.decide(t) for t in traces])


PASSAGE = np.r_[np.zeros(25), [0.6, 2.0, 1.2], np.zeros(25)]  # ppm at 53 stops: a plume crossed at stops 25-27
IN_GAS = PASSAGE > 0


@pytest.mark.parametrize("seed", range(5))
def test_rise_rule_finds_the_plume_passage_in_a_noisy_drifting_mox_trace(seed):
    sensor = MOXSensor(drift_std=2e-3, drift_rate=-5e-5)  # four times the default drift, and a trend
    hits = _decide(HitRule("rise"), _stops(sensor, PASSAGE, seed))
    assert hits[IN_GAS].all()
    assert not hits[~IN_GAS].any()


@pytest.mark.parametrize("seed", range(5))
def test_a_level_rule_on_the_same_mox_trace_keeps_firing_while_the_sensor_recovers(seed):
    """Why the MOX rule thresholds the rise: the same readings through the level rule give hits at clean-air
    stops after the passage (the response decays with τ_d ≈ 16 s over stops 8 s apart)."""
    sensor = MOXSensor()
    traces = _stops(sensor, PASSAGE, seed)
    level = _decide(HitRule("level"), traces)
    after = np.arange(PASSAGE.size) > np.flatnonzero(IN_GAS)[-1]
    assert level[after].any()
    assert not _decide(HitRule("rise"), traces)[after].any()


@pytest.mark.parametrize("sensor", [MOXSensor(), MOXSensor(drift_std=1e-2, drift_rate=2e-4),
                                    MOXSensor(drift_std=0.0, drift_rate=-1e-3)], ids=["default", "strong", "linear"])
def test_rise_rule_does_not_fire_on_drift_and_noise_alone(sensor):
    traces = _stops(sensor, np.zeros(600), seed=11)
    assert not _decide(HitRule("rise"), traces).any()


def test_level_rule_finds_the_passage_with_a_pid_and_not_clean_air():
    for seed in range(5):
        hits = _decide(HitRule("level"), _stops(PIDSensor(), PASSAGE, seed))
        assert hits[IN_GAS].all() and not hits[~IN_GAS].any()
    assert not _decide(HitRule("level"), _stops(PIDSensor(), np.zeros(600), seed=3)).any()


def test_level_rule_false_hits_on_a_drifting_pid_are_rare():
    """A PID whose baseline wanders by 0.14 ppm over the run: its clean-air output clipped at 0 ppm has a skewed
    upper tail, so the level rule sometimes fires (3 of 5000 readings on these seeds), far below the false-hit
    rate ε = 0.01 the estimators assume (ExperimentConfig.false_hit_rate)."""
    n = sum(_decide(HitRule("level"), _stops(PIDSensor(drift_std=0.002), np.zeros(1000), seed=k)).sum()
            for k in range(5))
    assert n / 5000 < 0.002


def test_noise_and_baseline_are_estimated_from_the_readings():
    """The estimates the rule learns match the sensor's truth (which only this test reads)."""
    sensor = MOXSensor(drift_std=0.0)
    rule = HitRule("rise")
    _decide(rule, _stops(sensor, np.r_[np.zeros(150), np.full(20, 3.0)], seed=2))
    assert rule.n_readings == 170
    # median of per-window residual stds (8 degrees of freedom): E[s] = c4 σ, the median a little below
    assert rule.noise == pytest.approx(sensor.noise_std, rel=0.08)
    assert np.isnan(rule.baseline)
    pid = PIDSensor(noise_std=0.05)
    level = HitRule("level")
    _decide(level, _stops(pid, np.r_[np.zeros(100), np.full(10, 2.0)], seed=2))
    assert level.baseline == pytest.approx(0.0, abs=0.03)  # a clean-air PID mean clipped at 0
    assert 0.02 < level.noise < 0.05


def test_warm_up_and_a_rise_that_is_k_standard_errors():
    rule = HitRule("rise", k=5.0, warm_up=3)
    ramp = 1.0 + 0.05 * np.arange(10)
    assert [rule.decide(ramp) for _ in range(3)] == [False, False, True]  # no hit before three readings
    noisy = HitRule("rise", k=5.0, warm_up=1)
    rng = np.random.default_rng(0)
    for _ in range(50):
        noisy.decide(1.0 + 0.01 * rng.standard_normal(10))
    i = np.arange(10) - 4.5
    se = noisy.noise / np.sqrt(i @ i)
    assert noisy.decide(1.0 + 5.2 * se * i)  # a noiseless line 5.2 standard errors steep
    assert not noisy.decide(1.0 + 4.8 * se * i)
    assert not noisy.decide(1.0 - 20 * se * i)  # a fall never is


@pytest.mark.parametrize("args, kwargs, err, match", [
    (("derivative",), {}, ValueError, "kind must be one of"),
    (("rise",), {"k": 0.0}, ValueError, "k"),
    (("rise",), {"warm_up": 0}, ValueError, "warm_up"),
])
def test_bad_rule_settings(args, kwargs, err, match):
    with pytest.raises(err, match=match):
        HitRule(*args, **kwargs)


def test_bad_traces():
    rule = HitRule("rise")
    with pytest.raises(ValueError, match="at least 3 samples"):
        rule.decide([1.0, 1.1])
    with pytest.raises(ValueError, match="finite"):
        rule.decide([1.0, np.nan, 1.0])
    with pytest.raises((ValueError, TypeError), match="trace"):
        rule.decide(np.ones((2, 5)))
    with pytest.raises(ValueError, match="at least one"):
        HitRule("level").decide([])
    assert HIT_RULE_KINDS == ("rise", "level")
