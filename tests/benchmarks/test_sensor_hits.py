"""benchmarks/sensor_hits.py counts each sensor's hits against the concentration the ideal sensor reads at the same
stop (the gas of a seed does not depend on the sensor)."""

from ._scripts import load_script


def test_tour_counts_are_consistent_and_the_ideal_sensor_hits_exactly_at_one_ppm():
    counts = load_script("sensor_hits").tour_hits([0], stops=100)
    ideal, mox, pid = counts["ideal"], counts["mox"], counts["pid"]
    assert ideal["stops"] == mox["stops"] == pid["stops"] == 100
    assert ideal["hits"] == ideal["ideal"] > 5 and ideal["below"] == ideal["clean"] == ideal["missed"] == 0
    for r in (mox, pid):
        assert r["hits"] == r["ideal"] + r["below"] + r["clean"]
        assert r["ideal"] + r["missed"] == ideal["hits"]
        assert r["falling"] <= r["missed"]
