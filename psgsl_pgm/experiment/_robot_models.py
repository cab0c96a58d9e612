"""What the robot brings to a house instead of the simulator's truth: the basis of its wind estimate, and its
detector model estimated on reference houses.

* **Wind.** The mean flow through a house is driven by its windows: its shape is the potential flow from the
  inlet windows to the outlet windows of the map (:func:`psgsl_pgm.sim.potential_flow` at unit mean speed), a
  property of the floor plan alone; its strength and sign are what the anemometer readings fix
  (:class:`psgsl_pgm.olfaction.MeanWindEstimator`, one least-squares coefficient). A map without both kinds of
  window (e.g. a world file with a CFD export and no windows) gets the two uniform flows along x and y.
* **Detector.** The robot's p(label | class, distance) is counted from camera frames taken along the exploration
  tour of the *reference* houses (the seeds that also give p(o) and p(o | room), never evaluated), labelled by
  the simulator's detector and compared with those houses' true class maps
  (:meth:`psgsl_pgm.sim.DetectorModel.from_counts`: Dirichlet-smoothed confusion, false-positive rate, and the
  maximum-likelihood detection curve). The evaluation's frames are then *read* with this estimate, while they
  are *made* by the simulator's detector. With ``realistic=True`` the reference frames are made by a detector
  of the realistic kind (:meth:`psgsl_pgm.sim.DetectorModel.realistic`, furniture occlusion, each reference
  house's own persistent errors and distractor sites from ``frame_seed``) — the calibration a robot makes with
  its own detector on labelled houses; the estimate is still the per-cell model of ``from_counts``, which
  knows nothing of the errors' persistence.
* **Gas hits.** The robot knows which kind of gas sensor it carries, not its parameters: the ideal
  :class:`psgsl_pgm.sim.GasSensor` reports a calibrated, thresholded reading whose hit is used as it is; for a
  metal-oxide sensor the robot thresholds the rate of rise, for a photo-ionisation detector the
  baseline-subtracted level (:class:`psgsl_pgm.olfaction.HitRule`, noise and baseline estimated online from its
  own readings).
* **Gas classes.** The confusion p(ζ | γ, strength) of the robot's electronic nose
  (:class:`psgsl_pgm.sim.ElectronicNose`) is counted on reference exposures of its own device to each gas at known
  concentrations, as a lab calibrates an e-nose (:func:`robot_gas_confusion`); the device's patterns and noise
  are never read.
* **Source detector.** The probability m that a pass within reach of a source does not detect it is counted on
  reference passes of the robot's own detector (:func:`robot_source_miss_probability`): a detector that missed
  k of n passes has m = k / n, never the simulator's parameter.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..olfaction import HitRule
from ..sim import (HOUSE_CLASSES, Camera, DetectorErrors, DetectorModel, MOXSensor, PIDSensor, default_house,
                   potential_flow, take_frame)
from ..sim._classes import OTHER, match_names
from ..sim._house_ontology import REFERENCE_SEEDS
from ._tour import exploration_tour

__all__ = ["STRENGTH_EDGES", "robot_detector_model", "robot_gas_confusion", "robot_hit_rule",
           "robot_source_miss_probability", "wind_basis"]

_STOP_STRIDE = 3  # frames at every third stop of each reference tour (~10^6 labelled cells over ten houses)


def wind_basis(house) -> np.ndarray:
    """(K, H, W, 2) basis fields of the robot's mean-wind estimate in ``house`` (see the module docstring).

    K = 1 (the unit-mean-speed potential flow from the inlet to the outlet windows) when the map has both, else
    K = 2 (uniform unit flows along x and along y on the free cells).
    """
    grid = house.grid
    if house.inlet.any() and house.outlet.any():
        flow = potential_flow(grid, house.inlet, house.outlet, mean_speed=1.0).velocity
        return np.where(grid.free[..., None], flow, 0.0)[None]
    basis = np.zeros((2,) + grid.shape + (2,))
    basis[0, ..., 0] = grid.free
    basis[1, ..., 1] = grid.free
    return basis


def robot_hit_rule(sensor) -> HitRule | None:
    """The robot's hit rule for a gas sensor of ``sensor``'s kind (its class only; no attribute is read).

    None for a sensor that decides its own hits (:class:`psgsl_pgm.sim.GasSensor`: a calibrated ppm reading and
    its threshold, used unchanged); a fresh :class:`psgsl_pgm.olfaction.HitRule` per run otherwise: ``"rise"``
    for a :class:`psgsl_pgm.sim.MOXSensor` (a t-test from the first reading), ``"level"`` from a clean-air zero of
    0 ppm for a :class:`psgsl_pgm.sim.PIDSensor` (what a ppm instrument zeroed in fresh air reads, a property of
    the kind).
    """
    kind = type(sensor)
    if issubclass(kind, MOXSensor):
        return HitRule("rise", warm_up=1)
    if issubclass(kind, PIDSensor):  # ppm output, zeroed in fresh air before a run
        return HitRule("level", warm_up=1, zero=0.0)
    return None


@lru_cache(maxsize=4)
def _estimated(seeds: tuple, pseudo_count: float, frame_seed: int, realistic: bool = False) -> DetectorModel:
    truth_c, labels, dist = [], [], []
    classes = None
    rng = np.random.default_rng(frame_seed)
    camera = Camera(occlusion="furniture") if realistic else Camera()
    for s in seeds:
        house = default_house(s)
        errors = None
        if realistic:
            detector = DetectorModel.realistic(house.classes)
            errors = DetectorErrors.draw(detector, house, rng)
        else:
            detector = DetectorModel.default(house.classes)  # the reference house's (simulated) detector
        classes = detector.classes if classes is None else classes
        idx = match_names(house.classes, classes)
        idx = np.where(idx < 0, list(classes).index(OTHER), idx)
        truth = idx[house.class_map]
        tour = exploration_tour(house)
        for stop, headings in zip(tour.stops[::_STOP_STRIDE], tour.headings[::_STOP_STRIDE]):
            for heading in headings:
                frame = take_frame(house, (stop[0], stop[1], heading), camera=camera, detector=detector, rng=rng,
                                   errors=errors)
                truth_c.append(truth[frame.cells[:, 0], frame.cells[:, 1]])
                labels.append(frame.labels)
                dist.append(frame.distance)
    return DetectorModel.from_counts(classes, np.concatenate(truth_c), np.concatenate(labels), np.concatenate(dist),
                                     pseudo_count=pseudo_count)


def robot_detector_model(classes=HOUSE_CLASSES, *, reference_seeds=REFERENCE_SEEDS, pseudo_count: float = 1.0,
                         frame_seed: int = 0, realistic: bool = False) -> DetectorModel | None:
    """The robot's detector model, estimated from frames of the reference houses (module docstring).

    Parameters
    ----------
    classes : tuple of str
        The classes of the detector to be modelled; ``None`` is returned unless they are the reference houses'
        classes (a world with other classes has no reference frames: its detector is then read with the
        simulator's own model, and the caller says so).
    reference_seeds : tuple of int, keyword-only
        Houses never evaluated (default: those of :func:`psgsl_pgm.sim.house_ontology`).
    pseudo_count : float, keyword-only
        Dirichlet α of :meth:`DetectorModel.from_counts`.
    frame_seed : int, keyword-only
        Seed of the detector's random labels on the reference frames.
    realistic : bool, keyword-only
        Make the reference frames with a realistic camera and detector (module docstring).

    Returns
    -------
    DetectorModel or None
    """
    if tuple(classes) != tuple(HOUSE_CLASSES):
        return None
    seeds = tuple(int(s) for s in reference_seeds)
    if not seeds:
        raise ValueError("reference_seeds must name at least one reference house")
    if not isinstance(realistic, (bool, np.bool_)):
        raise TypeError(f"realistic must be True or False, got {type(realistic).__name__} {realistic!r}")
    if realistic:
        return _estimated(seeds, float(pseudo_count), int(frame_seed), True)
    return _estimated(seeds, float(pseudo_count), int(frame_seed))


#: Reference passes counted per estimate of the source detector's miss probability (standard error ≤ 0.025).
SOURCE_PASSES = 400


@lru_cache(maxsize=8)
def robot_source_miss_probability(world_model="ideal", *, passes: int = SOURCE_PASSES, seed: int = 0) -> float:
    """The robot's estimate of its source detector's miss probability m (module docstring).

    Parameters
    ----------
    world_model : str or WorldModel
        The world whose detector the robot carries (:class:`psgsl_pgm.sim.WorldModel`).
    passes : int, keyword-only
        Reference passes within reach of a source, each one detection trial of the detector.
    seed : int, keyword-only
        Seed of the reference trials (never an evaluated episode's).

    Returns
    -------
    float
        k / n, the fraction of reference passes that did not detect the source.

    Examples
    --------
    >>> robot_source_miss_probability("ideal")
    0.0
    """
    from ..sim import WorldModel

    model = world_model if isinstance(world_model, WorldModel) else WorldModel.parse(world_model)
    n = int(passes)
    if n < 1:
        raise ValueError(f"passes must be a positive number of reference passes, got {passes!r}")
    detector = model.source_detector()
    rng = np.random.default_rng([int(seed), 0x5DE7])
    missed = sum(not detector.detects(True, rng) for _ in range(n))
    return missed / n


#: The robot's strength bins of its e-nose's readings (response units: the response at 1 ppm has length ≈ 1);
#: weak readings, whose classification is poorest, get the finest bins.
STRENGTH_EDGES = (0.0, 0.5, 0.6, 0.7, 0.85, 1.0, 1.3, 2.0, np.inf)

#: Reference exposures per gas of the e-nose calibration (≥ 2 000 classified readings per strength bin).
GAS_EXPOSURES = 40_000


def robot_gas_confusion(gases, *, exposures: int = GAS_EXPOSURES, seed: int = 0, pseudo_count: float = 1.0):
    """The robot's confusion p(ζ | γ, strength bin) of its electronic nose, counted on reference exposures.

    Each of ``exposures`` reference readings per gas exposes the robot's device (a default
    :class:`psgsl_pgm.sim.ElectronicNose`, the kind it carries) to that gas at a known concentration: clean air
    (0 ppm) for a quarter of them, the others log-uniform over 0.01–100 ppm (the range of a plume in a house, from
    background to beside the source). The named gas of every classified reading is counted in the bin of its
    strength (:data:`STRENGTH_EDGES`), with ``pseudo_count`` added to every cell (Dirichlet smoothing: no
    confusion is ever certain).

    Parameters
    ----------
    gases : tuple of str
        The gases γ of the table, in order (a subset of the device's gases: an ontology's gases).
    exposures : int, keyword-only
    seed : int, keyword-only
        Seed of the reference exposures (never an evaluated episode's).
    pseudo_count : float, keyword-only

    Returns
    -------
    confusion : (B, m, m) ndarray
        ``confusion[b, g, z]`` = p(ζ = z | γ = g, bin b); rows sum to one.
    edges : (B + 1,) ndarray
        :data:`STRENGTH_EDGES`.

    Raises
    ------
    TypeError
        ``gases`` is one string instead of a sequence of names.

    Examples
    --------
    >>> conf, edges = robot_gas_confusion(("smoke", "ammonia"), exposures=2000)
    >>> conf.shape, bool(conf[-1, 0, 0] > conf[1, 0, 0])     # strong readings are named right more often
    ((8, 2, 2), True)
    """
    if isinstance(gases, str):
        raise TypeError(f"gases must be a sequence of gas names, got the string {gases!r}")
    conf, edges = _counted_confusion(tuple(str(g) for g in gases), int(exposures), int(seed), float(pseudo_count))
    return conf.copy(), edges.copy()


@lru_cache(maxsize=8)
def _counted_confusion(gases: tuple, exposures: int, seed: int, pseudo_count: float):
    from ..sim import ElectronicNose

    nose = ElectronicNose()
    missing = [g for g in gases if g not in nose.gases]
    if not gases or missing:
        raise ValueError(f"gases must be gases the e-nose knows, {nose.gases}, got {list(gases)}")
    n = int(exposures)
    if n < 1:
        raise ValueError(f"exposures must be a positive number of reference readings, got {exposures!r}")
    if not (np.isfinite(pseudo_count) and pseudo_count > 0):
        raise ValueError(f"pseudo_count must be a positive count, got {pseudo_count!r}")
    edges = np.array(STRENGTH_EDGES)
    m, bins = len(gases), len(edges) - 1
    counts = np.zeros((bins, m, m))
    rng = np.random.default_rng([int(seed), 0xE405])
    for g, gas in enumerate(gases):
        x = np.where(rng.random(n) < 0.25, 0.0, 10.0 ** rng.uniform(-2.0, 2.0, n))
        label, strength = nose.decide(nose.respond(x, gas, rng))
        named = label >= 0
        # the device may name a gas outside `gases` (it knows more): such a reading counts for none of the table's
        names_idx = np.array([gases.index(nose.gases[i]) if nose.gases[i] in gases else -1 for i in range(len(nose.gases))])
        z = names_idx[label[named]]
        b = np.clip(np.searchsorted(edges, strength[named], side="right") - 1, 0, bins - 1)
        keep = z >= 0
        np.add.at(counts, (b[keep], g, z[keep]), 1.0)
    counts += float(pseudo_count)
    return counts / counts.sum(axis=2, keepdims=True), edges
