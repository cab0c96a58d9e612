r"""PMFS's own navigation (Ojeda, Monroy & Gonzalez-Jimenez, "Robotic Gas Source Localization with Probabilistic
Mapping and Online Dispersion Simulation", IEEE Transactions on Robotics 40, 2024, arXiv:2304.08879; the
``MovingStatePMFS`` of MAPIRlab/GasSourceLocalization, written here from its description): the policy
``pmfs-nav``, which needs the estimator ``pmfs`` (:class:`psgsl_pgm.olfaction.FilamentPMFS`).

PMFS moves to learn its hit map where the simulated sources disagree, not to reduce the entropy of p(s | g):

* **The open move set** O. At every stop the cells around the robot join O and stay in it; the robot's own cell is
  left out of the current choice. PMFS adds the cells of a (2E + 1)² window of its grid (E =
  ``openMoveSetExpasion`` = 5 cells) that a straight free line reaches; here the planner's candidate cells within
  the horizon (geodesic, :meth:`FreeSpace.candidates`), the same neighbourhood on the loop's lattice of stops.
* **Interest** of a cell c ∈ O. With conf_c the hit map's confidence and Var_c the variance over the simulated
  sources of their hit probability at c, weighted by each source's score
  (:meth:`psgsl_pgm.olfaction.FilamentPMFS.hit_variance`),

  .. math:: V(c) = \operatorname{Var}_c\,(1 - \mathrm{conf}_c), \qquad
            X(c) = \sum_{p \in W(c)} (1 - \mathrm{conf}_p)\, e^{-\lVert p - c\rVert / \ell},

  W(c) the free cells of the window of half-side R = 5 ℓ around c, ℓ the estimator's ``hit_block`` (the side of
  the cells PMFS compares, 0.3 m by default: PMFS measures the distance in its cells). A cell's interest is X(c)
  (exploration) during the first ``INITIAL_EXPLORATION`` decisions, where V(c) = 0, and, drawn once per
  decision, with probability ``EXPLORATION_PROBABILITY``; V(c) otherwise (search).
* **The move**: to the cell of largest interest (the first on ties), the camera facing the direction of travel.
  PMFS does not weigh the travel: the goal may lie anywhere in O. A goal within the horizon is driven to; one
  beyond it is approached through the candidate within the horizon nearest to it (geodesic), and the next
  decision chooses again (usually the same goal, as O and the maps change little in one stop).

Deviations from the published code, and why: the window's cells are summed without PMFS's line-of-sight test
(the loop has no per-cell visibility map; a wall inside the window adds the unmapped cells behind it to X); the
variance is that of the regions' current scores rather than of the scores at the last refresh
(:meth:`~psgsl_pgm.olfaction.FilamentPMFS.hit_variance`); a goal PMFS's navigation fails to reach is moved to its
closed set, whereas every goal here is reachable (O holds planner candidates only). The exploration coin comes from
a generator seeded by the estimator's seed (the run's) and the number of decisions so far.
"""

from __future__ import annotations

import numpy as np

from ._policies import Decision, Situation, _candidates, _first_max, _towards

__all__ = ["EXPLORATION_PROBABILITY", "INITIAL_EXPLORATION", "choose_pmfs_nav", "pmfs_interest"]

#: Decisions of pure exploration at the start (PMFS's ``initialExplorationMoves``, 5 in its launch files).
INITIAL_EXPLORATION = 5
#: Probability of an exploration decision afterwards (PMFS's ``explorationProbability``, 0.05 in its launch files).
EXPLORATION_PROBABILITY = 0.05
_WINDOW = 5  # half-side of the exploration window in PMFS's cells (its openMoveSetExpasion)
_STATE = "pmfs-nav: state"  # Situation.cache key


def _estimator(sit: Situation):
    est = sit.beliefs.estimator
    if not callable(getattr(est, "hit_variance", None)):
        raise ValueError(f"policy 'pmfs-nav' needs the estimator 'pmfs' (PMFS's simulated hit maps), got "
                         f"{type(est).__name__}")
    return est


def _exploration(sit: Situation, est, cells) -> np.ndarray:
    """(K,) X(c) of the module docstring for the flat ``cells``."""
    geo = est.geometry
    h, w = geo.shape
    ell = float(est.hit_block)
    half = max(int(round(_WINDOW * ell / geo.resolution)), 1)
    unsure = ((1.0 - est.confidence) * geo.free).astype(np.float64)
    d = geo.resolution * np.hypot(*np.mgrid[-half : half + 1, -half : half + 1])
    kernel = np.exp(-d / ell)
    padded = np.pad(unsure, half)
    out = np.empty(len(cells))
    for k, c in enumerate(np.asarray(cells, np.int64).tolist()):
        r, q = divmod(c, w)
        out[k] = float((padded[r : r + 2 * half + 1, q : q + 2 * half + 1] * kernel).sum())
    return out


def pmfs_interest(sit: Situation, cells, *, explore: bool) -> np.ndarray:
    """(K,) the interest of each flat cell of ``cells`` (module docstring): X(c) when ``explore``, else V(c), and
    X(c) where V(c) = 0.

    Parameters
    ----------
    sit : Situation
        Its estimator must be PMFS (:class:`psgsl_pgm.olfaction.FilamentPMFS`).
    cells : (K,) array_like of int
        Flat cells.
    explore : bool, keyword-only
        An exploration decision.

    Returns
    -------
    interest : (K,) ndarray of float64
        X in units of cells weighted by e^{-d/ℓ} (≥ 0), V in (hit probability)² (≥ 0); PMFS compares the two
        where they mix, as here.
    """
    est = _estimator(sit)
    cells = np.asarray(cells, np.int64)
    x = _exploration(sit, est, cells)
    if explore:
        return x
    v = (est.hit_variance() * (1.0 - est.confidence)).ravel()[cells]
    return np.where(v == 0, x, v)


def choose_pmfs_nav(sit: Situation) -> Decision:
    """The ``pmfs-nav`` decision (module docstring)."""
    est = _estimator(sit)
    state = sit.cache.get(_STATE)
    if state is None:
        state = sit.cache[_STATE] = {"open": [], "decisions": 0}
    cells, drive, pred, tau = _candidates(sit, far=False)
    known = set(state["open"])
    state["open"].extend(int(c) for c in cells.tolist() if int(c) not in known)  # O grows, in first-seen order
    choice = np.array([c for c in state["open"] if c != sit.cell], np.int64)
    if choice.size == 0:  # nowhere else to go: the nearest candidate
        choice = cells
    n = state["decisions"]
    rng = np.random.default_rng([int(est.seed), 0x504D4653, n])
    explore = n < INITIAL_EXPLORATION or bool(rng.random() < EXPLORATION_PROBABILITY)
    state["decisions"] = n + 1
    interest = pmfs_interest(sit, choice, explore=explore)
    goal = int(choice[_first_max(interest[:, None])])
    to = sit.space.position(goal) - sit.space.position(sit.cell)
    heading = float(np.arctan2(to[1], to[0])) if np.hypot(*to) > 0 else sit.heading
    near = np.flatnonzero(cells == goal)
    if near.size:
        k = int(near[0])
        return Decision(goal, (heading,), sit.space.path(pred, goal), float(drive[k]),
                        float(interest.max()))
    step = _towards(sit, goal)
    return Decision(step.cell, step.headings, step.path, step.drive, float(interest.max()))
