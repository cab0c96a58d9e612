"""The one validation vocabulary (psgsl_pgm._shared._validate) and its type contract, on the core and on every wing."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from psgsl_pgm import GridMap, field_of_view, fuse, semantic_source_probability, update_class_probs
from psgsl_pgm._shared._validate import (
    SUM_RTOL,
    as_float_array,
    bool_mask,
    distribution,
    file_field,
    flag,
    index,
    positive,
    real_number,
    real_pair,
    unit_interval,
)


@pytest.mark.parametrize("bad, kind", [
    (np.array([True, False]), "booleans"),
    (np.array([1 + 2j, 0j]), "complex"),
    (np.array(["0.5", "0.5"]), "real numeric"),
    (np.array([object(), 1.0], dtype=object), "real numeric"),
    ("0.5", "real numeric"),
    (None, "real numeric"),
    ([[0.5], [0.2, 0.8]], "real numeric"),  # ragged
])
def test_non_real_arrays_are_type_errors_naming_the_argument(bad, kind):
    with pytest.raises(TypeError, match=f"class_probs .*{kind}"):
        as_float_array(bad, "class_probs")


def test_huge_python_integers_are_value_errors_never_overflow():
    for call in (lambda: as_float_array([1, 10**400], "counts"), lambda: real_number(10**400, "counts"),
                 lambda: positive(-(10**400), "counts"),
                 lambda: file_field("a.yaml", "counts", 10**400)):
        with pytest.raises(ValueError, match=r"counts.*too large for a float64 \(-?1000+…\(401 digits\)\)"):
            call()
    np.testing.assert_array_equal(as_float_array([2**70, 1], "x"), [2.0**70, 1.0])  # converted safely
    with pytest.raises(ValueError, match=r"class_probs must hold finite numbers.*too large"):
        semantic_source_probability([[10**400, 0]], [1.0, 0.0], [0.5, 0.5])


def test_flags_must_be_bool():
    assert flag(True, "normalize") is True and flag(np.bool_(False), "normalize") is False
    for bad in (None, "no", 0, 1, [], 1.0):
        with pytest.raises(TypeError, match=r"normalize must be True or False, got"):
            flag(bad, "normalize")


def test_scalars_name_argument_expected_and_received():
    assert positive(2, "resolution", "metres") == 2.0 and positive(0, "min_range", allow_zero=True) == 0.0
    with pytest.raises(ValueError, match=r"^resolution must be a positive finite number in metres, got -1$"):
        positive(-1, "resolution", "metres")
    with pytest.raises(TypeError, match=r"^resolution must be a positive number in metres, got bool True$"):
        positive(True, "resolution", "metres")
    with pytest.raises(ValueError, match=r"^tempering must lie in \(0, 1\], got 0$"):
        unit_interval(0, "tempering", low_open=True)
    with pytest.raises(ValueError, match=r"^k must be an int >= 2, got float 2.5$"):
        index(2.5, "k", minimum=2)
    with pytest.raises(TypeError, match=r"^k must be an int >= 2, got str '3'$"):
        index("3", "k", minimum=2)
    with pytest.raises(ValueError, match=r"^k must be an int in \[0, 3\], got 4$"):
        index(4, "k", maximum=3)
    with pytest.raises(ValueError, match=r"^origin must be an \(x, y\) pair in metres, got shape \(3,\)$"):
        real_pair([1, 2, 3], "origin")
    with pytest.raises(TypeError, match=r"origin must be an \(x, y\) pair of real numbers in metres, got booleans"):
        real_pair([True, False], "origin")
    with pytest.raises(TypeError, match=r"^origin must be an \(x, y\) pair of real numbers in metres, got \(True, 2.0\)$"):
        real_pair((True, 2.0), "origin")  # numpy would read it as the floats (1.0, 2.0)
    with pytest.raises(ValueError, match=r"^b.yaml: field 'resolution' must be > 0, got 0$"):
        file_field("b.yaml", "resolution", 0, positive=True)
    with pytest.raises(ValueError, match=r"field 'resolution' must be a number, got str '1'"):
        file_field("b.yaml", "resolution", "1")


def test_bool_mask_accepts_bool_and_0_1_only():
    m = bool_mask(np.array([[0, 1]]), "outlets")
    assert m.dtype == bool and not m.flags.writeable
    with pytest.raises(TypeError, match="outlets must be a boolean array"):
        bool_mask(np.array([[0.5, 1.0]]), "outlets")
    with pytest.raises(ValueError, match=r"outlets must have the map's shape \(2, 2\), got \(1, 2\)"):
        bool_mask([[0, 1]], "outlets", (2, 2))


def test_one_tolerance_per_dtype():
    assert SUM_RTOL == {np.dtype(np.float64): 1e-6, np.dtype(np.float32): 1e-4}
    p64 = np.array([0.5, 0.5 + 5e-7])
    assert distribution(p64, "p").dtype == np.float64
    with pytest.raises(ValueError, match="tolerance 1e-06"):
        distribution(np.array([0.5, 0.5 + 2e-6]), "p")
    p32 = np.array([0.5, 0.5 + 5e-5], dtype=np.float32)
    assert distribution(p32, "p").dtype == np.float32  # float32 stays float32
    with pytest.raises(ValueError, match="tolerance 0.0001"):
        distribution(np.array([0.5, 0.5002], dtype=np.float32), "p")


@settings(max_examples=30, deadline=None)
@given(q=arrays(np.float32, (3, 4), elements=st.floats(0.0625, 1.0, width=32)))
def test_semantic_gsl_problem_accepts_what_the_core_accepts(q):
    """float32 and slightly-off (1e-8) distributions are accepted by SemanticGSLProblem as by the core."""
    pytest.importorskip("pgmpy", reason="the networks extra is not installed (pip install 'psgsl-pgm[networks]')")
    from psgsl_pgm.networks import SemanticGSLProblem

    lik = (q / q.sum(axis=1, keepdims=True)).astype(np.float32)  # float32 rows: sums off by up to ~1e-7
    background = np.full(4, 0.25) + np.array([1e-8, 0, 0, 0])
    semantic_source_probability(lik, lik[0], background)  # the core accepts these
    problem = SemanticGSLProblem(lik[0], background, cells=3, observation_cells=[0, 1, 2],
                                 observation_likelihoods=lik, source_prior=lik[1, :3] / lik[1, :3].sum())
    assert problem.source_likelihood.dtype == np.float64
    np.testing.assert_allclose(problem.source_likelihood.sum(), 1.0, rtol=1e-15)
    with pytest.raises(ValueError, match=r"background must sum to 1 along its last axis \(tolerance 1e-06\)"):
        SemanticGSLProblem(lik[0], np.full(4, 0.25) + 1e-5, cells=3)


def test_every_wing_speaks_the_same_vocabulary():
    for module in ("matplotlib", "PIL", "pgmpy"):  # the wings: the sim and networks extras
        pytest.importorskip(module, reason="the all extra is not installed (pip install 'psgsl-pgm[all]')")
    from psgsl_pgm.olfaction import GridInfotaxis, PlumeModel
    from psgsl_pgm.sim import GasSensor
    from psgsl_pgm.teaching import approximation_error

    msg = r"must be a positive finite number in metres, got 0"
    for call in (lambda: GridMap(np.zeros((2, 2), bool), 0), lambda: PlumeModel(np.zeros((2, 2), bool), resolution=0)):
        with pytest.raises(ValueError, match="resolution " + msg):
            call()
    with pytest.raises(ValueError, match=r"GasSensor.window must be a positive finite number, got 0"):
        GasSensor(window=0.0)
    with pytest.raises(ValueError, match=r"^n_problems must be an int >= 1, got 0$"):
        approximation_error([4], n_problems=0)
    with pytest.raises(ValueError, match=r"^false_hit_rate must lie in \[0, 1\), got 1.0$"):
        GridInfotaxis(np.zeros((3, 3), bool), resolution=0.1, false_hit_rate=1.0)
    with pytest.raises(TypeError, match="occupancy must be boolean"):
        field_of_view(np.full((2, 2), 0.5), (0.5, 0.5, 0), max_range=1, half_angle=1)
    with pytest.raises(TypeError, match="likelihood must be a real numeric array, got booleans"):
        update_class_probs([0.5, 0.5], np.array([True, False]))
    with pytest.raises(TypeError, match=r"posteriors\[0\] must be real"):
        fuse(np.array([0.5 + 0j, 0.5]))
