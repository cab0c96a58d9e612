"""ClassBeliefMap backed by dask arrays chunked over cells: lazy, equal to the numpy map, zarr end to end."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import given, seed, settings
from hypothesis import strategies as st

da = pytest.importorskip("dask.array", reason="dask is not installed (pip install 'psgsl-pgm[dask]')")
import dask  # noqa: E402
from dask.callbacks import Callback  # noqa: E402

from psgsl_pgm import ClassBeliefMap, fuse, kitchen_ontology, semantic_source_probability  # noqa: E402

RTOL = 1e-12  # both maps hold float64 beliefs (float32 input too), so both paths give float64 results


@pytest.fixture(autouse=True)
def _synchronous():
    with dask.config.set(scheduler="synchronous"):  # no thread pool: deterministic and frugal on shared cores
        yield


ONTOLOGY = kitchen_ontology()
LIK = ONTOLOGY.source_likelihood("smoke")
PRIOR = ONTOLOGY.class_prior
CLASSES = tuple(ONTOLOGY.classes)
K = len(CLASSES)


class CountingTasks(Callback):
    """Counts the tasks a dask scheduler runs while active."""

    def __init__(self):
        super().__init__()
        self.tasks = 0

    def _pretask(self, key, dsk, state):
        self.tasks += 1


class RecordingArray:
    """A numpy array behind the array protocol dask reads (like a zarr array), recording every non-empty read."""

    def __init__(self, values):
        self.values, self.shape, self.dtype, self.ndim = values, values.shape, values.dtype, values.ndim
        self.reads = []

    def __getitem__(self, key):
        out = self.values[key]
        if out.size:
            self.reads.append(key)
        return out


def _beliefs(rng, shape, dtype=np.float64):
    q = rng.dirichlet(np.full(K, 0.4), size=shape)
    q[rng.random(shape) < 0.3] = rng.dirichlet(np.ones(K))  # some cells share one belief (ties)
    return q.astype(dtype)


def _close(got, expected):
    assert isinstance(got, np.ndarray) and got.dtype == expected.dtype and got.shape == expected.shape
    np.testing.assert_allclose(got, expected, rtol=RTOL, atol=RTOL * np.abs(expected).max())


def _room_table(rng, rooms):
    return rng.dirichlet(np.ones(K), size=rooms)


def _both_maps(how, rng, shape, chunks, dtype):
    """The same map twice: numpy-backed and dask-backed (chunked over cells)."""
    layers = shape[2] if len(shape) == 3 else None
    if how == "given":
        q = _beliefs(rng, shape, dtype)
        return ClassBeliefMap(q, CLASSES), ClassBeliefMap(da.from_array(q, chunks=chunks + (2,)), CLASSES)
    if how == "prior":
        return ClassBeliefMap.from_prior(shape, PRIOR, CLASSES), ClassBeliefMap.from_prior(shape, PRIOR, CLASSES,
                                                                                            chunks=chunks)
    labels = rng.integers(-1, 3, size=shape[:2])
    table = _room_table(rng, 3)
    ref = ClassBeliefMap.from_rooms(labels, table, PRIOR, CLASSES, layers=layers)
    if how == "rooms, dask labels":
        dask_labels = da.from_array(labels, chunks=chunks[:2])
        return ref, ClassBeliefMap.from_rooms(dask_labels, table, PRIOR, CLASSES, layers=layers)
    return ref, ClassBeliefMap.from_rooms(labels, table, PRIOR, CLASSES, layers=layers, chunks=chunks)


@st.composite
def maps(draw):
    """A 2-D or voxel map, its chunks, how it is built, and a few updates (cells repeat within and across)."""
    h, w = draw(st.integers(1, 9)), draw(st.integers(1, 9))
    shape = (h, w) + ((draw(st.integers(1, 4)),) if draw(st.booleans()) else ())
    chunks = tuple(draw(st.integers(1, n)) for n in shape)
    how = draw(st.sampled_from(["given", "prior", "rooms", "rooms, dask labels"]))
    dtype = draw(st.sampled_from([np.float64, np.float32]))
    n_updates = draw(st.integers(0, 3))
    sizes = [draw(st.integers(1, 6)) for _ in range(n_updates)]
    return shape, chunks, how, dtype, sizes, draw(st.integers(0, 2**32 - 1))


@seed(20261201)
@settings(max_examples=60, deadline=None)
@given(maps())
def test_a_chunked_map_equals_the_numpy_map_through_updates_columns_and_fusion(case):
    shape, chunks, how, dtype, sizes, rng_seed = case
    rng = np.random.default_rng(rng_seed)
    ref, lazy = _both_maps(how, rng, shape, chunks, dtype)
    for n in sizes:
        cells = np.column_stack([rng.integers(0, shape[0], n), rng.integers(0, shape[1], n)])
        layers = rng.integers(0, shape[2], n) if len(shape) == 3 else None
        lik = rng.dirichlet(np.ones(K), size=n) * rng.uniform(0.1, 3.0, size=(n, 1))
        ref.update(cells, lik, layers=layers)
        lazy.update(cells, lik, layers=layers)
    assert lazy.shape == ref.shape and lazy.is_voxel == ref.is_voxel
    probs = lazy.probs
    assert isinstance(probs, da.Array) and probs.chunks[:-1] == da.core.normalize_chunks(chunks, shape)
    _close(probs.compute(), ref.probs)
    np.testing.assert_array_equal(lazy.most_likely().compute(), ref.most_likely())
    p_z = lazy.source_probability(LIK, PRIOR)  # voxel maps: summed over the columns
    assert isinstance(p_z, da.Array) and p_z.shape == shape[:2]
    expected = ref.source_probability(LIK, PRIOR)
    _close(p_z.compute(), expected)
    _close(lazy.source_probability(LIK, PRIOR, normalize=False).compute(),
           ref.source_probability(LIK, PRIOR, normalize=False))
    g = rng.dirichlet(np.ones(expected.size)).reshape(expected.shape)
    fused = fuse(g, p_z)
    assert isinstance(fused, da.Array)
    _close(fused.compute(), fuse(g, expected))


def test_nothing_is_read_or_computed_until_the_result_is():
    rng = np.random.default_rng(3)
    source = RecordingArray(_beliefs(rng, (40, 30, 4)))  # a voxel map
    q = da.from_array(source, chunks=(10, 10, 4, K))
    labels = da.from_array(rng.integers(-1, 3, size=(40, 30)), chunks=10)
    g = rng.dirichlet(np.ones(1200)).reshape(40, 30)
    with CountingTasks() as counter:
        maps = [ClassBeliefMap(q, CLASSES), ClassBeliefMap.from_prior((40, 30, 4), PRIOR, CLASSES, chunks=10),
                ClassBeliefMap.from_rooms(labels, _room_table(rng, 3), PRIOR, CLASSES, layers=4)]
        results = [(m.probs, m.most_likely(), fuse(g, m.source_probability(LIK, PRIOR))) for m in maps]
    assert counter.tasks == 0 and source.reads == []
    for lazy in results:
        assert all(isinstance(r, da.Array) for r in lazy)
    with CountingTasks() as counter:
        total = results[0][2].sum().compute()
    assert counter.tasks > 0 and len(source.reads) == 12  # every chunk read once, when computed
    assert total == pytest.approx(1.0, rel=1e-12)


def test_an_update_reads_only_the_chunks_of_the_cells_it_touches_and_stays_exact():
    rng = np.random.default_rng(5)
    q = _beliefs(rng, (40, 30))
    source = RecordingArray(q)
    lazy, ref = ClassBeliefMap(da.from_array(source, chunks=(10, 10, K)), CLASSES), ClassBeliefMap(q, CLASSES)
    cells = np.array([[3, 4], [3, 4], [25, 17]])  # two chunks: (0, 0) and (2, 1)
    lik = rng.dirichlet(np.ones(K), size=3)
    for m in (lazy, ref):
        m.update(cells, lik)
    assert sorted((k[0].start, k[1].start) for k in source.reads) == [(0, 0), (20, 10)]
    source.reads.clear()
    for m in (lazy, ref):  # cells read before: from memory; (39, 29) is new, in chunk (3, 2)
        m.update([[25, 17], [39, 29]], [[0.9] + [0.1 / (K - 1)] * (K - 1)] * 2)
    assert [(k[0].start, k[1].start) for k in source.reads] == [(30, 20)]
    source.reads.clear()
    with CountingTasks() as counter:
        p_z = lazy.source_probability(LIK, PRIOR)
    assert counter.tasks == 0 and source.reads == []
    got_p, got_probs = dask.compute(p_z, lazy.probs)  # one graph: the beliefs and the semantic term
    _close(got_p, ref.source_probability(LIK, PRIOR))
    _close(got_probs, ref.probs)
    assert len(source.reads) == 12  # every chunk read once, the edited ones too


def test_many_frames_accumulate_in_log_space_as_in_the_numpy_map():
    """400 observations whose likelihood ratios (1 : 1e-3 …) take the other classes to 1e-1200, then back."""
    lazy = ClassBeliefMap.from_prior((2, 3), PRIOR, CLASSES, chunks=(1, 2))
    ref = ClassBeliefMap.from_prior((2, 3), PRIOR, CLASSES)
    oven, other = np.full(K, 1e-3), np.full(K, 1e-3)
    oven[0], other[1] = 1.0, 1.0
    for lik in (oven, other):
        for _ in range(200):
            for m in (lazy, ref):
                m.update([[1, 2], [1, 2]], np.tile(lik, (2, 1)))
    _close(lazy.probs.compute(), ref.probs)
    assert lazy.probs[1, 2, 0].compute() > 0.1  # the oven : microwave ratio came back from 1e-1200


def test_contradictory_evidence_is_refused_at_once_and_leaves_the_map_unchanged():
    prior = np.zeros(K)
    prior[:2] = 0.5
    lazy = ClassBeliefMap.from_prior((4, 4), prior, CLASSES, chunks=2)
    lazy.update([[0, 0]], [np.ones(K)])
    before = lazy.probs.compute()
    never = np.zeros(K)
    never[-1] = 1.0  # evidence only for a class the prior rules out
    with pytest.raises(ValueError, match=r"contradictory evidence at cell \(3, 1\)"):
        lazy.update([[0, 0], [3, 1]], [np.ones(K), never])
    np.testing.assert_array_equal(lazy.probs.compute(), before)
    handle = lazy.probs
    handle[0, 0] = 1.0 / K  # item assignment on the returned array leaves the map as it is
    np.testing.assert_array_equal(lazy.probs.compute(), before)


def test_bad_beliefs_raise_on_compute_with_global_cells_and_shapes_at_once():
    q = _beliefs(np.random.default_rng(1), (20, 30))
    q[17, 25, 1] = -0.25
    m = ClassBeliefMap(da.from_array(q, chunks=(6, 7, K)), CLASSES)  # no error yet: nothing was computed
    with pytest.raises(ValueError, match=r"class_probs must be non-negative .* at index \(17, 25, 1\)"):
        m.source_probability(LIK, PRIOR).compute()
    q[17, 25, 1] = 0.5
    with pytest.raises(ValueError, match=r"class_probs must sum to 1 .* at cell \(17, 25\)"):
        ClassBeliefMap(da.from_array(q, chunks=(6, 7, K)), CLASSES).probs.compute()
    with pytest.raises(ValueError, match=rf"k = {K} classes, got a dask array of shape \(4, 5, {K + 1}\)"):
        ClassBeliefMap(da.ones((4, 5, K + 1), chunks=2) / (K + 1), CLASSES)
    with pytest.raises(ValueError, match="chunks must have one entry per cell axis"):
        ClassBeliefMap.from_prior((4, 5), PRIOR, CLASSES, chunks=(2, 2, 2))
    with pytest.raises(ValueError, match=r"cells must lie inside the 4 x 5 map"):
        ClassBeliefMap.from_prior((4, 5), PRIOR, CLASSES, chunks=2).update([[4, 0]], [np.ones(K)])
    labels = da.from_array(np.array([[0, 1], [5, -1]]), chunks=1)
    table = _room_table(np.random.default_rng(2), 2)
    with pytest.raises(ValueError, match="room_class_table"):
        ClassBeliefMap.from_rooms(labels, table * 2, PRIOR, CLASSES)  # the ontology side: at once
    rooms = ClassBeliefMap.from_rooms(labels, table, PRIOR, CLASSES)  # the labels: when computed
    with pytest.raises(ValueError, match=r"room_labels must lie in \[-1, 1\]"):
        rooms.probs.compute()
    with pytest.raises(ValueError, match=r"room_labels must be an \(H, W\) map"):
        ClassBeliefMap.from_rooms(da.zeros((2, 2, 2), dtype=int, chunks=1), table, PRIOR, CLASSES)


def test_a_zarr_backed_voxel_map_end_to_end(tmp_path):
    zarr = pytest.importorskip("zarr", reason="zarr is not installed (pip install 'psgsl-pgm[dask]')")
    rng = np.random.default_rng(4)
    q = _beliefs(rng, (60, 50, 3), np.float32)  # float32 on disk, as a large map would be
    store = zarr.open_array(str(tmp_path / "beliefs.zarr"), mode="w", shape=q.shape, chunks=(16, 16, 3, K),
                            dtype="float32")
    store[:] = q
    lazy = ClassBeliefMap(da.from_zarr(str(tmp_path / "beliefs.zarr")), CLASSES)
    ref = ClassBeliefMap(q, CLASSES)
    cells, layers = np.array([[0, 0], [59, 49], [20, 33], [20, 33]]), np.array([0, 2, 1, 1])
    lik = rng.dirichlet(np.ones(K), size=4)
    for m in (lazy, ref):
        m.update(cells, lik, layers=layers)
    g = rng.dirichlet(np.ones(3000)).reshape(60, 50)
    post = fuse(g, lazy.source_probability(LIK, PRIOR))  # the columns summed, normalised, fused: all lazy
    assert isinstance(post, da.Array)
    da.to_zarr(post, str(tmp_path / "posterior.zarr"))  # streamed to disk chunk by chunk
    _close(np.asarray(zarr.open_array(str(tmp_path / "posterior.zarr"), mode="r")),
           fuse(g, ref.source_probability(LIK, PRIOR)))
    np.testing.assert_array_equal(zarr.open_array(str(tmp_path / "beliefs.zarr"), mode="r")[:], q)  # not written


@pytest.mark.slow
def test_a_chunked_map_on_a_real_scheduler_and_workers_equals_the_numpy_map(real_cluster):
    # the graphs of a chunked map (room evidence, log-space updates, lazy reductions, fusion) travel to two
    # worker processes and come back equal to the numpy map
    from distributed import Client, get_task_stream

    rng = np.random.default_rng(20)
    shape, layers = (30, 24), 3
    labels = rng.integers(-1, 3, size=shape)
    table = _room_table(rng, 3)
    ref = ClassBeliefMap.from_rooms(labels, table, PRIOR, CLASSES, layers=layers)
    lazy = ClassBeliefMap.from_rooms(da.from_array(labels, chunks=(8, 12)), table, PRIOR, CLASSES, layers=layers)
    for _ in range(3):
        cells = np.column_stack([rng.integers(0, shape[0], 5), rng.integers(0, shape[1], 5)])
        where = rng.integers(0, layers, 5)
        lik = rng.dirichlet(np.ones(K), size=5)
        ref.update(cells, lik, layers=where)
        lazy.update(cells, lik, layers=where)
    p_z = lazy.source_probability(LIK, PRIOR)
    g = rng.dirichlet(np.ones(p_z.size)).reshape(p_z.shape)
    with Client(real_cluster.address, timeout=30) as client:
        with get_task_stream(client) as stream:
            probs, most, got_p_z, fused = client.compute([lazy.probs, lazy.most_likely(), p_z, fuse(g, p_z)],
                                                         sync=True)
        pids = client.run(os.getpid)  # worker address -> pid
    ran_on = {pids[task["worker"]] for task in stream.data}
    assert len(stream.data) > 10 and ran_on <= {w.pid for w in real_cluster.workers}  # run by the workers
    _close(probs, ref.probs)
    np.testing.assert_array_equal(most, ref.most_likely())
    expected = ref.source_probability(LIK, PRIOR)
    _close(got_p_z, expected)
    _close(fused, fuse(g, expected))
