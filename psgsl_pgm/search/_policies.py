r"""Policies of the closed loop in a house: given the beliefs and the robot's pose, choose the next pose.

Every policy sees a :class:`Situation` (the variant's posterior, the beliefs, the robot's cell and heading,
the free space) and returns a :class:`Decision` (the next cell, the camera headings there, the path).

**Candidates: every room.** Candidate poses p = (cell, heading) are those of :meth:`FreeSpace.candidates`:
the cells of the ``spacing`` lattice within ``horizon`` (geodesic) of the robot, and — with ``far_spacing``
(:class:`SearchConfig`, 1 m by default) — the cells of a coarser lattice over the whole reachable free space
beyond it, each at its geodesic travel time. Why the whole free space and not frontiers, room targets or a
tree search: after the "not found" update the posterior's mass sits where the robot has not been, often in
another room (a bed in a dead-end bedroom), and only a candidate there has a P_f large enough to pay for the
drive; a frontier is ill-defined here (the map is known; what is unexplored is the belief), room-level targets
would need a second scoring rule for "a room", and a tree search over short moves multiplies the cost of a
decision by the branching factor per level while still seeing only a few metres ahead. The 1-m far lattice
matches the found diameter 2r (a candidate every found disc), keeps ≈ 100 candidates in the embedded house,
and a decision is one pass of the same gains over them; the robot re-plans at every stop, so a far target is
only a direction until it is within the horizon. ``greedy`` keeps the horizon's candidates (it drives towards
the MAP cell and re-plans every ``horizon`` metres). Near and far, the candidates include the finder cells of
:meth:`FreeSpace.cover`, so that a stop can find every source a drivable cell can (the closed loop covers its
space with its detection model before the first decision): a far target's P_f is then that of the stop that
finds the hypotheses there, not of the lattice cell nearest them, which near furniture may find none of them.

:math:`P_f` is the probability of finding the source at p under the detection model of the success rule
(:class:`psgsl_pgm.search.DetectionModel`):

.. math:: P_f(p) = (1 - m) \sum_{c:\, d(p, R(c)) \le r} p(c),

R(c) the found region of hypothesis c (an object's footprint or c itself), m the miss probability; the belief
after "not found at p" is :math:`p(c)\, w_p(c) / (1 - P_f)`, :math:`w_p(c) = m` on those hypotheses, 1 elsewhere —
the update the loop then applies.

**Scoring rule** (:data:`SCORES`). Each candidate pose costs the time

.. math:: \tau(p) = d(p)/v + t_\text{turn}\,|\Delta\theta(p)|/(\pi/2) + t_\text{sense},

the geodesic drive d at speed v, the camera turn Δθ from the current heading (``turn_time`` per quarter turn,
as on the tour), and the fixed time of one gas reading.

* ``"per-time"`` (the default) — a policy's gain G(p) is divided by τ(p) (a loss grows with the time spent
  on it):

  .. math:: \text{score}(p) = \begin{cases} G(p) / \tau(p) & G(p) > 0 \\
            G(p)\, \tau(p) & \text{otherwise} \end{cases}

* ``"gain"`` — :math:`\text{score}(p) = G(p)`: the most informative candidate pose, however long it takes to reach.
  Dividing by τ favours the short, cheap moves around the robot where every pose gains little; in the house that kept
  infotaxis out of the bedroom (docs/results/closed-loop.md).

The best score wins; ties go to the first candidate (lattice order) and the first heading. The robot always
moves (:meth:`FreeSpace.candidates`).

* ``infotaxis`` — the expected information of the next stop, Vergassola et al. (2007) with the probability
  :math:`P_f(p)` of finding the source there, and the objective of eq. (29) of the paper, :math:`\varphi_G + \varphi_O`:

  .. math:: G(p) = P_f(p)\, H(S) + \big(1 - P_f(p)\big) \big[\varphi_G(p) + \varphi_O(p)\big],

  :math:`\varphi_G = I(S; \text{hit at } p)` under the variant's posterior and
  :math:`\varphi_O = \sum_{n \in F_p} I(S; O_n)` (eq. (31); exact mutual information of each cell's class) —
  :math:`\varphi_O = 0` for ``olfaction``. Both terms are information about S in nats, so no weight is needed (Sec.
  "Information Gain Optimization"). With the analytic-plume estimator (PMFS's score), whose posterior is recomputed from
  a hit map rather than updated by Bayes' rule, :math:`\varphi_G` is the expected entropy drop under that estimator's
  own update (:func:`olfactory_gain`). Decided by exact branch and bound (:func:`_choose_infotaxis`,
  :func:`_branch_and_bound`): upper bounds of φ_G and φ_O, then the exact score of the poses whose bound reaches the
  best one (every pose under its own update).
* ``space-aware-infotaxis`` — Loisy & Eloy (2022): the value V = log₂(D + 2^{H−1} − ½), with D the expected
  distance to the source and H the entropy in bits, estimates log₂ of the remaining search. On their lattice the
  source is found on its own cell, so a belief that has not found it has D ≥ 1 move, V ≥ 0, and V = 0 (the
  found state) is the least value. In the house a stop finds every hypothesis within the found radius r, a move
  rules out about one found diameter ℓ = 2r, and H is counted over cells of one found disc
  (H − log₂(π r²/Δx²), floored at 0), so that one "cell" is what one visit can rule out; the lattice's D is then
  1 + D_r/ℓ, with D_r = E[max(d(p, s) − r, 0)] the expected geodesic distance past the found radius (the last
  move, the one that finds the source, counts one as on the lattice):

  .. math:: V = \log_2(1 + D_r/\ell + 2^{H-1} - \tfrac12) \;\ge\; 0,

  0 exactly for a belief the stop finds. (Taking D/ℓ for the lattice's D instead makes V negative within one
  found diameter of the belief's mass, down to −∞ at D = ℓ/2, so that a stop which finds the source — value 0 —
  scores below one that does not, and the robot circles the source.)
  G(p) = V_now − (1 − P_f) Σ_h P(h | p, F̄) V_h(p) over the gas outcome h ∈ {miss, hit}, with D_h and H_h
  those of p(s | h, F̄) ∝ p(s) w_p(s) P(h | s) (:func:`space_aware_gain` computes them from cached rows without
  forming that belief); the semantic extension subtracts the view's expected information φ_O(p)/ln 2 bits from
  H_h. As V_h ≥ 0, a stop that surely finds the source (P_f = 1) gains V_now, the most any stop can. Decided by
  exact branch and bound (:func:`_choose_space_aware`, :func:`_branch_and_bound`): a rigorous
  per-tile upper bound of every pose's score, then the exact score of the few poses whose bound reaches the best
  one, the same arg max as scoring every pose; the bound needs no geodesic distances from the pose (a Dijkstra
  each), which dominated the decisions in large homes.
* ``greedy`` — drive towards the most probable cell: the candidate within the horizon nearest (geodesic) to
  the MAP cell, with the camera towards it.
* ``semantic-modes`` — semantics alone, no gas: drive towards the mode of
  :math:`p(s \mid z, \bar F) \propto p(s \mid z)\, p(s)\, P(\bar F \mid s)`,
  the variant's semantic term (eq. ``prob-semantics-final``) times the source region's prior and the "not found"
  factors of every move so far (:attr:`OlfactoryEstimator.log_conditioning`), as ``greedy`` drives towards the
  MAP cell, but to the drivable cell nearest the mode once it is within the horizon (not only to the lattice).
  Once the robot has passed a mode without finding the source, the factors rule it out and the next mode becomes
  the target: the robot visits the modes of the semantic term in turn. Needs a semantic variant.
* ``nearest-object`` — the baseline a practitioner writes first, semantics alone and no gas: visit the objects
  of the robot's map one after another, each time the one of highest probability of finding the source there
  per second of travel (:func:`object_scores`). The objects are the footprints the robot's map segments its
  furniture into (the found regions of :class:`DetectionModel`; their classes are unknown to the robot); the
  value of object j is P_f(j) = (1 − m) Σ_{c ∈ j} p(s = c | z, F̄), with p(s | z, F̄) the normalised
  ``semantic-modes`` score p(s | z) p(s) P(F̄ | s). Through eq. ``prob-semantics-final`` the semantic term is
  Σ_i p(o_ci | z_c) p(o_i | s, γ)/p(o_i) with the class beliefs of the room map: before any frame
  p(o | z, room) = p(o | room), so the value is the footprint's sum of p(o | s, γ) p(o | room)/p(o), and as
  frames arrive the detector's evidence about what stands there replaces the room's guess; the "not found"
  factors rule out an object once passed. The cost is the travel time τ_j = d_j/v + t_sense (:func:`travel_time`,
  no turn: the camera faces the object on arrival), d_j the geodesic distance to the nearest drivable cell within
  r of the footprint, where the robot finds a source there; the score is P_f(j)/τ_j (:func:`score_per_time`).
  Why the ratio: for boxes searched with certain detection at fixed costs, visiting in decreasing order of p/c
  minimises the expected time to find (swapping adjacent visits i, j changes it by p_j c_i − p_i c_j; Kadane &
  Simon 1977, Ann. Statist. 5:237–255); here the costs depend on where the robot stands, so the rule is applied
  greedily at every stop. Neither the most probable object (ignores the drive) nor the nearest (ignores the
  semantics). The robot drives to that cell directly when it is within the horizon, else towards it as
  ``greedy``, re-planning at every stop; ties go to the first object in the map's order. With no object left
  (every footprint ruled out, or none in the map) it goes on as ``semantic-modes``. Needs a semantic variant.
* ``entrotaxis`` — Hutchinson, Oh & Chen (2018): the entropy of the predicted measurement of the stop (found,
  or the gas reading), on the candidates of ``infotaxis`` (:mod:`psgsl_pgm.search._entrotaxis`).
* ``surge-cast``, ``spiral`` — reactive baselines: gas hits and anemometer readings only, no p(s | g), variant
  ``olfaction`` only (:mod:`psgsl_pgm.search._reactive`).
* ``pmfs-nav`` — PMFS's own navigation (Ojeda et al.): to where the simulated sources disagree most about a
  reading and the hit map is least confident; estimator ``pmfs`` only (:mod:`psgsl_pgm.search._pmfs_nav`).
* ``tour`` — the fixed exploration tour (:func:`psgsl_pgm.experiment.exploration_tour`), back and forth.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.special import entr

from .._shared._validate import one_of
from ..core._infogain import semantic_information_gain
from ._detection import DetectionModel

__all__ = ["Decision", "ESTIMATOR_OF", "POLICIES", "REACTIVE", "SCORES", "SEMANTICS_ALONE", "Situation",
           "check_estimator", "check_reactive", "check_score",
           "check_semantics_alone", "object_scores", "olfactory_gain", "score_per_time", "semantic_mode",
           "travel_time"]

#: Policies of the closed loop.
POLICIES = ("tour", "greedy", "infotaxis", "space-aware-infotaxis", "semantic-modes", "nearest-object",
            "entrotaxis", "surge-cast", "spiral", "pmfs-nav")
#: Policies that read the semantic term alone, no gas: they need a semantic variant.
SEMANTICS_ALONE = ("semantic-modes", "nearest-object")
#: Rules that turn a pose's gain G and time τ into its score (module docstring).
SCORES = ("per-time", "gain")


@dataclass
class Situation:
    """What a policy may look at.

    Attributes
    ----------
    posterior : (H, W) ndarray
        The variant's current p(s | ·).
    beliefs : psgsl_pgm.experiment.VariantPosteriors
    variant : str
    space : FreeSpace
    cell : int
        The robot's flat cell.
    heading : float
        The camera's current heading, rad.
    speed, turn_time, sense_time : float
        m/s, s per quarter turn, s per gas reading.
    horizon, found_radius : float
        m.
    cache : dict
        Per-run cache of static rows (the hit model and its binary entropy per candidate cell; they depend on the
        map and the estimator only); one dict per run, empty at the start.
    score : {"per-time", "gain"}
        How ``infotaxis`` and ``space-aware-infotaxis`` score a pose (:data:`SCORES`).
    detection : DetectionModel, optional
        The detection model of P_f (:mod:`psgsl_pgm.search._detection`); default: discs of ``found_radius``
        (no footprints, a detector that never misses).
    far_spacing : float, optional
        Lattice spacing (m) of the candidates beyond ``horizon`` over the whole free space; None: none.
    """

    posterior: np.ndarray
    beliefs: object
    variant: str
    space: object
    cell: int
    heading: float
    speed: float
    turn_time: float
    sense_time: float
    horizon: float
    found_radius: float
    cache: dict = field(default_factory=dict)
    score: str = "per-time"
    detection: object = None
    far_spacing: float | None = None


@dataclass(frozen=True)
class Decision:
    """The next stop: ``cell`` (flat), camera ``headings`` there, ``path`` (flat cells from the robot's cell,
    inclusive), ``drive`` (m) and the winning ``score``."""

    cell: int
    headings: tuple
    path: np.ndarray
    drive: float
    score: float = float("nan")


def _wrap(a):
    return np.angle(np.exp(1j * np.asarray(a, dtype=np.float64)))


def travel_time(drive, turn, *, speed: float, turn_time: float, sense_time: float) -> np.ndarray:
    r"""The time of each candidate pose, broadcast over ``drive`` and ``turn`` (s):

    .. math:: \tau = \frac{\text{drive}}{\text{speed}} + t_\text{turn}\, \frac{|\text{turn}|}{\pi / 2}
              + t_\text{sense}

    with :math:`t_\text{turn}` = ``turn_time`` and :math:`t_\text{sense}` = ``sense_time``.

    Parameters
    ----------
    drive : array_like of float
        Distance driven to each pose, m.
    turn : array_like of float
        Turn at each pose, rad (its sign does not matter); broadcast with ``drive``.
    speed : float, keyword-only
        Driving speed, m/s (> 0).
    turn_time : float, keyword-only
        Time of a quarter turn (π/2), s.
    sense_time : float, keyword-only
        Time spent sensing at each pose, s.

    Returns
    -------
    numpy.ndarray
        τ, s, float64 of the broadcast shape of ``drive`` and ``turn``.

    Examples
    --------
    >>> float(travel_time(2.0, np.pi / 2, speed=0.5, turn_time=2.0, sense_time=1.0))  # 4 + 2 + 1
    7.0
    """
    return (np.asarray(drive, dtype=np.float64) / speed + turn_time * np.abs(turn) / (np.pi / 2) + sense_time)


def score_per_time(gain, tau) -> np.ndarray:
    r"""The pose-scoring rule ``"per-time"``: a gain per second, a loss times the time spent on it.

    .. math:: \text{score} = \begin{cases} G / \tau & G > 0 \\ G\, \tau & \text{otherwise} \end{cases}

    Parameters
    ----------
    gain : array_like of float
        G, each pose's expected gain (e.g. bits of entropy reduced).
    tau : array_like of float
        τ, each pose's travel time, s (> 0; :func:`travel_time`); broadcast with ``gain``.

    Returns
    -------
    numpy.ndarray
        The scores, float64 of the broadcast shape (a negative gain scores lower the longer it takes).

    Raises
    ------
    ValueError
        A travel time is not positive.

    Examples
    --------
    >>> score_per_time([2.0, -1.0], [4.0, 4.0]).tolist()
    [0.5, -4.0]
    """
    gain = np.asarray(gain, dtype=np.float64)
    tau = np.asarray(tau, dtype=np.float64)
    if np.any(tau <= 0):
        raise ValueError("travel times must be positive")
    return np.where(gain > 0, gain / tau, gain * tau)


#: The reactive policies: no map of the source, gas hits and anemometer readings only
#: (:mod:`psgsl_pgm.search._reactive`).
REACTIVE = ("surge-cast", "spiral")


def check_reactive(policy: str, variant: str, *, where: str = "") -> None:
    """ValueError when ``policy`` is reactive (:data:`REACTIVE`) and ``variant`` is not ``olfaction``: a reactive
    policy uses no semantic term; ``where`` prefixes the message."""
    if policy in REACTIVE and variant != "olfaction":
        raise ValueError(f"{where}policy {policy!r} (reactive: gas hits and wind only) runs with variant "
                         f"'olfaction' only, got {variant!r}")


#: Policies that read one estimator's own maps, and that estimator.
ESTIMATOR_OF = {"pmfs-nav": "pmfs"}


def check_estimator(policy: str, estimator: str, *, where: str = "") -> None:
    """ValueError when ``policy`` needs an estimator of its own (:data:`ESTIMATOR_OF`) and ``estimator`` is
    another; ``where`` prefixes the message."""
    need = ESTIMATOR_OF.get(policy)
    if need is not None and estimator != need:
        raise ValueError(f"{where}policy {policy!r} runs with estimator {need!r} only, got {estimator!r}")


def check_semantics_alone(policy: str, variant: str, *, where: str = "") -> None:
    """ValueError when ``policy`` reads semantics alone (:data:`SEMANTICS_ALONE`) and ``variant`` is
    ``olfaction``, which has no semantic term, and when a reactive policy (:data:`REACTIVE`) is given a semantic
    variant; ``where`` prefixes the message (e.g. ``"grid entries: "``)."""
    if policy in SEMANTICS_ALONE and variant == "olfaction":
        raise ValueError(f"{where}policy {policy!r} (semantics alone, no gas) needs a semantic variant "
                         f"('semantics' or 'semantics+rooms'), got 'olfaction'")
    check_reactive(policy, variant, where=where)


def check_score(value) -> str:
    """``value`` if it names a scoring rule of :data:`SCORES`; TypeError or ValueError naming them otherwise."""
    return one_of(value, "score", SCORES)


def _score(sit: Situation, gain, tau) -> np.ndarray:
    """The score of every candidate pose under ``sit.score`` (module docstring)."""
    if check_score(sit.score) == "per-time":
        return score_per_time(gain, tau)
    return np.asarray(gain, dtype=np.float64)  # "gain"


def _candidates(sit: Situation, *, far: bool = True):
    cells, drive, pred = sit.space.candidates(sit.cell, sit.horizon, sit.far_spacing if far else None)
    turn = _wrap(sit.space.headings[None, :] - sit.heading)  # (1, n_h)
    tau = travel_time(drive[:, None], turn, speed=sit.speed, turn_time=sit.turn_time, sense_time=sit.sense_time)
    return cells, drive, pred, tau


def _detection(sit: Situation) -> DetectionModel:
    """The situation's detection model (a disc model of ``found_radius`` when none is given, kept in the cache)."""
    if sit.detection is not None:
        return sit.detection
    model = sit.cache.get("detection")
    if model is None or model.found_radius != sit.found_radius:
        model = sit.cache["detection"] = DetectionModel(sit.space.grid, sit.found_radius)
    return model


def _found_mass(sit: Situation, cells):
    """P_f of each candidate cell, (K,), and the hypotheses it finds (list of flat arrays), by the detection
    model (:meth:`DetectionModel.found_probability`)."""
    model = _detection(sit)
    rows = model.cell_rows(cells, sit.space.position(cells))
    return model.found_probability(sit.posterior, rows), rows


def _hit_rows(sit: Situation, cells) -> list:
    """Per candidate cell, the (H·W,) static row P(hit at the cell | s), cached per cell for the run with its
    per-tile extremes (they depend on the map and the estimator's plume model only; the cache is emptied when
    that model is re-solved with a new wind estimate). The rows of the cells not cached yet are solved together,
    in the order given."""
    model = sit.beliefs.estimator.model
    if sit.cache.get("model") is not model:
        sit.cache.clear()
        sit.cache["model"] = model
    cells = np.asarray(cells).tolist()
    missing = [c for c in cells if ("row", c) not in sit.cache]
    if missing:
        p = sit.beliefs.estimator.hit_probability(sit.space.position(missing)).reshape(len(missing), -1)
        # per tile: [lo_t, hi_t, min(H_b(lo_t), H_b(hi_t))], and [0, 1, 0] for the cells that are not free
        stats = np.empty((len(missing), 3, sit.space.n_tiles + 1))
        stats[:, 0, :-1], stats[:, 1, :-1] = sit.space.tile_extremes(p)
        stats[:, :, -1] = (0.0, 1.0, 0.0)
        low, high = stats[:, 0, :-1], stats[:, 1, :-1]
        stats[:, 2, :-1] = np.minimum(entr(low) + entr(1.0 - low), entr(high) + entr(1.0 - high))
        # the tile statistics of every cell solved under this model, one (slots, 3, T + 1) table (a candidate
        # set is then one gather, not a stack of per-cell arrays)
        table, n_used = sit.cache.get("tile table", (None, 0))
        if table is None or n_used + len(missing) > table.shape[0]:
            grown = np.empty((max(2 * n_used + len(missing), 64),) + stats.shape[1:])
            if n_used:
                grown[:n_used] = table[:n_used]
            table = grown
        table[n_used : n_used + len(missing)] = stats
        for j, (c, row) in enumerate(zip(missing, p)):
            row.flags.writeable = False
            sit.cache[("row", c)] = row
            sit.cache[("slot", c)] = n_used + j
            st = table[n_used + j]  # a view: a grown table is a new array, this one keeps its (final) values
            st.flags.writeable = False
            sit.cache[("tiles", c)] = st
        sit.cache["tile table"] = (table, n_used + len(missing))
    return [sit.cache[("row", c)] for c in cells]


def _hit_blocks(sit: Situation, cells) -> list:
    """Per candidate cell, the (3, H·W) static rows [P(hit at the cell | s), H_b = entr(P) + entr(1 − P),
    entr(P)], cached per cell for the run (built from :func:`_hit_rows`)."""
    rows = _hit_rows(sit, cells)
    out = []
    for c, row in zip(np.asarray(cells).tolist(), rows):
        block = sit.cache.get(c)
        if block is None:
            e1 = entr(row)
            block = np.stack([row, e1 + entr(1.0 - row), e1])
            block.flags.writeable = False
            sit.cache[c] = block
        out.append(block)
    return out


def _olfactory_bound(sit: Situation, cells) -> np.ndarray:
    """(K,) an upper bound of the computed φ_G of each candidate cell (:func:`olfactory_gain`).

    With m_t the posterior mass of tile t (:attr:`FreeSpace.tile`; the tile of the cells that are not free
    taken as P ∈ [0, 1]) and P = P(hit | s) ∈ [lo_t, hi_t] on its cells (static, :func:`_hit_rows`):
    p̄ = Σ_s p(s) P(s) ∈ [L, U] = [Σ m_t lo_t, Σ m_t hi_t] and, H_b being concave,
    Σ_s p(s) H_b(P(s)) ≥ Σ m_t min(H_b(lo_t), H_b(hi_t)); so φ_G ≤ max_{[L, U]} H_b − Σ m_t min(H_b(lo_t),
    H_b(hi_t)) (the maximum at ½ when it lies in [L, U]), plus 1e-9, far above the rounding of either side
    (≲ 1e-12 for sums of 1e4 terms)."""
    _hit_rows(sit, cells)
    slots = [sit.cache[("slot", c)] for c in np.asarray(cells).tolist()]
    stats = sit.cache["tile table"][0][slots]  # (K, 3, T + 1)
    low, high, h_low = np.moveaxis(stats @ sit.space.tile_sums(sit.posterior.ravel()), 1, 0)
    p = np.clip(np.minimum(np.maximum(0.5, low), high), 0.0, 1.0)
    return np.maximum(entr(p) + entr(1.0 - p) - h_low, 0.0) + 1e-9


def _signal_bound(sit: Situation, cells):
    """(K,) an upper bound of the computed φ_G of each candidate cell that needs no row of the plume operator's
    inverse (:meth:`~psgsl_pgm.olfaction.GridInfotaxis.information_gain_bound`: one forward solve for every cell
    at once), or None when the estimator offers none."""
    bound_of = getattr(sit.beliefs.estimator, "information_gain_bound", None)
    if bound_of is None:
        return None
    return bound_of(sit.posterior).ravel()[np.asarray(cells)]


def _distances_past(sit: Situation, cell: int) -> np.ndarray:
    """(H·W,) max(d(cell, s) − r, 0), the geodesic distance from ``cell`` past the found radius r, 0 where
    unreachable (no mass there), cached for the run (the distances of space-aware infotaxis's value)."""
    key = ("past", int(cell), float(sit.found_radius))
    d = sit.cache.get(key)
    if d is None:
        d = sit.space.distances(cell)
        d = np.where(np.isfinite(d), np.maximum(d - sit.found_radius, 0.0), 0.0)
        d.flags.writeable = False
        sit.cache[key] = d
    return d


def _reading_factors(sit: Situation, cells):
    """Per candidate cell, the (2, H·W) log factors log L_g(s), g ∈ {miss, hit}, by which the estimator's own
    update would multiply the posterior after one reading there, or None for a Bayesian estimator (whose factor is
    the hit model P(g | s) itself). A pseudo-likelihood estimator (PMFS) says so by ``reading_log_ratio``
    (:meth:`psgsl_pgm.olfaction.PMFSEstimator.reading_log_ratio`); its factors depend on the readings so far."""
    ratio = getattr(sit.beliefs.estimator, "reading_log_ratio", None)
    if ratio is None:
        return None
    return ratio(sit.space.position(cells)).reshape(len(cells), 2, -1)


def _expected_entropy_drop(post, p_hit, log_factors, *, shared=None) -> np.ndarray:
    """H(p) − Σ_g P(g) H(q_g), q_g ∝ p L_g, for one candidate; ``p_hit`` = P(hit), ``log_factors`` (2, H·W);
    ``shared``: :func:`_posterior_parts` of ``post``, when several candidates share it."""
    e_post, h_post, support = _posterior_parts(post) if shared is None else shared
    out = h_post
    for g, prob in ((0, 1.0 - p_hit), (1, p_hit)):
        ell = log_factors[g]
        ell = ell - ell[support].max()  # L_g up to a constant, at most 1 where p > 0
        lik = np.exp(ell)
        z = float(lik @ post)
        # H(q) = log Z − Σ q log(p L / max L) = log Z + [L·entr(p) − (p ∘ L)·log L] / Z
        out -= prob * (np.log(z) + (lik @ e_post - (post * lik) @ ell) / z)
    return out


def _posterior_parts(post):
    """(entr(p) (H·W,), H(p) = Σ entr(p), the flat indices where p > 0 in order) of the posterior ``post``."""
    e_post = entr(post)
    return e_post, float(e_post.sum()), np.flatnonzero(post > 0)


def olfactory_gain(sit: Situation, cells) -> np.ndarray:
    r""":math:`\varphi_G`, the information about S one gas reading at p is expected to bring, (K,) nats.

    For a Bayesian estimator (grid Infotaxis)

    .. math:: \varphi_G = I(S; \text{hit at } p) = H_b\Big(\sum_s p(s)\, P_p(s)\Big) - \sum_s p(s)\, H_b(P_p(s))

    under the variant's posterior (:meth:`OlfactoryEstimator.information_gain` with ``posterior=``, the static rows
    cached). That mutual information is the expected drop of H(S) *when the posterior is updated by Bayes' rule
    with P_p(s)*. The PMFS posterior is not: it is recomputed from the hit map, each compared cell's factor is
    bounded in [1 − γ, 1] and saturates with its confidence, so repeated readings at one stop move it less and
    less, while I(S; hit at p) under the same posterior stays what it was — the policy keeps expecting
    information the estimator never takes in, and cycles between two stops. For such an estimator
    (``reading_log_ratio``, :func:`_reading_factors`) φ_G is the expected entropy drop under its own update,

    .. math:: \varphi_G(p) = H(S) - \sum_{g \in \{\text{miss}, \text{hit}\}} P(g \text{ at } p)\, H(q_g),
              \qquad q_g \propto p(s \mid \cdot)\, L_g(s),

    with :math:`P(\text{hit at } p) = \sum_s p(s)\, P_p(s)` from the estimator's hit model :math:`h_p(s)` (the same
    predictive as above) and :math:`L_g` its update factor. For a Bayes update :math:`L_g = P(g \mid s)` and this is the
    mutual information again (the two definitions of infotaxis, Vergassola et al. 2007, coincide); for PMFS it may be
    negative (a reading expected to spread the posterior). Exact, one pass over the free cells per candidate and
    outcome."""
    factors = _reading_factors(sit, cells)
    post = sit.posterior.ravel()
    if factors is not None:
        p_hit = np.array([r @ post for r in _hit_rows(sit, cells)])
        shared = _posterior_parts(post)
        return np.array([_expected_entropy_drop(post, ph, f, shared=shared) for ph, f in zip(p_hit, factors)])
    # one (2, H·W) product per candidate, on its cached rows in place (no (K, H·W) copy)
    dots = np.array([b[:2] @ post for b in _hit_blocks(sit, cells)]).reshape(-1, 2)
    p_bar = dots[:, 0]
    return np.maximum(entr(p_bar) + entr(1.0 - p_bar) - dots[:, 1], 0.0)


def _semantic_gain(sit: Situation):
    """(H·W,) I(S; O_n) of every cell under the variant's beliefs (exact predictive), None for olfaction."""
    if sit.variant == "olfaction":
        return None
    b = sit.beliefs
    return semantic_information_gain(b.maps[sit.variant].probs, b.likelihood, b.class_prior,  # the gas mixture when
                                     olfactory=b.estimator.posterior, predictive="exact",   # the gas is unknown
                                     gas_probs=getattr(b, "gas_probs", None)).ravel()


def _view_information(sit: Situation, cells, gain=None) -> np.ndarray:
    """φ_O for every candidate × heading (zeros for the olfaction variant); ``gain``: :func:`_semantic_gain`, if
    computed already."""
    if sit.variant == "olfaction":
        return np.zeros((len(cells), len(sit.space.headings)))
    return sit.space.view_gain(_semantic_gain(sit) if gain is None else gain, cells)


def _first_max(score) -> int:
    """The flat index of the winner of a (K, n_headings) ``score``: its first maximum, in lattice order and then
    heading order (``np.argmax``)."""
    return int(np.argmax(score))


def _best(score, cells, pred, drive, sit, *, headings=None, flat=None):
    """The :class:`Decision` of the winning pose of ``score`` (``flat``: its flat index, if known)."""
    flat = _first_max(score) if flat is None else flat
    k, h = divmod(flat, score.shape[1])
    cell = int(cells[k])
    heading = float(sit.space.headings[h]) if headings is None else float(headings[k])
    return Decision(cell, (heading,), sit.space.path(pred, cell), float(drive[k]), float(score.ravel()[flat]))


def infotaxis_gain(sit: Situation, cells):
    r"""G(p) of infotaxis, (K, n_headings): :math:`P_f\, H(S) + (1 - P_f)(\varphi_G + \varphi_O)`, nats."""
    p_f, _ = _found_mass(sit, cells)
    phi_g = olfactory_gain(sit, cells)
    phi_o = _view_information(sit, cells)
    h = float(entr(sit.posterior).sum())
    return _infotaxis_formula(p_f, h, phi_g, phi_o)


def _infotaxis_formula(p_f, h, phi_g, phi_o):
    """P_f H + (1 − P_f)(φ_G + φ_O), (K, n_headings), the same floating-point operations for every candidate."""
    return p_f[:, None] * h + (1.0 - p_f[:, None]) * (phi_g[:, None] + phi_o)


_CHUNK = 8  # candidates evaluated together by _branch_and_bound


def _branch_and_bound(bound, evaluate, n_headings: int, *, chunk: int = _CHUNK, refine=None):
    """The first maximum of every candidate pose's score, evaluating only the candidates whose bound can win.

    The candidates are evaluated in chunks of ``chunk``, from the highest bound down (equal bounds in candidate
    order); within a chunk, those whose bound is below the best score found so far are skipped, and the search
    stops at the first chunk in which every bound is (the later bounds are lower still). With valid bounds a
    skipped candidate scores below one already found, so the winner is the one :func:`_first_max` picks from
    every candidate's score: the first maximum in candidate (lattice) order, then heading order — a candidate
    whose bound equals the best score is evaluated, so a tie with it goes to the earlier candidate, as when
    every candidate is scored.

    Parameters
    ----------
    bound : (K,) ndarray
        An upper bound of each candidate's largest score over its headings (+inf: always evaluated; a NaN
        bound is never evaluated).
    evaluate : callable
        ``evaluate(k)`` → (len(k), n_headings) the exact scores of the candidates ``k`` ((m,) int array, in
        the order of evaluation); each row must depend on its own candidate only.
    n_headings : int
        The number of headings (columns of the score).
    chunk : int
        Candidates evaluated together.
    refine : callable, optional
        ``refine(k)`` → (len(k),) a second upper bound of the candidates ``k`` (dearer than ``bound``: asked only
        for the candidates whose ``bound`` can still win); those whose second bound is below the best score are
        skipped too. A NaN second bound is taken as +inf (the candidate is evaluated).

    Returns
    -------
    flat : int
        The winner's flat index into ``score`` (candidate, heading = divmod(flat, n_headings)).
    score : (K, n_headings) ndarray
        The exact score of every evaluated candidate, −inf for those skipped.
    """
    order = np.argsort(-bound, kind="stable")
    score = np.full((len(bound), n_headings), -np.inf)
    best = -np.inf
    for start in range(0, len(order), chunk):
        k = order[start : start + chunk]
        k = k[bound[k] >= best]
        if k.size == 0:
            break
        if refine is not None:
            second = np.asarray(refine(k), dtype=np.float64)
            k = k[~(second < best)]  # NaN: evaluated
            if k.size == 0:
                continue
        score[k] = evaluate(k)
        best = max(best, float(score[k].max()))
    return _first_max(score), score


def _choose_infotaxis(sit: Situation) -> Decision:
    """The infotaxis decision, the best-scoring pose of :func:`infotaxis_gain`, by branch and bound.

    Every candidate's score has an upper bound: G ≤ P_f H + (1 − P_f)(B_G + B_O), with B_G ≥ φ_G and B_O ≥ φ_O
    at every heading (:meth:`FreeSpace.view_bound`), through the same monotone floating-point operations and the
    same scoring rule as the score itself (so it bounds the *computed* score); where P_f exceeds 1 by rounding
    (1 − P_f < 0) the bound is P_f H, the score with φ_G = φ_O = 0; when a bound is not finite, every candidate is
    evaluated. B_G is first the bound that needs no row of the plume operator's inverse (:func:`_signal_bound`,
    one forward solve for all candidates), and for the candidates that can still win the smaller of it and the
    per-tile bound of their rows (:func:`_olfactory_bound`): the rows are solved only for those. The
    candidates are evaluated exactly — φ_G and φ_O, each candidate's own products, the very numbers of
    :func:`infotaxis_gain` — from the highest bound down, until the next bound is below the best score found
    (:func:`_branch_and_bound`); the others cannot win. The winner is the first maximum in lattice order, the
    candidate :func:`infotaxis_gain` would pick.
    """
    cells, drive, pred, tau = _candidates(sit)
    if getattr(sit.beliefs.estimator, "reading_log_ratio", None) is not None:  # φ_G under its own update: no bound
        return _best(_score(sit, infotaxis_gain(sit, cells), tau), cells, pred, drive, sit)
    p_f, _ = _found_mass(sit, cells)
    h = float(entr(sit.posterior).sum())
    gain = _semantic_gain(sit)
    b_o = np.zeros(len(cells)) if gain is None else sit.space.view_bound(gain, cells)
    over = p_f > 1.0  # 1 − P_f < 0 (P_f one rounding above 1): the score is largest with φ_G = φ_O = 0
    b_o = np.where(over, 0.0, b_o)

    def bound_of(b_g, k=slice(None)):  # the score's bound through the score's own operations
        b_g = np.where(over[k], 0.0, b_g)
        return _score(sit, _infotaxis_formula(p_f[k], h, b_g, b_o[k, None]), tau[k]).max(axis=1)

    b_signal = _signal_bound(sit, cells)  # no row needed: the rows are solved only for the candidates it keeps
    refine = None
    if b_signal is None:
        bound = bound_of(_olfactory_bound(sit, cells))
    else:
        bound = bound_of(b_signal)
        refine = lambda k: bound_of(np.minimum(b_signal[k], _olfactory_bound(sit, cells[k])), k)  # noqa: E731
    if not np.isfinite(bound).all():  # no bound: evaluate every one
        bound, refine = np.full(len(cells), np.inf), None

    def evaluate(k):
        phi_o = _view_information(sit, cells[k], gain)
        return _score(sit, _infotaxis_formula(p_f[k], h, olfactory_gain(sit, cells[k]), phi_o), tau[k])

    flat, score = _branch_and_bound(bound, evaluate, tau.shape[1], refine=refine)
    return _best(score, cells, pred, drive, sit, flat=flat)


def space_aware_gain(sit: Situation, cells):
    """G(p) of space-aware infotaxis, (K, n_headings), bits of log₂(remaining search).

    With u = p ∘ w_p the posterior times the likelihood w_p of "not found at p" (the detection model) and ℓ the
    likelihood of a gas outcome, the outcome's unnormalised posterior is u ℓ, Z = ℓ·u, and its entropy and
    expected distance are H = log Z + [ℓ·entr(u) + u·entr(ℓ)]/Z and D = (ℓ ∘ d_p)·u / Z (entr(x) = −x log x);
    entr(u) = w entr(p) + p entr(w). Every term is a product of a static row (ℓ, entr(ℓ), d_p, cached per cell)
    with p or entr(p), corrected on the few hypotheses that p finds: no (K, H·W) logarithm per decision.

    An estimator that does not update by Bayes' rule (PMFS, see :func:`olfactory_gain`) forms the outcome's
    posterior with its own factor instead, u ∘ L_h / (L_h·u); the outcome keeps the predictive weight
    P(h | p, F̄) = (P(h | ·)·u) / Σu of its hit model.
    """
    p_f, rows = _found_mass(sit, cells)
    sa = _SpaceAware(sit)
    factors = _reading_factors(sit, cells)
    if factors is not None:  # the estimator's own update (PMFS)
        return _space_aware_own_update(sit, sa, cells, p_f, rows, factors)
    return _space_aware_values(sit, sa, cells, p_f, rows)


class _SpaceAware:
    """The parts of :func:`space_aware_gain` shared by every candidate of a decision."""

    def __init__(self, sit: Situation):
        space = sit.space
        self.post = post = sit.posterior.ravel()
        self.ell = 2.0 * sit.found_radius
        self.disc_bits = np.log2(np.pi * sit.found_radius**2 / space.resolution**2)
        self.dist_now = _distances_past(sit, sit.cell)
        self.v_now = self.value(float(post @ self.dist_now), float(entr(post).sum() / np.log(2)))
        self.a = 1.0 - _detection(sit).miss_probability  # w = 1 − a on the hypotheses found at p, 1 elsewhere
        self.e_w = float(entr(1.0 - self.a))  # entr(w) on those hypotheses (0 for a detector that never misses)
        self.e = entr(post)
        self.pe = np.stack([post, self.e], axis=1)  # (n, 2)
        self.gain = _semantic_gain(sit)  # I(S; O_n) per cell, None for olfaction

    def value(self, d, h_bits):
        """V = log₂(1 + d/ℓ + 2^{max(H − disc, 0) − 1} − ½) ≥ 0 of the expected distance d ≥ 0 past the found
        radius (m) and the entropy H (bits); 0 for a belief the stop finds."""
        return np.log2(d / self.ell + 2.0 ** (np.maximum(h_bits - self.disc_bits, 0.0) - 1.0) + 0.5)


def _space_aware_own_update(sit: Situation, sa: _SpaceAware, cells, p_f, rows, factors) -> np.ndarray:
    """:func:`space_aware_gain` for an estimator that updates by its own factors L_h (PMFS): each outcome's
    posterior u ∘ L_h / (L_h·u), weighted by the hit model's predictive P(h | p, F̄) (loops over candidates:
    tens)."""
    space = sit.space
    post, a = sa.post, sa.a
    phi_o_bits = _view_information(sit, cells) / np.log(2)
    expected = np.zeros((len(cells), len(space.headings)))
    for k, (row, c, f) in enumerate(zip(rows, np.asarray(cells).tolist(), factors)):
        u = post.copy()
        u[row] *= 1.0 - a
        mass = u.sum()
        if not mass > 0:
            continue
        d = _distances_past(sit, c)
        z_hit = float(_hit_rows(sit, [c])[0] @ u)
        for prob, log_l in ((mass - z_hit, f[0]), (z_hit, f[1])):  # P(h | p, F̄) · mass, log L_h
            if not prob > 0:
                continue
            q = u * np.exp(log_l - log_l[u > 0].max())
            q /= q.sum()
            h_bits = float(entr(q).sum()) / np.log(2)
            expected[k] += prob / mass * sa.value(float(q @ d), h_bits - phi_o_bits[k])
    return sa.v_now - (1.0 - p_f[:, None]) * expected

def _space_aware_values(sit: Situation, sa: _SpaceAware, cells, p_f, rows, phi_o_bits=None) -> np.ndarray:
    """:func:`space_aware_gain` of ``cells`` with their P_f and found hypotheses (:func:`_found_mass`) and, if
    computed already, their φ_O in bits (:func:`_view_bits`): each candidate's own products and the same
    element-wise operations, whichever other candidates come with it."""
    post, e, pe, a, e_w = sa.post, sa.e, sa.pe, sa.a, sa.e_w
    k_n = len(cells)
    dense = np.empty((k_n, 6))  # per candidate: L·p, L·e, H_b·p, entr(L)·p, (L∘d)·p, d·p  (L = P(hit), e = entr(p))
    corr = np.empty((k_n, 8))  # the same six over the hypotheses the candidate finds, then Σp and Σe there
    for k, (block, row, c) in enumerate(zip(_hit_blocks(sit, cells), rows, np.asarray(cells).tolist())):
        d = _distances_past(sit, c)  # loop over candidates (tens): products on cached rows, no copies
        lpe = block[0] @ pe
        ld = block[0] * d
        dense[k] = (lpe[0], lpe[1], block[1] @ post, block[2] @ post, ld @ post, d @ post)
        b_m, p_m, e_m = block[:, row], post[row], e[row]
        corr[k] = (b_m[0] @ p_m, b_m[0] @ e_m, b_m[1] @ p_m, b_m[2] @ p_m, ld[row] @ p_m, d[row] @ p_m,
                   p_m.sum(), e_m.sum())

    def times_u(j):  # X·u = X·p − a Σ_found X p  (u = p ∘ w)
        return dense[:, j] - a * corr[:, j]

    mass = post.sum() - a * corr[:, 6]  # Σ u = 1 − P_f
    ent_u = (e.sum() - a * corr[:, 7]) + e_w * corr[:, 6]  # Σ entr(u)
    z_hit = times_u(0)
    l_ent_u = times_u(1) + e_w * corr[:, 0]  # ℓ_hit · entr(u)
    u_e_bin = times_u(2)  # u · (entr(ℓ_hit) + entr(ℓ_miss))
    u_e_hit = times_u(3)  # u · entr(ℓ_hit)
    d_hit = times_u(4)
    d_all = times_u(5)
    outcomes = ((z_hit, l_ent_u + u_e_hit, d_hit),  # hit
                (mass - z_hit, (ent_u - l_ent_u) + (u_e_bin - u_e_hit), d_all - d_hit))  # miss
    if phi_o_bits is None:
        phi_o_bits = _view_bits(sit, sa, cells)  # (K, n_h)
    expected = np.zeros((k_n, len(sit.space.headings)))
    norm = np.where(mass > 0, mass, 1.0)
    for z, t, d in outcomes:
        pos = z > 0
        zz = np.where(pos, z, 1.0)
        h_bits = np.where(pos, np.log(zz) + t / zz, 0.0) / np.log(2)
        d_h = np.where(pos, d / zz, 0.0)
        expected += (np.where(pos, z, 0.0) / norm)[:, None] * sa.value(d_h[:, None], h_bits[:, None] - phi_o_bits)
    return sa.v_now - (1.0 - p_f[:, None]) * expected


def _view_bits(sit: Situation, sa: _SpaceAware, cells) -> np.ndarray:
    """φ_O / ln 2 for every candidate × heading (zeros for the olfaction variant), row by row."""
    if sa.gain is None:
        return np.zeros((len(cells), len(sit.space.headings))) / np.log(2)
    return sit.space.view_gain(sa.gain, cells) / np.log(2)


_EPS = float(np.finfo(np.float64).eps)


def _space_aware_tiles(sit: Situation, cells) -> np.ndarray:
    """(K, 4, T + 1) per candidate cell and tile t: P(hit | s) ∈ [lo_t, hi_t] on its cells (:func:`_hit_rows`),
    min(entr(lo_t), entr(hi_t)) ≤ entr(P) and min(entr(1 − hi_t), entr(1 − lo_t)) ≤ entr(1 − P) there (entr is
    concave), cached per cell with the rows."""
    _hit_rows(sit, cells)
    out = []
    for c in np.asarray(cells).tolist():
        st = sit.cache.get(("sa-tiles", c))
        if st is None:
            lo, hi = sit.cache[("tiles", c)][:2]
            st = np.stack([lo, hi, np.minimum(entr(lo), entr(hi)), np.minimum(entr(1.0 - hi), entr(1.0 - lo))])
            st.flags.writeable = False
            sit.cache[("sa-tiles", c)] = st
        out.append(st)
    return np.stack(out)


def _space_aware_stack(sit: Situation, cells):
    """(K, 4, T + 1) :func:`_space_aware_tiles` and, per candidate, the tiles' floors δ of the distance past the
    found radius (:func:`_distances_past`), the tiles sorted by δ and δ in that order ((K, T + 1) each,
    :meth:`FreeSpace.tile_distance_floor`), kept in the run cache for the last candidate set only (a decision repeated at the same cell; emptied with the rows when the plume model
    changes)."""
    _hit_rows(sit, cells)  # first: empties the cache if the plume model changed
    key = (int(sit.cell), float(sit.horizon), sit.far_spacing)
    hit = sit.cache.get("sa-stack")
    if hit is not None and hit[0] == key and np.array_equal(hit[1], cells):
        return hit[2:]
    floors = [sit.space.tile_distance_floor(c) for c in np.asarray(cells).tolist()]
    delta = np.maximum(np.stack([f[0] for f in floors]) - sit.found_radius, 0.0)  # ≤ max(d − r, 0), same order
    near_first = np.stack([f[1] for f in floors])
    out = (_space_aware_tiles(sit, cells), delta, near_first, np.take_along_axis(delta, near_first, axis=1))
    sit.cache["sa-stack"] = (key, np.array(cells)) + out
    return out


def _space_aware_bound(sit: Situation, sa: _SpaceAware, cells, p_f, rows, drive, phi_o_bits) -> np.ndarray:
    """(K, n_headings) an upper bound of the computed G(p) of :func:`space_aware_gain` of each candidate pose,
    without the costly parts of its exact value: no geodesic distances from the candidate (a Dijkstra each), no
    entr of its rows.

    G = V_now − (1 − P_f) Σ_h (Z_h/M) V(D_h, H_h − φ_O/ln 2) grows as each V_h falls, and V is non-decreasing in
    D and H where its argument is positive. Computed for each candidate (one product of its row with p and
    entr(p), as in :func:`space_aware_gain`): Z_h and the part ℓ_h·entr(u) of the entropy's numerator; φ_O is
    given. Bounded per tile t, with U_t the tile's sum of u (tile sums of p corrected on the found hypotheses),
    ℓ_h ∈ [lo_t, hi_t] on it (hit; [1 − hi_t, 1 − lo_t] for a miss) and d_p (the distances past the found radius,
    max(d − r, 0)) ≥ δ_t = max(floor_t − r, 0) (:meth:`FreeSpace.tile_distance_floor`, and max(· − r, 0) is
    non-decreasing): u·entr(ℓ_h) ≥ Σ U_t min(entr(lo_t), entr(hi_t)) (entr is concave),
    and (ℓ_h ∘ d_p)·u = Σ_t W_t d̄_t with W_t = Σ_{s ∈ t} ℓ_h u ∈ [lo_t U_t, hi_t U_t], Σ W_t = Z_h, d̄_t ≥ δ_t: at
    least the least Σ W_t δ_t under those constraints (the mass above the lower ends poured into the tiles
    nearest first). Every computed sum differs from its exact value by at most err = 8 ε (H·W + |found|) times
    the sum of the magnitudes of its terms (d_p ≤ 2 (drive + max d_robot) + 1 m); the intervals are widened by a
    few err, H is taken at its least over the interval of Z, each weight Z_h/M at the end of its interval that
    makes the term smallest, and the result raised by 1e-9 (1 + the magnitudes) for the operations after the
    sums. Not finite (so never pruned) when a bound fails: a found row with repeated hypotheses, P_f > 1, an
    argument of V that may be ≤ 0, …"""
    space = sit.space
    cells = np.asarray(cells)
    k_n, t1 = len(cells), space.n_tiles + 1
    post, e, a, e_w = sa.post, sa.e, sa.a, sa.e_w
    sizes = np.array([len(r) for r in rows], dtype=np.int64)
    idx = np.concatenate(rows).astype(np.int64) if k_n else np.empty(0, np.int64)
    owner = np.repeat(np.arange(k_n), sizes)
    simple = np.ones(k_n, bool)  # rows of distinct hypotheses (sorted): u = p (1 − a) on them, p elsewhere
    if idx.size:
        repeated = np.zeros(idx.size, bool)
        repeated[1:] = (idx[1:] <= idx[:-1]) & (owner[1:] == owner[:-1])
        simple[owner[repeated]] = False
    found_p = np.bincount(owner * t1 + space.tile[idx], weights=post[idx], minlength=k_n * t1).reshape(k_n, t1)
    u_t = np.maximum(space.tile_sums(post)[None, :] - a * found_p, 0.0)  # Σ u per tile (≥ 0 exactly)
    st, delta, near_first, delta_sorted = _space_aware_stack(sit, cells)
    lo, hi = st[:, 0], st[:, 1]
    # per candidate: ℓ·p, ℓ·e over the map and over the found hypotheses, Σp and Σe there
    sums = np.empty((k_n, 6))
    for k, (row, found) in enumerate(zip(_hit_rows(sit, cells), rows)):  # candidates (tens): one product each
        p_m, e_m, l_m = post[found], e[found], row[found]
        sums[k, :2] = row @ sa.pe
        sums[k, 2:] = (l_m @ p_m, l_m @ e_m, p_m.sum(), e_m.sum())
    mass = post.sum() - a * sums[:, 4]  # as the computed M, exactly
    norm = np.where(mass > 0, mass, 1.0)
    z_hit = sums[:, 0] - a * sums[:, 2]
    a_hit = sums[:, 1] - a * sums[:, 3] + e_w * sums[:, 2]  # ℓ_hit · entr(u)
    a_all = (e.sum() - a * sums[:, 5]) + e_w * sums[:, 4]  # Σ entr(u)
    # rounding of the computed sums: terms of magnitude ≤ p (1 + d) and e + p (2 + e_w), H·W + |found| of them
    d_max = 2.0 * (np.asarray(drive, dtype=np.float64) + float(np.max(sa.dist_now)) + sit.found_radius) + 1.0
    scale = 2.0 * float(np.abs(post).sum()) * (3.0 + e_w + d_max) + 2.0 * float(e.sum())
    err = 8.0 * _EPS * (post.size + sizes) * scale
    # per tile: the lower ends of W_t (hit: lo U, miss: U − hi U) and the room above them, (hi − lo) U, for both
    lo_u, hi_u = lo * u_t, hi * u_t
    u_delta = np.einsum("kt,kt->k", u_t, delta)
    caps = np.take_along_axis(hi_u - lo_u, near_first, axis=1)
    before = np.cumsum(caps, axis=1)
    before -= caps
    total = np.zeros((k_n, phi_o_bits.shape[1]))
    magnitude = np.zeros(k_n)
    outcomes = ((lo_u.sum(axis=1), np.einsum("kt,kt->k", lo_u, delta), np.einsum("kt,kt->k", st[:, 2], u_t),
                 z_hit, a_hit, 4.0 * err),  # hit
                (u_t.sum(axis=1) - hi_u.sum(axis=1), u_delta - np.einsum("kt,kt->k", hi_u, delta),
                 np.einsum("kt,kt->k", st[:, 3], u_t), mass - z_hit, a_all - a_hit, 8.0 * err))  # miss
    for w_lo, base, e_min_u, z, t_known, slack in outcomes:
        z_lo, z_hi = z - slack, z + slack
        t_lo = t_known - slack + e_min_u - err
        poured = np.clip((z_lo - w_lo)[:, None] - before, 0.0, caps)
        dn_lo = base + np.einsum("kt,kt->k", poured, delta_sorted) - err
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            z_star = np.where(t_lo > 0, np.minimum(np.maximum(t_lo, z_lo), z_hi), z_lo)  # arg min of log Z + t/Z
            safe = np.where(z_star > 0, z_star, 1.0)
            h_lo = np.where(z_star > 0, np.log(safe) + t_lo / safe, -np.inf)
            h_lo = h_lo / np.log(2) - 1e-9 * (1.0 + np.abs(h_lo))
            d_lo = np.maximum(dn_lo, 0.0) / np.where(z_hi > 0, z_hi, 1.0)
            h_eff = np.maximum(h_lo[:, None] - phi_o_bits * (1.0 + 1e-12) - 1e-12 - sa.disc_bits, 0.0)
            arg = (d_lo[:, None] / sa.ell + 2.0 ** (h_eff - 1.0) + 0.5) * (1.0 - 1e-9)
            v_lo = np.where(arg > 0, np.log2(np.where(arg > 0, arg, 1.0)), -np.inf)
            term = np.where(v_lo >= 0, (np.maximum(z_lo, 0.0) / norm)[:, None] * v_lo, (z_hi / norm)[:, None] * v_lo)
        term = np.where((z_hi <= 0)[:, None], 0.0, term)  # an outcome of no mass adds nothing
        total += term
        magnitude += np.abs(term).max(axis=1)
    with np.errstate(invalid="ignore"):
        g = sa.v_now - (1.0 - p_f[:, None]) * total
        g = g + (1e-9 * (1.0 + abs(sa.v_now) + magnitude))[:, None]
    ok = simple & (p_f <= 1.0) & np.isfinite(phi_o_bits).all(axis=1)
    return np.where(ok[:, None] & np.isfinite(g), g, np.inf)


def _choose_space_aware(sit: Situation) -> Decision:
    """The space-aware infotaxis decision, the best-scoring pose of :func:`space_aware_gain`, by branch and bound.

    Every candidate pose's score has an upper bound: the scoring rule (monotone in G) of the bound of
    :func:`_space_aware_bound` on its computed G; a candidate's bound is the largest over its headings. The
    candidates are evaluated exactly — :func:`_space_aware_values`, each candidate's own products, the very
    numbers of :func:`space_aware_gain` — from the highest bound down, until the next bound is below the best score
    found (:func:`_branch_and_bound`); the others cannot win (the bound costs one product of its row and O(tiles)
    per candidate: no Dijkstra from it, no entr of its rows). The winner is the first maximum in lattice order,
    the candidate :func:`space_aware_gain` would pick.
    """
    cells, drive, pred, tau = _candidates(sit)
    if getattr(sit.beliefs.estimator, "reading_log_ratio", None) is not None:  # its own update: no bound
        return _best(_score(sit, space_aware_gain(sit, cells), tau), cells, pred, drive, sit)
    sa = _SpaceAware(sit)
    p_f, rows = _found_mass(sit, cells)
    phi = _view_bits(sit, sa, cells)  # exact (the views are cached per position), used by both
    bound = _score(sit, _space_aware_bound(sit, sa, cells, p_f, rows, drive, phi), tau).max(axis=1)

    def evaluate(k):
        return _score(sit, _space_aware_values(sit, sa, cells[k], p_f[k], [rows[i] for i in k.tolist()], phi[k]),
                      tau[k])

    flat, score = _branch_and_bound(bound, evaluate, tau.shape[1])
    return _best(score, cells, pred, drive, sit, flat=flat)


def _reachable_nearest(sit: Situation, target: int) -> int:
    """The drivable cell nearest (straight line) to the flat cell ``target`` among those the robot can drive to:
    the nearest drivable cell of the whole map may lie in another component of the free space (a pocket behind
    furniture), and a robot steering towards it never arrives. First minimum: the lowest flat index among equals."""
    space = sit.space
    reachable = np.flatnonzero(space.nav.ravel() & np.isfinite(space.distances(sit.cell)))
    gap = ((space.centres[reachable] - space.centres[target]) ** 2).sum(axis=1)
    return int(reachable[int(np.argmin(gap))])


def _towards(sit: Situation, target: int) -> Decision:
    """The candidate within the horizon nearest (geodesic) to the flat cell ``target``, then the quickest, with the
    camera towards the target (``greedy``, ``semantic-modes``)."""
    cells, drive, pred, tau = _candidates(sit, far=False)  # towards the target, re-planned within the horizon
    # geodesic distance from each candidate to the target cell (symmetric graph: one Dijkstra from the reachable
    # drivable cell nearest the target, then straight to the target cell)
    goal = _reachable_nearest(sit, target)
    straight = float(np.linalg.norm(sit.space.centres[target] - sit.space.centres[goal]))
    d_target = sit.space.distances(goal)[cells] + straight
    rank = np.lexsort((tau.min(axis=1), d_target))  # nearest to the target cell, then quickest
    k = int(rank[0])
    to = sit.space.position(target) - sit.space.position(cells[k])
    heading = float(np.arctan2(to[1], to[0])) if np.hypot(*to) > 0 else sit.heading
    return Decision(int(cells[k]), (heading,), sit.space.path(pred, int(cells[k])), float(drive[k]),
                    float(-d_target[k]))


def _semantic_log_score(sit: Situation, policy: str) -> np.ndarray:
    """(H, W) log p(s | z) + log p(s) + log P(F̄ | s), the unnormalised log of p(s | z, F̄) for the situation's
    semantic variant (module docstring): no gas reading enters it. ValueError naming ``policy`` for ``olfaction``."""
    check_semantics_alone(policy, sit.variant)
    est = sit.beliefs.estimator
    with np.errstate(divide="ignore"):
        return np.log(sit.beliefs.semantic(sit.variant)) + np.log(est.prior) + est.log_conditioning


def semantic_mode(sit: Situation) -> int:
    """Flat index of the mode of p(s | z, F̄) ∝ p(s | z) p(s) P(F̄ | s) for the situation's semantic variant (the
    ``semantic-modes`` policy, module docstring): no gas reading enters it. First maximum on ties."""
    score = _semantic_log_score(sit, "semantic-modes")
    skip = sit.cache.get(_STUCK)
    if skip is not None:
        score.ravel()[skip] = -np.inf
    return int(np.argmax(score))


_STUCK = "semantic-modes: modes out of reach"  # Situation.cache key: flat cells no drivable cell gets closer to


def _semantic_step(sit: Situation) -> Decision:
    """``semantic-modes``: to the reachable drivable cell nearest the mode (the found rule is a distance to it;
    a drivable cell in another component of the free space cannot be driven to), directly when it is within the
    horizon, else towards it as ``greedy``. A mode that stands after the robot reached that cell cannot be
    visited more closely: the mode and every cell whose nearest drivable cell is the robot's are set aside for the
    run (kept in ``sit.cache``), and the next mode is the target."""
    space = sit.space
    for _ in range(8):  # a handful of set-asides per decision at most; then drive on regardless
        target = semantic_mode(sit)
        goal = _reachable_nearest(sit, target)
        if goal != sit.cell:
            break
        near = np.flatnonzero(space._nearest_nav == sit.cell)
        sit.cache[_STUCK] = np.union1d(sit.cache.get(_STUCK, np.zeros(0, np.int64)), np.append(near, target))
    dist, pred = space.reach(sit.cell, sit.horizon)
    if goal != sit.cell and np.isfinite(dist[goal]):
        to = space.position(target) - space.position(goal)
        heading = float(np.arctan2(to[1], to[0])) if np.hypot(*to) > 0 else sit.heading
        return Decision(int(goal), (heading,), space.path(pred, int(goal)), float(dist[goal]), 0.0)
    return _towards(sit, goal)


def _object_finders(sit: Situation):
    """(pairs,) flat drivable cells and (pairs,) object indices: every drivable cell within r of each footprint of
    the detection model (where the robot finds a source in that object), sorted by object then cell; cached for
    the run with the model it was computed for."""
    model = _detection(sit)
    hit = sit.cache.get("nearest-object: finders")
    if hit is None or hit[0] is not model:
        nav = np.flatnonzero(sit.space.nav.ravel())
        near = model.near_footprints(sit.space.centres[nav])  # (n_nav, J): the rule's own comparison
        obj, k = np.nonzero(near.T)
        hit = sit.cache["nearest-object: finders"] = (model, nav[k], obj)
    return hit[1], hit[2]


def object_scores(sit: Situation):
    """The ``nearest-object`` scores of every object of the robot's map (module docstring).

    Returns
    -------
    score : (J,) ndarray
        P_f(j)/τ_j, 1/s; 0 for an object of no mass or out of reach.
    value : (J,) ndarray
        P_f(j) = (1 − m) Σ_{c ∈ j} p(s = c | z, F̄), the probability of finding the source at object j.
    tau : (J,) ndarray
        s, travel time to the nearest drivable cell that finds object j (inf when none is reachable).
    goal : (J,) ndarray of int
        That cell (flat; −1 when none is reachable); the lowest flat index among equally near cells.

    ValueError for the ``olfaction`` variant.
    """
    model = _detection(sit)
    log_score = _semantic_log_score(sit, "nearest-object").ravel()
    top = np.max(log_score)
    p = np.exp(log_score - top) if np.isfinite(top) else np.zeros(log_score.size)
    p = p / p.sum() if p.sum() > 0 else p
    n_obj = len(model.footprints)
    owned = model.owner >= 0
    value = (1.0 - model.miss_probability) * np.bincount(model.owner[owned], weights=p[owned], minlength=n_obj)
    cells, obj = _object_finders(sit)
    dist = sit.space.distances(sit.cell)[cells]
    d = np.full(n_obj, np.inf)
    np.minimum.at(d, obj, dist)
    goal = np.full(n_obj, -1, dtype=np.int64)
    at = np.isfinite(dist) & (dist == d[obj])
    first = np.flatnonzero(at)[np.unique(obj[at], return_index=True)[1]]  # first (lowest cell) of each object
    goal[obj[first]] = cells[first]
    tau = travel_time(d, 0.0, speed=sit.speed, turn_time=sit.turn_time, sense_time=sit.sense_time)
    score = np.where(np.isfinite(tau) & (value > 0), score_per_time(value, np.where(np.isfinite(tau), tau, 1.0)),
                     0.0)
    return score, value, tau, goal


def _nearest_object_step(sit: Situation) -> Decision:
    """``nearest-object``: to the finder cell of the best-scoring object (first maximum), directly within the
    horizon, else towards it as ``greedy``; with no object of positive score, as ``semantic-modes``."""
    score = object_scores(sit)
    if not np.any(score[0] > 0):
        return _semantic_step(sit)
    j = int(np.argmax(score[0]))
    goal = int(score[3][j])
    space = sit.space
    model = _detection(sit)
    to = space.centres[model.footprints[j]].mean(axis=0) - space.position(goal)  # the camera faces the object
    heading = float(np.arctan2(to[1], to[0])) if np.hypot(*to) > 0 else sit.heading
    dist, pred = space.reach(sit.cell, sit.horizon)
    if np.isfinite(dist[goal]):
        return Decision(goal, (heading,), space.path(pred, goal), float(dist[goal]), float(score[0][j]))
    return _towards(sit, goal)
