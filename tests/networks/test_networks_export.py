"""networks/: the committed XMLBIF and BIF files equal a fresh export and load back with the same posteriors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pgmpy.readwrite import BIFReader, XMLBIFReader

from psgsl_pgm.networks import (
    check_normalised,
    exact_gas_posterior,
    exact_information_gain,
    exact_source_posterior,
    network_kind,
)
from psgsl_pgm.networks._export import CANONICAL, canonical_network, network_text

NETWORKS_DIR = Path(__file__).resolve().parents[2] / "networks"
READERS = {"xmlbif": XMLBIFReader, "bif": BIFReader}


@pytest.mark.parametrize("fmt", sorted(READERS))
@pytest.mark.parametrize("name", sorted(CANONICAL))
def test_committed_file_equals_fresh_export(name, fmt):
    path = NETWORKS_DIR / f"{name}.{fmt}"
    assert path.is_file(), f"{path} is missing: run `psgsl export-networks networks`"
    _, model = canonical_network(name)
    assert path.read_text(encoding="utf-8") == network_text(model, fmt), (
        f"{path.name} is stale: regenerate with `psgsl export-networks networks`"
    )


@pytest.mark.parametrize("fmt", sorted(READERS))
@pytest.mark.parametrize("name", sorted(CANONICAL))
def test_committed_file_loads_back_with_same_posteriors(name, fmt):
    problem, model = canonical_network(name)
    loaded = READERS[fmt](str(NETWORKS_DIR / f"{name}.{fmt}")).get_model()
    assert loaded.check_model() and check_normalised(loaded)
    assert set(loaded.nodes()) == set(model.nodes()) and set(loaded.edges()) == set(model.edges())
    assert network_kind(loaded) == network_kind(model)
    for node in model.nodes():  # full-precision round trip of every CPD, states in the same order
        original, back = model.get_cpds(node), loaded.get_cpds(node)
        assert back.state_names[node] == original.state_names[node]
        np.testing.assert_array_equal(back.get_values(), original.get_values())
    expected = problem.closed_form_posterior()
    np.testing.assert_allclose(exact_source_posterior(loaded, problem), expected, rtol=1e-12, atol=0)
    np.testing.assert_array_equal(exact_source_posterior(loaded, problem), exact_source_posterior(model, problem))
    np.testing.assert_allclose(exact_gas_posterior(loaded, problem), problem.closed_form_gas_posterior(),
                               rtol=1e-12, atol=0)
    if network_kind(model) == "A":
        np.testing.assert_array_equal(exact_information_gain(loaded, problem),
                                      exact_information_gain(model, problem))


def test_drawings_exist():
    for name in CANONICAL:
        assert (NETWORKS_DIR / f"{name}.png").stat().st_size > 1000
