"""Building the class beliefs p(o_c | z_c): Bayesian updates and room-category evidence (Sec. "Model")."""

from __future__ import annotations

import numpy as np
from scipy.special import logsumexp

from .._shared._validate import (
    as_array,
    as_float_array,
    check_distribution,
    check_last_axis,
    check_nonnegative,
    describe,
)
from ._ratios import likelihood_ratio

__all__ = ["update_class_probs", "room_evidence"]


def update_class_probs(class_probs, likelihood):
    r"""Bayesian update of per-cell class beliefs with an observation likelihood :math:`p(z \mid o)`.

    For a new observation :math:`z'` of cell c:

    .. math:: p(o_{ci} \mid z_c, z') \propto p(o_{ci} \mid z_c)\, p(z' \mid o_{ci})

    Every observation of a cell — a detector's confusion column for the label it reported, "seen, nothing
    detected", or the room-category factor from :func:`room_evidence` — is applied this way. Observations
    are assumed conditionally independent given the cell's class (the paper's :math:`Z_c \mid O_c`).

    Parameters
    ----------
    class_probs : (..., k) array_like
        Current beliefs (each cell sums to 1), or a single (k,) prior to start every cell from.
    likelihood : (k,) or (..., k) array_like
        :math:`p(z \mid o)` for each class, per cell or shared; any positive scale (only ratios matter),
        broadcastable against ``class_probs``.

    Returns
    -------
    posterior : (..., k) ndarray
        The broadcast shape of the inputs; float32 only if both inputs are float32.

    Raises
    ------
    ValueError
        Inputs that are not probabilities/likelihoods, shapes that do not broadcast, or a cell where the
        observation has zero likelihood under every class the belief allows (contradictory evidence).

    Examples
    --------
    A cell believed oven/microwave 50/50; a detector that says "oven" with p = 0.8 for ovens and 0.2 for
    microwaves:

    >>> from psgsl_pgm import update_class_probs
    >>> update_class_probs([0.5, 0.5], [0.8, 0.2])
    array([0.8, 0.2])
    """
    q = as_float_array(class_probs, "class_probs", min_ndim=1)
    lik = as_float_array(likelihood, "likelihood", min_ndim=1)
    k = q.shape[-1]
    check_distribution(q, "class_probs")  # first: an empty class axis is class_probs' fault, not likelihood's
    check_last_axis(lik, "likelihood", k)
    check_nonnegative(lik, "likelihood")
    try:
        shape = np.broadcast_shapes(q.shape, lik.shape)
    except ValueError:
        raise ValueError(
            f"likelihood must broadcast against class_probs {q.shape}, got {describe(lik)}"
        ) from None
    dtype = np.float32 if (q.dtype == np.float32 and lik.dtype == np.float32) else np.float64

    scale = lik.max(axis=-1, keepdims=True)
    if np.any(scale == 0):
        cell = np.argwhere(scale[..., 0] == 0)[0] if scale.ndim > 1 else ()
        raise ValueError(f"likelihood is zero for every class at cell {tuple(int(i) for i in cell)}")
    post = q * (lik / scale)  # p(o|z) p(z'|o), likelihood rescaled to max 1 against underflow
    norm = post.sum(axis=-1, keepdims=True, dtype=np.float64)
    bad = norm[..., 0] <= np.finfo(np.float64).tiny
    if np.any(bad):  # tiny products: redo those cells in log space; zero products: contradiction
        with np.errstate(divide="ignore"):
            logpost = np.log(np.broadcast_to(q, shape)[bad], dtype=np.float64) + np.log(
                np.broadcast_to(lik, shape)[bad], dtype=np.float64
            )
        lognorm = logsumexp(logpost, axis=-1, keepdims=True)
        if not np.all(np.isfinite(lognorm)):
            cell = np.argwhere(bad)[np.flatnonzero(~np.isfinite(lognorm[:, 0]))[0]]
            raise ValueError(
                f"contradictory evidence at cell {tuple(int(i) for i in cell)}: the observation has zero "
                "likelihood under every class the belief allows"
            )
        post = np.broadcast_to(post, shape).copy()
        norm = np.broadcast_to(norm, shape[:-1] + (1,)).copy()
        post[bad] = np.exp(logpost - lognorm)
        norm[bad] = 1.0
    return (post / norm).astype(dtype, copy=False)


def room_evidence(room_labels, room_class_table, class_prior):
    r"""Room-category map as evidence on the object classes (Sec. "Model"; "Validation").

    A cell known to lie in room r is an observation :math:`Z` with likelihood

    .. math:: p(r \mid o) \propto \frac{p(o \mid r)}{p(o)}.

    This returns that factor per cell, to be applied with :func:`update_class_probs`; starting from
    ``class_prior`` it yields exactly :math:`p(o \mid r)`.

    Parameters
    ----------
    room_labels : (...) array_like of int
        Room index of every cell into the rows of ``room_class_table``; ``-1`` for no room (factor 1).
    room_class_table : (r, k) array_like
        :math:`p(o \mid \text{room})`, one distribution over the k classes per room (e.g.
        ``Ontology.room_table``).
    class_prior : (k,) array_like
        :math:`p(o)`; positive wherever a room row is.

    Returns
    -------
    factor : (..., k) ndarray
        :math:`p(o \mid \text{room}_c) / p(o)`, float64 (a room whose ratios would exceed float64, under a
        prior near 1e-310, has them scaled to a maximum of 1: the same likelihood).

    Raises
    ------
    TypeError
        ``room_labels`` are not integers.
    ValueError
        ``room_class_table`` rows or ``class_prior`` are not distributions, ``class_prior`` does not have the
        table's k classes, a label lies outside [-1, r - 1], or a class that a room makes possible has prior 0.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm import room_evidence, update_class_probs
    >>> prior = np.array([0.1, 0.9])                      # oven, other
    >>> table = np.array([[0.3, 0.7]])                    # kitchen
    >>> f = room_evidence([0, -1], table, prior)
    >>> update_class_probs(prior, f).round(3)
    array([[0.3, 0.7],
           [0.1, 0.9]])
    """
    labels = as_array(room_labels, "room_labels", "integer room indices (-1 = none)")
    if not np.issubdtype(labels.dtype, np.integer):
        if labels.dtype.kind == "f" and labels.size and np.all(np.isfinite(labels)) and np.all(labels == np.round(labels)):
            labels = labels.astype(np.int64)
        else:
            raise TypeError(f"room_labels must be integer room indices (-1 = none), got {describe(labels)}")
    table = as_float_array(room_class_table, "room_class_table", dtype=np.float64, ndim=2)
    check_distribution(table, "room_class_table (each row, p(o | room))")
    prior = as_float_array(class_prior, "class_prior", dtype=np.float64, ndim=1)
    n_rooms, k = table.shape
    if prior.shape != (k,):
        raise ValueError(f"class_prior must have shape ({k},) like room_class_table's classes, got {describe(prior)}")
    check_distribution(prior, "class_prior")
    if labels.size and (labels.min() < -1 or labels.max() >= n_rooms):
        raise ValueError(
            f"room_labels must lie in [-1, {n_rooms - 1}] for a table of {n_rooms} rooms, got values in "
            f"[{labels.min()}, {labels.max()}]"
        )
    zero = prior == 0
    if np.any(zero & (table > 0).any(axis=0)):
        raise ValueError(
            f"class_prior is zero for classes {np.flatnonzero(zero & (table > 0).any(axis=0)).tolist()} that a "
            "room makes possible; p(o | room) / p(o) is undefined there"
        )
    ratios = np.ones((n_rooms + 1, k))
    ratios[:n_rooms] = likelihood_ratio(table, prior, zero)  # p(o|r)/p(o), 0 for classes of zero prior
    return ratios[labels]  # label -1 picks the last row: ones
