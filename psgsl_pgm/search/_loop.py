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

from dataclasses import asdict, dataclass, field, fields

import numpy as np

from .._shared._validate import index, one_of, positive, real_pair, unit_interval
from ..experiment._config import ExperimentConfig
from ._policies import check_score
from ._space import FreeSpace
from ._stepper import ClosedLoopEpisode

__all__ = ["ENDS", "SearchConfig", "SearchRun", "run_closed_loop"]

#: How a run may end (:class:`SearchConfig` ``end``).
ENDS = ("declare", "reach")


@dataclass(frozen=True)
class SearchConfig:
    """Settings of the closed loop (the physics — speed, turn time, sensors — are the experiment's).

    Parameters
    ----------
    found_radius : float
        m; the source is found when the robot comes this close (the lab's benchmark rule).
    time_budget : float
        s of simulated time.
    horizon : float
        m of geodesic distance within which candidate positions are considered.
    spacing : float
        m, lattice spacing of candidate positions.
    n_headings : int
        Camera headings per candidate position.
    clearance : float
        m, the robot's distance from walls, furniture and windows (the tour's).
    start : (2,) tuple
        Start position, m (the tour's).
    credible : float
        Mass of the declared credible region.
    score : {"per-time", "gain"}
        How ``infotaxis`` and ``space-aware-infotaxis`` score a candidate pose: its gain per second of driving,
        turning and sensing (the default), or its gain alone (:mod:`psgsl_pgm.search._policies`).
    far_spacing : float or None
        m, lattice spacing of the candidate positions beyond ``horizon``, over the whole reachable free space
        (:mod:`psgsl_pgm.search._policies`); None: no candidates beyond the horizon.
    miss_probability : float or None
        In [0, 1): the robot's probability that a move within ``found_radius`` of the source's found region does
        not detect it (:class:`DetectionModel`). None: the robot's estimate counted on reference passes of its
        detector (:func:`psgsl_pgm.experiment.robot_source_miss_probability`) with ``end="declare"``, 0 (the
        deterministic rule) with ``end="reach"``.
    end : {"declare", "reach"}
        How a run ends. ``"declare"``: at the robot's first declaration (:mod:`psgsl_pgm.search._declare`),
        right when it lies within ``success_radius`` of the source; passing near the source is evidence, not the
        end. ``"reach"``: when the robot's path first passes within ``found_radius`` of the source and the
        detector fires (the rule of earlier results, kept to reproduce them; no declaration is made).
    declare_mass : float
        κ in (0, 1): the posterior mass within ``declare_radius`` of the most probable hypothesis's found region
        at which the robot declares it.
    declare_radius : float
        m, the reach of the declared region around the declared hypothesis's found region.
    success_radius : float
        m: a declaration is right when it lies this close to the source (to the source object's footprint).
    """

    found_radius: float = 0.5
    time_budget: float = 1000.0
    horizon: float = 2.0
    spacing: float = 0.5
    n_headings: int = 8
    clearance: float = 0.25
    start: tuple = (0.8, 6.0)
    credible: float = 0.9
    score: str = "per-time"
    far_spacing: float | None = 1.0
    miss_probability: float | None = None
    end: str = "declare"
    declare_mass: float = 0.9
    declare_radius: float = 0.5
    success_radius: float = 1.0

    def __post_init__(self):
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "score":
                v = check_score(v)
            elif f.name == "start":
                v = tuple(real_pair(v, "start", "an (x, y)", "metres").tolist())
            elif f.name == "n_headings":
                v = index(v, "n_headings", minimum=1)
            elif f.name == "credible":
                v = unit_interval(v, "credible", low_open=True, high_open=True)
            elif f.name == "miss_probability":
                v = None if v is None else unit_interval(v, "miss_probability", high_open=True)
            elif f.name == "end":
                v = one_of(v, "end", ENDS)
            elif f.name == "declare_mass":
                v = unit_interval(v, "declare_mass", low_open=True, high_open=True)
            elif f.name == "far_spacing" and v is None:
                pass
            else:
                v = positive(v, f.name, "metres" if f.name != "time_budget" else "seconds")
            object.__setattr__(self, f.name, v)

    def to_dict(self) -> dict:
        """The settings as JSON types. The default ``score`` is left out (as runs stored before the option
        existed have it); ``far_spacing`` and ``miss_probability`` are always written, so that runs stored
        before the "not found" update and the far candidates — other searches — never resume into a new grid.
        The declaration settings are written with ``end="declare"`` only: a ``"reach"`` run's settings are those
        of runs stored before declarations."""
        d = asdict(self)
        d["start"] = list(self.start)
        if d["score"] == "per-time":
            del d["score"]
        if self.end == "reach":  # the settings of runs stored before declarations, unchanged
            for k in ("end", "declare_mass", "declare_radius", "success_radius"):
                del d[k]
            d["miss_probability"] = 0.0 if self.miss_probability is None else self.miss_probability
        return d


@dataclass(frozen=True, eq=False)
class SearchRun:
    """One closed-loop search (step 0 = before the first stop).

    Attributes
    ----------
    source, seed, policy, variant, estimator : identification
    source_xy : (2,) ndarray
        True source position, m.
    found : bool
        Whether the robot's true path passed within ``found_radius`` of the source's found region (with
        ``end="reach"``: and the detector fired — the run's end).
    time_to_find : float
        s of simulated time of that first pass; ``time_budget`` when there was none (``found`` says so).
    geodesic : float
        Geodesic distance from the start to the nearest drivable point within ``found_radius`` of the source, m.
    driven : float
        Path length driven until found (or the budget), m.
    time : (n + 1,) ndarray
        s since the start, at each stop (step 0: 0).
    position : (n + 1, 2) ndarray
        Robot position at each stop (step 0: the start).
    heading : (n + 1,) ndarray
        Camera heading of the stop's last frame, rad.
    hit : (n + 1,) ndarray of bool
    path_length : (n + 1,) ndarray
        m driven up to each stop.
    error, map_error, spread : (n + 1,) ndarray
        ‖E[s] − s‖, ‖s_MAP − s‖ and √E‖s − E[s]‖² of the variant's posterior, m.
    region_area : (n + 1,) ndarray
        Area of the credible region (smallest set of cells holding ``credible`` of the mass), m².
    region_hit : (n + 1,) ndarray of bool
        Whether that region contains the true source's cell.
    hpd_level : (n + 1,) ndarray
        HPD level of the true source's cell (:func:`psgsl_pgm.search.hpd_level`): the posterior mass of every cell
        at least as probable as it.
    path : (p, 2) ndarray
        Every cell centre driven through, m (for drawing).
    final_posterior : (H, W) ndarray of float32
    config : dict
        ``{"experiment": ExperimentConfig dict, "search": SearchConfig dict}``.
    declared : bool
        Whether the robot declared a source within the budget (``end="declare"``).
    declared_xy : (2,) ndarray
        The declared point, m (NaN without a declaration).
    time_to_declare : float
        s of simulated time of the declaration (NaN without one).
    declared_error : float
        m, distance from the declared point to the source (its object's footprint); NaN without a declaration.
    declared_correct : bool
        Whether the declaration lies within ``success_radius`` of the source.
    declared_mass : float
        The posterior mass M that backed the declaration (:mod:`psgsl_pgm.search._declare`); NaN without one.
    """

    source: str
    seed: int
    policy: str
    variant: str
    estimator: str
    source_xy: np.ndarray
    found: bool
    time_to_find: float
    geodesic: float
    driven: float
    time: np.ndarray
    position: np.ndarray
    heading: np.ndarray
    hit: np.ndarray
    path_length: np.ndarray
    error: np.ndarray
    map_error: np.ndarray
    spread: np.ndarray
    region_area: np.ndarray
    region_hit: np.ndarray
    path: np.ndarray
    final_posterior: np.ndarray
    config: dict = field(default_factory=dict)
    hpd_level: np.ndarray = field(default_factory=lambda: np.zeros(0))
    declared: bool = False
    declared_xy: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    time_to_declare: float = float("nan")
    declared_error: float = float("nan")
    declared_correct: bool = False
    declared_mass: float = float("nan")

    @property
    def n_steps(self) -> int:
        return len(self.time) - 1

    @property
    def end(self) -> str:
        """How the run ended (:class:`SearchConfig` ``end``; runs stored before declarations: ``"reach"``)."""
        return str(self.config.get("search", {}).get("end", "reach"))

    @property
    def succeeded(self) -> bool:
        """The run's success: a right declaration (``end="declare"``), or the find (``end="reach"``)."""
        return bool(self.declared_correct) if self.end == "declare" else bool(self.found)

    @property
    def time_to_success(self) -> float:
        """s until the success (:attr:`succeeded`), or the time budget without one: the event time of the
        survival statistics, censored at the budget."""
        if self.end == "reach":
            return float(self.time_to_find)
        budget = float(self.config["search"]["time_budget"])
        return float(self.time_to_declare) if self.declared_correct else budget

    @property
    def false_declaration(self) -> bool:
        """Whether the run ended in a wrong declaration."""
        return bool(self.declared and not self.declared_correct)

    @property
    def path_ratio(self) -> float:
        """Path length driven until found (or the budget) / geodesic distance from the start to the source."""
        return float(self.driven / self.geodesic) if self.geodesic > 0 else float("nan")


def run_closed_loop(source="oven", seed: int = 0, policy: str = "infotaxis", variant: str = "semantics+rooms",
                    estimator: str = "infotaxis", *, config: ExperimentConfig | None = None,
                    search: SearchConfig | None = None, world=None, space: FreeSpace | None = None,
                    world_spec=None, recorder=None) -> SearchRun:
    """Run one closed-loop search in the simulated house.

    Parameters
    ----------
    source : str or (2,) array_like
        :func:`psgsl_pgm.experiment.parse_source`.
    seed : int
        World seed (house jitter, wind, gas, sensors, detector).
    policy : {"tour", "greedy", "infotaxis", "space-aware-infotaxis", "semantic-modes", "nearest-object"}
    variant : {"olfaction", "semantics", "semantics+rooms"}
        Which posterior the robot uses (the experiment's code path for it).
    estimator : {"infotaxis", "pmfs"}
    config : ExperimentConfig, optional, keyword-only
        Physics and estimator settings (the validation experiment's).
    search : SearchConfig, optional, keyword-only
    world : psgsl_pgm.sim.World, optional, keyword-only
    space : FreeSpace, optional, keyword-only
        Prepared geometry of the world's house (shares caches between runs).
    world_spec : world, optional, keyword-only
        The house, ontology, source region (the estimators' prior) and mapper beliefs
        (:func:`psgsl_pgm.load_world`); default: the embedded house, :func:`psgsl_pgm.sim.default_world` — the
        validation experiment's own setting. A world file's ``start`` (or, when it names none, its default start,
        :meth:`WorldSpec.start_for`) replaces ``search.start``.
    recorder : psgsl_pgm.experiment._record.EpisodeRecorder, optional, keyword-only
        Logs the readings, frames, every variant's posterior and each chosen pose (``--record``); the run itself
        is unchanged.

    Returns
    -------
    SearchRun
    """

    episode = ClosedLoopEpisode(source, seed, policy, variant, estimator, config=config, search=search, world=world,
                                space=space, world_spec=world_spec, recorder=recorder)
    while not episode.done:  # one stop per pass (ClosedLoopEpisode.take)
        episode.take(episode.planned_move())
    return episode.result()
