"""SemanticGSLProblem validation, network construction errors, and the underflow guard."""

from __future__ import annotations

import subprocess
import sys
from functools import reduce
from pathlib import Path

import numpy as np
import pytest

from psgsl_pgm.networks import (
    MAX_TABLE_CELLS,
    MIN_EVIDENCE,
    SemanticGSLProblem,
    build_network_a,
    build_network_b,
    check_normalised,
    exact_source_posterior,
    log_evidence,
    network_evidence,
)
from psgsl_pgm.networks._underflow import check_result

LIK, BG = [0.6, 0.3, 0.1], [0.2, 0.3, 0.5]


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        (dict(source_likelihood=[0.6, 0.3, 0.2]), ValueError, "sum to 1"),
        (dict(source_likelihood=[1.1, -0.1, 0.0]), ValueError, "non-negative"),
        (dict(source_likelihood=[np.nan, 0.5, 0.5]), ValueError, "finite"),
        (dict(source_likelihood=[1.0]), ValueError, "k >= 2"),
        (dict(source_likelihood=[[0.6, 0.4], [0.5]]), TypeError, "source_likelihood must be a real numeric array"),
        (dict(background=[0.5, 0.5, 0.0]), ValueError, "strictly positive"),
        (dict(background=[0.5, 0.5]), ValueError, r"shape \(3,\)"),
        (dict(cells=0), ValueError, "positive count"),
        (dict(cells="abc"), TypeError, "sequence of names"),
        (dict(cells=["a", "b", "a"]), ValueError, "unique"),
        (dict(cells=["a", "b c", "d"]), ValueError, "identifier"),
        (dict(cells=["a", "1b", "d"]), ValueError, "start with a letter"),
        (dict(class_names=["x", "y"]), ValueError, "class_names must have 3 names"),
        (dict(cells=[3]), TypeError, r"cells\[0\] must be a str"),
        (dict(cells=["a", "b", "c"], class_names=["x", "y", 4]), TypeError, r"class_names\[2\] must be a str"),
        (dict(observation_cells=[[0], [1, 2]], observation_likelihoods=[[1, 1, 1]] * 2), TypeError,
         "observation_cells must be a 1-D integer array"),
        (dict(observation_cells=[], observation_likelihoods=[[1, 1, 1]]), ValueError,
         "observation_cells and observation_likelihoods must have one entry per observation, got 0 observation "
         r"cell\(s\) and 1 likelihood row"),
        (dict(observation_cells=[0, 1]), ValueError, r"observation_likelihoods not given"),
        (dict(observation_cells=[3], observation_likelihoods=[[1, 1, 1]]), ValueError, "index the 3 cells"),
        (dict(observation_cells=[0.5], observation_likelihoods=[[1, 1, 1]]), TypeError, "integer"),
        (dict(observation_cells=[0], observation_likelihoods=[[1, 1]]), ValueError, r"\(1, 3\)"),
        (dict(observation_cells=[0], observation_likelihoods=[[0, 0, 0]]), ValueError, "all-zero"),
        (dict(observation_cells=[0, 0], observation_likelihoods=[[1, 0, 0], [0, 1, 1]]), ValueError,
         "exclude every class"),
        (dict(olfactory_likelihood=[1.0, 1.0]), ValueError, r"shape \(3,\)"),
        (dict(olfactory_likelihood=[0.0, 0.0, 0.0]), ValueError, "probability zero"),
        (dict(source_prior=[0.5, 0.5, 0.5]), ValueError, "sum to 1"),
        (dict(shape=[(1, 3)]), TypeError, "shape must be a tuple of ints"),
        (dict(shape=[(1, 3), 1]), TypeError, "shape must be a tuple of ints"),
        (dict(shape=(2, 2)), ValueError, r"product is the number of cells \(cells gives n = 3\)"),
        (dict(gas_observations=[[0.5, 0.5]]), ValueError, r"\(N_zeta, 1\)"),
    ],
)
def test_bad_input_is_refused_with_a_clear_message(kwargs, error, match):
    args = dict(source_likelihood=LIK, background=BG, cells=3)
    args.update(kwargs)
    lik, bg = args.pop("source_likelihood"), args.pop("background")
    with pytest.raises(error, match=match):
        SemanticGSLProblem(lik, bg, **args)


def test_bad_class_prior_and_rng():
    problem = SemanticGSLProblem(LIK, BG, cells=3)
    with pytest.raises(ValueError, match="'background', 'marginal'"):
        problem.closed_form_posterior(class_prior="uniform")
    with pytest.raises(ValueError, match=r"shape \(3,\)"):
        problem.closed_form_posterior(class_prior=[0.5, 0.5])
    with pytest.raises(TypeError, match="Generator"):
        SemanticGSLProblem.random(0, 3, 2)


def test_random_is_reproducible_and_valid():
    a = SemanticGSLProblem.random(np.random.default_rng(3), 9, 4, m=2, shape=(3, 3))
    b = SemanticGSLProblem.random(np.random.default_rng(3), 9, 4, m=2, shape=(3, 3))
    for name in ("source_likelihood", "background", "observation_likelihoods", "olfactory_likelihood",
                 "source_prior", "gas_prior", "gas_observations"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert (a.n, a.k, a.m, a.shape) == (9, 4, 2, (3, 3))
    assert a.cell_names[0] == "c0" and a.class_names[-1] == "o3" and a.gas_names == ("gas0", "gas1")
    np.testing.assert_allclose(a.marginal_class_prior().sum(), 1.0, rtol=1e-15)


def test_marginal_class_prior_is_the_cell_average_of_p_o():
    problem = SemanticGSLProblem.random(np.random.default_rng(4), 5, 3, m=2)
    mean_source = problem.gas_prior @ problem.source_likelihood
    pi = problem.source_prior[:, None]
    per_cell = pi * mean_source + (1 - pi) * problem.background  # p(o_c) = p(s_c) L̄ + (1 − p(s_c)) β
    np.testing.assert_allclose(problem.marginal_class_prior(), per_cell.mean(axis=0), rtol=1e-14)


def test_network_construction_errors():
    problem = SemanticGSLProblem.random(np.random.default_rng(5), MAX_TABLE_CELLS + 1, 2, max_observations=0)
    with pytest.raises(ValueError, match="2\\^21 columns.*n > 20"):
        build_network_b(problem, "table")
    with pytest.raises(ValueError, match="'chain' or 'table'"):
        build_network_b(problem, "xor")
    with pytest.raises(TypeError, match="SemanticGSLProblem"):
        build_network_a("problem")
    other = SemanticGSLProblem.random(np.random.default_rng(6), 4, 2)
    with pytest.raises(ValueError, match="disagree on the cells"):
        exact_source_posterior(build_network_a(other), problem)
    with pytest.raises(ValueError, match="elimination_order"):
        exact_source_posterior(build_network_a(other), other, elimination_order="minfill")


def test_evidence_of_a_network():
    problem = SemanticGSLProblem(LIK, BG, cells=["x", "y"], observation_cells=[1, 1],
                                 observation_likelihoods=[[1, 0.5, 0.5], [0.2, 1, 1]],
                                 gas_observations=None)
    assert network_evidence(build_network_a(problem)) == {"G": "observed", "Z_y_0": "observed",
                                                          "Z_y_1": "observed"}
    assert network_evidence(build_network_b(problem, "table"))["alpha"] == "true"


def test_strict_normalisation_check_catches_what_pgmpy_tolerates():
    problem = SemanticGSLProblem(LIK, BG, cells=2)
    model = build_network_a(problem)
    cpd = model.get_cpds("O_c0")
    cpd.values = cpd.values * (1 + 1e-6)  # within pgmpy's 0.01, far outside 1e-12
    assert model.check_model()
    with pytest.raises(ValueError, match="O_c0.*summing to 1"):
        check_normalised(model)


@pytest.mark.parametrize("network", ["A", "B"])
def test_log_evidence_equals_brute_force_sum_over_the_network(network):
    """log_evidence (used by the underflow guard) == log Σ over every configuration of Π CPDs."""
    problem = SemanticGSLProblem.random(np.random.default_rng(8), 3, 2, m=2, max_observations=2)
    model = build_network_a(problem) if network == "A" else build_network_b(problem, "table")
    evidence = network_evidence(model)
    factors = [cpd.to_factor() for cpd in model.get_cpds()]
    joint = reduce(lambda x, y: x * y, factors)  # the full joint over every node (small network)
    joint = joint.reduce(list(evidence.items()), inplace=False)  # p(everything else, evidence)
    np.testing.assert_allclose(log_evidence(problem, network), np.log(joint.values.sum()), rtol=1e-12)


def test_underflow_raises_instead_of_nan():
    """n = 700 observed cells: p(evidence) ~ 10^-330 — pgmpy alone would return NaN; we raise."""
    from pgmpy.inference import VariableElimination

    n = 700
    problem = SemanticGSLProblem([0.5, 0.3, 0.2], [1 / 3, 1 / 3, 1 / 3], cells=n,
                                 observation_cells=np.arange(n),
                                 observation_likelihoods=np.tile([1.0, 0.01, 0.01], (n, 1)))
    assert log_evidence(problem, "A") < np.log(MIN_EVIDENCE)
    model = build_network_a(problem)
    with pytest.raises(ValueError, match="would underflow.*closed_form_posterior"):
        exact_source_posterior(model, problem)
    with np.errstate(all="ignore"):  # what the guard prevents: pgmpy silently normalises 0/0
        raw = VariableElimination(model).query(["S"], evidence=network_evidence(model), show_progress=False)
    assert np.all(np.isnan(raw.values))
    assert np.all(np.isfinite(problem.closed_form_posterior()))


def test_check_result_refuses_nan_and_zero():
    with pytest.raises(ValueError, match="NaN"):
        check_result(np.array([np.nan, 1.0]), "S")
    with pytest.raises(ValueError, match="all-zero"):
        check_result(np.zeros(3), "S")


def test_importing_the_core_does_not_import_pgmpy():
    code = "import sys, psgsl_pgm; print('pgmpy' in sys.modules)"
    repo = Path(__file__).resolve().parents[2]
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=repo)
    assert out.stdout.strip() == "False"
