"""The electronic nose: gas-specific responses, a classifier that is worse on weak readings, its own random stream."""

from __future__ import annotations

import numpy as np
import pytest

from psgsl_pgm.sim import ENOSE_GASES, ElectronicNose, draw_gas, make_world


def _accuracy(nose, x, gas, n=4000, seed=0):
    rng = np.random.default_rng(seed)
    label, strength = nose.decide(nose.respond(np.full(n, x), gas, rng))
    return float(np.mean(label == nose.gases.index(gas))), float(np.mean(label < 0)), strength


@pytest.mark.parametrize("gas", ENOSE_GASES)
def test_weak_readings_classify_worse(gas):
    nose = ElectronicNose()
    acc = [_accuracy(nose, x, gas)[0] for x in (0.05, 0.15, 0.3, 0.6)]
    assert all(a < b for a, b in zip(acc, acc[1:])), acc   # accuracy grows with the concentration
    assert acc[0] < 0.3 and acc[-1] > 0.9 and _accuracy(nose, 20.0, gas)[0] > 0.999


def test_strength_does_not_depend_on_the_gas():
    """Equal-length patterns: at one concentration every gas gives the same strength distribution (what lets the
    robot treat the strength as no evidence about the gas)."""
    nose = ElectronicNose()
    for x in (0.0, 0.3, 3.0):
        means = [_accuracy(nose, x, g, n=20000, seed=3)[2].mean() for g in ENOSE_GASES]
        assert np.ptp(means) < 0.01, (x, means)


def test_clean_air_is_mostly_unclassified():
    nose = ElectronicNose()
    _, none, _ = _accuracy(nose, 0.0, "smoke")
    assert none > 0.85


def test_bad_arguments_name_what_was_expected():
    with pytest.raises(ValueError, match="sensitivity is required"):
        ElectronicNose(gases=("smoke", "chlorine"))
    with pytest.raises(ValueError, match="sensitivity must be"):
        ElectronicNose(gases=("a", "b"), sensitivity=np.ones((3, 3)))
    with pytest.raises(ValueError, match="column of zeros"):
        ElectronicNose(gases=("a", "b"), sensitivity=[[1.0, 0.0], [1.0, 0.0]])
    with pytest.raises(ValueError, match="noise_std"):
        ElectronicNose(noise_std=0.0)
    nose = ElectronicNose()
    with pytest.raises(ValueError, match="gas must be one of"):
        nose.classify(1.0, "chlorine", np.random.default_rng(0))
    with pytest.raises(ValueError, match="concentration"):
        nose.classify(-1.0, "smoke", np.random.default_rng(0))


def test_draw_gas_is_seeded_and_covers_the_gases():
    draws = [draw_gas(ENOSE_GASES, s) for s in range(40)]
    assert draws == [draw_gas(ENOSE_GASES, s) for s in range(40)]
    assert set(draws) == set(ENOSE_GASES)
    with pytest.raises(TypeError, match="seed"):
        draw_gas(ENOSE_GASES, 1.5)


def test_world_with_an_enose_draws_every_other_stream_as_without():
    """Opt-in: the e-nose's own stream leaves the gas readings, the wind and the frames as they were."""
    kw = dict(seed=3, warm_up=5.0)
    plain = make_world(**kw)
    nosed = make_world(**kw, enose=ElectronicNose(), gas_type="ammonia")
    assert plain.enose is None and plain.gas_type is None
    for xy in ((7.5, 1.0), (3.0, 6.0)):
        a, b = plain.sense_gas(xy), nosed.sense_gas(xy)
        smell = nosed.sniff()
        assert smell.label in (None, *ENOSE_GASES) and smell.strength >= 0
        assert a == b
        np.testing.assert_array_equal(plain.sense_wind(xy), nosed.sense_wind(xy))
        fa, fb = plain.camera_frame((*xy, 0.0)), nosed.camera_frame((*xy, 0.0))
        np.testing.assert_array_equal(fa.labels, fb.labels)
    assert plain.time == nosed.time


def test_world_enose_guards():
    with pytest.raises(ValueError, match="go together"):
        make_world(seed=0, warm_up=0.0, enose=ElectronicNose())
    with pytest.raises(ValueError, match="gas_type must be one of"):
        make_world(seed=0, warm_up=0.0, enose=ElectronicNose(), gas_type="chlorine")
    with pytest.raises(TypeError, match="enose must be"):
        make_world(seed=0, warm_up=0.0, enose="nose", gas_type="smoke")
    w = make_world(seed=0, warm_up=0.0, enose=ElectronicNose(), gas_type="smoke")
    with pytest.raises(ValueError, match="call sense_gas first"):
        w.sniff()
    with pytest.raises(ValueError, match="no electronic nose"):
        make_world(seed=0, warm_up=0.0).sniff()


def test_near_the_source_the_enose_names_the_gas():
    w = make_world(seed=0, warm_up=30.0, enose=ElectronicNose(), gas_type="natural gas")
    named = []
    for _ in range(5):
        w.sense_gas(w.source + np.array([0.0, 0.6]))
        named.append(w.sniff().label)
    assert named.count("natural gas") >= 4, named
