"""One search run: the robot follows the tour, every variant sees the same readings and frames.

Data flow per stop (paper Secs. "Model" and "Validation"):

    gas reading g_t  ──> olfactory estimator ──────────────────────────> p(s | g)           "olfaction"
    camera frames z_t ─> class beliefs p(o_c | z_c) (from p(o))  ──> p(s | z) ─┐
                     └─> class beliefs p(o_c | z_c, room_c)      ──> p(s | z) ─┤ fuse with p(s | g)
                                                                                ├──> p(s | g, z)   "semantics"
                                                                                └──> p(s | g, z)   "semantics+rooms"

The olfactory estimator is one object shared by the three variants, so they differ *only* in the semantic
factor of eq. (11).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._config import VARIANTS, ExperimentConfig
from ._metrics import credible_region, error_and_spread, hpd_level
from ._step import VariantPosteriors, robot_hit_rule, semantic_terms, start_run, visit
from ._tour import Tour, exploration_tour

__all__ = ["RunResult", "run_config", "run_search", "semantic_terms", "step_metrics", "walk"]


@dataclass(frozen=True, eq=False)
class RunResult:
    """Per-step metrics of one run (step 0 = before the first stop).

    Attributes
    ----------
    source, seed, estimator : identification of the run
    source_xy : (2,) ndarray
        True source position, metres.
    time : (n + 1,) ndarray
        Simulated time since the robot started, s.
    position : (n + 1, 2) ndarray
        Robot position at each step (the start for step 0).
    hit : (n + 1,) ndarray of bool
        Gas hit at each step (False at step 0).
    error, spread : (n + 1, 3) ndarray
        ‖E[s] − s_true‖ and the standard deviation √E‖s − E[s]‖² (m) for each variant of :data:`VARIANTS`.
    snapshots : dict
        ``{step: (3, H, W) ndarray}`` posteriors at the requested steps (for Fig. progression).
    config : dict
        The :class:`ExperimentConfig` of the run, as a dict.
    region_hit : (n + 1, 3) ndarray of bool
        Whether each variant's 90 % credible region (:func:`credible_region`) contains the true source's cell.
    region_area : (n + 1, 3) ndarray
        That region's area, m².
    hpd_level : (n + 1, 3) ndarray
        HPD level of the true source's cell (:func:`hpd_level`).
    """

    source: str
    seed: int
    estimator: str
    source_xy: np.ndarray
    time: np.ndarray
    position: np.ndarray
    hit: np.ndarray
    error: np.ndarray
    spread: np.ndarray
    snapshots: dict = field(default_factory=dict)
    config: dict = field(default_factory=dict)
    region_hit: np.ndarray = field(default_factory=lambda: np.zeros((0, len(VARIANTS)), bool))
    region_area: np.ndarray = field(default_factory=lambda: np.zeros((0, len(VARIANTS))))
    hpd_level: np.ndarray = field(default_factory=lambda: np.zeros((0, len(VARIANTS))))

    @property
    def n_steps(self) -> int:
        return len(self.time) - 1


def walk(world, tour: Tour, config: ExperimentConfig, *, camera: bool = True):
    """Drive ``world``'s robot along ``tour``: yields ``(j, stop, gas reading, wind, frames)`` per stop.

    Between stops the world advances by the driving time (distance / ``config.speed``); at a look-around
    waypoint by ``config.turn_time`` per heading (:func:`visit`). ``camera=False`` skips the frames
    (calibration runs). Gas hits are the robot's decision (:func:`robot_hit_rule`).
    """
    hits = robot_hit_rule(world.gas_sensor)  # the robot's hit decision for its kind of sensor, fresh per walk
    for j, stop in enumerate(tour.stops):
        drive = float(np.linalg.norm(stop - tour.stops[j - 1])) if j else 0.0
        reading, wind, frames = visit(world, stop, tour.headings[j], config, drive=drive, camera=camera, hits=hits)
        yield j, stop, reading, wind, frames


def run_search(source="oven", seed: int = 0, estimator: str = "infotaxis", *, config: ExperimentConfig | None = None,
               snapshot_at=(), world=None, tour: Tour | None = None, world_spec=None, recorder=None) -> RunResult:
    """Run one search in a house (the embedded one, or a world file's) and measure every variant at every step.

    Parameters
    ----------
    source : str or (2,) array_like
        See :func:`parse_source`: a class name (``"oven"``), a position, or a source name of the world file.
    seed : int
        Seed of the world (house jitter, wind, gas, sensors, detector).
    estimator : {"infotaxis", "analytic-plume", "particle-filter", "pmfs", "grgsl"}
        Olfactory estimator p(s | g).
    config : ExperimentConfig, optional, keyword-only
    snapshot_at : sequence of float, keyword-only
        Fractions of the search (0 = before the first stop, 1 = the end) whose three posteriors are kept, at
        step round(f · n).
    world : psgsl_pgm.sim.World, optional, keyword-only
        A prepared world (default: ``world_spec.make_world(seed, source, warm_up=config.warm_up)``).
    tour : Tour, optional, keyword-only
        Default: :func:`exploration_tour` of the world's house from the world file's start.
    world_spec : psgsl_pgm.sim.WorldSpec, optional, keyword-only
        The house, ontology, wind, start, source region and optional mapper beliefs
        (:func:`psgsl_pgm.load_world`); default: the embedded house, :func:`psgsl_pgm.sim.default_world`.
        The source region is the estimators' prior p(s) (uniform on it, zero elsewhere); with a
        ``semantic_map`` the class beliefs come from it instead of the simulated camera.
    recorder : psgsl_pgm.experiment._record.EpisodeRecorder, optional, keyword-only
        Logs the readings, frames and posteriors of the episode (``--record``); the run itself is unchanged.

    Returns
    -------
    RunResult

    Raises
    ------
    TypeError
        ``config`` is not an :class:`ExperimentConfig`, or ``seed`` is not an integer.
    ValueError
        An unknown ``estimator`` or source, or ``snapshot_at`` holds a value outside [0, 1].

    Examples
    --------
    Two stops of the tour after 5 s of gas (a whole tour takes about a minute):

    >>> from psgsl_pgm.experiment import ExperimentConfig, run_search
    >>> run = run_search("oven", 0, config=ExperimentConfig(stops=2, warm_up=5.0))
    >>> run.n_steps, run.error.shape                           # steps 0..2, one column per variant
    (2, (3, 3))
    """
    config, spec, setting, world = start_run(source, seed, estimator, config, world=world, world_spec=world_spec)
    if recorder is not None:
        world = recorder.watch(world)
    house = world.house
    tour = exploration_tour(house, start=setting.start_for(house)) if tour is None else tour
    if config.stops is not None and config.stops < len(tour):
        tour = tour.first(config.stops)
    beliefs = VariantPosteriors(world, estimator, config, setting=setting, seed=int(seed))  # as the closed loop
    centres = house.grid.cell_centres()
    truth = world.source

    n = len(tour)
    fractions = np.asarray(snapshot_at, dtype=np.float64).ravel()
    if not (np.isfinite(fractions).all() and ((fractions >= 0) & (fractions <= 1)).all()):
        raise ValueError(f"snapshot_at must hold fractions in [0, 1], got {snapshot_at!r}")
    keep = {int(round(f * n)) for f in fractions}
    err = np.empty((n + 1, len(VARIANTS)))
    spr = np.empty((n + 1, len(VARIANTS)))
    times = np.zeros(n + 1)
    pos = np.empty((n + 1, 2))
    hits = np.zeros(n + 1, dtype=bool)
    region_hit = np.zeros((n + 1, len(VARIANTS)), dtype=bool)
    region_area = np.empty((n + 1, len(VARIANTS)))
    level = np.empty((n + 1, len(VARIANTS)))
    truth_cell = int(np.ravel_multi_index(tuple(int(v) for v in house.grid.world_to_cell(truth)), house.shape))
    cell_area = house.grid.resolution**2
    snaps = {}
    t0 = world.time

    def record(step):
        post = beliefs.posteriors(VARIANTS)  # p(s | g), and p(s | g, z) without / with rooms
        err[step], spr[step], region_hit[step], region_area[step], level[step] = step_metrics(
            post, centres, truth, truth_cell, cell_area)
        times[step] = world.time - t0
        if step in keep:
            snaps[step] = post
        if recorder is not None:  # the pose the tour goes to next
            recorder.step(post, beliefs, chosen=(*tour.stops[step], tour.headings[step][0]) if step < n else None)

    pos[0] = tour.stops[0]
    record(0)
    for j, stop, reading, wind, frames in walk(world, tour, config, camera=not beliefs.mapped):
        if beliefs.gas_belief is not None:  # gas unknown: the e-nose names the gas of the same window
            beliefs.observe_smell(world.sniff())
        beliefs.observe(stop, reading, wind, frames)
        pos[j + 1], hits[j + 1] = stop, reading.hit
        record(j + 1)
    label = spec if isinstance(spec, str) else f"{spec[0]:g},{spec[1]:g}"
    return RunResult(label, int(seed), estimator, truth, times, pos, hits, err, spr, snaps,
                     run_config(config, setting), region_hit, region_area, level)


def step_metrics(post, centres, truth, truth_cell, cell_area):
    """Per-variant metrics of posteriors ``post`` (V, H, W): error and spread (:func:`error_and_spread`), and the
    calibration of the declared 90 % region — whether it holds ``truth_cell`` (flat index; None: no known source,
    False), its area (m², ``cell_area`` per cell) and the HPD level of ``truth_cell`` (NaN without one)."""
    known = truth_cell is not None
    err, spr = error_and_spread(post, centres, truth if known else centres[0, 0])  # the spread needs no source
    if not known:
        err = np.full_like(err, np.nan)
    hit, area, level = np.zeros(len(post), bool), np.empty(len(post)), np.full(len(post), np.nan)
    for v in range(len(post)):
        region = credible_region(post[v], 0.9)
        area[v] = float(region.sum()) * cell_area
        if truth_cell is not None:
            hit[v] = region.ravel()[truth_cell]
            level[v] = hpd_level(post[v], truth_cell)
    return err, spr, hit, area, level


def run_config(config: ExperimentConfig, world_spec) -> dict:
    """The settings a stored run is checked against: the config, plus the world file unless it is the embedded house."""
    out = config.to_dict()
    if world_spec is not None and world_spec.builtin is None:
        out["world"] = str(world_spec.path)
    return out
