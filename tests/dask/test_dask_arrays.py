"""Dask arrays chunked over cells through the core: lazy results equal to the numpy path, zarr end to end."""

from __future__ import annotations

import numpy as np
import pytest

da = pytest.importorskip("dask.array", reason="dask is not installed (pip install 'psgsl-pgm[dask]')")
import dask  # noqa: E402

from psgsl_pgm import fuse, kitchen_ontology, semantic_information_gain, semantic_source_probability  # noqa: E402

# Relative tolerance per result dtype. float64: the project's exactness tolerance. float32: the compiled pass sums
# the K = 5 classes' terms q_ci ρ_i in float32 (ρ rounded to float32 too), so each path's cell weight carries a
# relative error of at most (K + 1)·u, u = eps32 / 2 = 2^-24, and the final division rounds once more (u); two
# such results differ by at most 2·(K + 2)·u = 14·u ≈ 8.3e-7 (the chunked and the in-memory pass may group those
# float32 sums differently). Measured on an AMD EPYC: 1.8e-7.
_K = 5  # classes of the kitchen ontology (checked in the `onto` fixture)
RTOL = {np.float64: 1e-12, np.float32: 2 * (_K + 2) * float(np.finfo(np.float32).eps) / 2}


@pytest.fixture(autouse=True)
def _synchronous():
    with dask.config.set(scheduler="synchronous"):  # no thread pool: deterministic and frugal on shared cores
        yield


@pytest.fixture(scope="module")
def onto():
    ont = kitchen_ontology()
    assert len(ont.classes) == _K  # RTOL[np.float32] is derived from the number of classes
    return ont.source_likelihood("smoke"), ont.class_prior, len(ont.classes)


def _beliefs(rng, shape, k, dtype=np.float64):
    q = rng.dirichlet(np.full(k, 0.4), size=shape)
    q[rng.random(shape) < 0.3] = rng.dirichlet(np.ones(k))  # some cells share one belief (ties)
    return q.astype(dtype)


def _close(got, expected, *, inputs=None):
    """Equal within the tolerance of the less precise of the result's dtype and the ``inputs`` dtype (float32
    beliefs fused with a float64 distribution give a float64 result that carries float32 rounding)."""
    assert isinstance(got, np.ndarray) and got.dtype == expected.dtype and got.shape == expected.shape
    rtol = max(RTOL[expected.dtype.type], RTOL[np.dtype(inputs or expected.dtype).type])
    np.testing.assert_allclose(got, expected, rtol=rtol, atol=rtol * np.abs(expected).max())


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("shape, chunks", [((37, 41), (10, 13)), ((9, 8, 6), (4, 3, 6)), ((500,), (64,))])
def test_semantic_source_probability_chunked_equals_numpy(onto, dtype, shape, chunks):
    lik, prior, k = onto
    rng = np.random.default_rng(11)
    q = _beliefs(rng, shape, k, dtype)
    dq = da.from_array(q, chunks=(*chunks, 2))  # the class axis split too: rechunked internally
    got = semantic_source_probability(dq, lik, prior)
    assert isinstance(got, da.Array) and got.chunks[0][0] == chunks[0]
    _close(got.compute(), semantic_source_probability(q, lik, prior))
    _close(semantic_source_probability(dq, lik, prior, normalize=False).compute(),
           semantic_source_probability(q, lik, prior, normalize=False))
    sp = rng.dirichlet(np.ones(q[..., 0].size)).reshape(shape)
    _close(semantic_source_probability(dq, lik, prior, source_prior=sp).compute(),  # float32 beliefs: float32 out
           semantic_source_probability(q, lik, prior, source_prior=sp))
    if len(shape) > 1:
        _close(semantic_source_probability(dq, lik, prior, column_axis=-1).compute(),
               semantic_source_probability(q, lik, prior, column_axis=-1))


def test_gas_mixture_and_dask_source_prior(onto):
    _, prior, k = onto
    rng = np.random.default_rng(2)
    lik = rng.dirichlet(np.ones(k), size=3)
    gas = np.array([0.5, 0.3, 0.2])
    q = _beliefs(rng, (30, 20), k)
    sp = rng.dirichlet(np.ones(600)).reshape(30, 20)
    got = semantic_source_probability(da.from_array(q, chunks=(7, 20, k)), lik, prior, gas_probs=gas,
                                      source_prior=da.from_array(sp, chunks=(5, 5)))
    _close(got.compute(), semantic_source_probability(q, lik, prior, gas_probs=gas, source_prior=sp))


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_fuse_chunked_equals_numpy(onto, dtype):
    rng = np.random.default_rng(5)
    g = rng.dirichlet(np.full(900, 0.3)).reshape(30, 30).astype(dtype)
    z = rng.dirichlet(np.ones(900)).reshape(30, 30).astype(dtype)
    z[:3] = 0  # disjoint supports in part of the map: log 0 handled as in the numpy path
    z /= z.sum(dtype=np.float64)
    pr = rng.dirichlet(np.ones(900) * 5).reshape(30, 30)
    dg = da.from_array(g, chunks=(8, 7))
    got = fuse(dg, z)
    assert isinstance(got, da.Array)
    _close(got.compute(), fuse(g, z))
    _close(fuse(dg, da.from_array(z, chunks=10), g, prior=pr).compute(), fuse(g, z, g, prior=pr))


@pytest.mark.parametrize("predictive", ["paper", "exact"])
@pytest.mark.parametrize("olfactory", ["uniform", "numpy", "dask"])
def test_information_gain_chunked_equals_numpy(onto, predictive, olfactory):
    lik, prior, k = onto
    rng = np.random.default_rng(8)
    q = _beliefs(rng, (25, 31), k)
    q[:2, :2] = np.eye(k)[0]  # cells known to be ovens: the element-wise (non-series) branch
    f = None if olfactory == "uniform" else rng.dirichlet(np.full(775, 0.05)).reshape(25, 31)
    f_in = da.from_array(f, chunks=(6, 31)) if olfactory == "dask" else f
    got = semantic_information_gain(da.from_array(q, chunks=(6, 9, k)), lik, prior, olfactory=f_in,
                                    predictive=predictive)
    assert isinstance(got, da.Array)
    _close(got.compute(), semantic_information_gain(q, lik, prior, olfactory=f, predictive=predictive))


def test_results_are_lazy_and_validation_happens_on_compute_with_global_cells(onto):
    lik, prior, k = onto
    q = _beliefs(np.random.default_rng(1), (20, 30), k)
    q[17, 25, 1] = -0.25
    dq = da.from_array(q, chunks=(6, 7, k))
    p = semantic_source_probability(dq, lik, prior)  # no error yet: nothing was computed
    gain = semantic_information_gain(dq, lik, prior)
    for lazy in (p, gain, fuse(p, p)):
        with pytest.raises(ValueError, match=r"class_probs must be non-negative .* at index \(17, 25, 1\)"):
            lazy.compute()
    q[17, 25, 1] = 0.5
    with pytest.raises(ValueError, match=r"class_probs must sum to 1 .* at cell \(17, 25\)"):
        semantic_source_probability(da.from_array(q, chunks=(6, 7, k)), lik, prior).compute()


def test_shape_and_type_errors_are_immediate(onto):
    lik, prior, k = onto
    with pytest.raises(ValueError, match=f"must have {k} classes on its last axis"):
        semantic_source_probability(da.ones((4, 5, k + 1), chunks=2) / (k + 1), lik, prior)
    with pytest.raises(ValueError, match="cell axes before the class axis"):
        semantic_source_probability(da.ones(k, chunks=2) / k, lik, prior)
    with pytest.raises(TypeError, match="class_probs must be a real numeric array"):
        semantic_information_gain(da.ones((4, k), dtype=bool, chunks=2), lik, prior)
    with pytest.raises(ValueError, match="posteriors\\[1\\] must have the shape of posteriors\\[0\\]"):
        fuse(da.ones(4, chunks=2) / 4, np.ones(5) / 5)
    a, b = np.zeros(6), np.zeros(6)
    a[0], b[1] = 1, 1
    with pytest.raises(ValueError, match=r"posteriors\[0\] and posteriors\[1\] have no cell where both"):
        fuse(da.from_array(a, chunks=2), b).compute()


def test_a_zarr_class_belief_array_end_to_end(onto, tmp_path):
    zarr = pytest.importorskip("zarr", reason="zarr is not installed (pip install 'psgsl-pgm[dask]')")
    lik, prior, k = onto
    rng = np.random.default_rng(4)
    q = _beliefs(rng, (3000,), k, np.float32)
    store = zarr.open_array(str(tmp_path / "beliefs.zarr"), mode="w", shape=q.shape, chunks=(256, k),
                            dtype="float32")
    store[:] = q
    dq = da.from_zarr(str(tmp_path / "beliefs.zarr"))
    g = rng.dirichlet(np.ones(3000))
    post = fuse(g, semantic_source_probability(dq, lik, prior))
    da.to_zarr(post.rechunk(256), str(tmp_path / "posterior.zarr"))  # streamed to disk chunk by chunk
    _close(np.asarray(zarr.open_array(str(tmp_path / "posterior.zarr"), mode="r")),  # p(s | z) is float32 here
           fuse(g, semantic_source_probability(q, lik, prior)), inputs=np.float32)
    _close(semantic_information_gain(dq, lik, prior, olfactory=g).compute(),
           semantic_information_gain(q, lik, prior, olfactory=g), inputs=np.float32)
