"""The examples in the teaching helpers' docstrings run."""

import doctest
import importlib

import pytest

MODULES = ["_approximation", "_graph", "_maps", "_views"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(f"psgsl_pgm.teaching.{name}")
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0
