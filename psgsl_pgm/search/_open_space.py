r"""The open-space source-tracking POMDP of Vergassola et al. (2007) in the form of Loisy & Eloy (2022).

An N × N grid of cells of side Δx holds the source; the agent starts at the centre cell having received one
hit there. At each step it moves one cell along ±x or ±y (moves off the grid are impossible, staying is not
allowed), searches the new cell (the episode ends if the source is there; otherwise that cell's probability
is set to zero) and then observes a binary hit with

.. math:: P(\text{hit} \mid d) = 1 - e^{-\mu(d)}, \qquad
          \mu(d) = \frac{R\,\Delta t}{\ln(2\lambda/\Delta x)}\, K_0\!\left(\frac{d}{\lambda}\right),

d the Euclidean distance between the agent's and the source's cell centres, in cells (Loisy & Eloy 2022,
Proc. R. Soc. A 478: 20220118, observation model in 2-D, with the agent radius a = Δx/2; their code OTTO,
``SourceTracking._set_mu0_Poisson`` / ``_mean_number_of_hits``). The binary hit is their Poisson hit count
truncated to two values (h = 0 or h ≥ 1).

The belief is updated exactly by Bayes' rule on the whole grid at once (no loop over cells): a likelihood
table over the (2N − 1)² offsets is sliced at the agent's position. "Not found here" is the closed loop's
detection model (:class:`psgsl_pgm.search.DetectionModel`) on the grid of unit cells with ``found_radius`` 0:
the source is found in the agent's own cell, with probability 1 − ``miss_probability`` (default 1, OTTO's rule),
and "not found" multiplies that cell's probability by ``miss_probability`` (0 by default). The success rule of
:meth:`OpenSpaceSearch.move`, P_end of the policies and the update all use that one model. Policies score the four moves from the
belief after "not found here" and the two outcomes hit / miss:

* ``infotaxis`` — minimise the expected entropy (1 − P_end) Σ_h P(h) H(p_h) (Vergassola et al. 2007);
* ``space-aware-infotaxis`` — minimise (1 − P_end) Σ_h P(h) log₂(D_h + 2^{H_h − 1} − ½), D_h the expected
  Manhattan distance from the new cell to the source and H_h the entropy in bits (Loisy & Eloy 2022,
  eq. of the space-aware heuristic; where the argument is ≤ 0 it is used without the log, as in OTTO);
* ``greedy`` — move to the neighbour with the highest probability.

Ties go to the first move in the order −x, +x, −y, +y (OTTO's order) within 1e-10.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.special import k0, xlogy

from .._shared._validate import unit_interval
from ..geometry._grid import GridMap
from ._detection import DetectionModel

__all__ = ["OPEN_SPACE_POLICIES", "OpenSpaceSearch", "grid_size", "hit_probability", "open_space_benchmark"]

#: Policies of the open-space benchmark.
OPEN_SPACE_POLICIES = ("infotaxis", "space-aware-infotaxis", "greedy")

_MOVES = np.array([(0, -1), (0, 1), (-1, 0), (1, 0)])  # (row, col) offsets: −x, +x, −y, +y
_TIE = 1e-10


def _positive(value, name: str) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__} {value!r}")
    v = float(value)
    if not (np.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return v


def mean_hits(distance, *, lambda_over_dx: float, r_dt: float) -> np.ndarray:
    """μ(d) = R·Δt / ln(2λ/Δx) · K0(d/λ), d in cells (float64 array of d's shape)."""
    lam = _positive(lambda_over_dx, "lambda_over_dx")
    r = _positive(r_dt, "r_dt")
    if not 2 * lam > 1:
        raise ValueError(f"lambda_over_dx must exceed 1/2 (ln(2λ/Δx) > 0), got {lambda_over_dx!r}")
    d = np.asarray(distance, dtype=np.float64)
    with np.errstate(divide="ignore"):
        return r / np.log(2 * lam) * k0(d / lam)


def hit_probability(distance, *, lambda_over_dx: float, r_dt: float) -> np.ndarray:
    """P(hit | d) = 1 − exp(−μ(d)) (1 at d = 0, where K0 diverges).

    Parameters
    ----------
    distance : array_like of float
        d, the distance between the agent's and the source's cell centres, in cells (Δx), ≥ 0; any shape.
    lambda_over_dx : float, keyword-only
        λ/Δx, the dispersion length scale in cells; must exceed 1/2 (so that ln(2λ/Δx) > 0).
    r_dt : float, keyword-only
        R·Δt, the source's emission rate times the sensing time (dimensionless, > 0).

    Returns
    -------
    numpy.ndarray
        P(hit | d), float64 of ``distance``'s shape, in [0, 1].

    Raises
    ------
    TypeError
        ``lambda_over_dx`` or ``r_dt`` is not a real number.
    ValueError
        ``lambda_over_dx`` or ``r_dt`` is not positive and finite, or ``lambda_over_dx`` ≤ 1/2.

    Examples
    --------
    >>> hit_probability([0.0, 1.0, 5.0], lambda_over_dx=1, r_dt=1).round(4).tolist()
    [1.0, 0.4552, 0.0053]
    """
    return -np.expm1(-mean_hits(distance, lambda_over_dx=lambda_over_dx, r_dt=r_dt))


def grid_size(*, lambda_over_dx: float, r_dt: float, p_outside: float = 1e-3) -> int:
    """Smallest odd N such that, after the first hit, P(source farther than (N−1)/2 cells) < ``p_outside``.

    The radial distribution of the source after one hit at the origin, in an unbounded plane, is
    ∝ P(hit | r) · 2πr (annuli of unit width at r = 1, 2, …, 1000 λ/Δx); N = 2 r* + 1 with r* the first radius
    whose disc holds more than 1 − ``p_outside`` of it (OTTO's ``_autoset_Ngrid`` with binary hits).

    Parameters
    ----------
    lambda_over_dx : float, keyword-only
        λ/Δx, the dispersion length scale in cells; must exceed 1/2.
    r_dt : float, keyword-only
        R·Δt, the source's emission rate times the sensing time (dimensionless, > 0).
    p_outside : float, default 1e-3, keyword-only
        The probability (> 0) the source may keep outside the grid after the first hit.

    Returns
    -------
    int
        N, odd: the grid's side in cells.

    Raises
    ------
    TypeError
        ``lambda_over_dx``, ``r_dt`` or ``p_outside`` is not a real number.
    ValueError
        One of them is not positive and finite, or ``lambda_over_dx`` ≤ 1/2.

    Examples
    --------
    >>> [grid_size(lambda_over_dx=l, r_dt=r) for l, r in ((1, 1), (2, 2), (3, 1))]
    [19, 35, 51]
    """
    lam = _positive(lambda_over_dx, "lambda_over_dx")
    p_out = _positive(p_outside, "p_outside")
    r = np.arange(1, int(1000 * lam), dtype=np.float64)
    mass = hit_probability(r, lambda_over_dx=lam, r_dt=r_dt) * 2 * np.pi * r
    inside = np.cumsum(mass) / mass.sum()
    first = int(np.flatnonzero(1 - inside < p_out)[0])
    return 2 * (first + 1) + 1


@functools.lru_cache(maxsize=16)
def _unit_detection(n: int, miss_probability: float) -> DetectionModel:
    """The detection model on the n × n grid of unit cells, radius 0 (shared by episodes: it caches rows)."""
    return DetectionModel(GridMap(np.zeros((n, n), bool), 1.0), 0.0, miss_probability=miss_probability)


def _entropy_bits(p, axis):
    return -np.sum(xlogy(p, p), axis=axis) / np.log(2)


class OpenSpaceSearch:
    """One episode of the open-space POMDP: the belief, the agent, and the exact Bayesian update.

    Parameters
    ----------
    lambda_over_dx, r_dt : float, keyword-only
        λ/Δx and R·Δt.
    n : int, optional, keyword-only
        Odd grid size; default :func:`grid_size`.
    miss_probability : float, keyword-only
        m in [0, 1): probability of not finding the source in its own cell (0: OTTO's rule).

    Attributes
    ----------
    n : int
    agent : (2,) ndarray of int
        (row, col) of the agent; starts at the centre (n // 2, n // 2).
    belief : (n, n) ndarray of float64
        p(source cell | history); after construction the prior after one hit at the centre,
        ∝ 1 − exp(−μ(d)) on every cell but the centre (0 there).
    """

    def __init__(self, *, lambda_over_dx: float, r_dt: float, n: int | None = None, miss_probability: float = 0.0):
        self.lambda_over_dx = _positive(lambda_over_dx, "lambda_over_dx")
        self.r_dt = _positive(r_dt, "r_dt")
        if n is None:
            n = grid_size(lambda_over_dx=lambda_over_dx, r_dt=r_dt)
        if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)):
            raise TypeError(f"n must be an odd integer, got {n!r}")
        if n < 3 or n % 2 == 0:
            raise ValueError(f"n must be an odd integer >= 3, got {n}")
        self.n = int(n)
        # the detection model on unit cells (x = col + ½, y = row + ½): found only in the source's own cell
        self.detection = _unit_detection(self.n, unit_interval(miss_probability, "miss_probability",
                                                               high_open=True))
        off = np.arange(-(self.n - 1), self.n)
        d = np.hypot(off[:, None], off[None, :])  # (2n−1, 2n−1) distances of every offset
        self._p_hit = hit_probability(d, lambda_over_dx=lambda_over_dx, r_dt=r_dt)
        self._manhattan = (np.abs(off)[:, None] + np.abs(off)[None, :]).astype(np.float64)
        self.agent = np.array([self.n // 2, self.n // 2])
        belief = self.likelihood(self.agent, True).copy()
        belief[tuple(self.agent)] = 0.0
        self.belief = belief / belief.sum()

    @staticmethod
    def _xy(cells) -> np.ndarray:
        """(m, 2) positions (x, y) of (m, 2) (row, col) cells on the unit grid."""
        c = np.asarray(cells, dtype=np.float64).reshape(-1, 2)
        return c[:, ::-1] + 0.5

    def _flat(self, cells) -> np.ndarray:
        c = np.asarray(cells).reshape(-1, 2)
        return c[:, 0] * self.n + c[:, 1]

    def _window(self, table, cell):
        r0, c0 = self.n - 1 - int(cell[0]), self.n - 1 - int(cell[1])
        return table[r0 : r0 + self.n, c0 : c0 + self.n]

    def likelihood(self, cell, hit: bool) -> np.ndarray:
        """(n, n) P(hit or miss at ``cell`` | source in each cell) (a read-only view)."""
        p = self._window(self._p_hit, cell)
        return p if hit else 1.0 - p

    def neighbours(self, cell=None) -> np.ndarray:
        """(m, 2) cells reachable in one move (in the order −x, +x, −y, +y) and (m,) move indices."""
        cell = self.agent if cell is None else np.asarray(cell)
        nxt = cell[None, :] + _MOVES
        ok = ((nxt >= 0) & (nxt < self.n)).all(axis=1)
        return nxt[ok], np.flatnonzero(ok)

    def outcomes(self):
        """Quantities of every legal move, vectorised over moves and cells.

        Returns
        -------
        dict with
            ``cells`` (m, 2), ``p_end`` (m,) probability that the source is in the new cell, ``p_hit`` (m,)
            P(hit | not found there), ``posterior`` (m, 2, n, n) beliefs after (miss, hit), ``entropy``
            (m, 2) their entropies in bits, ``distance`` (m, 2) their expected Manhattan distances from the
            new cell.
        """
        cells, _ = self.neighbours()
        det = self.detection
        rows = det.cell_rows(self._flat(cells), self._xy(cells))  # the hypotheses each move can find
        p_end = det.found_probability(self.belief, rows)  # (1 − m) p(new cell)
        w = np.ones((len(cells), self.n * self.n))
        w[np.repeat(np.arange(len(cells)), [len(r) for r in rows]), np.concatenate(rows)] = det.miss_probability
        q = self.belief[None] * w.reshape(len(cells), self.n, self.n)  # p(s) P(not found | s)
        rest = 1.0 - p_end
        q /= np.where(rest > 0, rest, 1.0)[:, None, None]  # p(s | not in the new cell)
        lik = np.stack([self._window(self._p_hit, c) for c in cells])  # (m, n, n): loop over ≤ 4 moves
        joint = np.stack([q * (1.0 - lik), q * lik], axis=1)  # (m, 2, n, n)
        z = joint.sum(axis=(2, 3))  # (m, 2) P(miss), P(hit)
        post = joint / np.where(z > 0, z, 1.0)[:, :, None, None]
        dist = np.stack([self._window(self._manhattan, c) for c in cells])  # (m, n, n)
        return {
            "cells": cells,
            "p_end": p_end,
            "p_hit": z[:, 1],
            "p_outcome": z,
            "posterior": post,
            "entropy": _entropy_bits(post, axis=(2, 3)),
            "distance": np.einsum("mhij,mij->mh", post, dist),
        }

    def scores(self, policy: str) -> tuple[np.ndarray, np.ndarray]:
        """(cells (m, 2), values (m,)) of the legal moves; the policy takes the smallest value."""
        if policy == "greedy":
            cells, _ = self.neighbours()
            return cells, 1.0 - self.belief[cells[:, 0], cells[:, 1]]
        o = self.outcomes()
        if policy == "infotaxis":
            value = (1.0 - o["p_end"]) * np.sum(o["p_outcome"] * o["entropy"], axis=1)
        elif policy == "space-aware-infotaxis":
            arg = o["distance"] + 2.0 ** (o["entropy"] - 1.0) - 0.5
            with np.errstate(divide="ignore", invalid="ignore"):
                term = np.where(arg > 0, np.log2(np.where(arg > 0, arg, 1.0)), arg)
            value = (1.0 - o["p_end"]) * np.sum(o["p_outcome"] * term, axis=1)
        else:
            raise ValueError(f"policy must be one of {OPEN_SPACE_POLICIES}, got {policy!r}")
        # a move onto a cell that surely holds the source ends the search: always take it
        return o["cells"], np.where(o["p_end"] > 1 - _TIE, -np.inf, value)

    def choose(self, policy: str) -> np.ndarray:
        """The cell the policy moves to (first of the tied best, in the order −x, +x, −y, +y)."""
        cells, value = self.scores(policy)
        best = np.flatnonzero(value <= value.min() + _TIE)[0]
        return cells[best]

    def move(self, cell, source, rng) -> bool:
        """Move to ``cell``; True if the source is there, else search it, draw the hit and update the belief."""
        cell = np.asarray(cell)
        if np.abs(cell - self.agent).sum() != 1 or not ((cell >= 0) & (cell < self.n)).all():
            raise ValueError(f"cell {cell.tolist()} is not one legal move from {self.agent.tolist()}")
        self.agent = cell
        if self.detection.found(self._xy(cell), int(self._flat(source)[0]))[0] and (
                self.detection.miss_probability == 0 or rng.random() >= self.detection.miss_probability):
            return True
        d = float(np.hypot(*(cell - np.asarray(source))))
        hit = bool(rng.random() < float(hit_probability(d, lambda_over_dx=self.lambda_over_dx, r_dt=self.r_dt)))
        self.observe(hit)
        return False

    def observe(self, hit: bool) -> None:
        """Bayes' rule for "not in the agent's cell" and a hit/miss at the agent's cell."""
        (row,) = self.detection.cell_rows(self._flat(self.agent), self._xy(self.agent))
        w = np.ones(self.n * self.n)
        w[row] = self.detection.miss_probability  # P(not found here | s): the detection model's
        b = self.belief * w.reshape(self.n, self.n)
        b *= self.likelihood(self.agent, bool(hit))
        total = b.sum()
        if not total > 0:
            raise ValueError("the observation has zero probability under the belief")
        self.belief = b / total


def open_space_benchmark(policy: str, *, lambda_over_dx: float, r_dt: float, episodes: int, seed: int,
                         max_steps: int | None = None, n: int | None = None, miss_probability: float = 0.0) -> dict:
    """Monte-Carlo evaluation of a policy on the open-space POMDP (source drawn from the initial belief).

    Parameters
    ----------
    policy : {"infotaxis", "space-aware-infotaxis", "greedy"}
    lambda_over_dx, r_dt : float, keyword-only
        λ/Δx and R·Δt.
    episodes : int, keyword-only
        Number of episodes.
    seed : int, keyword-only
        Seed of the one random stream (source draws and hits).
    max_steps : int, optional, keyword-only
        Episodes longer than this are stopped and counted as not found; default 20 n².
    n : int, optional, keyword-only
        Grid size; default :func:`grid_size`.
    miss_probability : float, keyword-only
        Probability of not finding the source in its own cell (:class:`OpenSpaceSearch`).

    Returns
    -------
    dict
        ``mean_steps`` (mean T over the episodes that found the source), ``sem`` (its standard error),
        ``median``, ``p_not_found`` (fraction of episodes stopped at ``max_steps``), ``steps`` ((episodes,)
        int array, T of each episode; ``max_steps`` where not found), ``n`` (grid size), ``episodes``.

    Raises
    ------
    ValueError
        An unknown ``policy``, ``episodes`` or ``max_steps`` below 1, or parameters :class:`OpenSpaceSearch`
        refuses.
    TypeError
        ``episodes`` or ``seed`` is not an integer.

    Examples
    --------
    Three episodes on an 11 x 11 grid:

    >>> from psgsl_pgm.search import open_space_benchmark
    >>> r = open_space_benchmark("greedy", lambda_over_dx=5.0, r_dt=1.0, episodes=3, seed=0, n=11)
    >>> r["steps"].tolist(), r["mean_steps"], r["p_not_found"]
    ([6, 22, 33], 20.333333333333332, 0.0)
    """
    if policy not in OPEN_SPACE_POLICIES:
        raise ValueError(f"policy must be one of {OPEN_SPACE_POLICIES}, got {policy!r}")
    for name, v in (("episodes", episodes), ("seed", seed)):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
            raise TypeError(f"{name} must be an integer, got {v!r}")
    if episodes < 1:
        raise ValueError(f"episodes must be >= 1, got {episodes}")
    template = OpenSpaceSearch(lambda_over_dx=lambda_over_dx, r_dt=r_dt, n=n, miss_probability=miss_probability)
    cap = 20 * template.n ** 2 if max_steps is None else int(max_steps)
    if cap < 1:
        raise ValueError(f"max_steps must be >= 1, got {max_steps}")
    rng = np.random.default_rng(int(seed))
    prior = template.belief.ravel()
    steps = np.empty(int(episodes), dtype=np.int64)
    found = np.zeros(int(episodes), dtype=bool)
    for e in range(int(episodes)):  # loop over episodes (each step is vectorised over cells)
        source = np.unravel_index(int(rng.choice(prior.size, p=prior)), template.belief.shape)
        env = OpenSpaceSearch(lambda_over_dx=lambda_over_dx, r_dt=r_dt, n=template.n,
                              miss_probability=miss_probability)
        t = 0
        while t < cap:
            t += 1
            if env.move(env.choose(policy), source, rng):
                found[e] = True
                break
        steps[e] = t
    ok = steps[found]
    mean = float(ok.mean()) if ok.size else float("nan")
    sem = float(ok.std(ddof=1) / np.sqrt(ok.size)) if ok.size > 1 else float("nan")
    return {"policy": policy, "lambda_over_dx": float(lambda_over_dx), "r_dt": float(r_dt), "n": template.n,
            "episodes": int(episodes), "seed": int(seed), "mean_steps": mean, "sem": sem,
            "median": float(np.median(ok)) if ok.size else float("nan"),
            "p_not_found": float(1.0 - found.mean()), "steps": steps}
