r"""Semantic maps larger than memory: the core functions on dask arrays chunked over cells.

:func:`psgsl_pgm.semantic_source_probability`, :func:`psgsl_pgm.fuse` and
:func:`psgsl_pgm.semantic_information_gain` dispatch here (one test at their top, :func:`is_dask_array`)
when an input is a ``dask.array.Array``; they then return a lazy dask array of the cells' shape, chunked like
the input. The class beliefs are never materialised: every chunk goes through the kernels of the numpy path
(eq. (20) per chunk), and whatever couples the cells — the normaliser of p(s | z), the
log-sum-exp of :func:`fuse`, the normaliser U and the entropy H(S) of the information gain — is a global dask
reduction. Only cell-sized intermediates (1/k of the beliefs: weights, log-posteriors) wait for a reduction;
dask spills them to disk if a worker's memory runs short. The information gain needs the beliefs twice and
reads them twice rather than holding them.
A zarr-backed class-belief array works as is: ``dask.array.from_zarr(store)``.

:class:`psgsl_pgm.ClassBeliefMap` builds its dask-backed maps here too: the beliefs as given (checked per chunk,
float64), the prior or the room evidence broadcast over chunked cells, and the cells an update touched spliced
into the lazy beliefs (only their chunks change; :func:`read_cells_dask` reads those cells' rows once).

Validation is lazy too: the checks of the numpy path (finite, non-negative, normalised, compatible supports)
run per chunk, or on the global reductions, when the result is computed, and raise the same ValueError
(cell indices are global). Shapes, dtypes and the ontology inputs are checked at once.

dask is imported only here, and only when a dask array arrives: the core imports without dask installed.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "broadcast_cells_dask",
    "class_beliefs_dask",
    "fresh_handle",
    "fuse_dask",
    "information_gain_dask",
    "is_dask_array",
    "read_cells_dask",
    "room_beliefs_dask",
    "semantic_source_probability_dask",
    "splice_cells_dask",
]


def is_dask_array(x) -> bool:
    """Whether ``x`` is a ``dask.array.Array`` (without importing dask)."""
    return type(x).__module__.startswith("dask.array") and hasattr(x, "chunks") and hasattr(x, "dask")


# ---------------------------------------------------------------------------------------------- helpers


def _float_dtype(x, name: str) -> np.dtype:
    """The floating dtype the numpy path would use for ``x`` (real numbers only)."""
    dt = np.dtype(x.dtype)
    if dt.kind not in "fiu":
        raise TypeError(f"{name} must be a real numeric array, got a dask array of dtype {dt}")
    return np.dtype(np.float32) if dt == np.float32 else np.dtype(np.float64)


def _offset(block_info) -> tuple:
    """Global index of a block's first element (from dask's ``block_info``)."""
    if not block_info or None not in block_info:
        return ()
    return tuple(int(lo) for lo, _ in block_info[None]["array-location"])


def _relocate(exc: ValueError, offset: tuple, cell_shape: tuple | None = None) -> ValueError:
    """Make the block-local "at cell/index (…)" of a numpy-path message global.

    With ``cell_shape`` (a class-belief chunk, which the numpy path flattens to (n, k)), the first index is the
    flat cell number within the chunk; otherwise the indices are the chunk's own.
    """
    import re

    number = r"(?<![\w.])-?\d+(?![\w.])"  # not the 64 of "np.int64(…)"

    def shift(m):
        idx = [int(v) for v in re.findall(number, m.group(2))]
        if not idx:
            return m.group(0)
        if cell_shape is not None:
            cell = np.unravel_index(idx[0], cell_shape)
            glob = [int(c) + o for c, o in zip(cell, offset)] + idx[1:]
        else:
            glob = [i + o for i, o in zip(idx, offset)] + idx[len(offset):]
        return f"{m.group(1)} {tuple(glob)}"

    return ValueError(re.sub(r"(at (?:cell|index))\s*(\((?:[^()]|\([^()]*\))*\))", shift, str(exc), count=1))


def _sum_check(total, name: str, dtype):
    """0-d block function: refuse a sum that is not 1 (as :func:`psgsl_pgm._shared._validate.check_sums`)."""
    from .._shared._validate import check_sums

    check_sums(np.asarray(total, dtype=np.float64).reshape(()), name, dtype)
    return total


def _positive_check(total, message: str):
    if not np.asarray(total).reshape(()) > 0:
        raise ValueError(message)
    return total


def _nonnegative_block(block, name: str, block_info=None):
    from .._shared._validate import check_nonnegative

    try:
        check_nonnegative(block, name)
    except ValueError as exc:
        raise _relocate(exc, _offset(block_info)) from None
    return block


def _after(x, *checks):
    """``x`` with lazy 0-d checks attached: computing ``x`` runs them first."""
    import dask.array as da

    for check in checks:
        x = da.map_blocks(_first, x, check, dtype=x.dtype, meta=np.empty((0,) * x.ndim, dtype=x.dtype))
    return x


def _first(block, *checked):
    return block


def _recomputed(x, after):
    """``x`` recomputed from its sources once ``after`` is known.

    For a second pass over the class beliefs: without this, dask would keep every chunk that feeds the first
    pass's global reduction in memory until the reduction is done — the whole (k times larger) map.
    """
    from dask.graph_manipulation import bind

    return bind(x, after)


def _as_dask(x, name: str, like):
    """A dask array of ``like``'s shape and chunks from ``x`` (numpy or dask), validated lazily (non-negative)."""
    import dask.array as da

    arr = x if is_dask_array(x) else da.from_array(np.asarray(x), chunks=like.chunks)
    _float_dtype(arr, name)
    if arr.shape != like.shape:
        raise ValueError(f"{name} must have the cells' shape {like.shape}, got a dask array of shape {arr.shape}")
    if arr.chunks != like.chunks:
        arr = arr.rechunk(like.chunks)
    return arr.map_blocks(_nonnegative_block, name, dtype=arr.dtype)


def _class_chunks(q, k: int, name: str):
    """Validate the (..., k) shape of a dask class-belief array and put the class axis in one chunk."""
    if q.ndim < 2:
        raise ValueError(f"{name} must have cell axes before the class axis, shape (..., {k}); got {q.shape}")
    if q.shape[-1] != k:
        raise ValueError(f"{name} must have {k} classes on its last axis, got a dask array of shape {q.shape}")
    if q.numblocks[-1] != 1:
        q = q.rechunk({q.ndim - 1: -1})
    return q


# ------------------------------------------------------------------------------------- p(s | z)


def _semantic_block(q, lik, prior, gas, validate, block_info=None):
    """w_c = Σ_i p(o_ci|z_c) ρ_i (float64) on one chunk, with the kernel and checks of the numpy path."""
    from ..kernels._belief import belief_weights
    from ._beliefs_check import check_belief_stats
    from ._ratios import class_ratio

    ratio = class_ratio(lik, prior, gas)
    q2 = np.ascontiguousarray(q.reshape(-1, q.shape[-1]))
    w, stats = belief_weights(q2, ratio.rho, ratio.zero_prior.astype(np.float64))
    if validate:
        try:
            check_belief_stats(q2, stats, ratio.zero_prior)
        except ValueError as exc:
            raise _relocate(exc, _offset(block_info), q.shape[:-1]) from None
    return np.asarray(w, dtype=np.float64).reshape(q.shape[:-1])


def semantic_weights_dask(class_probs, source_likelihood, class_prior, *, gas_probs=None, validate=True):
    """Per-cell weights w_c = Σ_i p(o_ci|z_c) ρ_i (lazy, float64: the numpy path rounds once, at the end)."""
    import dask.array as da

    from ._ratios import class_ratio

    ratio = class_ratio(source_likelihood, class_prior, gas_probs)  # the ontology side: small, checked now
    dtype = _float_dtype(class_probs, "class_probs")
    q = _class_chunks(class_probs, ratio.k, "class_probs")
    lik = np.asarray(source_likelihood, dtype=np.float64)
    gas = None if gas_probs is None else np.asarray(gas_probs, dtype=np.float64)
    prior = np.asarray(class_prior, dtype=np.float64)
    return da.map_blocks(_semantic_block, q, lik, prior, gas, validate, drop_axis=q.ndim - 1, dtype=np.float64,
                         meta=np.empty((0,) * (q.ndim - 1)))


def semantic_source_probability_dask(class_probs, source_likelihood, class_prior, *, gas_probs=None,
                                     column_axis=None, normalize=True, source_prior=None, validate=True):
    """:func:`psgsl_pgm.semantic_source_probability` for a dask ``class_probs``; returns a lazy dask array."""
    import dask.array as da

    from ._columns import column_sum

    dtype = _float_dtype(class_probs, "class_probs")  # float32 in, float32 out (rounded once, at the end)
    weights = semantic_weights_dask(class_probs, source_likelihood, class_prior, gas_probs=gas_probs,
                                    validate=validate)
    if source_prior is not None:
        prior = _as_dask(source_prior, "source_prior", weights).astype(np.float64)
        total = da.map_blocks(_sum_check, prior.sum(dtype=np.float64), "source_prior", _float_dtype(
            source_prior, "source_prior"), dtype=np.float64)
        weights = _after(weights * prior, total)  # p(s_c) p(z | s_c)
    weights = column_sum(weights, column_axis, weights.ndim)  # Σ_{v∈c} p(s_v | z): a dask reduction
    if not normalize:
        return weights.astype(dtype)
    total = da.map_blocks(
        _positive_check, weights.sum(dtype=np.float64),
        "no cell can hold the source: every cell's class beliefs (times source_prior) give zero weight to the "
        "classes that source_likelihood allows", dtype=np.float64)
    # the global normaliser: one reduction over all chunks (the weights, 1/k of the beliefs, wait for it)
    return (weights / total).astype(dtype)


# ---------------------------------------------------------------------------------------------- fuse


def _log_block(*blocks, m: int, has_prior: bool, block_info=None):
    """Σ_j log p(s|e_j) − (m−1) log p(s) on one chunk, as in the numpy path of :func:`fuse`."""
    arrays = blocks[:m]
    with np.errstate(divide="ignore", invalid="ignore"):
        log_p = np.sum([np.log(a, dtype=np.float64) for a in arrays], axis=0)
        if has_prior:
            pr = np.asarray(blocks[m], dtype=np.float64)
            support = np.isfinite(log_p)
            if np.any(support & (pr == 0)):
                cell = np.argwhere(support & (pr == 0))[0] + np.array(_offset(block_info) or 0)
                raise ValueError(f"prior is zero at cell {tuple(int(i) for i in cell)} where every posterior is "
                                 "positive")
            log_p = np.where(support, log_p - (m - 1) * np.log(pr), -np.inf)
    return log_p


def _exp_block(log_p, norm, dtype):
    with np.errstate(invalid="ignore"):
        return np.exp(log_p - norm).astype(dtype, copy=False)


def _lse_block(log_p, *posteriors):
    """One chunk's (max log p, Σ exp(log p − max), then Σ p_j for every posterior): shape (1,)*ndim + (2 + m,)."""
    mx = np.max(log_p)
    with np.errstate(invalid="ignore"):
        s = np.sum(np.exp(log_p - mx)) if np.isfinite(mx) else 0.0
    sums = [np.sum(p, dtype=np.float64) for p in posteriors]
    return np.array([mx, s, *sums]).reshape((1,) * log_p.ndim + (2 + len(posteriors),))


def _norm_check(parts, *overlaps, m: int, names: tuple, dtypes: tuple):
    """log Σ_c exp(log p_c) from the chunks' partial results of :func:`_lse_block`, after the numpy path's
    checks of :func:`psgsl_pgm.fuse`: every input sums to 1; a conflict (−inf) names the disjoint pair."""
    from .._shared._validate import check_sums

    parts = np.asarray(parts, dtype=np.float64).reshape(-1, 2 + len(names))
    for j, (name, dt) in enumerate(zip(names, dtypes)):
        check_sums(parts[:, 2 + j].sum(), name, dt, over="over all cells")
    mx = parts[:, 0].max()
    if not np.isfinite(mx):
        for (i, j), overlap in zip(_pairs(m), overlaps):
            if not bool(np.asarray(overlap).reshape(())):
                raise ValueError(f"the posteriors conflict: posteriors[{i}] and posteriors[{j}] have no cell where "
                                 "both are positive, so their product is zero everywhere")
        raise ValueError("the posteriors conflict: their product is zero in every cell (no single cell is positive "
                         "in all)")
    finite = np.isfinite(parts[:, 0])
    return np.asarray(np.log(np.sum(parts[finite, 1] * np.exp(parts[finite, 0] - mx))) + mx)


def _pairs(m: int):
    return [(i, j) for i in range(m) for j in range(i + 1, m)]


def fuse_dask(*posteriors, prior=None):
    """:func:`psgsl_pgm.fuse` when a posterior (or the prior) is a dask array; returns a lazy dask array.

    One pass over the inputs gives the log-sum-exp normaliser and every input's sum (checked to be 1); the
    log-posterior chunks (cell-sized, like the inputs) wait for it and are then exponentiated.
    """
    import dask.array as da

    first = next(p for p in (*posteriors, prior) if is_dask_array(p))
    if first.ndim < 1:
        raise ValueError(f"posteriors must have at least 1 dimension(s), got a dask array of shape {first.shape}")
    arrays, names = [], []
    for j, p in enumerate(posteriors):
        if not (is_dask_array(p) or np.shape(p) == first.shape):
            raise ValueError(f"posteriors[{j}] must have the shape of posteriors[0], {first.shape}, got shape "
                             f"{np.shape(p)}")
        arrays.append(_as_dask(p, f"posteriors[{j}]", first))
        names.append(f"posteriors[{j}]")
    dtypes = [_float_dtype(a, n) for a, n in zip(arrays, names)]
    out_dtype = np.float32 if all(a.dtype == np.float32 for a in arrays) else np.float64
    extra = []
    if prior is not None:
        extra = [_as_dask(prior, "prior", first).astype(np.float64)]
        names.append("prior")
        dtypes.append(np.dtype(np.float64))
    m = len(arrays)
    log_p = da.map_blocks(_log_block, *arrays, *extra, m=m, has_prior=prior is not None, dtype=np.float64)
    width = 2 + len(names)
    parts = da.map_blocks(_lse_block, log_p, *arrays, *extra, new_axis=log_p.ndim, dtype=np.float64,
                          chunks=(*((1,) * len(c) for c in log_p.chunks), (width,)))
    overlaps = [((arrays[i] > 0) & (arrays[j] > 0)).any() for i, j in _pairs(m)]  # only read on a conflict
    norm = da.map_blocks(_norm_check, parts.rechunk(-1), *overlaps, m=m, names=tuple(names), dtypes=tuple(dtypes),
                         drop_axis=tuple(range(parts.ndim)), chunks=(), dtype=np.float64)
    return da.map_blocks(_exp_block, log_p, norm, out_dtype, dtype=out_dtype)


# ---------------------------------------------------------------------------------- information gain


def _gain_inputs(lik, prior, gas):
    """ρ, ρ log ρ and the zero-prior mask, as the numpy path of the information gain builds them."""
    from scipy.special import xlogy

    from ._ratios import class_ratio

    ratio = class_ratio(lik, prior, gas)
    return ratio.rho, xlogy(ratio.rho, ratio.rho), ratio.zero_prior.astype(np.float64)


def _validated_block(q, lik, prior, gas, block_info=None):
    """The numpy path's checks of one class-belief chunk (messages with global cell indices); returns it."""
    _semantic_block(q, lik, prior, gas, True, block_info=block_info)
    return q


def _olfactory_chunk(f, n: int):
    """The kernels' olfactory arguments for one chunk: (f flat, 0) or (empty, 1/n) for the uniform prior."""
    if f is None:
        return np.empty(0), 1.0 / n
    return np.ascontiguousarray(f, dtype=np.float64).reshape(-1), 0.0


def _gain_totals_block(q, f, lik, prior, gas, n):
    """Partial sums of U = Σ f_c w_c and Σ xlogy(f_c w_c, f_c w_c) over one chunk: shape (1,)*ndim + (2,)."""
    from scipy.special import xlogy

    from ..kernels._belief import belief_moments

    rho, rho_log_rho, zero = _gain_inputs(lik, prior, gas)
    fc, fu = _olfactory_chunk(f, n)
    # the same w_n as the numpy path's (belief_weights accumulates differently for float32 beliefs)
    w, _, _ = belief_moments(np.ascontiguousarray(q.reshape(-1, q.shape[-1])), rho, rho_log_rho, zero, fc, fu, False)
    fw = (fc if fc.size else fu) * np.asarray(w, dtype=np.float64)
    return np.array([fw.sum(), xlogy(fw, fw).sum()]).reshape((1,) * (q.ndim - 1) + (2,))


def _gain_block(q, f, totals, lik, prior, gas, predictive, n, radius):
    """I(S; O_n) on one chunk given the map's U and H(S), with the kernels of the numpy path."""
    from ..kernels._belief import belief_moments, gain_from_moments

    rho, rho_log_rho, zero = _gain_inputs(lik, prior, gas)
    q2 = np.ascontiguousarray(q.reshape(-1, q.shape[-1]))
    fc, fu = _olfactory_chunk(f, n)
    paper = predictive == "paper"
    w, moments, _ = belief_moments(q2, rho, rho_log_rho, zero, fc, fu, paper)  # checked in the first pass
    total, entropy = float(totals[0]), float(totals[1]) if paper else 0.0
    gain = gain_from_moments(q2, w, moments, fc, fu, total, rho, rho_log_rho, entropy, radius, paper)
    return gain.reshape(q.shape[:-1])


def _entropy(parts):
    """(U, H(S)) from Σ f w and Σ xlogy(f w, f w): p = f w / U, H = log U − Σ f w log(f w) / U."""
    total = parts[0]
    if not total > 0:
        raise ValueError("olfactory and the semantic term have no cell in common: their fusion is zero everywhere")
    return np.array([total, np.log(total) - parts[1] / total])


def information_gain_dask(class_probs, source_likelihood, class_prior, *, olfactory=None, gas_probs=None,
                          predictive="paper", validate=True, radius):
    """:func:`psgsl_pgm.semantic_information_gain` for a dask ``class_probs``: a lazy float64 dask array.

    ``radius`` is the numpy path's series radius (where the moment series replaces the element-wise sum),
    handed in by the public function so that both paths use one value.

    Two passes over the beliefs: one global reduction for U = Σ_c f_c w_c and H(S), then the per-cell gain of
    every chunk with the kernels of the numpy path (:mod:`psgsl_pgm.kernels._belief`, as :mod:`psgsl_pgm.core._infogain`
    calls them).
    """
    import dask.array as da

    from ._ratios import class_ratio

    if predictive not in ("paper", "exact"):
        raise ValueError(f"predictive must be 'paper' or 'exact', got {predictive!r}")
    ratio = class_ratio(source_likelihood, class_prior, gas_probs)
    _float_dtype(class_probs, "class_probs")
    q = _class_chunks(class_probs, ratio.k, "class_probs")
    cell_shape, ndim = q.shape[:-1], q.ndim - 1
    n = int(np.prod(cell_shape))
    like = da.zeros(cell_shape, chunks=q.chunks[:-1], dtype=np.float64)
    lik = np.asarray(source_likelihood, dtype=np.float64)
    gas = None if gas_probs is None else np.asarray(gas_probs, dtype=np.float64)
    prior = np.asarray(class_prior, dtype=np.float64)
    checked = q.map_blocks(_validated_block, lik, prior, gas, dtype=q.dtype) if validate else q
    if olfactory is None:
        f, f_index = None, None
    else:
        f = _as_dask(olfactory, "olfactory", like).astype(np.float64)
        f = _after(f, da.map_blocks(_sum_check, f.sum(dtype=np.float64), "olfactory", np.float64, dtype=np.float64))
        f_index = tuple(range(ndim))
    cells, cls, two = tuple(range(ndim)), ndim, ndim + 1
    parts = da.blockwise(_gain_totals_block, cells + (two,), checked, cells + (cls,), f, f_index, lik, None, prior,
                         None, gas, None, n, None, new_axes={two: 2}, adjust_chunks={i: 1 for i in cells},
                         concatenate=True, dtype=np.float64, meta=np.empty((0,) * (ndim + 1)))
    totals = da.map_blocks(_entropy, parts.sum(axis=cells), dtype=np.float64)  # (U, H(S)): global reductions
    q2 = _recomputed(q, totals)  # the second pass reads the beliefs again; f (cell-sized) is kept
    return da.blockwise(_gain_block, cells, q2, cells + (cls,), f, f_index, totals, (two,), lik, None, prior, None,
                        gas, None, predictive, None, n, None, radius, None, concatenate=True, dtype=np.float64,
                        meta=np.empty((0,) * ndim))


# ------------------------------------------------------------------------------------ class-belief maps


def _dask_array_module():
    """``dask.array``, or a ModuleNotFoundError naming the extra that provides it."""
    try:
        import dask.array as da
    except ModuleNotFoundError:
        raise ModuleNotFoundError("a chunked (dask-backed) class-belief map needs dask: "
                                  "pip install 'psgsl-pgm[dask]'") from None
    return da


def _cell_chunks(chunks, shape: tuple) -> tuple:
    """dask chunks of the cell axes ``shape`` from ``chunks`` (an int for every axis, or one entry per axis)."""
    da = _dask_array_module()
    if isinstance(chunks, (bool, np.bool_)) or not isinstance(chunks, (int, np.integer, str, tuple)):
        raise TypeError(f"chunks must be an int or a tuple with one entry per cell axis {shape}, got {chunks!r}")
    if isinstance(chunks, tuple) and len(chunks) != len(shape):
        raise ValueError(f"chunks must have one entry per cell axis {shape}, got {chunks!r}")
    return da.core.normalize_chunks(chunks, shape, dtype=np.float64)


def _distribution_block(block, name: str, block_info=None):
    """One chunk checked as the numpy path's :func:`psgsl_pgm._shared._validate.distribution` does, then float64."""
    from .._shared._validate import distribution

    try:
        arr = distribution(block, name)
    except ValueError as exc:
        raise _relocate(exc, _offset(block_info)) from None
    return arr.astype(np.float64)


def class_beliefs_dask(class_probs, name: str):
    """Class beliefs (..., k) as :class:`psgsl_pgm.ClassBeliefMap` holds them, lazily: float64, the class axis in
    one chunk, every chunk checked when computed (finite, non-negative, normalised; global cell indices)."""
    _float_dtype(class_probs, name)
    q = _class_chunks(class_probs, class_probs.shape[-1], name)
    return q.map_blocks(_distribution_block, name, dtype=np.float64, meta=np.empty((0,) * q.ndim))


def broadcast_cells_dask(row: np.ndarray, shape: tuple, chunks):
    """``row`` (k,) in every cell of ``shape``: a lazy (*shape, k) dask array chunked over the cells."""
    da = _dask_array_module()
    cells = _cell_chunks(chunks, shape)
    return da.broadcast_to(row, shape + row.shape, chunks=cells + (row.shape,))


def _room_block(labels, table, prior, block_info=None):
    """p(o | room_c) on one chunk of room labels, as the numpy path of ClassBeliefMap.from_rooms computes it."""
    from ._beliefs import room_evidence, update_class_probs

    try:
        return update_class_probs(prior, room_evidence(labels, table, prior))
    except ValueError as exc:
        raise _relocate(exc, _offset(block_info)) from None


def room_beliefs_dask(room_labels, room_table, class_prior: np.ndarray, *, layers: int | None, chunks):
    """p(o | room_c) over a room-label map, lazily: (H, W, k), or (H, W, L, k) with ``layers``.

    ``room_labels`` is a dask array (chunked over cells; ``chunks`` rechunks it) or, with ``chunks``, an array
    that fits. The ontology side (``room_table`` against ``class_prior``) is checked at once; the labels per chunk.
    """
    from .._shared._validate import as_float_array
    from ._beliefs import room_evidence

    da = _dask_array_module()
    table = as_float_array(room_table, "room_class_table", dtype=np.float64, ndim=2)
    room_evidence(np.array([-1]), table, class_prior)  # the table, the prior and their compatibility, now
    labels = room_labels if is_dask_array(room_labels) else np.asarray(room_labels)
    if labels.ndim != 2:
        raise ValueError(f"room_labels must be an (H, W) map, got shape {labels.shape}")
    if np.dtype(labels.dtype).kind not in "iuf":
        raise TypeError(f"room_labels must be integer room indices (-1 = none), got an array of dtype {labels.dtype}")
    shape = labels.shape + (() if layers is None else (layers,))
    if chunks is not None:
        cells = _cell_chunks(chunks, shape)
    else:
        cells = labels.chunks + (() if layers is None else ((layers,),))
    labels = labels.rechunk(cells[:2]) if is_dask_array(labels) else da.from_array(labels, chunks=cells[:2])
    k = table.shape[1]
    probs = labels.map_blocks(_room_block, table, class_prior, new_axis=2, chunks=labels.chunks + ((k,),),
                              dtype=np.float64, meta=np.empty((0, 0, 0)))
    if layers is None:
        return probs
    return da.broadcast_to(probs[:, :, None, :], shape + (k,), chunks=cells + ((k,),))


def read_cells_dask(x, cells: tuple) -> np.ndarray:
    """The class rows (n, k) of some cells of a dask (..., k) array: computes only the chunks holding them."""
    return np.asarray(x.vindex[tuple(np.asarray(i, dtype=np.intp) for i in cells)].compute(), dtype=np.float64)


def _splice_block(block, edits, block_id=None):
    edit = edits.get(block_id[:-1])
    if edit is None:
        return block
    out = block.copy()
    out[edit[0]] = edit[1]
    return out


def splice_cells_dask(x, cells: tuple, rows: np.ndarray):
    """``x`` (..., k) with the class rows of ``cells`` (one index array per cell axis) replaced by ``rows``
    (n, k), lazily: the chunks that hold none of them pass through unchanged."""
    starts = [np.cumsum((0,) + c) for c in x.chunks[:-1]]
    block = [np.searchsorted(s, i, side="right") - 1 for s, i in zip(starts, cells)]
    local = [i - s[b] for i, s, b in zip(cells, starts, block)]
    ids = np.ravel_multi_index(block, x.numblocks[:-1])
    order = np.argsort(ids, kind="stable")
    blocks, first = np.unique(ids[order], return_index=True)
    edits = {}
    for b, sel in zip(blocks, np.split(order, first[1:])):  # the edits of each chunk that has some
        edits[tuple(int(i) for i in np.unravel_index(b, x.numblocks[:-1]))] = (tuple(i[sel] for i in local), rows[sel])
    return x.map_blocks(_splice_block, edits, dtype=x.dtype, meta=np.empty((0,) * x.ndim, dtype=x.dtype))


def fresh_handle(x):
    """A new dask Array object on ``x``'s graph (item assignment on it leaves ``x`` as it is)."""
    da = _dask_array_module()
    return da.Array(x.dask, x.name, x.chunks, meta=x)
