"""Fixtures shared by the test folders (tests/core, tests/geometry, tests/sim, tests/olfaction, tests/experiment, ...)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def house():
    """The simulator's embedded house, seed 0 (the validation experiment's floor plan); read-only use."""
    from psgsl_pgm.sim import default_house  # the sim extra: only the tests that ask for this fixture need it

    return default_house(0)
