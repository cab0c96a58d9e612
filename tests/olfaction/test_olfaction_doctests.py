"""The docstring examples of psgsl_pgm.olfaction run and give what they show."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = ["_analytic", "_calibrate", "_grid", "_hitmap", "_infotaxis", "_operator", "_plume", "_pmfs"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(f"psgsl_pgm.olfaction.{name}")
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0
    assert result.failed == 0
