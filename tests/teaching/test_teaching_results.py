"""The closed-loop grid shipped for notebook 08 is the one the results page shows, and reads as documented."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from psgsl_pgm.teaching import closed_loop_results

PAGE = Path(__file__).resolve().parents[2] / "docs" / "results" / "closed-loop"


@pytest.mark.parametrize("name", ["summary.json", "paired.json"])
def test_shipped_copy_equals_the_results_page(name):
    if not (PAGE / name).is_file():
        pytest.skip("no docs/results next to the package (an installed copy)")
    shipped = closed_loop_results()[0 if name == "summary.json" else 1]
    assert shipped == json.loads((PAGE / name).read_text()), (
        f"psgsl_pgm/data/closed_loop/{name} differs from docs/results/closed-loop/{name}: copy the new one over")


def test_every_arm_has_a_survival_curve_and_its_rmst():
    summary, paired = closed_loop_results()
    assert set(summary) == {"oven/infotaxis", "bed/infotaxis", "5,6/infotaxis"}
    for table in summary.values():
        for arm in table.values():
            t, s = np.asarray(arm["km"]["t"]), np.asarray(arm["km"]["survival"])
            tau = arm["rmst"]["tau"]
            area = np.sum(np.diff(np.append(t[t <= tau], tau)) * s[t <= tau])
            np.testing.assert_allclose(area, arm["rmst"]["value"], rtol=1e-9)
    assert paired["oven/infotaxis"]["infotaxis/semantics+rooms - infotaxis/olfaction"]["primary"]


def test_one_source():
    summary, paired = closed_loop_results(source="bed")
    assert list(summary) == ["bed/infotaxis"] and list(paired) == ["bed/infotaxis"]


def test_bad_source_names_the_choices():
    with pytest.raises(ValueError, match=r"expected one of \['5,6', 'bed', 'oven'\], got 'sofa'"):
        closed_loop_results(source="sofa")
    with pytest.raises(TypeError, match="expected a string or None, got int"):
        closed_loop_results(source=3)
