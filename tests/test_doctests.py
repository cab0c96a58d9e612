"""Every docstring example in the package runs and shows what it says (one runner for all modules)."""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "psgsl_pgm"
# modules whose docstrings hold examples (found from the source text, so nothing is imported at collection)
MODULES = sorted(
    ".".join(("psgsl_pgm",) + p.relative_to(PACKAGE).with_suffix("").parts)
    for p in PACKAGE.rglob("*.py")
    if ">>> " in p.read_text(encoding="utf-8") and p.name != "__main__.py"
)


@pytest.fixture
def agg_figures():
    plt = pytest.importorskip("matplotlib.pyplot")
    backend = plt.get_backend()
    plt.switch_backend("Agg")
    yield
    plt.close("all")
    plt.switch_backend(backend)


def test_examples_were_found():
    assert len(MODULES) >= 30


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name, agg_figures):
    if name.split(".")[1] == "gym":  # the gym extra
        pytest.importorskip("gymnasium")
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0
    assert result.failed == 0
