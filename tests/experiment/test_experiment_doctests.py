"""The docstring examples of psgsl_pgm.experiment run and give what they show."""

from __future__ import annotations

import doctest
import importlib

import pytest

MODULES = ["_config", "_metrics", "_ontology", "_tour"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(f"psgsl_pgm.experiment.{name}")
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0
    assert result.failed == 0
