"""The per-step code shared by the fixed tour (:func:`run_search`) and the closed loop (:mod:`psgsl_pgm.search`).

One :class:`VariantPosteriors` holds the robot's state of knowledge — one olfactory estimator p(s | g) and two
class-belief maps (from p(o), and from the room-category map) fed by the same frames — and turns it into the
posterior of each information variant of :data:`VARIANTS`:

    olfaction        p(s | g)
    semantics        p(s | g, z)     ∝ p(s | g) · p(s | z)        (class beliefs from p(o))
    semantics+rooms  p(s | g, z)     ∝ p(s | g) · p(s | z)        (class beliefs from p(o | room))

:func:`visit` is the robot's physics at one stop: drive (the gas keeps evolving), one gas reading (its hit
decided by the robot's rule for its kind of sensor, :func:`robot_hit_rule`), one wind reading, and the camera
frames at the requested headings (turning between them). :func:`start_run` checks a
run's settings and makes its world, the same way for both.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .._shared._memo import ContentCache, content_digest
from ..core._beliefs import room_evidence, update_class_probs
from ..core._class_beliefs import ClassBeliefMap
from ..core._fusion import fuse
from ..core._gas_belief import GasBelief
from ..core._semantic import semantic_source_probability
from ..olfaction import (FilamentPMFS, GridInfotaxis, GrGSL, MeanWindEstimator, ParticleFilter, PlumeModel,
                         PMFSEstimator)
from ..sim import default_world, match_names, reindex
from ._config import ESTIMATORS, UNKNOWN_GAS, VARIANTS, ExperimentConfig, parse_source
from ._robot_models import robot_detector_model, robot_gas_confusion, robot_hit_rule, wind_basis

__all__ = ["VariantPosteriors", "make_estimator", "robot_hit_rule", "semantic_terms", "start_run", "visit"]

#: The plume models solved at the first wind reading, shared by the runs of a process, keyed by their content:
#: every policy, variant and condition of an episode starts with the same look-around at the same start, so
#: they read the same wind and solve the same model, and its hit rows are the same column by column (the
#: transposed sparse solve takes one right-hand side at a time). Two are kept (each holds its LU factors and up
#: to 512 rows).
_FIRST_PLUMES = ContentCache(maxsize=2)


def start_run(source, seed, estimator, config, *, world=None, world_spec=None, gas_type=None, extra_sources=(),
              extra_gas_types=None):
    """The checked settings and the world of one run (the fixed tour's or the closed loop's).

    Parameters
    ----------
    source : str or (2,) array_like
        :func:`parse_source`.
    seed : int
        World seed.
    estimator : {"infotaxis", "analytic-plume", "particle-filter", "pmfs", "grgsl"}
    config : ExperimentConfig or None
        None: the defaults.
    world : psgsl_pgm.sim.World, optional, keyword-only
        A prepared world (default: ``world_spec.make_world(seed, source, warm_up=config.warm_up)``).
    world_spec : psgsl_pgm.sim.WorldSpec, optional, keyword-only
        Default: the embedded house, :func:`psgsl_pgm.sim.default_world`.
    gas_type : str, optional, keyword-only
        With ``config.gas == "unknown"``: the episode's true gas (a gas of the ontology; e.g. the benchmark's
        episode draw); default: drawn from the ontology's gases with ``seed`` (:func:`psgsl_pgm.sim.draw_gas`).

    Returns
    -------
    config : ExperimentConfig
    spec : str or tuple
        The parsed source.
    setting : psgsl_pgm.sim.WorldSpec
        ``world_spec`` or the embedded house.
    world : psgsl_pgm.sim.World
        With ``config.gas == "unknown"``: a world whose source emits a gas drawn from the ontology's gases with the
        run's seed (:func:`psgsl_pgm.sim.draw_gas`), carrying an electronic nose
        (:class:`psgsl_pgm.sim.ElectronicNose`); the robot is not told which gas.
    """
    config = ExperimentConfig() if config is None else config
    if not isinstance(config, ExperimentConfig):
        raise TypeError(f"config must be an ExperimentConfig, got {type(config).__name__}")
    if estimator not in ESTIMATORS:
        raise ValueError(f"estimator must be one of {ESTIMATORS}, got {estimator!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise TypeError(f"seed must be an integer, got {seed!r}")
    spec = parse_source(source)
    setting = default_world() if world_spec is None else world_spec
    if gas_type is not None and config.gas != UNKNOWN_GAS:
        raise ValueError(f"gas_type names the true gas of a run whose gas is unknown to the robot; config.gas is "
                         f"{config.gas!r}, not {UNKNOWN_GAS!r}")
    if gas_type is not None and gas_type not in setting.ontology.gases:
        raise ValueError(f"gas_type must be one of the ontology's gases {setting.ontology.gases}, got {gas_type!r}")
    if world is None:
        extra = {}
        if config.gas == UNKNOWN_GAS:  # the episode's gas, drawn from the ontology's and not told to the robot
            from ..sim import ElectronicNose, draw_gas

            gas = draw_gas(setting.ontology.gases, int(seed)) if gas_type is None else gas_type
            extra = {"enose": ElectronicNose(), "gas_type": gas}
        if len(extra_sources):  # several sources (psgsl_pgm.sim.make_world, "Several sources")
            extra["extra_sources"] = [parse_source(x) for x in extra_sources]
            if config.gas == UNKNOWN_GAS:
                extra["extra_gas_types"] = ([extra["gas_type"]] * len(extra_sources) if extra_gas_types is None
                                            else list(extra_gas_types))
        world = setting.make_world(int(seed), spec, warm_up=config.warm_up, model=config.world_model, **extra)
    return config, spec, setting, world


def semantic_terms(maps, likelihood, class_prior, *, gas_probs=None):
    """p(s | z) of each class-belief map (eq. (20)); (len(maps), H, W).

    Voxel maps (H, W, L, k) are reduced to columns, p(s_c | z) = Σ_{v ∈ c} p(s_v | z) (Sec. "Voxelized Scene
    Representations"). With ``gas_probs`` = p(γ | ζ) and an (m, k) ``likelihood`` p(o | s, γ): the gas mixture
    p(s | z, ζ) = Σ_γ p(γ | ζ) p(s | z, γ) (Sec. "Probabilistic Gas Classification").
    """
    return np.stack([semantic_source_probability(m.probs, likelihood, class_prior, gas_probs=gas_probs,
                                                 column_axis=2 if m.probs.ndim == 4 else None) for m in maps])


def make_estimator(name, model, config, *, prior=None, seed: int = 0):
    """The olfactory estimator ``name`` of :data:`ESTIMATORS` on ``model`` with ``config``'s settings; ``seed``
    seeds the estimators that draw random numbers (``particle-filter``, ``pmfs``), the run's seed where one is given."""
    if name == "infotaxis":
        return GridInfotaxis.from_model(model, prior=prior, tempering=config.tempering,
                                        false_hit_rate=config.false_hit_rate, missed_hit_rate=config.missed_hit_rate,
                                        parameter_grid=config.parameter_grid)
    if name == "analytic-plume":
        return PMFSEstimator.from_model(model, prior=prior, tempering=config.pmfs_tempering)
    if name == "particle-filter":
        return ParticleFilter.from_model(model, prior=prior, tempering=config.tempering,
                                         false_hit_rate=config.false_hit_rate, seed=seed)
    if name == "pmfs":
        return FilamentPMFS.from_model(model, prior=prior, seed=seed, tempering=config.filament_pmfs_tempering)
    if name == "grgsl":
        return GrGSL.from_model(model, prior=prior)
    raise ValueError(f"estimator must be one of {ESTIMATORS}, got {name!r}")


def visit(world, stop, headings, config: ExperimentConfig, *, drive: float = 0.0, turn: float = 0.0,
          camera: bool = True, hits=None):
    """The robot at one stop: returns ``(gas reading, wind, frames)``.

    The world first advances by ``drive`` / ``config.speed`` (driving ``drive`` metres) and by ``turn`` seconds
    (turning before the stop's first frame), both skipped when zero; then one gas reading and one wind
    reading at ``stop``; then one frame per heading, with ``config.turn_time`` after each when there are
    several (a look-around). ``camera=False`` skips the frames (calibration runs).

    Parameters
    ----------
    world : psgsl_pgm.sim.World
        The simulated world; it is advanced in place.
    stop : (float, float)
        Where the robot stands, (x, y) in metres.
    headings : sequence of float
        Camera headings for the stop's frames, radians (one frame each).
    config : ExperimentConfig
        The robot's speed (m/s) and turn time (s).
    drive : float, default 0.0, keyword-only
        Metres driven to reach the stop (time passes at ``config.speed``).
    turn : float, default 0.0, keyword-only
        Seconds spent turning before the first frame.
    camera : bool, default True, keyword-only
        Take the frames; False skips them.
    hits : psgsl_pgm.olfaction.HitRule, optional, keyword-only
        The run's hit rule (``robot_hit_rule``): the returned reading's ``hit`` is then its decision on the
        reading's samples. Without one the sensor's own hit is returned.

    Returns
    -------
    reading : psgsl_pgm.sim.GasReading
        The gas reading, its ``hit`` decided.
    wind : (2,) ndarray of float64
        The anemometer's (u_x, u_y), m/s.
    frames : list of psgsl_pgm.sim.Frame
        One per heading (empty with ``camera=False``).

    Raises
    ------
    ValueError
        The sensor leaves the hit decision to the robot and no ``hits`` rule is given, or ``stop`` lies off the
        map.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.experiment import ExperimentConfig, visit
    >>> from psgsl_pgm.sim import make_world
    >>> world = make_world(seed=0)
    >>> reading, wind, frames = visit(world, (7.0, 2.0), [0.0, np.pi / 2], ExperimentConfig(), drive=0.5)
    >>> type(reading.hit).__name__, wind.shape, len(frames)
    ('bool', (2,), 2)
    """
    if drive:
        world.advance(float(drive) / config.speed)
    if turn:
        world.advance(float(turn))
    reading = world.sense_gas(stop)
    if hits is not None:
        reading = replace(reading, hit=hits.decide(reading.trace))
    elif reading.hit is None:
        raise ValueError("this gas sensor leaves the hit decision to the robot: pass hits=robot_hit_rule(sensor)")
    wind = world.sense_wind(stop)
    frames = []
    for heading in headings if camera else ():
        frames.append(world.camera_frame((stop[0], stop[1], heading)))
        if len(headings) > 1:
            world.advance(config.turn_time)  # turn to the next heading
    return reading, wind, frames


class VariantPosteriors:
    """The robot's beliefs in a world, and the posterior of every information variant (see module docstring).

    Parameters
    ----------
    world : psgsl_pgm.sim.World
    estimator : {"infotaxis", "analytic-plume", "particle-filter", "pmfs", "grgsl"}
    config : ExperimentConfig
    setting : world spec, optional, keyword-only
        The ontology, source region (the estimators' prior) and optional mapper beliefs of the world
        (:func:`psgsl_pgm.load_world`); default :func:`psgsl_pgm.sim.default_world`.
    variants : sequence of str, optional, keyword-only
        The variants whose posteriors are wanted (default: all of :data:`VARIANTS`); only their class-belief maps
        are kept and updated (a closed-loop run needs its own variant's only).
    seed : int, optional, keyword-only
        The run's seed, for an estimator that draws random numbers (:func:`make_estimator`); 0 by default.

    Attributes
    ----------
    estimator : OlfactoryEstimator
        p(s | g), shared by the variants.
    maps : dict
        ``{"semantics": ClassBeliefMap, "semantics+rooms": ClassBeliefMap}`` (the core's class beliefs, in
        the detector's class order decided here, once), for the semantic variants among ``variants``.
    likelihood, class_prior : (k,) ndarray
        p(o | s, γ) and β = p(o | ¬s) in the detector's class order; with the gas unknown (``config.gas ==
        "unknown"``) ``likelihood`` is the (m, k) table of every gas of the ontology.
    gas_belief : psgsl_pgm.GasBelief or None
        With the gas unknown: p(γ | ζ_1:t) from the e-nose's classifications (:meth:`observe_smell`), with the
        confusion counted on reference exposures (:func:`psgsl_pgm.experiment.robot_gas_confusion`); None when
        the gas is told.
    model : PlumeModel
        The plume model in use (re-solved when the wind estimate moves, see :meth:`observe`).
    wind : psgsl_pgm.olfaction.MeanWindEstimator
        The robot's estimate of the mean flow from its anemometer readings.
    detector_model : psgsl_pgm.sim.DetectorModel or None
        The robot's model of its detector (estimated on reference houses), used to read the frames; ``None``
        reads them with the simulator's detector (``config.detector_model == "simulator"``, or a world whose
        classes have no reference houses).
    mapped : bool
        Whether the class beliefs come from a mapper (then the camera is not used).
    """

    def __init__(self, world, estimator: str, config: ExperimentConfig, *, setting=None, variants=VARIANTS,
                 seed: int = 0):
        variants = tuple(variants)
        bad = [v for v in variants if v not in VARIANTS]
        if bad or not variants:
            raise ValueError(f"variants must be among {VARIANTS}, got {list(variants)}")
        self.variants = variants
        setting = default_world() if setting is None else setting
        house = world.house
        ontology = setting.ontology
        unknown = config.gas == UNKNOWN_GAS
        if not unknown and config.gas not in ontology.gases:
            raise ValueError(f"gas must be one of the ontology's gases {ontology.gases} or {UNKNOWN_GAS!r}, got "
                             f"{config.gas!r}")
        classes = world.detector.classes
        order = match_names(classes, ontology.classes)
        if (order < 0).any():
            raise ValueError(f"the detector's classes {classes} are not all in the ontology {ontology.classes}")
        # p(o | s, γ) in the detector's order (with ε = config.off_ontology of off-ontology sources mixed in)
        self.likelihood = ontology.source_likelihood(None if unknown else config.gas,
                                                     off_ontology=config.off_ontology)[..., order]
        self.gas_belief = None
        if unknown:  # p(γ | ζ_1:t), uniform before the first classified reading
            self.gas_belief = GasBelief(ontology.gases, *robot_gas_confusion(tuple(ontology.gases)))
        self.class_prior = beta = ontology.class_prior[order]  # β = p(o | ¬s)
        room_table = ontology.room_table[:, order]
        room_table = room_table / room_table.sum(axis=1, keepdims=True)
        self.mapped = setting.class_beliefs is not None  # a mapper's beliefs replace the simulated camera
        labels = reindex(house.room_labels, house.room_names, ontology.rooms)  # house rooms -> ontology rows
        has_rooms = len(ontology.rooms) > 0  # without p(o | room) every room is at the class prior
        if self.mapped:
            given = setting.class_beliefs[..., order]
            plain = ClassBeliefMap(given, classes)
            if has_rooms:
                factor = room_evidence(labels, room_table, beta)  # p(o | room) / p(o); 1 outside listed rooms
                if given.ndim == 4:
                    factor = factor[:, :, None, :]
                rooms = ClassBeliefMap(update_class_probs(given, factor), classes)  # p(o | z, room) ∝ p(o | z) p(o | room) / p(o)
            else:
                rooms = ClassBeliefMap(given.copy(), classes)
        else:
            plain = ClassBeliefMap.from_prior(house.shape, beta, classes)
            rooms = ClassBeliefMap.from_rooms(labels, room_table, beta, classes) if has_rooms else \
                ClassBeliefMap.from_prior(house.shape, beta, classes)
        self.maps = {v: m for v, m in (("semantics", plain), ("semantics+rooms", rooms)) if v in variants}
        # the robot's own models, never the simulator's: the mean wind from its anemometer readings (a still-air
        # plume until the first reading), the detector model counted on reference houses
        self._config = config
        self.wind = MeanWindEstimator(wind_basis(house), house.grid)
        self._outlets = house.outlet
        self._wind_solved = np.zeros(self.wind.basis.shape[0])  # coefficients behind the current plume model
        self.n_wind_solves = 0
        self.model = self._plume(self._wind_solved)
        # the robot calibrates its detector with the camera it carries: frames of the reference houses taken as
        # its world takes them (occluding, with persistent errors, in a world whose model has the camera)
        from ..sim._world_model import WorldModel

        own_camera = "camera" in WorldModel.parse(config.world_model or setting.model)
        self.detector_model = robot_detector_model(classes, realistic=own_camera) \
            if config.detector_model == "estimated" else None
        self.estimator = make_estimator(estimator, self.model, config,
                                        prior=setting.region_mask(house).astype(np.float64), seed=seed)

    def _plume(self, coefficients) -> PlumeModel:
        """The plume model with the mean wind Σ a_k φ_k of ``coefficients`` (one sparse LU factorisation)."""
        self.n_wind_solves += 1
        cfg = self._config
        grid, field = self.wind.grid, self.wind.field(coefficients)

        def make():
            return PlumeModel.from_grid_map(grid, field, outlets=self._outlets, diffusivity=cfg.diffusivity,
                                            lifetime=cfg.lifetime, encounter_scale=cfg.encounter_scale)

        if self.wind.n_readings != 1:
            return make()
        key = content_digest(grid.occupancy, float(grid.resolution),
                             tuple(np.asarray(grid.origin, dtype=np.float64).ravel().tolist()),
                             np.asarray(field, dtype=np.float64), self._outlets, float(cfg.diffusivity),
                             float(cfg.lifetime), float(cfg.encounter_scale))
        return _FIRST_PLUMES.get(key, make)

    def _refresh_wind(self) -> None:
        """Re-solve the plume with the current wind estimate at readings 1, 2, 4, 8, … when the coefficients moved
        by more than ``config.wind_refresh`` (relative, in norm) since the last solve; the estimator then
        re-assimilates its readings under the new model (:meth:`OlfactoryEstimator.replace_model`)."""
        n = self.wind.n_readings
        if n & (n - 1):  # not a power of two
            return
        a = self.wind.coefficients
        if np.linalg.norm(a - self._wind_solved) <= self._config.wind_refresh * np.linalg.norm(a):
            return
        self._wind_solved = a
        self.model = self._plume(a)
        self.estimator.replace_model(self.model)

    def observe(self, stop, reading, wind, frames) -> None:
        """Assimilate one stop: the anemometer reading into the wind estimate (re-solving the plume on schedule),
        the gas reading into p(s | g), every frame — read with the robot's detector model — into both
        class-belief maps. ``wind`` None (a robot without an anemometer): the wind estimate keeps what it had (the
        still-air plume without any reading) and the estimator gets no wind."""
        if wind is not None:
            self.wind.add(stop, wind)
            self._refresh_wind()
        self.estimator.update(stop, reading.hit, wind)
        for frame in frames if self.maps else ():
            if self.detector_model is not None:  # the labels read with the robot's model of its detector
                frame = replace(frame, likelihood=self.detector_model.likelihood(frame.labels, frame.distance))
            for m in self.maps.values():  # the same frames for both maps: one observation stream
                m.observe(frame)

    @property
    def gas_probs(self):
        """(m,) p(γ | ζ_1:t), the weight of the semantic term's gas mixture; None when the gas is told."""
        return None if self.gas_belief is None else self.gas_belief.probs

    def observe_smell(self, smell) -> None:
        """Assimilate one e-nose classification (a :class:`psgsl_pgm.sim.Smell`) into p(γ | ζ_1:t): a reading
        named as a gas outside the ontology, or not named, changes nothing (the confusion is counted among the
        ontology's gases). Nothing to do when the gas is told."""
        if self.gas_belief is not None and smell.label in self.gas_belief.gases:
            self.gas_belief.update(smell.label, smell.strength)

    def condition(self, log_likelihood) -> None:
        """Condition p(s | g) on an observation of s other than a gas reading (the closed loop's "not found
        here", :class:`psgsl_pgm.search.DetectionModel`): every variant's p(s | g, z) ∝ p(s | g) p(s | z) then
        holds its factor exactly once (the fixed tour of the validation experiment never calls this)."""
        self.estimator._condition(log_likelihood)  # the posterior is read at the next record, after the reading

    def semantic(self, variant: str) -> np.ndarray:
        """p(s | z) of a semantic variant, (H, W)."""
        if variant not in self.maps:
            raise ValueError(f"variant must be one of the semantic variants kept, {tuple(self.maps)}, got {variant!r}")
        return semantic_terms([self.maps[variant]], self.likelihood, self.class_prior, gas_probs=self.gas_probs)[0]

    def posteriors(self, variants=VARIANTS) -> np.ndarray:
        """(len(variants), H, W) posterior of each variant now."""
        bad = [v for v in variants if v not in self.variants]
        if bad:
            raise ValueError(f"variants must be among {self.variants} (the variants kept), got {bad}")
        p_g = self.estimator.posterior  # p(s | g)
        semantic = [v for v in variants if v != "olfaction"]
        p_z = dict(zip(semantic, semantic_terms([self.maps[v] for v in semantic], self.likelihood,
                                                self.class_prior, gas_probs=self.gas_probs))) if semantic else {}
        return np.stack([p_g if v == "olfaction" else fuse(p_g, p_z[v]) for v in variants])  # p(s|g,z) ∝ p(s|g) p(s|z)
