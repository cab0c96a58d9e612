"""One entry point for every policy's next stop: the policies of :mod:`._policies` and the methods of the field
built on them (:mod:`._entrotaxis`, :mod:`._reactive`, :mod:`._pmfs_nav`), which import :mod:`._policies` and so cannot be called
from it."""

from __future__ import annotations

import numpy as np

from ._entrotaxis import choose_entrotaxis
from ._pmfs_nav import choose_pmfs_nav
from ._policies import (POLICIES, REACTIVE, Decision, Situation, _choose_infotaxis, _choose_space_aware,
                        _nearest_object_step, _semantic_step, _towards)
from ._reactive import reactive_step

__all__ = ["choose"]


def choose(policy: str, sit: Situation) -> Decision:
    r"""The next pose of ``policy`` (one of :data:`POLICIES` but ``tour``, which follows its own plan).

    Parameters
    ----------
    policy : str
        The policy's name: ``"greedy"`` (towards the MAP cell), ``"semantic-modes"``, ``"nearest-object"``,
        ``"infotaxis"``, ``"space-aware-infotaxis"``, ``"entrotaxis"``, a reactive policy of :data:`REACTIVE`
        (``"surge-cast"``, ``"spiral"``) or ``"pmfs-nav"``.
    sit : Situation
        What the robot knows at this stop: its pose, the posterior over source cells, its free space and the
        settings the policy scores with.

    Returns
    -------
    Decision
        The next stop: flat cell, camera headings there, the path to it, the drive (m) and the winning score.

    Raises
    ------
    ValueError
        ``policy`` is ``"tour"`` or not a policy name.

    Notes
    -----
    The scoring policies rank candidate poses p by a gain G(p) per time :math:`\tau(p)` (s) of
    :func:`travel_time`, with :func:`score_per_time` (or by G(p) alone under ``SearchConfig(score="gain")``).
    With :math:`P_f(p)` the probability that a stop at p finds the source (:class:`DetectionModel`),
    ``"infotaxis"`` expects the information of the stop, the objective of eq. (29) of the paper when the source
    is not found:

    .. math:: G(p) = P_f(p)\, H(S) + \big(1 - P_f(p)\big) \big[\varphi_G(p) + \varphi_O(p)\big]

    with :math:`\varphi_G(p)` the information of one gas reading
    (:meth:`psgsl_pgm.olfaction.OlfactoryEstimator.information_gain`) and
    :math:`\varphi_O(p) = \sum_{n \in F_p} I(S; O_n)` that of the camera's view
    (:func:`psgsl_pgm.view_information_gain`). ``"entrotaxis"`` scores the entropy of the stop's predicted measurement
    (found; not found with a hit; not found with a miss),

    .. math:: G(p) = H_b(P_f(p)) + \big(1 - P_f(p)\big)\, H_b(\bar P_p),

    :math:`H_b` the binary entropy (both gains in nats) and :math:`\bar P_p` the predicted probability of a hit at p
    given that the stop does not find the source.

    Examples
    --------
    The situation of a closed-loop episode after its first stop (the loop asks the same at every stop):

    >>> from psgsl_pgm.experiment import ExperimentConfig
    >>> from psgsl_pgm.search import choose
    >>> from psgsl_pgm.search._stepper import ClosedLoopEpisode
    >>> episode = ClosedLoopEpisode("oven", 0, None, "semantics+rooms", config=ExperimentConfig(warm_up=5.0))
    >>> episode.take(episode.first_move())
    >>> decision = choose("nearest-object", episode.situation())
    >>> decision.drive > 0, len(decision.headings)             # metres to the next stop, camera headings there
    (True, 1)
    """
    if policy == "greedy":
        return _towards(sit, int(np.argmax(sit.posterior)))  # the MAP cell
    if policy == "semantic-modes":
        return _semantic_step(sit)
    if policy == "nearest-object":
        return _nearest_object_step(sit)
    if policy == "infotaxis":
        return _choose_infotaxis(sit)
    if policy == "space-aware-infotaxis":
        return _choose_space_aware(sit)
    if policy == "entrotaxis":
        return choose_entrotaxis(sit)
    if policy in REACTIVE:
        return reactive_step(policy, sit)
    if policy == "pmfs-nav":
        return choose_pmfs_nav(sit)
    raise ValueError(f"policy must be one of {POLICIES[1:]} here (the tour is planned), got {policy!r}")
