"""class_ratio remembers validated ontology inputs by their exact bytes: a repeated call returns the same ρ, a
changed (or invalid) input is validated and computed afresh, and no caller shares an array with the memo."""

from __future__ import annotations

import numpy as np
import pytest

from psgsl_pgm.core._ratios import _MEMO, _class_ratio, class_ratio


def _same(a, b):
    for x, y in ((a.rho, b.rho), (a.class_prior, b.class_prior), (a.zero_prior, b.zero_prior)):
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()


def test_repeated_inputs_give_the_computed_ratio_and_fresh_arrays():
    lik = np.array([0.4, 0.25, 0.3, 0.05])
    prior = np.array([0.1, 0.2, 0.3, 0.4])
    first = class_ratio(lik, prior)
    _same(first, _class_ratio(lik, prior, None))
    first.rho[:] = -1.0  # a caller writing into its result changes nothing for the next caller
    first.class_prior[:] = 0.0
    second = class_ratio(lik, prior)
    _same(second, _class_ratio(lik, prior, None))
    assert second.rho is not first.rho and second.rho.min() >= 0


def test_an_input_changed_in_place_is_validated_and_computed_again():
    lik = np.array([0.5, 0.5, 0.0])
    prior = np.array([0.2, 0.3, 0.5])
    class_ratio(lik, prior)
    prior[:] = (0.5, 0.3, 0.2)  # the caller's array changes after the first call
    _same(class_ratio(lik, prior), _class_ratio(lik, np.array([0.5, 0.3, 0.2]), None))
    prior[:] = (0.5, 0.6, 0.2)  # no longer a distribution
    with pytest.raises(ValueError, match="class_prior"):
        class_ratio(lik, prior)
    prior[:] = (0.0, 0.8, 0.2)  # zero prior under positive likelihood
    with pytest.raises(ValueError, match="class_prior is zero"):
        class_ratio(lik, prior)


def test_gas_mixtures_are_keyed_by_their_weights_and_the_memo_stays_small():
    rows = np.array([[0.6, 0.3, 0.1], [0.1, 0.3, 0.6]])
    prior = np.full(3, 1 / 3)
    a = class_ratio(rows, prior, np.array([0.9, 0.1]))
    b = class_ratio(rows, prior, np.array([0.1, 0.9]))
    assert a.rho.tobytes() != b.rho.tobytes()
    _same(b, _class_ratio(rows, prior, np.array([0.1, 0.9])))
    for j in range(20):
        class_ratio(rows, prior, np.array([j / 20, 1 - j / 20]))
    assert len(_MEMO) <= 8
    with pytest.raises(ValueError, match="gas_probs"):
        class_ratio(rows, prior)  # two gas rows need p(γ | ζ), memo or not
