"""Shared helpers of the executable proofs: exact tables from pgmpy, entropies, d-separation over sets."""

from __future__ import annotations

import itertools

import numpy as np
from pgmpy.inference import VariableElimination

RTOL = 1e-10  # every exact identity is checked to this relative tolerance


def table(model, variables, evidence=None) -> np.ndarray:
    """p(variables | evidence) from pgmpy's exact inference, axes in ``variables`` order, states as in
    the model's CPDs (cell order for S, class order for O_c, (no, yes) for S_i)."""
    infer = VariableElimination(model)
    factor = infer.query(list(variables), evidence=evidence or {}, show_progress=False)
    values = np.transpose(factor.values, [factor.variables.index(v) for v in variables])
    for axis, v in enumerate(variables):  # reorder states to the model's own order
        wanted = list(model.get_cpds(v).state_names[v])
        have = list(factor.state_names[v])
        values = np.take(values, [have.index(s) for s in wanted], axis=axis)
    return values


def normalised(x) -> np.ndarray:
    x = np.asarray(x, dtype=np.float64)
    return x / x.sum()


def entropy(p) -> float:
    p = np.asarray(p, dtype=np.float64).ravel()
    p = p[p > 0]
    return float(-np.sum(p * np.log(p)))


def dconnected_sets(model, xs, ys, observed) -> bool:
    """True if any x in ``xs`` is d-connected to any y in ``ys`` given ``observed`` (pgmpy is_dconnected)."""
    return any(model.is_dconnected(x, y, observed=list(observed)) for x, y in itertools.product(xs, ys))


def assert_close(actual, expected, *, rtol=RTOL, what=""):
    """Entry-wise relative comparison (sums of non-negative terms: relative accuracy holds entry-wise)."""
    np.testing.assert_allclose(np.asarray(actual), np.asarray(expected), rtol=rtol, atol=0, err_msg=what)
