r"""One closed-loop episode, stop by stop: the state and the per-stop body of :func:`run_closed_loop`.

:func:`psgsl_pgm.search.run_closed_loop` is the loop ::

    episode = ClosedLoopEpisode(source, seed, policy, variant, estimator, ...)
    while not episode.done:
        episode.take(episode.planned_move())
    return episode.result()

and an outside decision maker (the gymnasium environment, :mod:`psgsl_pgm.gym`) drives the same object with its own
moves: :meth:`ClosedLoopEpisode.move_to` turns a :class:`Decision` into a :class:`Move`, and :meth:`take` runs the
very code of the loop — drive, the success rule on the way, the detector, one stop's readings and frames, the
"found" / "not found" update, the record and the declaration rule (:mod:`psgsl_pgm.search._loop` describes them).
The stepping object reads the simulator's truth only where the loop does: for the success rule and the metrics of
the record; what a decision maker may look at is :meth:`situation` (the robot's beliefs and pose) and the last
readings (:attr:`reading`, :attr:`wind`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..experiment._config import VARIANTS, ExperimentConfig
from ..experiment._metrics import _error_and_spread
from ..experiment._step import VariantPosteriors, robot_hit_rule, start_run, visit
from ..experiment._tour import shared_tour
from ._declare import declaration_error, declared_region, propose_declaration
from ._detection import DetectionModel
from ._metrics import credible_region, hpd_level
from ._choose import choose
from ._policies import POLICIES, Situation, check_estimator, check_semantics_alone
from ._settings import SearchConfig, SearchRun
from ._several import match_declarations, more_sources_probability
from ._space import FreeSpace

__all__ = ["ClosedLoopEpisode", "Move", "SEVERAL_ESTIMATORS"]

#: The estimators that declare several sources one by one (their posterior is re-assimilated after a declaration,
#: :meth:`psgsl_pgm.olfaction.OlfactoryEstimator.recondition`).
SEVERAL_ESTIMATORS = ("infotaxis", "analytic-plume")


@dataclass(frozen=True)
class Move:
    """One move of the robot: drive along ``seg`` to ``stop`` and read there.

    Attributes
    ----------
    stop : (2,) ndarray
        The stop, m.
    drive : float
        m driven to it.
    turn : float
        s of turning the camera before the stop's first frame.
    seg : (p, 2) ndarray
        The path's points from the robot's position to the stop, m (both included).
    headings : tuple of float
        Camera headings at the stop, rad (one frame each).
    cell : int or None
        The stop's flat cell as the decision named it (None: the loop snaps the stop, as for the tour).
    """

    stop: np.ndarray
    drive: float
    turn: float
    seg: np.ndarray
    headings: tuple
    cell: int | None = None


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


class ClosedLoopEpisode:
    """The state of one closed-loop search between stops (module docstring).

    Parameters
    ----------
    source, seed, policy, variant, estimator, config, search, world, space, world_spec, recorder, gas_type
    extra_sources, extra_gas_types
        As :func:`psgsl_pgm.search.run_closed_loop`; ``policy`` None: the moves come from outside
        (:meth:`move_to`), and :meth:`result` labels the run ``"external"``.

    Attributes
    ----------
    time : float
        s of simulated time since the start.
    done : bool
        Whether the episode has ended: a declaration (``end="declare"``), the detected pass (``end="reach"``) or
        the time budget.
    declaration : tuple or None
        ``(Declaration, time)`` of the robot's declaration.
    reading, wind
        The last stop's gas reading (:class:`psgsl_pgm.sim.GasReading`, its ``hit`` the robot's decision) and
        anemometer reading ((2,) m/s); None before the first stop.
    posterior : (H, W) ndarray
        The variant's current posterior.
    cell : int
        The robot's flat cell; ``heading`` its camera heading, rad.
    """

    def __init__(self, source="oven", seed: int = 0, policy: str | None = "infotaxis",
                 variant: str = "semantics+rooms", estimator: str = "infotaxis", *,
                 config: ExperimentConfig | None = None, search=None, world=None, space: FreeSpace | None = None,
                 world_spec=None, recorder=None, gas_type: str | None = None, extra_sources=(),
                 extra_gas_types=None):

        search = SearchConfig() if search is None else search
        if not isinstance(search, SearchConfig):
            raise TypeError(f"search must be a SearchConfig, got {type(search).__name__}")
        if policy is not None and policy not in POLICIES:
            raise ValueError(f"policy must be one of {POLICIES}, got {policy!r}")
        if variant not in VARIANTS:
            raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")
        if policy is not None:
            check_semantics_alone(policy, variant)
            check_estimator(policy, estimator)
        self.several = search.source_count_prior is not None  # declares sources one by one (module _several)
        if self.several and estimator not in SEVERAL_ESTIMATORS:
            raise ValueError(f"estimator must be one of {SEVERAL_ESTIMATORS} with source_count_prior (their "
                             f"posterior is re-assimilated after each declaration), got {estimator!r}")
        more = {} if not len(extra_sources) else {"extra_sources": extra_sources, "extra_gas_types": extra_gas_types}
        config, spec, setting, world = start_run(source, seed, estimator, config, world=world, world_spec=world_spec,
                                                 gas_type=gas_type, **more)
        if recorder is not None:
            world = recorder.watch(world)
        house = world.house
        # a world file's start (its own default when it names none: the navigable cell nearest the map's centre,
        # as `world check` measures from); the embedded house: the search settings' start
        start_xy = search.start if world_spec is None else tuple(float(v) for v in setting.start_for(house))
        if space is None:
            space = FreeSpace.shared(house, world.camera, clearance=search.clearance, spacing=search.spacing,
                                     n_headings=search.n_headings)
        beliefs = VariantPosteriors(world, estimator, config, setting=setting, variants=(variant,), seed=int(seed))
        self.hits = robot_hit_rule(world.gas_sensor)  # the robot's hit decision for its kind of sensor
        tour = shared_tour(house, start=start_xy, clearance=search.clearance)  # the same for every run here
        self._plan = _tour_plan(tour) if policy == "tour" else None
        self.centres = house.grid.cell_centres().reshape(-1, 2)
        truth = world.source
        r = search.found_radius
        self.sense_time = world.gas_sensor.window
        self.budget = search.time_budget
        self.declaring = search.end == "declare"
        if search.miss_probability is not None:
            robot_m = search.miss_probability
        elif self.declaring:  # the robot's estimate, counted on reference passes of its detector
            from ..experiment._robot_models import robot_source_miss_probability

            robot_m = robot_source_miss_probability(config.world_model or "ideal")
        else:
            robot_m = 0.0
        self.robot_m = robot_m
        detection = DetectionModel.shared(house, r, miss_probability=robot_m)
        self.truth_hypothesis = detection.source_cell(truth, world.source_object, house)
        self.truth_region = (detection.centres[detection.region_mask(self.truth_hypothesis).ravel()]
                             if world.source_object is not None else None)  # the scoring's footprint of an object
        self._hyps = [self.truth_hypothesis]  # every source's hypothesis (the truth: the success rule only)
        self._regions = [self.truth_region]
        for xy, obj in zip(world.sources[1:], world.source_objects[1:]):
            h = detection.source_cell(xy, obj, house)
            self._hyps.append(h)
            self._regions.append(detection.centres[detection.region_mask(h).ravel()] if obj is not None else None)
        space.cover(detection)  # stops that can find every findable source (FreeSpace.cover)
        start_cell = space.snap(start_xy)
        # the robot searches for a source it can find: p(s) ∝ p(s) [s findable] (FreeSpace.findable)
        findable = np.where(space.findable(detection, start_cell), 0.0, -np.inf)
        beliefs.condition(findable)
        if self.several:  # the factors kept apart, to drop a declared source's (module _several)
            self._ll_findable = findable.ravel().astype(np.float64)
            self._ll_not_found = np.zeros(findable.size)
            self._ll_found = np.zeros(findable.size)
            self._excluded = np.zeros(findable.size, bool)
            self._found_since = False  # a detection away from the declared sources since the last declaration
            self._declared_cells: list = []
        self.declarations: list = []  # (Declaration, time) of each declaration
        self.stopped = False  # the robot stopped declaring: p(another source) fell below the level
        self._more = [float("nan")] if self.several else []
        # end="reach": the detector's misses drawn as runs stored before declarations drew them
        self._misses = (np.random.default_rng([int(seed), 0x5EA2C4])
                        if not self.declaring and robot_m > 0 else None)
        self.source, self.spec, self.seed = source, spec, int(seed)
        self.policy, self.variant, self.estimator = policy, variant, estimator
        self.config, self.search, self.setting, self.world = config, search, setting, world
        self.space, self.beliefs, self.detection, self.recorder = space, beliefs, detection, recorder
        self.truth, self.r, self.start_xy, self.tour = truth, r, start_xy, tour

        # geodesic distance from the start to where the source counts as found
        d_start = space.distances(start_cell)
        reachable = space.nav.ravel() & self._near(space.centres)
        self.geodesic = float(d_start[reachable].min()) if reachable.any() else float("inf")

        self._rec = {k: [] for k in ("time", "position", "heading", "hit", "path_length", "error", "map_error",
                                     "spread", "region_area", "region_hit", "hpd_level")}
        self._gas_trace = []  # p(γ | ζ_1:t) per stop, when the gas is unknown
        self._cell_area = house.grid.resolution**2
        self._truth_cell = space.cell_of(truth)
        self.t0 = world.time

        start = space.position(start_cell)
        self._start = start
        self.path_pts = [start]
        self.length = 0.0
        self.found, self.t_found = False, 0.0  # a start within reach is found at t = 0 by the first stop's check
        self.declaration = None  # (Declaration, time)
        self.reading, self.wind = None, None
        self.posterior = self._record(start, tour.headings[0][-1], False, 0.0)
        self._first_headings = tuple(float(h) for h in tour.headings[0])
        self.cell, self.heading = start_cell, self._first_headings[-1]
        self.first = True
        self.cache: dict = {}  # static per-cell rows of the decisions (hit model), for this run's estimator

    # --- the success rule (the simulator's truth: scoring only) -------------------------------------------------

    def _near(self, points) -> np.ndarray:  # the success rule: the detection model with the truth as hypothesis
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        out = self.detection.found(pts, self.truth_hypothesis)
        for h in self._hyps[1:]:  # several sources: within reach of any
            out = out | self.detection.found(pts, h)
        return out

    def _found_on(self, seg) -> np.ndarray:  # the success rule where the robot truly is as it passes seg's points
        arcs = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(seg, axis=0), axis=1))])
        return self._near(self.world.true_positions(seg, times=self.world.time + arcs / self.config.speed))

    def _record(self, pos, heading, hit, length):
        rec, space, search, variant = self._rec, self.space, self.search, self.variant
        post = self.beliefs.posteriors((variant,))[0]
        err, spr = _error_and_spread(post.reshape(1, -1), self.centres, self.truth)  # metrics of a valid posterior
        best = int(np.argmax(post))
        region = credible_region(post, search.credible)
        rec["time"].append(self.world.time - self.t0)
        rec["position"].append(np.asarray(pos, dtype=np.float64))
        rec["heading"].append(float(heading))
        rec["hit"].append(bool(hit))
        rec["path_length"].append(float(length))
        rec["error"].append(float(err[0]))
        rec["map_error"].append(float(np.linalg.norm(space.centres[best] - self.truth)))
        rec["spread"].append(float(spr[0]))
        rec["region_area"].append(float(region.sum()) * self._cell_area)
        rec["region_hit"].append(bool(region.ravel()[self._truth_cell]))
        rec["hpd_level"].append(hpd_level(post, self._truth_cell))
        if self.beliefs.gas_belief is not None:
            self._gas_trace.append(self.beliefs.gas_probs)
        if self.recorder is not None:
            self.recorder.step(self.beliefs.posteriors((variant,)), self.beliefs)
        return post

    # --- the robot's side ----------------------------------------------------------------------------------------

    @property
    def time(self) -> float:
        return self.world.time - self.t0

    @property
    def done(self) -> bool:
        return ((self.found and not self.declaring) or (self.declaration is not None and not self.several)
                or self.stopped or self.time >= self.budget)

    def situation(self) -> Situation:
        """What a policy may look at now (:class:`psgsl_pgm.search.Situation`)."""
        config, search = self.config, self.search
        return Situation(self.posterior, self.beliefs, self.variant, self.space, self.cell, self.heading,
                         config.speed, config.turn_time, self.sense_time, search.horizon, self.r, self.cache,
                         search.score, self.detection, search.far_spacing)

    def first_move(self) -> Move:
        """The common first stop: the tour's look-around at the start."""
        return Move(self._start, 0.0, 0.0, self._start[None], self._first_headings)

    def move_to(self, dec) -> Move:
        """The :class:`Move` of a :class:`psgsl_pgm.search.Decision` taken at the robot's cell and heading."""
        seg = self.space.position(dec.path)
        headings = dec.headings
        turn = self.config.turn_time * abs(float(np.angle(np.exp(1j * (headings[0] - self.heading))))) / (np.pi / 2)
        return Move(seg[-1], dec.drive, turn, seg, headings, dec.cell)

    def planned_move(self) -> Move:
        """The next move of the episode's own policy (the first stop first, then the tour's plan or the policy's
        decision)."""
        if self.first:
            return self.first_move()
        if self._plan is not None:
            stop, headings = next(self._plan)
            prev = self.path_pts[-1]
            drive = float(np.linalg.norm(stop - prev))
            n_pts = max(2, int(np.ceil(drive / self.world.house.grid.resolution)) + 1)
            seg = prev[None] + np.linspace(0, 1, n_pts)[:, None] * (stop - prev)[None]
            seg[-1] = stop  # exactly the stop, so that the next drive is the tour's own distance
            return Move(stop, drive, 0.0, seg, headings)  # the tour turns between its own headings (visit)
        if self.policy is None:
            raise ValueError("this episode has no policy of its own: give its moves with move_to")
        return self.move_to(choose(self.policy, self.situation()))

    def _arc_to(self, seg, k) -> float:
        return float(np.sum(np.linalg.norm(np.diff(seg[: k + 1], axis=0), axis=1))) if k else 0.0

    def take(self, move: Move) -> None:
        """Run one stop of the loop: drive ``move``, read, update the beliefs, record, and apply the declaration
        rule (:mod:`psgsl_pgm.search._loop`)."""
        if self.done:
            raise ValueError("the episode has ended: no further move")
        world, config, detection, beliefs = self.world, self.config, self.detection, self.beliefs
        self.first = False
        stop, drive, turn, seg, headings = move.stop, move.drive, move.turn, move.seg, move.headings
        if move.cell is not None:
            self.cell = move.cell
        if self.recorder is not None:
            self.recorder.choose((stop[0], stop[1], headings[0]))
        # within reach of the source on the way?
        hits_on_path = self._found_on(seg)
        detected = False
        if not self.declaring:  # end="reach": the first detected pass ends the run
            if hits_on_path.any() and (self._misses is None or self._misses.random() >= self.robot_m):
                k = int(np.argmax(hits_on_path))
                arc = self._arc_to(seg, k)
                t = world.time - self.t0 + arc / config.speed
                if t <= self.budget:
                    self.found, self.t_found = True, t
                    self.length += arc
                    self.path_pts.extend(seg[1 : k + 1])
                    world.advance(arc / config.speed)
                    return
        if self.declaring and self.several and self.declarations:  # a firing where a declared source is: explained
            hits_on_path = hits_on_path & ~self._near_declared(seg)
        if self.declaring and hits_on_path.any():
            k = int(np.argmax(hits_on_path))
            if not self.found:  # the first pass within reach (a secondary time; it does not end the run)
                t = world.time - self.t0 + self._arc_to(seg, k) / config.speed
                if t <= self.budget:
                    self.found, self.t_found = True, t
            if world.detect_source(True):  # the detector fires at the first point within reach: the robot stops
                detected = True
                seg = seg[: k + 1]
                drive = self._arc_to(seg, k) if len(seg) > 1 else 0.0
                stop = seg[-1]
                if self._plan is None:
                    self.cell = self.space.snap(stop)
        reading, wind, frames = visit(world, stop, headings, config, drive=drive, turn=turn,
                                      camera=not beliefs.mapped, hits=self.hits)
        post = self.posterior
        if detected:  # found here: the hypotheses found first from the detection's point
            found_ll = detection.found_log_likelihood(seg)
            if not np.any(post.ravel()[np.isfinite(found_ll)] > 0):  # the belief cannot explain it (pose error):
                found_ll = detection.found_log_likelihood(seg[-1:])   # found from the point, first or not
            if np.any(post.ravel()[np.isfinite(found_ll)] > 0):  # else the robot's model has no such hypothesis
                beliefs.condition(found_ll)
                if self.several:
                    self._ll_found = self._ll_found + np.asarray(found_ll, dtype=np.float64).ravel()
                    self._found_since = True
        else:
            nf = detection.not_found_log_likelihood(seg)
            beliefs.condition(nf)  # not found on the way nor at the stop
            if self.several:
                self._ll_not_found = self._ll_not_found + np.asarray(nf, dtype=np.float64).ravel()
        if beliefs.gas_belief is not None:  # the e-nose names the gas of the same window
            beliefs.observe_smell(world.sniff())
        beliefs.observe(stop, reading, wind, frames)
        self.length += float(np.sum(np.linalg.norm(np.diff(seg, axis=0), axis=1))) if len(seg) > 1 else 0.0
        self.path_pts.extend(seg[1:])
        self.heading = headings[-1]
        if self._plan is not None:
            self.cell = self.space.snap(stop)
        self.reading, self.wind = reading, wind
        self.posterior = post = self._record(stop, self.heading, reading.hit, self.length)
        if self.declaring and world.time - self.t0 <= self.budget:
            proposal = propose_declaration(post, detection, radius=self.search.declare_radius)
            if self.several and self.declarations:  # the mass given a further source, times P(one exists)
                proposal = replace(proposal, mass=proposal.mass * self._more_probability())
            if proposal.mass >= self.search.declare_mass:  # the rule (module _declare): M >= κ
                if not self.several:
                    self.declaration = (proposal, world.time - self.t0)
                else:
                    self._declare(proposal, world.time - self.t0)
        if self.several:
            self._more.append(self._more_probability() if self.declarations else float("nan"))
            if self.declarations and self._more[-1] < self.search.more_sources_level:
                self.stopped = True

    # --- several sources (module _several) -----------------------------------------------------------------------

    def _near_declared(self, seg) -> np.ndarray:
        """(p,) whether each believed point of ``seg`` is within reach of a declared hypothesis (robot side)."""
        pts = np.asarray(seg, dtype=np.float64).reshape(-1, 2)
        out = np.zeros(len(pts), bool)
        for c in self._declared_cells:
            out |= self.detection.found(pts, c)
        return out

    def _declare(self, proposal, t: float) -> None:
        """Declare ``proposal`` and condition the target belief on "a source not yet declared": the declared
        region removed, the declared source's "found" factors dropped, the "not found" ones kept."""
        if self.declaration is None:
            self.declaration = (proposal, t)
        self.declarations.append((proposal, t))
        self._declared_cells.append(proposal.cell)
        reach = max(self.search.declare_radius, self.search.success_radius)  # one leak as the scoring counts it
        self._excluded |= declared_region(self.detection, proposal.cell, reach).ravel()
        self._ll_found = np.zeros_like(self._ll_found)
        self._found_since = False
        ll = self._ll_findable + self._ll_not_found
        ll[self._excluded] = -np.inf
        last = more_sources_probability(self.search.source_count_prior, len(self.declarations), 1.0) == 0.0
        if last or not np.isfinite(ll).any():
            self.stopped = True  # the prior's largest count, or no hypothesis left
            return
        try:
            self.beliefs.estimator.recondition(ll)
        except ValueError:  # nothing the robot's model allows is left to search
            self.stopped = True
            return
        self.posterior = self.beliefs.posteriors((self.variant,))[0]

    def _more_probability(self) -> float:
        """P(N > k | data) of module _several: Z from the robot's prior of a source's place and its "not found"
        factors."""
        pi = np.asarray(self.beliefs.estimator.prior, dtype=np.float64).ravel().copy()
        if self.variant != "olfaction":
            pi = pi * np.asarray(self.beliefs.semantic(self.variant), dtype=np.float64).ravel()
        pi[~np.isfinite(self._ll_findable) | self._excluded] = 0.0
        total = pi.sum()
        if not total > 0:
            return 0.0
        if self._found_since and np.any(pi * np.exp(self._ll_not_found + self._ll_found) > 0):
            return 1.0  # a detection no declared source explains: the detector has no false alarms
        escape = float(np.sum(pi * np.exp(self._ll_not_found)) / total)
        return more_sources_probability(self.search.source_count_prior, len(self.declarations), min(escape, 1.0))

    # --- the run ------------------------------------------------------------------------------------------------

    def declaration_outcome(self) -> dict:
        """The declaration's fields of :class:`SearchRun` (empty without one): its point, time, error and whether
        it is right (the scoring reads the simulator's truth). With several sources: the first declaration, scored
        against the nearest source (the time to the first source found)."""
        if self.declaration is None:
            return {}
        proposal, t_dec = self.declaration
        err = declaration_error(proposal.xy, self.truth, self.truth_region)
        for xy, region in zip(self.world.sources[1:], self._regions[1:]):  # several sources: the nearest
            err = min(err, declaration_error(proposal.xy, xy, region))
        return {"declared": True, "declared_xy": proposal.xy, "time_to_declare": float(t_dec),
                "declared_error": err, "declared_correct": bool(err <= self.search.success_radius),
                "declared_mass": float(proposal.mass)}

    def several_outcome(self) -> dict:
        """The several-source fields of :class:`SearchRun` (empty for one source and a one-source robot)."""
        if not self.several and len(self._hyps) == 1:
            return {}
        out = {"sources_xy": self.world.sources}
        if self.several:
            rows = np.array([[p.xy[0], p.xy[1], t, p.mass] for p, t in self.declarations]).reshape(-1, 4)
            out |= {"declarations": rows, "more_probability": np.array(self._more),
                    "declared_source": match_declarations(rows[:, :2], self.world.sources,
                                                          radius=self.search.success_radius,
                                                          regions=self._regions)}
        return out

    def gas_outcome(self) -> dict:
        """The gas fields of :class:`SearchRun` when the robot was not told the gas (empty otherwise): the true gas,
        the belief's gases and p(γ | ζ_1:t) at every stop."""
        if self.beliefs.gas_belief is None:
            return {}
        return {"gas": str(self.world.gas_type), "gas_names": tuple(self.beliefs.gas_belief.gases),
                "gas_probs": np.array(self._gas_trace)}

    def result(self):
        """The episode as a :class:`psgsl_pgm.search.SearchRun`."""

        spec, budget, found = self.spec, self.budget, self.found
        label = spec if isinstance(spec, str) else f"{spec[0]:g},{spec[1]:g}"
        arrays = {k: np.array(v) for k, v in self._rec.items()}
        return SearchRun(label, self.seed, "external" if self.policy is None else self.policy, self.variant,
                         self.estimator, self.truth, bool(found), float(self.t_found) if found else float(budget),
                         self.geodesic, float(self.length), arrays["time"], arrays["position"], arrays["heading"],
                         arrays["hit"].astype(bool), arrays["path_length"], arrays["error"], arrays["map_error"],
                         arrays["spread"], arrays["region_area"], arrays["region_hit"].astype(bool),
                         np.array(self.path_pts), self.posterior.astype(np.float32),
                         {"experiment": self.config.to_dict(),
                          "search": self.search.to_dict() | {"start": [float(v) for v in self.start_xy]}},
                         arrays["hpd_level"], **self.gas_outcome(), **self.declaration_outcome(),
                         **self.several_outcome())
