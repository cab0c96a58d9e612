r"""The robot's class beliefs :math:`p(o_c \mid z_c)`: a dense map over cells or voxels, updated frame by frame.

Beliefs start from the class prior :math:`p(o)` — optionally times the room-category evidence
:math:`p(o \mid \text{room}) / p(o)` of :func:`psgsl_pgm.room_evidence` — and every observation of a cell
multiplies in its likelihood :math:`p(z \mid o)` (Bayes' rule, :func:`psgsl_pgm.update_class_probs`; the paper's
:math:`Z_c \mid O_c` of Sec. "Model"):

.. math:: p(o_c \mid z_c, z') \propto p(o_c \mid z_c)\, p(z' \mid o_c).

The map accumulates :math:`\log p(o_c \mid z_c)` up to a per-cell constant, so that thousands of frames neither
underflow nor lose the ratios between unlikely classes; :attr:`ClassBeliefMap.probs` is kept normalised
for the cells each frame touches. A voxel map (H, W, L, k) reduces to the 2-D cells of the olfactory grid
with :meth:`ClassBeliefMap.source_probability` (the paper's Sec. "Voxelized Scene Representations").

A map can be backed by a dask array chunked over the cells (e.g. a zarr store, ``dask.array.from_zarr``):
its beliefs, columns and p(s | z) are then lazy dask arrays (:class:`ClassBeliefMap`, Notes).

Data flow: maps and frames (cells + likelihood vectors, e.g. from ``psgsl_pgm.sim.take_frame``) → this map
→ :func:`psgsl_pgm.semantic_source_probability` → :func:`psgsl_pgm.fuse`.
"""

from __future__ import annotations

import numpy as np

from .._shared._validate import as_float_array, check_last_axis, check_nonnegative, describe, distribution, index
from ..kernels._logsumexp import logsumexp
from . import _dask_arrays
from ._beliefs import room_evidence, update_class_probs
from ._dask_arrays import is_dask_array
from ._semantic import semantic_source_probability

__all__ = ["ClassBeliefMap"]


def _class_names(classes) -> tuple[str, ...]:
    if isinstance(classes, (str, bytes)) or not hasattr(classes, "__iter__"):
        raise TypeError(f"classes must be a sequence of class names, got {type(classes).__name__} {classes!r}")
    names = tuple(classes)
    if not all(isinstance(c, str) for c in names):
        raise TypeError(f"classes must be a sequence of str, got {names!r}")
    if len(set(names)) != len(names) or len(names) < 1:
        raise ValueError(f"classes must be distinct names, got {names!r}")
    return names


class ClassBeliefMap:
    r"""Dense per-cell (or per-voxel) class beliefs :math:`p(o_c \mid z_c)`.

    Beliefs start from the class prior :math:`p(o)` (or the room evidence of :meth:`from_rooms`), and every
    observation :math:`z'` of a cell multiplies in its likelihood (Bayes' rule, as
    :func:`psgsl_pgm.update_class_probs`):

    .. math:: p(o_c \mid z_c, z') \propto p(o_c \mid z_c)\, p(z' \mid o_c)

    :meth:`source_probability` turns the beliefs into the semantic term :math:`p(s_c \mid z)`.

    Parameters
    ----------
    class_probs : (H, W, k) or (H, W, L, k) array_like or dask array
        Initial beliefs; every cell (voxel) sums to 1 (tolerance of the core: 1e-6 in float64, 1e-4 in
        float32). Held in float64. A ``dask.array.Array`` chunked over the cells (e.g.
        ``dask.array.from_zarr``) makes a dask-backed map (see Notes).
    classes : sequence of str
        The k class names, in the order of the last axis (decided once by the caller, e.g. the experiment).

    Attributes
    ----------
    classes : tuple of str
    n_frames : int
        Frames applied with :meth:`observe`.

    Notes
    -----
    **Dask-backed maps** (maps larger than memory; needs the ``dask`` extra). Built from a dask
    ``class_probs``, from ``from_prior(..., chunks=...)`` or from ``from_rooms`` with a dask ``room_labels``
    or ``chunks``, the map never materialises its beliefs: :attr:`probs`, :meth:`most_likely` and
    :meth:`source_probability` return lazy dask arrays chunked over the cells (the voxel columns and the
    normaliser of :math:`p(s \mid z)` are dask reductions, see :mod:`psgsl_pgm.core._dask_arrays`), ready for
    :func:`psgsl_pgm.fuse`. The beliefs given are checked chunk by chunk when computed. :meth:`update` and
    :meth:`observe` work as on a numpy map (same log-space arithmetic, same errors, raised at once, the map
    unchanged on error): the first update of a cell reads its row — one compute of the chunks holding the
    cells, nothing else — and the updated cells are then kept in memory and spliced into the lazy beliefs.
    That suits a few frames on a large map; a robot mapping frame by frame over a map that fits keeps the
    numpy map (the fast path).

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm import ClassBeliefMap
    >>> m = ClassBeliefMap.from_prior((2, 3), [0.5, 0.5], ("oven", "other"))
    >>> m.update([[0, 1]], [[0.8, 0.2]])                 # one observation of cell (0, 1)
    >>> m.probs[0, 1].round(6).tolist(), m.probs[0, 0].tolist()
    ([0.8, 0.2], [0.5, 0.5])

    The same map chunked over its cells (a dask array, e.g. ``dask.array.from_zarr(store)``, works alike):

    >>> d = ClassBeliefMap.from_prior((2, 3), [0.5, 0.5], ("oven", "other"), chunks=(1, 3))
    >>> d.update([[0, 1]], [[0.8, 0.2]])
    >>> p = d.source_probability([0.9, 0.1], [0.5, 0.5])  # lazy: a dask array, nothing computed yet
    >>> type(p).__name__, p.compute().round(4).tolist()
    ('Array', [[0.1543, 0.2284, 0.1543], [0.1543, 0.1543, 0.1543]])
    """

    def __init__(self, class_probs, classes):
        self.classes = _class_names(classes)
        self.n_frames = 0
        if is_dask_array(class_probs):  # chunked over cells, lazy: psgsl_pgm.core._dask_arrays
            self._init_dask(class_probs)
            return
        p = distribution(class_probs, "class_probs").astype(np.float64)
        if p.ndim not in (3, 4) or p.shape[-1] != len(self.classes):
            raise ValueError(
                f"class_probs must have shape (H, W, k) or (H, W, L, k) with k = {len(self.classes)} classes, "
                f"got {describe(p)}"
            )
        p = np.array(p, dtype=np.float64)  # own copy, as given (within the tolerance; cells renormalise on update)
        with np.errstate(divide="ignore"):
            self._log = np.log(p)  # log p(o_c | z_c), exact up to a per-cell constant
        self._probs = p

    def _init_dask(self, class_probs) -> None:
        if class_probs.ndim not in (3, 4) or class_probs.shape[-1] != len(self.classes):
            raise ValueError(
                f"class_probs must have shape (H, W, k) or (H, W, L, k) with k = {len(self.classes)} classes, "
                f"got a dask array of shape {class_probs.shape}"
            )
        self._probs = _dask_arrays.class_beliefs_dask(class_probs, "class_probs")  # as given, checked per chunk
        self._log = None  # read at the cells an update touches, then kept with them in the edits
        self._edit_cells = np.zeros(0, dtype=np.intp)  # flat indices of the updated cells (voxels), sorted
        self._edit_log = np.zeros((0, len(self.classes)))  # their log p(o_c | z_c), normalised
        self._edit_probs = np.zeros((0, len(self.classes)))  # their p(o_c | z_c)
        self._spliced = self._probs  # the beliefs with the edits in: lazy, rebuilt after each update

    # --- construction ---------------------------------------------------------------------------------------
    @classmethod
    def from_prior(cls, shape, class_prior, classes, *, chunks=None) -> "ClassBeliefMap":
        r"""Every cell (voxel) at the class prior :math:`p(o)`.

        Parameters
        ----------
        shape : (2,) or (3,) tuple of int
            (H, W) or (H, W, L).
        class_prior : (k,) array_like
            p(o).
        classes : sequence of str
        chunks : int or tuple, optional, keyword-only
            A dask-backed map chunked over the cells like this (an int for every cell axis, or one entry per
            cell axis, as ``dask.array`` takes them); needs dask. Nothing is allocated until it is computed.
        """
        prior = distribution(class_prior, "class_prior", ndim=1)
        dims = tuple(index(s, "shape entries", minimum=1) for s in _shape_tuple(shape))
        if chunks is not None:
            return cls(_dask_arrays.broadcast_cells_dask(prior.astype(np.float64), dims, chunks), classes)
        return cls(np.broadcast_to(prior.astype(np.float64), dims + prior.shape), classes)

    @classmethod
    def from_rooms(cls, room_labels, room_table, class_prior, classes, *, layers: int | None = None,
                   chunks=None) -> "ClassBeliefMap":
        r"""Beliefs conditioned on a room-category map: :math:`p(o \mid \text{room}_c)` (the prior where the label
        is -1).

        Parameters
        ----------
        room_labels : (H, W) array_like of int
            Room index into the rows of ``room_table``; -1 = no room evidence.
        room_table : (r, k) array_like
            :math:`p(o \mid \text{room})`, rows in the order of the labels, columns in the order of ``classes``.
        class_prior : (k,) array_like
            p(o).
        classes : sequence of str
        layers : int, optional, keyword-only
            A voxel map with this many layers (the same room evidence in every layer).
        chunks : int or tuple, optional, keyword-only
            A dask-backed map chunked over the cells like this (one entry per cell axis of the map: (H, W), or
            (H, W, L) with ``layers``); needs dask. A dask ``room_labels`` gives a dask-backed map too, chunked
            like the labels (and whole layer columns) unless ``chunks`` says otherwise. The room table is checked
            at once, the labels chunk by chunk when the map is computed.
        """
        prior = distribution(class_prior, "class_prior", ndim=1)
        if chunks is not None or is_dask_array(room_labels):
            n = None if layers is None else index(layers, "layers", minimum=1)
            return cls(_dask_arrays.room_beliefs_dask(room_labels, room_table, prior.astype(np.float64), layers=n,
                                                      chunks=chunks), classes)
        factor = room_evidence(room_labels, room_table, prior)  # p(o | r) / p(o)
        probs = update_class_probs(prior.astype(np.float64), factor)
        if probs.ndim != 3:
            raise ValueError(f"room_labels must be an (H, W) map, got shape {probs.shape[:-1]}")
        if layers is not None:
            n = index(layers, "layers", minimum=1)
            probs = np.repeat(probs[:, :, None, :], n, axis=2)
        return cls(probs, classes)

    # --- state ----------------------------------------------------------------------------------------------
    @property
    def probs(self) -> np.ndarray:
        """(H, W, k) or (H, W, L, k) float64: p(o_c | z_c), normalised per cell (read-only view; for a
        dask-backed map a lazy dask array, chunked over the cells with the class axis in one chunk)."""
        if self._log is None:
            return _dask_arrays.fresh_handle(self._spliced)
        view = self._probs.view()
        view.flags.writeable = False
        return view

    @property
    def shape(self) -> tuple[int, ...]:
        """(H, W) or (H, W, L): the cells (voxels)."""
        return self._probs.shape[:-1]

    @property
    def is_voxel(self) -> bool:
        """Whether the map holds voxels (H, W, L)."""
        return self._probs.ndim == 4

    def most_likely(self) -> np.ndarray:
        """(H, W) or (H, W, L) int: arg max class per cell (voxel); lazy for a dask-backed map."""
        if self._log is None:
            return self._spliced.argmax(axis=-1)
        return self._probs.argmax(axis=-1)

    # --- updates --------------------------------------------------------------------------------------------
    def update(self, cells, likelihood, *, layers=None) -> None:
        """Multiply observation likelihoods into the beliefs of the observed cells (voxels).

        Parameters
        ----------
        cells : (n, 2) array_like of int
            (row, col) of each observation.
        likelihood : (n, k) array_like
            p(z_j | o) of each observation over the map's classes (any positive scale per row).
        layers : (n,) array_like of int, optional, keyword-only
            Voxel layer of each observation (voxel maps only, and required there).

        A cell observed several times in one call gets every likelihood (observations are conditionally
        independent given the class). Evidence of probability zero under every class a cell still allows is
        a :class:`ValueError`, and the map is left unchanged.
        """
        self._apply(cells, likelihood, layers)

    def _apply(self, cells, likelihood, layers) -> None:
        rc = _as_cells(cells, "cells")
        k = len(self.classes)
        lik = as_float_array(likelihood, "likelihood", dtype=np.float64, ndim=2)
        check_last_axis(lik, "likelihood", k)
        if lik.shape[0] != rc.shape[0]:
            raise ValueError(f"likelihood must have one row per cell ({rc.shape[0]}), got {describe(lik)}")
        if (layers is not None) != self.is_voxel:
            raise ValueError("voxel observations (layers) need a voxel map and 2-D observations a 2-D map")
        if rc.shape[0] == 0:
            return
        check_nonnegative(lik, "likelihood")
        scale = lik.max(axis=1, keepdims=True)
        if np.any(scale == 0):
            raise ValueError(f"likelihood is zero for every class in row {int(np.argmin(scale[:, 0]))}")
        bounds = self.shape[:2]
        if rc.min() < 0 or (rc >= np.array(bounds)).any():
            raise ValueError(f"cells must lie inside the {bounds[0]} x {bounds[1]} map")
        idx = (rc[:, 0], rc[:, 1])
        if self.is_voxel:
            lay = _as_cells(layers, "layers", ndim=1)
            if lay.shape != (rc.shape[0],):
                raise ValueError(f"layers must have one entry per cell ({rc.shape[0]}), got shape {lay.shape}")
            if lay.min() < 0 or lay.max() >= self.shape[2]:
                raise ValueError(f"layers must lie in [0, {self.shape[2]}), got range [{lay.min()}, {lay.max()}]")
            idx = idx + (lay,)
        with np.errstate(divide="ignore"):
            loglik = np.log(lik / scale)
        flat = np.ravel_multi_index(idx, self.shape)
        touched, inverse = np.unique(flat, return_inverse=True)
        add = np.zeros((touched.size, k))
        np.add.at(add, inverse, loglik)  # several observations of one cell: their product
        if self._log is None:
            self._apply_dask(touched, add)
            return
        log_flat = self._log.reshape(-1, k)
        new = _posterior_log(log_flat[touched], add, touched, self.shape)
        log_flat[touched] = new
        self._probs.reshape(-1, k)[touched] = np.exp(new)

    def _apply_dask(self, touched: np.ndarray, add: np.ndarray) -> None:
        """The log-space update of a dask-backed map: the touched cells' rows, read once, then kept as edits."""
        known = self._edit_cells
        pos = np.searchsorted(known, touched)
        hit = pos < known.size
        hit[hit] = known[pos[hit]] == touched[hit]
        old = np.empty(add.shape)
        old[hit] = self._edit_log[pos[hit]]
        fresh = touched[~hit]
        if fresh.size:  # cells no update touched before: their rows as given (one compute of their chunks)
            rows = _dask_arrays.read_cells_dask(self._probs, np.unravel_index(fresh, self.shape))
            with np.errstate(divide="ignore"):
                old[~hit] = np.log(rows)
        new = _posterior_log(old, add, touched, self.shape)  # raises before anything changes
        probs = np.exp(new)
        self._edit_log[pos[hit]] = new[hit]
        self._edit_probs[pos[hit]] = probs[hit]
        if fresh.size:
            cells = np.concatenate([known, fresh])
            order = np.argsort(cells, kind="stable")
            self._edit_cells = cells[order]
            self._edit_log = np.concatenate([self._edit_log, new[~hit]])[order]
            self._edit_probs = np.concatenate([self._edit_probs, probs[~hit]])[order]
        self._spliced = _dask_arrays.splice_cells_dask(
            self._probs, np.unravel_index(self._edit_cells, self.shape), self._edit_probs)

    def observe(self, frame) -> None:
        """Apply one camera frame: any object with ``cells`` (n, 2), ``likelihood`` (n, k), ``layers`` ((n,)
        or ``None``) and ``classes`` (must equal the map's), e.g. a ``psgsl_pgm.sim.Frame``."""
        missing = [a for a in ("cells", "likelihood", "layers", "classes") if not hasattr(frame, a)]
        if missing:
            raise TypeError(f"frame must have .cells, .likelihood, .layers and .classes; "
                            f"{type(frame).__name__} lacks {', '.join('.' + m for m in missing)}")
        if tuple(frame.classes) != self.classes:
            raise ValueError(f"frame classes {tuple(frame.classes)} differ from the map's {self.classes}")
        if (frame.layers is not None) != self.is_voxel:
            raise ValueError("voxel frames need a voxel map and 2-D frames a 2-D map")
        self._apply(frame.cells, frame.likelihood, frame.layers)
        self.n_frames += 1

    # --- the semantic term ----------------------------------------------------------------------------------
    def source_probability(self, source_likelihood, class_prior, **options) -> np.ndarray:
        r""":math:`p(s_c \mid z)` over the 2-D cells (eq. (20)); voxel columns are summed (Sec.
        "Voxelized Scene Representations", eq. (21): :math:`p(s_c \mid z) = \sum_{v \in c} p(s_v \mid z)`).
        Options as for :func:`psgsl_pgm.semantic_source_probability`."""
        if self.is_voxel:
            options = {"column_axis": 2} | options
        if self._log is None:  # lazy: the dask path of semantic_source_probability
            return semantic_source_probability(self._spliced, source_likelihood, class_prior, **options)
        return semantic_source_probability(self._probs, source_likelihood, class_prior, **options)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({'x'.join(map(str, self.shape))} cells, {len(self.classes)} classes, {self.n_frames} frames)"


def _posterior_log(old: np.ndarray, add: np.ndarray, touched: np.ndarray, shape: tuple) -> np.ndarray:
    """Normalised log p(o_c | z_c, z') of the touched cells from their log beliefs and summed log-likelihoods
    (n, k); contradictory evidence (zero under every class a cell allows) is a ValueError naming the cell."""
    new = old + add
    norm = logsumexp(new, axis=1, keepdims=True)
    if not np.all(np.isfinite(norm)):
        cell = np.unravel_index(int(touched[np.flatnonzero(~np.isfinite(norm[:, 0]))[0]]), shape)
        raise ValueError(
            f"contradictory evidence at cell {tuple(int(i) for i in cell)}: the observations have zero "
            "likelihood under every class the belief allows"
        )
    new -= norm  # keep the log beliefs normalised where touched (bounded, no drift over many frames)
    return new


def _shape_tuple(shape) -> tuple:
    if isinstance(shape, (str, bytes)) or not hasattr(shape, "__len__") or len(shape) not in (2, 3):
        raise TypeError(f"shape must be (H, W) or (H, W, L), got {shape!r}")
    return tuple(shape)


def _as_cells(x, name: str, ndim: int = 2) -> np.ndarray:
    """Integer index array: (n, 2) cells or (n,) layers."""
    arr = np.asarray(x)
    if arr.size == 0:
        return np.zeros((0, 2) if ndim == 2 else (0,), dtype=np.intp)
    if arr.dtype == bool or not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"{name} must hold integer indices, got {describe(arr)}")
    if ndim == 2 and (arr.ndim != 2 or arr.shape[1] != 2):
        raise ValueError(f"{name} must have shape (n, 2) (row, col), got {describe(arr)}")
    if ndim == 1 and arr.ndim != 1:
        raise ValueError(f"{name} must have shape (n,), got {describe(arr)}")
    return arr.astype(np.intp)
