"""The closed-loop part of ``psgsl demo``."""

import json

from psgsl_pgm.search import run_search_demo


def test_search_demo_compares_with_and_without_semantics(tmp_path):
    summary = run_search_demo(tmp_path, budget=10.0, workers=1, progress=False)
    assert set(summary) == {"infotaxis/olfaction", "infotaxis/semantics+rooms"}
    assert json.loads((tmp_path / "oven-infotaxis" / "summary.json").read_text()) == summary
    assert all(s["time_to_find"]["budget"] == 10.0 for s in summary.values())
    assert (tmp_path / "oven-infotaxis" / "survival.png").stat().st_size > 0
