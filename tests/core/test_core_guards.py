"""Documented contracts that a one-line slip would break silently: the order of the gases asked for, the COCO
alias table, and the scale of the unnormalised semantic weights."""

from __future__ import annotations

import re

import numpy as np
import pytest

import psgsl_pgm.io._coco as coco
from psgsl_pgm import Ontology, semantic_source_probability
from psgsl_pgm.io._coco import COCO_ALIASES, COCO_CLASSES, canonical_class

_THREE_GASES = {
    "classes": ["oven", "fridge", "sink"],
    "gases": {"smoke": {"oven": 0.8, "fridge": 0.1, "sink": 0.05},
              "ammonia": {"oven": 0.05, "fridge": 0.15, "sink": 0.7},
              "ethanol": {"oven": 0.2, "fridge": 0.6, "sink": 0.1}},
}


@pytest.mark.parametrize("asked", [["ethanol", "smoke"], ["ammonia", "smoke", "ethanol"], ["smoke", "smoke"],
                                   ("ethanol",)])
def test_source_likelihood_rows_follow_the_order_asked(asked):
    ont = Ontology.from_dict(_THREE_GASES)
    assert ont.gases == ("smoke", "ammonia", "ethanol")
    got = ont.source_likelihood(list(asked))
    assert got.shape == (len(asked), len(ont.classes))
    for row, gas in zip(got, asked):
        np.testing.assert_array_equal(row, ont.source_likelihood(gas))
    # the rows hold the file's numbers: smoke's oven entry is 0.8 wherever smoke was asked
    oven = ont.classes.index("oven")
    np.testing.assert_allclose(got[:, oven], [_THREE_GASES["gases"][g]["oven"] for g in asked], rtol=1e-12)


def _documented_aliases() -> dict[str, str]:
    """Alias -> COCO name, read from the table in psgsl_pgm.io._coco's docstring (the documented contract)."""
    table = {}
    for line in coco.__doc__.splitlines():
        m = re.match(r"^``([^`]+)``\s{2,}(.+)$", line)
        if m and m.group(2).strip() != "(none)":
            for alias in m.group(2).split(","):
                table[alias.strip()] = m.group(1)
    return table


def test_every_documented_alias_maps_to_its_documented_coco_name():
    documented = _documented_aliases()
    assert {"washbasin": "sink", "basin": "sink", "wc": "toilet", "fridge": "refrigerator"}.items() <= \
        documented.items()
    for alias, name in documented.items():
        assert canonical_class(alias) == name, alias
        assert canonical_class(alias.upper().replace(" ", "_")) == name, alias  # any case, separators ignored
    # the table in the code and the documented one are the same table
    assert {a: c for a, c in COCO_ALIASES.items()} == documented
    assert set(documented.values()) <= set(COCO_CLASSES)


def test_sink_and_toilet_are_told_apart():
    assert [canonical_class(n) for n in ("Washbasin", "basin", "WC", "sink", "toilet")] == \
        ["sink", "sink", "toilet", "sink", "toilet"]


def test_unnormalised_weights_have_the_documented_scale():
    # normalize=False: w_c = Σ_i q_ci ρ_i with ρ_i = p(o_i | s) / p(o_i) scaled so that the largest possible
    # per-cell weight (a cell certain of the class of largest ratio) is 1
    rng = np.random.default_rng(3)
    k = 6
    lik, prior = rng.dirichlet(np.ones(k)), rng.dirichlet(np.ones(k) * 2)
    q = rng.dirichlet(np.ones(k) * 0.7, size=(5, 7))
    rho = lik / prior
    want = q @ rho / rho.max()
    for dtype, rtol in ((np.float64, 1e-12), (np.float32, (k + 2) * 2.0**-24)):
        np.testing.assert_allclose(semantic_source_probability(q.astype(dtype), lik, prior, normalize=False),
                                   want.astype(dtype), rtol=rtol)
    best = np.eye(k)[[int(np.argmax(rho)), int(np.argmin(rho))]]
    np.testing.assert_allclose(semantic_source_probability(best, lik, prior, normalize=False),
                               [1.0, rho.min() / rho.max()], rtol=1e-14)
    # with a source prior: the same weights times p(s_c); with a column sum: summed over that axis
    sp = rng.dirichlet(np.ones(35)).reshape(5, 7)
    np.testing.assert_allclose(semantic_source_probability(q, lik, prior, normalize=False, source_prior=sp),
                               want * sp, rtol=1e-12)
    np.testing.assert_allclose(semantic_source_probability(q, lik, prior, normalize=False, column_axis=1),
                               want.sum(axis=1), rtol=1e-12)
    # a gas mixture: ρ from Σ_γ p(γ | ζ) p(o | s, γ), scaled the same way
    lik2 = np.stack([lik, rng.dirichlet(np.ones(k))])
    gas = np.array([0.3, 0.7])
    rho2 = (gas @ lik2) / prior
    np.testing.assert_allclose(semantic_source_probability(q, lik2, prior, gas_probs=gas, normalize=False),
                               q @ rho2 / rho2.max(), rtol=1e-12)
