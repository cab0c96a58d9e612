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
from ..experiment._config import VARIANTS, ExperimentConfig
from ..experiment._metrics import _error_and_spread
from ..experiment._step import VariantPosteriors, robot_hit_rule, start_run, visit
from ..experiment._tour import exploration_tour
from ._declare import declaration_error, propose_declaration
from ._detection import DetectionModel
from ._metrics import credible_region, hpd_level
from ._choose import choose
from ._policies import POLICIES, Situation, check_score, check_semantics_alone
from ._space import FreeSpace

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
    gas : str
        The episode's true gas when the robot was not told it (``gas: unknown``); "" otherwise.
    gas_names : tuple of str
        The gases of the robot's belief p(γ | ζ_1:t), in the order of ``gas_probs``'s columns; () when told.
    gas_probs : (n + 1, m) ndarray
        p(γ | ζ_1:t) at each stop (step 0: the uniform prior); (0, 0) when the gas was told.
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
    gas: str = ""
    gas_names: tuple = ()
    gas_probs: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    @property
    def gas_unknown(self) -> bool:
        """Whether the robot searched without being told the gas."""
        return bool(self.gas_names)

    @property
    def gas_identified(self) -> bool:
        """Whether the most probable gas at the run's end is the true one, alone (a tie — e.g. the uniform prior of a
        run that ended before any classified reading — is not an identification); False when the gas was told."""
        if not self.gas_unknown:
            return False
        p = self.gas_probs[-1]
        i = self.gas_names.index(self.gas)
        return bool(p[i] > np.max(np.delete(p, i), initial=-np.inf))

    def time_to_gas(self, level: float = 0.9) -> tuple[float, bool]:
        """(s until p(true γ | ζ_1:t) first reached ``level``, whether it did): the first such stop's time, or the
        time budget without one — also for a run that ended (declared) before: it never names the gas (censored
        at the budget). A run whose gas was told has no such time: ValueError."""
        if not self.gas_unknown:
            raise ValueError("time_to_gas needs a run whose gas the robot was not told (gas: unknown)")
        p_true = self.gas_probs[:, self.gas_names.index(self.gas)]
        reached = np.flatnonzero(p_true >= level)
        budget = float(self.config["search"]["time_budget"])
        if reached.size == 0 or self.time[reached[0]] > budget:
            return budget, False
        return float(self.time[reached[0]]), True

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


def _tour_plan(tour):
    """Tour stops back and forth for ever: yields (stop, headings)."""
    order = list(range(len(tour)))
    forward = True
    j = 0
    while True:
        seq = order[1:] if j == 0 else (order[::-1][1:] if not forward else order[1:])
        for k in seq:
            hs = tour.headings[k]
            if not forward and len(hs) == 1:
                hs = hs + np.pi  # travel direction, reversed
            yield tour.stops[k], tuple(float(h) for h in hs)
        forward = not forward
        j += 1


def run_closed_loop(source="oven", seed: int = 0, policy: str = "infotaxis", variant: str = "semantics+rooms",
                    estimator: str = "infotaxis", *, config: ExperimentConfig | None = None,
                    search: SearchConfig | None = None, world=None, space: FreeSpace | None = None,
                    world_spec=None, recorder=None, gas_type: str | None = None) -> SearchRun:
    """Run one closed-loop search in the simulated house: the robot senses, updates its beliefs, chooses its next
    stop, and declares the source (module docstring).

    Parameters
    ----------
    source : str or (2,) array_like
        The true source: an object class of the house (the first object of that class emits), a world file's source
        name, or a position "x,y" / (x, y) in metres (:func:`psgsl_pgm.experiment.parse_source`).
    seed : int
        World seed (house jitter, wind, gas, sensors, detector, the source detector's misses).
    policy : str
        How the robot chooses its next stop, one of :data:`psgsl_pgm.search.POLICIES`: ``"tour"`` (the
        validation experiment's fixed exploration tour, back and forth), ``"greedy"`` (the most probable reachable
        cell), ``"infotaxis"`` (φ = φ_G + φ_O per second, eq. (29)), ``"space-aware-infotaxis"``,
        ``"semantic-modes"`` and ``"nearest-object"`` (semantics alone), or a method of the field
        (``"entrotaxis"``, ``"surge-cast"``, ``"spiral"``; :mod:`psgsl_pgm.search._policies`).
    variant : {"olfaction", "semantics", "semantics+rooms"}
        Which posterior the robot uses (the experiment's code path for it): p(s | g) alone, fused with p(s | z) of
        class beliefs from the camera, or of class beliefs that start from the room map.
    estimator : str
        The olfactory estimator giving p(s | g), one of :data:`psgsl_pgm.experiment.ESTIMATORS`.
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
    >>> from psgsl_pgm.search import SearchConfig, run_closed_loop
    >>> run = run_closed_loop("oven", 0, "nearest-object", "semantics+rooms",
    ...                       search=SearchConfig(time_budget=120.0))  # doctest: +SKIP
    >>> run.declared, run.declared_correct  # doctest: +SKIP
    (True, True)
    """

    search = SearchConfig() if search is None else search
    if not isinstance(search, SearchConfig):
        raise TypeError(f"search must be a SearchConfig, got {type(search).__name__}")
    if policy not in POLICIES:
        raise ValueError(f"policy must be one of {POLICIES}, got {policy!r}")
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")
    check_semantics_alone(policy, variant)
    config, spec, setting, world = start_run(source, seed, estimator, config, world=world, world_spec=world_spec,
                                             gas_type=gas_type)
    if recorder is not None:
        world = recorder.watch(world)
    house = world.house
    # a world file's start (its own default when it names none: the navigable cell nearest the map's centre, as
    # `world check` measures from); the embedded house: the search settings' start
    start_xy = search.start if world_spec is None else tuple(float(v) for v in setting.start_for(house))
    if space is None:
        space = FreeSpace(house, world.camera, clearance=search.clearance, spacing=search.spacing,
                          n_headings=search.n_headings)
    beliefs = VariantPosteriors(world, estimator, config, setting=setting, variants=(variant,), seed=int(seed))
    hits = robot_hit_rule(world.gas_sensor)  # the robot's hit decision for its kind of sensor
    tour = exploration_tour(house, start=start_xy, clearance=search.clearance)
    plan = _tour_plan(tour) if policy == "tour" else None
    centres = house.grid.cell_centres().reshape(-1, 2)
    truth = world.source
    r = search.found_radius
    sense_time = world.gas_sensor.window
    budget = search.time_budget
    declaring = search.end == "declare"
    if search.miss_probability is not None:
        robot_m = search.miss_probability
    elif declaring:  # the robot's estimate, counted on reference passes of its detector
        from ..experiment._robot_models import robot_source_miss_probability

        robot_m = robot_source_miss_probability(config.world_model or "ideal")
    else:
        robot_m = 0.0
    detection = DetectionModel.from_house(house, r, miss_probability=robot_m)
    truth_hypothesis = detection.source_cell(truth, world.source_object, house)
    truth_region = (detection.centres[detection.region_mask(truth_hypothesis).ravel()]
                    if world.source_object is not None else None)  # the scoring's footprint of an object source
    space.cover(detection)  # stops that can find every findable source (FreeSpace.cover)
    start_cell = space.snap(start_xy)
    # the robot searches for a source it can find: p(s) ∝ p(s) [s findable] (FreeSpace.findable)
    beliefs.condition(np.where(space.findable(detection, start_cell), 0.0, -np.inf))
    # end="reach": the detector's misses drawn as runs stored before declarations drew them
    misses = (np.random.default_rng([int(seed), 0x5EA2C4]) if not declaring and robot_m > 0 else None)

    def near(points) -> np.ndarray:  # the success rule: the detection model with the truth as hypothesis
        return detection.found(np.asarray(points, dtype=np.float64).reshape(-1, 2), truth_hypothesis)

    def found_on(seg) -> np.ndarray:  # the success rule where the robot truly is as it passes seg's points
        arcs = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(seg, axis=0), axis=1))])
        return near(world.true_positions(seg, times=world.time + arcs / config.speed))

    # geodesic distance from the start to where the source counts as found
    d_start = space.distances(start_cell)
    reachable = space.nav.ravel() & near(space.centres)
    geodesic = float(d_start[reachable].min()) if reachable.any() else float("inf")

    rec = {k: [] for k in ("time", "position", "heading", "hit", "path_length", "error", "map_error", "spread",
                           "region_area", "region_hit", "hpd_level")}
    gas_trace = []  # p(γ | ζ_1:t) per stop, when the gas is unknown
    cell_area = house.grid.resolution**2
    truth_cell = space.cell_of(truth)
    t0 = world.time

    def record(pos, heading, hit, length):
        post = beliefs.posteriors((variant,))[0]
        err, spr = _error_and_spread(post.reshape(1, -1), centres, truth)  # metrics of a valid posterior
        best = int(np.argmax(post))
        region = credible_region(post, search.credible)
        rec["time"].append(world.time - t0)
        rec["position"].append(np.asarray(pos, dtype=np.float64))
        rec["heading"].append(float(heading))
        rec["hit"].append(bool(hit))
        rec["path_length"].append(float(length))
        rec["error"].append(float(err[0]))
        rec["map_error"].append(float(np.linalg.norm(space.centres[best] - truth)))
        rec["spread"].append(float(spr[0]))
        rec["region_area"].append(float(region.sum()) * cell_area)
        rec["region_hit"].append(bool(region.ravel()[truth_cell]))
        rec["hpd_level"].append(hpd_level(post, truth_cell))
        if beliefs.gas_belief is not None:
            gas_trace.append(beliefs.gas_probs)
        if recorder is not None:
            recorder.step(beliefs.posteriors((variant,)), beliefs)
        return post

    def arc_to(seg, k) -> float:
        return float(np.sum(np.linalg.norm(np.diff(seg[: k + 1], axis=0), axis=1))) if k else 0.0

    start = space.position(start_cell)
    path_pts = [start]
    length = 0.0
    found, t_found = False, 0.0  # a start within reach is found at t = 0 by the first stop's check
    declared = None  # (Declaration, time)
    post = record(start, tour.headings[0][-1], False, 0.0)
    headings = tuple(float(h) for h in tour.headings[0])
    cell, heading = start_cell, headings[-1]
    first = True
    cache: dict = {}  # static per-cell rows of the decisions (hit model), for this run's estimator
    while not (found and not declaring) and declared is None and world.time - t0 < budget:
        if first:  # the common first stop: the tour's look-around at the start
            stop, drive, turn, seg = start, 0.0, 0.0, start[None]
            first = False
        elif plan is not None:
            stop, headings = next(plan)
            prev = path_pts[-1]
            drive = float(np.linalg.norm(stop - prev))
            n_pts = max(2, int(np.ceil(drive / house.grid.resolution)) + 1)
            seg = prev[None] + np.linspace(0, 1, n_pts)[:, None] * (stop - prev)[None]
            seg[-1] = stop  # exactly the stop, so that the next drive is the tour's own distance
            turn = 0.0  # the tour turns between its own headings (visit), as in the experiment
        else:
            sit = Situation(post, beliefs, variant, space, cell, heading, config.speed, config.turn_time,
                            sense_time, search.horizon, r, cache, search.score, detection, search.far_spacing)
            dec = choose(policy, sit)
            cells = dec.path
            seg = space.position(cells)
            stop, drive, headings = seg[-1], dec.drive, dec.headings
            turn = config.turn_time * abs(float(np.angle(np.exp(1j * (headings[0] - heading))))) / (np.pi / 2)
            cell = dec.cell
        if recorder is not None:
            recorder.choose((stop[0], stop[1], headings[0]))
        # within reach of the source on the way?
        hits_on_path = found_on(seg)
        detected = False
        if not declaring:  # end="reach": the first detected pass ends the run
            if hits_on_path.any() and (misses is None or misses.random() >= robot_m):
                k = int(np.argmax(hits_on_path))
                arc = arc_to(seg, k)
                t = world.time - t0 + arc / config.speed
                if t <= budget:
                    found, t_found = True, t
                    length += arc
                    path_pts.extend(seg[1 : k + 1])
                    world.advance(arc / config.speed)
                    break
        elif hits_on_path.any():
            k = int(np.argmax(hits_on_path))
            if not found:  # the first pass within reach (a secondary time; it does not end the run)
                t = world.time - t0 + arc_to(seg, k) / config.speed
                if t <= budget:
                    found, t_found = True, t
            if world.detect_source(True):  # the detector fires at the first point within reach: the robot stops there
                detected = True
                seg = seg[: k + 1]
                drive = arc_to(seg, k) if len(seg) > 1 else 0.0
                stop = seg[-1]
                if plan is None:
                    cell = space.snap(stop)
        reading, wind, frames = visit(world, stop, headings, config, drive=drive, turn=turn,
                                      camera=not beliefs.mapped, hits=hits)
        if detected:  # found here: the hypotheses found first from the detection's point
            found_ll = detection.found_log_likelihood(seg)
            if not np.any(post.ravel()[np.isfinite(found_ll)] > 0):  # the belief cannot explain it (pose error):
                found_ll = detection.found_log_likelihood(seg[-1:])   # found from the point, first or not
            if np.any(post.ravel()[np.isfinite(found_ll)] > 0):  # else the robot's model has no such hypothesis
                beliefs.condition(found_ll)
        else:
            beliefs.condition(detection.not_found_log_likelihood(seg))  # not found on the way nor at the stop
        if beliefs.gas_belief is not None:  # the e-nose names the gas of the same window
            beliefs.observe_smell(world.sniff())
        beliefs.observe(stop, reading, wind, frames)
        length += float(np.sum(np.linalg.norm(np.diff(seg, axis=0), axis=1))) if len(seg) > 1 else 0.0
        path_pts.extend(seg[1:])
        heading = headings[-1]
        if plan is not None:
            cell = space.snap(stop)
        post = record(stop, heading, reading.hit, length)
        if declaring and world.time - t0 <= budget:
            proposal = propose_declaration(post, detection, radius=search.declare_radius)
            if proposal.mass >= search.declare_mass:  # the rule (module _declare): M >= κ
                declared = (proposal, world.time - t0)
    label = spec if isinstance(spec, str) else f"{spec[0]:g},{spec[1]:g}"
    arrays = {k: np.array(v) for k, v in rec.items()}
    decl = {}
    if beliefs.gas_belief is not None:
        decl = {"gas": str(world.gas_type), "gas_names": tuple(beliefs.gas_belief.gases),
                "gas_probs": np.array(gas_trace)}
    if declared is not None:
        proposal, t_dec = declared
        err = declaration_error(proposal.xy, truth, truth_region)
        decl |= {"declared": True, "declared_xy": proposal.xy, "time_to_declare": float(t_dec),
                "declared_error": err, "declared_correct": bool(err <= search.success_radius),
                "declared_mass": float(proposal.mass)}
    return SearchRun(label, int(seed), policy, variant, estimator, truth, bool(found),
                     float(t_found) if found else float(budget), geodesic, float(length), arrays["time"], arrays["position"],
                     arrays["heading"], arrays["hit"].astype(bool), arrays["path_length"], arrays["error"],
                     arrays["map_error"], arrays["spread"], arrays["region_area"], arrays["region_hit"].astype(bool),
                     np.array(path_pts), post.astype(np.float32),
                     {"experiment": config.to_dict(),
                      "search": search.to_dict() | {"start": [float(v) for v in start_xy]}},  # the start used
                     arrays["hpd_level"], **decl)
