r"""The closed loop in the simulated house: the policy chooses each stop from the beliefs it has built so far.

Per stop (the validation experiment's own per-step code, :class:`psgsl_pgm.experiment.VariantPosteriors` and
:func:`psgsl_pgm.experiment.visit`):

    drive along the geodesic path (the gas keeps evolving)  ->  found on the way?  ->  "not found" update
    ->  turn the camera  ->  one gas reading, one wind reading, one camera frame  ->  p(s | g) and both
    class-belief maps updated  ->  the variant's posterior  ->  the policy picks the next pose

Every policy starts with the tour's first stop (a look-around at the start). The search ends when the robot
finds the source at any point of its path (found), or at ``time_budget`` s of simulated time; a find at
t ≤ ``time_budget`` counts.

**Found, and "not found here".** One detection model (:class:`psgsl_pgm.search.DetectionModel`) decides both.
Under the hypothesis s = c the robot at x finds the source iff x lies within r = ``found_radius`` of c's found
region R(c): the footprint of the object that owns c in the robot's map (an oven: a robot cannot drive into
it, and its nearest drivable cell is 0.55 m from its centre), or c's own centre otherwise (a disc of radius r).
The success rule is that rule with the true source as hypothesis (the emitting object, or the cell holding a
point source), applied where the robot truly is: with a localisation error
(:class:`psgsl_pgm.sim.LocalisationError`) the robot plans, drives and records in the frame it believes, and only
the rule maps its path to the true one (:meth:`psgsl_pgm.sim.World.true_positions`, at the time it passes each
point). A move along path points x_1 … x_p (the drive and the stop) that does not find the source is an
observation F̄ with

.. math:: P(\bar F \mid s = c) = \begin{cases} m & \exists k:\ d(x_k, R(c)) \le r \\
                                              1 & \text{otherwise} \end{cases}

(m = ``miss_probability``, 0 by default: the visited hypotheses are ruled out), applied to p(s | g) after every
move (:meth:`VariantPosteriors.condition`, :meth:`OlfactoryEstimator.condition`): p(s | g, F̄) ∝ p(s | g)
P(F̄ | s). Since P(F̄ | s) depends on s only, every variant's fused posterior p(s | g, z, F̄) ∝ p(s | g, F̄)
p(s | z) holds it exactly once. With m > 0 a move within reach of the true source finds it with probability
1 − m (a draw from a generator seeded with the run's seed, used only then). The fixed tour of the validation
experiment (``psgsl experiment``) does not apply this update: it measures estimation along a fixed path, where
the robot is not searching.

**A source the robot can find.** Before its first decision the robot conditions p(s | g) on the event that the
source is one it can find at all, P(findable | s = c) = 1 if some drivable cell reachable from the start lies
within r of R(c), else 0 (:meth:`FreeSpace.findable`, from its own map and the same rule). The problem is a
search for such a source — ``psgsl search`` and ``psgsl world check`` refuse any other before a run
(:func:`psgsl_pgm.search.check_findable`) — and without the factor, mass on cells no stop can rule out (behind
furniture, in a gap narrower than the robot) stays in the belief for good and draws the planners to shuttle
beside it.
"""

from __future__ import annotations

from ..experiment._config import ExperimentConfig
from ._settings import ENDS, SearchConfig, SearchRun
from ._space import FreeSpace
from ._stepper import ClosedLoopEpisode

__all__ = ["ENDS", "SearchConfig", "SearchRun", "run_closed_loop"]


def run_closed_loop(source="oven", seed: int = 0, policy: str = "infotaxis", variant: str = "semantics+rooms",
                    estimator: str = "infotaxis", *, config: ExperimentConfig | None = None,
                    search: SearchConfig | None = None, world=None, space: FreeSpace | None = None,
                    world_spec=None, recorder=None, gas_type: str | None = None, extra_sources=(),
                    extra_gas_types=None) -> SearchRun:
    r"""Run one closed-loop search in the simulated house: the robot senses, updates its beliefs, chooses its next
    stop, and declares the source (module docstring).

    Parameters
    ----------
    source : str or (2,) array_like
        The true source: an object class of the house (the first object of that class emits), a world file's source
        name, or a position "x,y" / (x, y) in metres (:func:`psgsl_pgm.experiment.parse_source`).
    seed : int
        World seed (house jitter, wind, gas, sensors, detector, the source detector's misses).
    policy : str
        How the robot chooses its next stop, one of :data:`psgsl_pgm.search.POLICIES`: ``"tour"`` (the validation
        experiment's fixed exploration tour, back and forth), ``"greedy"`` (the most probable reachable cell),
        ``"infotaxis"`` (:math:`\varphi = \varphi_G + \varphi_O` per second, eq. (29)), ``"space-aware-infotaxis"``,
        ``"semantic-modes"`` and ``"nearest-object"`` (semantics alone), or a method of the field (``"entrotaxis"``,
        ``"surge-cast"``, ``"spiral"``; :mod:`psgsl_pgm.search._policies`).
    variant : {"olfaction", "semantics", "semantics+rooms"}
        Which posterior the robot uses (the experiment's code path for it): :math:`p(s \mid g)` alone, fused with
        :math:`p(s \mid z)` of class beliefs from the camera, or of class beliefs that start from the room map.
    estimator : str
        The olfactory estimator giving :math:`p(s \mid g)`, one of :data:`psgsl_pgm.experiment.ESTIMATORS`.
    config : ExperimentConfig, optional, keyword-only
        Physics, estimator and world-model settings (the validation experiment's; default ``ExperimentConfig()``).
    search : SearchConfig, optional, keyword-only
        The loop's settings: found radius, budget, candidates, the declaration rule and how a run ends (default
        ``SearchConfig()``).
    world : psgsl_pgm.sim.World, optional, keyword-only
        A prepared world (default: built from ``world_spec`` or the embedded house with ``seed`` and ``source``).
    space : FreeSpace, optional, keyword-only
        Prepared geometry of the world's house (shares caches between runs of one house).
    world_spec : world, optional, keyword-only
        The house, ontology, source region (the estimators' prior) and mapper beliefs
        (:func:`psgsl_pgm.load_world`); default: the embedded house, :func:`psgsl_pgm.sim.default_world` — the
        validation experiment's own setting. A world file's ``start`` (or, when it names none, its default start,
        :meth:`WorldSpec.start_for`) replaces ``search.start``.
    recorder : psgsl_pgm.experiment._record.EpisodeRecorder, optional, keyword-only
        Logs the readings, frames, every variant's posterior and each chosen pose (``--record``); the run itself
        is unchanged.
    gas_type : str, optional, keyword-only
        With ``config.gas == "unknown"``: the episode's true gas (default: drawn with ``seed``,
        :func:`psgsl_pgm.experiment._step.start_run`). The robot is not told it: it infers p(γ | ζ_1:t) from its
        electronic nose at every stop, and its semantic term, φ_O and P_f use the gas mixture
        Σ_γ p(γ | ζ) p(s | z, γ).
    extra_sources : sequence, keyword-only
        Further true sources that emit at the same time (0–2, each given as ``source``): the world sums their plumes
        and its detector reports any of them (:func:`psgsl_pgm.sim.make_world`). A robot told to expect several
        (``search.source_count_prior``) declares them one by one (:mod:`psgsl_pgm.search._several`).
    extra_gas_types : sequence of str, optional, keyword-only
        With the gas unknown: each further source's gas (default: the first source's).

    Returns
    -------
    SearchRun
        The run's trajectory, per-stop metrics, final posterior and its declaration.

    Raises
    ------
    TypeError
        ``search`` is not a :class:`SearchConfig`, or ``seed`` is not an integer.
    ValueError
        An unknown policy, variant, estimator or source; ``olfaction`` with a semantics-alone policy, or a
        semantic variant with a reactive one.

    Examples
    --------
    With 5 s of gas before the robot starts (the default is a minute):

    >>> from psgsl_pgm.experiment import ExperimentConfig
    >>> from psgsl_pgm.search import SearchConfig, run_closed_loop
    >>> run = run_closed_loop("oven", 0, "nearest-object", "semantics+rooms", config=ExperimentConfig(warm_up=5.0),
    ...                       search=SearchConfig(time_budget=120.0))
    >>> run.declared, run.declared_correct
    (True, True)
    """

    episode = ClosedLoopEpisode(source, seed, policy, variant, estimator, config=config, search=search, world=world,
                                space=space, world_spec=world_spec, recorder=recorder, gas_type=gas_type,
                                extra_sources=extra_sources, extra_gas_types=extra_gas_types)
    while not episode.done:  # one stop per pass (ClosedLoopEpisode.take)
        episode.take(episode.planned_move())
    return episode.result()
