"""benchmarks/calibration_missed_hits.py fits (κ, δ) on tours of reference homes: the joint fit is never worse
than δ = 0, under either wind estimate."""

import re

import pytest

from ._scripts import load_script


@pytest.mark.slow
def test_the_joint_fit_is_at_least_the_fit_without_missed_hits(capsys):
    module = load_script("calibration_missed_hits")
    module.main(["--homes", "1"])
    out = capsys.readouterr().out
    assert len(re.findall(r"^home 1000000, \w+: \d+ readings, \d+ hits$", out, re.M)) == 2
    fits = re.findall(r"^(whole-run|online) wind: n = (\d+), hits (\d+) \| δ = 0: κ̂ = ([\d.e+-]+), log L = "
                      r"([\d.e+-]+) \| joint: κ̂ = ([\d.e+-]+), δ̂ = ([\d.e+-]+), log L = ([\d.e+-]+)$", out, re.M)
    assert [f[0] for f in fits] == ["whole-run", "online"]
    for _, n, hits, k0, ll0, k1, d1, ll1 in fits:
        assert 0 < int(hits) < int(n)
        assert float(k0) > 0 and float(k1) > 0 and 0 <= float(d1) < 1
        assert float(ll1) >= float(ll0) - 0.01  # printed to 2 decimals
