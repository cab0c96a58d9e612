"""The simulated world of the validation experiment: house + wind + gas + sensors + camera, on one clock.

A :class:`World` owns every random stream (spawned from one seed) and advances gas and wind together;
the robot-side code only asks for readings at poses:

    world = make_world(seed=0)                 # default house, smoke from the oven, 60 s warm-up
    r = world.sense_gas((3.0, 6.0))            # advances the clock by one sensor window
    frame = world.camera_frame((3.0, 6.0, 0.0))

**Localisation error** (``make_world(localisation=LocalisationError(...))``, :mod:`psgsl_pgm.sim._pose`; default
none). The robot plans and believes in its estimated frame: every pose it passes to the world is the pose it
believes, and when it stands at a believed pose p it truly stands at p − e(t), e(t) being the localisation
offset at that moment (a robot that holds its believed pose while the estimate moves). The robot senses at its
stops, not while driving, as the search loop and the fixed tour do: the gas sensor (one position per window, at
the window's start), the anemometer (whose reading, in the robot's frame, turns by the heading error e_θ when
the robot reports it in its map frame) and the camera (the cells it sees from its true pose, placed in the map
where its believed pose puts them) all observe from the true pose, and return what the robot reports. A true
position beyond or inside a wall is pulled back along the offset to the last free point before the wall (the
robot cannot be inside or behind a wall it believes it is in front of). Only the success rule and the metrics map believed positions to true ones
(:meth:`World.true_positions`); the robot-side code never does.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .._shared._validate import real_pair
from ._camera import Camera, Frame, take_frame
from ._classes import reindex
from ._detector import DetectorErrors, DetectorModel
from ._filaments import FilamentModel, FilamentParams
from ._house import House, default_house
from ._mox import MOXSensor, PIDSensor
from ._pose import LocalisationError
from ._source_detector import SourceDetector
from ._semantic_map import SemanticMap
from ._sensors import Anemometer, GasReading, GasSensor
from ._wind import WindField, WindSequence, make_wind

__all__ = ["World", "make_world"]


class World:
    """A running simulation (build it with :func:`make_world`).

    Attributes
    ----------
    house : House
    wind : WindSequence
    gas : FilamentModel
    camera : Camera
    detector : DetectorModel
    detector_errors : DetectorErrors or None
        The detector's errors fixed for this world, drawn from its seed (None for a detector without
        persistent or recurring errors).
    gas_sensor : GasSensor, MOXSensor or PIDSensor
    anemometer : Anemometer
    source : (2,) ndarray
        Gas source position, metres.
    source_object : SceneObject or None
        The object that emits: the one named by class, or the object whose footprint holds the source position
        (None for a source in open space). The success rule of the closed loop counts its footprint
        (:meth:`SceneObject.mask`), not only its centre.
    localisation : LocalisationError or None
        The robot's localisation error (None: the robot is exactly where it believes; see the module docstring).
    source_detector : SourceDetector
        The close-range detector that confirms the source when the robot passes within reach
        (:meth:`detect_source`; default: one that never misses).
    enose : ElectronicNose or None
        The electronic nose that classifies the gas of each gas-sensor window (:meth:`sniff`); None: the robot
        carries none.
    gas_type : str or None
        The gas the source emits (the truth, for the metrics only; the robot never reads it). None when the
        world has no e-nose.
    extra_gas : tuple of FilamentModel
        The filament models of the further sources of a world with several (:func:`make_world`'s
        ``extra_sources``; empty: one source). They run on the same clock and wind as :attr:`gas`, and every
        reading sees the sum of all plumes (:func:`make_world`, "Several sources").
    """

    def __init__(self, house: House, wind: WindSequence, gas: FilamentModel, *, camera: Camera,
                 detector: DetectorModel, gas_sensor: GasSensor, anemometer: Anemometer, source_object=None,
                 seed: int = 0, localisation: LocalisationError | None = None, source=None,
                 source_detector: SourceDetector | None = None, enose=None, gas_type: str | None = None,
                 extra_sources=()):
        self.house = house
        # the source as named (an object's centre or a given point); the gas may be released beside it, where the
        # emitting object meets the air (make_world's gas_obstacles)
        self._source = None if source is None else np.asarray(source, dtype=np.float64).copy()
        self.wind = wind
        self.gas = gas
        self.camera = camera
        self.detector = detector
        self.gas_sensor = gas_sensor
        self.anemometer = anemometer
        self.source_object = source_object
        ss = np.random.SeedSequence([int(seed), 7])
        r1, r2, r3 = (np.random.default_rng(s) for s in ss.spawn(3))
        self._rng_gas_sensor, self._rng_anemometer, self._rng_camera = r1, r2, r3
        self._sensor_state = 0.0  # what the gas sensor continues from (a float, or e.g. a MOXState)
        self._sensor_time = None  # world time at the end of the last gas reading
        # the detector's errors fixed for this world (persistent instance labels, distractor sites): drawn once
        # from a fourth stream of the seed (the three above are untouched), only for a detector that has them
        self.detector_errors = (DetectorErrors.draw(detector, house, np.random.default_rng(ss.spawn(1)[0]))
                                if detector.correlated else None)
        if localisation is not None and not isinstance(localisation, LocalisationError):
            raise TypeError(f"localisation must be a LocalisationError or None, got {type(localisation).__name__}")
        self.localisation = localisation
        # the localisation offset's own stream: the seed's child of a fixed spawn key, so every other stream (the
        # three above and the detector's errors) draws as without it
        self._rng_pose = np.random.default_rng(np.random.SeedSequence(ss.entropy, spawn_key=(0x905E,)))
        self._offsets = np.zeros((0, 3))  # e at t = k dt for k < len, drawn on demand in step order
        if source_detector is not None and not isinstance(source_detector, SourceDetector):
            raise TypeError(f"source_detector must be a SourceDetector or None, got {type(source_detector).__name__}")
        self.source_detector = SourceDetector() if source_detector is None else source_detector
        # the source detector's own stream (a fixed spawn key, as the pose's): every other stream draws as without it
        self._rng_source = np.random.default_rng(np.random.SeedSequence(ss.entropy, spawn_key=(0x5DE7,)))
        from ._enose import ElectronicNose

        if enose is not None and not isinstance(enose, ElectronicNose):
            raise TypeError(f"enose must be an ElectronicNose or None, got {type(enose).__name__}")
        if (enose is None) != (gas_type is None):
            raise ValueError("enose and gas_type go together: an e-nose classifies the source's gas, gas_type; got "
                             f"enose={enose!r}, gas_type={gas_type!r}")
        if enose is not None and gas_type not in enose.gases:
            raise ValueError(f"gas_type must be one of the e-nose's gases {enose.gases}, got {gas_type!r}")
        self.enose, self.gas_type = enose, gas_type
        # the e-nose's own stream (a fixed spawn key): every other stream draws as without it
        self._rng_enose = np.random.default_rng(np.random.SeedSequence(ss.entropy, spawn_key=(0xE405,)))
        self._window_mean = None  # mean true concentration of the last gas-sensor window, ppm (for sniff)
        # further sources: (FilamentModel, named point, emitting object, gas) each; none in a one-source world
        self._extra = tuple(extra_sources)
        for gas_i, _, _, g in self._extra:
            if not isinstance(gas_i, FilamentModel) or gas_i.grid.shape != gas.grid.shape:
                raise TypeError("extra_sources must hold FilamentModels on the house's grid")
            if (enose is None) != (g is None) or (enose is not None and g not in enose.gases):
                raise ValueError(f"each further source's gas must be one of the e-nose's gases "
                                 f"{None if enose is None else enose.gases} (None without an e-nose), got {g!r}")
        self._window_means = None  # per source, of the last window (several sources only)

    @property
    def extra_gas(self) -> tuple:
        """The further sources' filament models (class docstring); empty in a one-source world."""
        return tuple(e[0] for e in self._extra)

    @property
    def n_sources(self) -> int:
        """How many sources emit (1 + the further ones)."""
        return 1 + len(self._extra)

    @property
    def sources(self) -> np.ndarray:
        """(n_sources, 2) every source's point, m, the first being :attr:`source` (the truth: scoring only)."""
        return np.array([self.source] + [np.asarray(e[1], dtype=np.float64) for e in self._extra])

    @property
    def source_objects(self) -> tuple:
        """Every source's emitting object (or None for a source in open space), in :attr:`sources`' order."""
        return (self.source_object,) + tuple(e[2] for e in self._extra)

    @property
    def gas_types(self) -> tuple:
        """Every source's gas, in :attr:`sources`' order (None entries: the world has no e-nose)."""
        return (self.gas_type,) + tuple(e[3] for e in self._extra)

    @property
    def source(self) -> np.ndarray:
        """(2,) the source position, m: the point named (the gas's release point unless the emitting object
        blocks the air there, see :func:`make_world`'s ``gas_obstacles``)."""
        return (self.gas.source if self._source is None else self._source).copy()

    @property
    def time(self) -> float:
        """Simulation time, s (0 = first filament release)."""
        return self.gas.time

    @property
    def dt(self) -> float:
        return self.gas.params.dt

    def advance(self, seconds: float) -> None:
        """Let gas and wind evolve for ``seconds`` (whole steps); every source's plume."""
        self.gas.run(seconds)
        for e in self._extra:
            e[0].run(seconds)

    def wind_now(self) -> WindField:
        """The wind snapshot in force."""
        return self.wind.at_time(self.time)

    def concentration(self, xy) -> np.ndarray:
        """True concentration (ppm) at points (..., 2) now, without sensor effects: the sum over the sources."""
        c = self.gas.concentration(xy)
        for e in self._extra:
            c = c + e[0].concentration(xy)
        return c

    def _offset_at(self, times) -> np.ndarray:
        """(..., 3) localisation offset e at ``times`` (s, world clock; the nearest step of ``dt``)."""
        k = np.maximum(np.rint(np.asarray(times, dtype=np.float64) / self.dt), 0).astype(np.int64)
        need = int(k.max(initial=0)) + 1
        have = len(self._offsets)
        if need > have:  # the same offsets whatever the order of the queries: drawn step after step
            err = self.localisation
            first = err.stationary(rng=self._rng_pose)[None, :] if have == 0 else np.zeros((0, 3))
            state = first[0] if have == 0 else self._offsets[-1]
            more = max(need - have - len(first), 1024)  # in blocks: fewer, longer draws of the same stream
            ahead = err.advance(state, more, self.dt, rng=self._rng_pose)
            self._offsets = np.concatenate([self._offsets, first, ahead])
        return self._offsets[k]

    def _pull_back(self, believed: np.ndarray, true: np.ndarray) -> np.ndarray:
        """``true`` (n, 2) with each point whose segment from its ``believed`` point (n, 2) crosses a wall (or
        leaves the map) moved back to the last free point of that segment before the wall (quarter-cell
        steps); a believed point that is itself in a wall leaves its true point as it is."""
        g = self.house.grid

        def blocked(p):
            rc = g.world_to_cell(p)
            inside = g.contains(rc)
            out = ~inside
            out[inside] = g.occupancy[rc[inside][:, 0], rc[inside][:, 1]]
            return out

        m = int(np.ceil(np.linalg.norm(true - believed, axis=-1).max(initial=0.0) / (g.resolution / 4))) + 1
        f = np.linspace(0.0, 1.0, m + 1)
        pts = believed[:, None, :] + f[None, :, None] * (true - believed)[:, None, :]  # (n, m + 1, 2)
        pts[:, -1] = true
        stop = blocked(pts)
        cut = np.flatnonzero(stop.any(axis=1) & ~stop[:, 0])
        if cut.size == 0:
            return true
        out = true.copy()
        out[cut] = pts[cut, np.argmax(stop[cut], axis=1) - 1]
        return out

    def detect_source(self, within_reach: bool) -> bool:
        """One trial of the close-range source detector (:class:`SourceDetector`) for a move that did
        (``within_reach``) or did not come within reach of the source; the closed loop decides reach with the true
        source and the robot's true path. Never True when not within reach."""
        return self.source_detector.detects(bool(within_reach), self._rng_source)

    def true_positions(self, points, *, times=None) -> np.ndarray:
        """The true positions (..., 2) of the believed positions ``points`` (..., 2), m — for the success rule
        and the metrics only, never for the robot.

        Parameters
        ----------
        points : (..., 2) array_like
            Positions the robot believes it is at, metres (map frame).
        times : float or (...) array_like, optional, keyword-only
            World-clock times (s) at which it is there (default: now); broadcast against ``points[..., 0]``.

        Returns
        -------
        (..., 2) ndarray
            ``points`` − e(times), pulled out of walls (see the module docstring); a copy of ``points``
            without localisation error.
        """
        p = np.asarray(points, dtype=np.float64)
        if p.ndim == 0 or p.shape[-1] != 2 or not np.isfinite(p).all():
            raise ValueError(f"points must be finite positions of shape (..., 2), got shape {p.shape}")
        if self.localisation is None:
            return p.copy()
        t = np.broadcast_to(np.asarray(self.time if times is None else times, dtype=np.float64), p.shape[:-1])
        if not np.isfinite(t).all():
            raise ValueError("times must be finite seconds of the world clock")
        flat = p.reshape(-1, 2)
        e = self._offset_at(t.reshape(-1))
        return self._pull_back(flat, flat - e[:, :2]).reshape(p.shape)

    def sense_gas(self, xy, *, duration: float | None = None) -> GasReading:
        """Hold the gas sensor at ``xy`` for one window (or ``duration`` s) while the world advances.

        The sensor samples the concentration after every time step and continues from its state at the end of
        the previous reading, wherever that was taken; the time since then is passed to the sensor's ``idle``
        first (:class:`GasSensor`: nothing changes; :class:`MOXSensor`: it recovers in clean air and its
        baseline drifts).

        With a localisation error, ``xy`` is where the robot believes it is, and the sensor samples at its true
        position when the window starts.
        """
        xy = np.asarray(xy, dtype=np.float64)
        if self.localisation is not None:
            xy = self.true_positions(xy)
        dt = self.dt
        sensor = self.gas_sensor
        n = sensor.samples(dt) if duration is None else max(1, int(round(duration / dt)))
        state = self._sensor_state
        if self._sensor_time is not None and self.time > self._sensor_time:
            state = sensor.idle(state, self.time - self._sensor_time, rng=self._rng_gas_sensor)
        samples = self.gas.sample(xy, n)  # the clock: one step per sample
        if self._extra:  # the plumes add up (make_world, "Several sources"); each model steps with the clock
            parts = [samples] + [e[0].sample(xy, n) for e in self._extra]
            self._window_means = [float(np.mean(p)) for p in parts]
            samples = np.sum(parts, axis=0)
        self._window_mean = float(np.mean(samples))
        reading = sensor.read(samples, dt, initial=state, rng=self._rng_gas_sensor)
        self._sensor_state, self._sensor_time = reading.state, self.time
        return reading

    def sniff(self):
        """The electronic nose's classification of the last gas-sensor window (:meth:`sense_gas`): a
        :class:`psgsl_pgm.sim._enose.Smell` of the window's mean concentration at the sensor, the gas being the
        source's. With several sources the device answers the gas that brought most of the window's
        concentration, at the total concentration (a mixture is classified as its dominant gas). Draws from the
        e-nose's own stream only; the clock does not move."""
        if self.enose is None:
            raise ValueError("this world has no electronic nose: make it with make_world(enose=..., gas_type=...)")
        if self._window_mean is None:
            raise ValueError("sniff classifies the last gas reading: call sense_gas first")
        gas = self.gas_type
        if self._extra and self._window_means is not None:
            gas = self.gas_types[int(np.argmax(self._window_means))]
        return self.enose.classify(self._window_mean, gas, self._rng_enose)

    def sense_wind(self, xy) -> np.ndarray:
        """(2,) anemometer reading at ``xy`` now (the snapshot in force, plus noise).

        With a localisation error, the wind at the true position, turned by the heading error e_θ (the reading
        in the robot's frame, reported in its map frame with the heading it believes).
        """
        if self.localisation is None:
            return self.anemometer.read(self.wind_now().at(xy), rng=self._rng_anemometer)
        xy = np.asarray(xy, dtype=np.float64)
        e = self._offset_at(self.time)
        u, v = self.wind_now().at(self._pull_back(xy.reshape(1, 2), xy.reshape(1, 2) - e[:2]))[0]
        c, s = np.cos(e[2]), np.sin(e[2])
        return self.anemometer.read(np.array([c * u - s * v, s * u + c * v]), rng=self._rng_anemometer)

    def camera_frame(self, pose, *, model: DetectorModel | None = None, layer_edges=None) -> Frame:
        """One camera frame from ``pose`` = (x, y, heading); see :func:`take_frame`.

        With a localisation error, ``pose`` is the pose the robot believes: the frame is taken from the true
        pose, and each observed cell is placed where the robot's believed pose puts it, q' = p + R(e_θ)(q − p_t)
        (p the believed and p_t the true position, q the cell's centre); cells placed off the map are dropped.
        The frame's ``pose`` is the believed one; its distances and bearings are the measured (true) ones.
        """
        if self.localisation is None:
            return take_frame(self.house, pose, camera=self.camera, detector=self.detector, rng=self._rng_camera,
                              model=model, layer_edges=layer_edges, errors=self.detector_errors)
        pose = np.asarray(pose, dtype=np.float64)
        if pose.shape != (3,) or not np.isfinite(pose).all():
            raise ValueError(f"pose must be a finite (x, y, heading) of shape (3,), got shape {pose.shape}")
        e = self._offset_at(self.time)
        p = pose[:2]
        p_true = self._pull_back(p[None], p[None] - e[None, :2])[0]
        frame = take_frame(self.house, (p_true[0], p_true[1], pose[2] - e[2]), camera=self.camera,
                           detector=self.detector, rng=self._rng_camera, model=model, layer_edges=layer_edges,
                           errors=self.detector_errors)
        g = self.house.grid
        c, s = np.cos(e[2]), np.sin(e[2])
        d = g.cell_to_world(frame.cells) - p_true
        cells = g.world_to_cell(p + np.stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]], axis=-1))
        keep = g.contains(cells)
        return replace(frame, pose=pose.copy(), cells=cells[keep],
                       layers=None if frame.layers is None else frame.layers[keep], distance=frame.distance[keep],
                       labels=frame.labels[keep], likelihood=frame.likelihood[keep],
                       bearing=None if frame.bearing is None else frame.bearing[keep])

    def semantic_map(self, class_prior, *, room_table=None, room_names=None, layers: int | None = None) -> SemanticMap:
        """Initial class beliefs over the house in the detector's class order.

        Parameters
        ----------
        class_prior : (k,) array_like
            p(o) over ``detector.classes``.
        room_table : (r, k) array_like, optional, keyword-only
            p(o | room) — given, beliefs start from the room-category map (the paper's "rooms" variant).
        room_names : sequence of str, optional, keyword-only
            Names of the rows of ``room_table`` (default: the house's room names); matched to the house's
            rooms ignoring case and spaces. A name the house lacks is a ValueError naming the closest room
            names; a room of the house that the names omit gives no evidence (the class prior).
        layers : int, optional, keyword-only
            Number of voxel layers (a voxel map).
        """
        classes = self.detector.classes
        if room_table is None:
            shape = self.house.shape if layers is None else self.house.shape + (int(layers),)
            return SemanticMap.from_prior(shape, class_prior, classes)
        names = self.house.room_names if room_names is None else tuple(room_names)
        if room_names is not None:  # a misspelt row would leave the house's room at the class prior silently
            from ..io._class_maps import unknown_names
            from ._classes import match_names

            missing = [n for n, i in zip(names, match_names(names, self.house.room_names)) if i < 0]
            if missing:
                text = unknown_names(missing, self.house.room_names, "room", "the house does not have")
                raise ValueError(f"room_names: {text}")
        labels = reindex(self.house.room_labels, self.house.room_names, names)
        return SemanticMap.from_rooms(labels, room_table, class_prior, classes, layers=layers)

    def __repr__(self) -> str:
        return f"World(t={self.time:.1f} s, source={tuple(np.round(self.source, 3))}, {self.gas.n_filaments} filaments)"


def _source(house: House, source):
    """(position (2,), emitting object or None) of a source given by class name, object or position."""
    from ._objects import SceneObject

    if isinstance(source, str):
        objs = house.objects_of_class(source)
        if not objs:
            from .._shared._validate import did_you_mean as _did_you_mean

            present = sorted({o.class_name for o in house.objects})
            raise ValueError(f"source class {source!r} has no object in the house{_did_you_mean(source, present)}; "
                             f"classes present: {present}")
        return objs[0].center, objs[0]
    if isinstance(source, SceneObject):
        if not any(o is source for o in house.objects):
            raise ValueError(f"source object {source!r} is not one of the house's objects")
        return source.center, source
    xy = real_pair(source, "source", "an (x, y)", "metres")
    return xy, object_at(house, xy)


def _blocked_for_gas(house: House, obstacles, source):
    """The gas's grid with ``obstacles`` as walls, and the release point: ``source``, or the centre of the nearest
    cell of a room outside walls and obstacles when they hold it (ValueError when no such cell is within 1 m)."""
    blocked = np.asarray(obstacles)
    if blocked.shape != house.grid.shape or blocked.dtype != bool:
        raise ValueError(f"gas_obstacles must be an (H, W) bool mask of the house's {house.grid.shape} grid, got "
                         f"{blocked.dtype} {blocked.shape}")
    grid = house.grid.with_occupancy(house.grid.occupancy | blocked)
    if not grid.is_occupied(source):
        return grid, source
    from scipy import ndimage as ndi

    rc = house.grid.world_to_cell(source)
    dist, (ri, ci) = ndi.distance_transform_edt(grid.occupancy | (house.room_labels < 0), return_indices=True)
    r, c = int(rc[0]), int(rc[1])
    if dist[r, c] * house.grid.resolution > 1.0:
        raise ValueError(f"source ({source[0]:g}, {source[1]:g}) lies more than 1 m inside the gas obstacles: no "
                         "place where its object meets the air")
    return grid, grid.cell_to_world(np.array([ri[r, c], ci[r, c]]))


def object_at(house: House, xy):
    """The object whose footprint polygon holds the point ``xy`` (m), or None.

    Where footprints overlap (an oven in a countertop), the last in ``house.objects`` — the one the class map
    shows there (:attr:`House.class_map`: later objects win). A point on the boundary counts as inside.
    """
    from matplotlib.path import Path as MplPath

    p = np.asarray(xy, dtype=np.float64)
    for o in reversed(house.objects):  # a handful of objects
        # the sign of matplotlib's margin depends on the polygon's orientation: test both, one of them widens
        if any(MplPath(fp).contains_point(p, radius=1e-9) for fp in (o.footprint, o.footprint[::-1])):
            return o
    return None


def make_world(house: House | None = None, *, source="oven", seed: int = 0, mean_speed: float = 0.2,
               perturbation: float = 0.3, params: FilamentParams | None = None, warm_up: float = 60.0,
               duration: float = 600.0, camera: Camera | None = None, detector: DetectorModel | None = None,
               gas_sensor=None, anemometer: Anemometer | None = None,
               wind: WindSequence | None = None, localisation: LocalisationError | None = None,
               gas_obstacles=None, source_detector: SourceDetector | None = None, enose=None,
               gas_type: str | None = None, extra_sources=(), extra_gas_types=None) -> World:
    """Build the validation world and run the gas for ``warm_up`` seconds.

    **Several sources** (``extra_sources``). The filament model is a passive-tracer model (Farrell et al. 2002,
    Environ. Fluid Mech. 2:143–169; GADEN, Monroy et al. 2017, Sensors 17:1479): each filament is carried by the
    wind and grows on its own, and the concentration at a point is the sum of the filaments' Gaussian puffs. The
    gas is dilute (ppm), so it does not change the wind, and filaments never interact: the field of several
    release points under one wind is exactly the sum of the single-source fields. The world therefore runs one
    filament model per source, all in the same wind (the potential flow or the CFD solve of the realistic world)
    on one clock, and every gas reading samples the sum. Each further source's filament noise has its own seed
    (``SeedSequence([seed, 0x5EC0, i])``), so the first source's plume, and every other stream, draw the same
    numbers as in a one-source world.

    Parameters
    ----------
    house : House, optional
        Default: ``default_house(seed)``.
    source : str, SceneObject or (2,) array_like, keyword-only
        A class name (the source is the centre of the first object of that class), one of ``house.objects``
        (its centre), or a position in metres. A position inside an object's footprint makes that object
        the emitting :attr:`World.source_object` (where footprints overlap, the one the class map shows there).
    seed : int, keyword-only
        One seed for everything (house jitter, wind perturbation, filament noise, sensors, detector).
    mean_speed, perturbation : float, keyword-only
        Wind, see :func:`make_wind`.
    params : FilamentParams, optional, keyword-only
    warm_up : float, keyword-only
        Seconds of gas release before the world is handed over.
    duration : float, keyword-only
        Seconds of wind snapshots before they loop.
    camera, detector, gas_sensor, anemometer : optional, keyword-only
        Defaults: ``Camera()``, ``DetectorModel.default(house.classes)``, ``GasSensor()``, ``Anemometer()``.
        ``gas_sensor`` may also be a :class:`MOXSensor` or a :class:`PIDSensor` (their hits are decided by the
        robot, :class:`psgsl_pgm.olfaction.HitRule`).
    wind : WindSequence, optional, keyword-only
        Given wind snapshots (e.g. a GADEN CFD export) instead of :func:`make_wind` between the house's windows
        (``mean_speed`` and ``perturbation`` are then unused); on the house's grid.
    localisation : LocalisationError, optional, keyword-only
        The robot's localisation error (default None: it is exactly where it believes, and the world draws
        nothing for it). Its offset has its own random stream, so the other streams draw the same numbers
        with and without it.
    gas_obstacles : (H, W) array_like of bool, optional, keyword-only
        Cells that block the gas as walls do, besides the walls: the furniture that blocks the air at the
        sensor's height in a CFD wind (:func:`psgsl_pgm.sim._lbm.cfd_obstacles`), so that filaments go round
        what the flow goes round. A source inside them releases its gas at the nearest cell outside them, where
        the emitting object meets the air; :attr:`World.source` stays the point named. Default: walls only.
    source_detector : SourceDetector, optional, keyword-only
        The close-range source detector (:meth:`World.detect_source`; default: one that never misses). It draws
        from its own random stream.
    enose : ElectronicNose, optional, keyword-only
        An electronic nose that classifies each gas-sensor window (:meth:`World.sniff`); default none. It draws
        from its own random stream.
    gas_type : str, optional, keyword-only
        The source's gas, one of ``enose.gases``; required with ``enose`` (and only with it).
    extra_sources : sequence, keyword-only
        Further sources that emit at the same time, each given as ``source`` is (at most 2: a world has 1–3
        sources); default none.
    extra_gas_types : sequence of str, optional, keyword-only
        With ``enose``: each further source's gas (default: ``gas_type`` for all); without: None.

    Returns
    -------
    World

    Raises
    ------
    TypeError
        ``house``, ``localisation`` or ``gas_sensor`` is of the wrong type.
    ValueError
        ``warm_up`` is negative or not finite; ``wind`` is not a :class:`WindSequence` on the house's grid;
        ``source`` names no object of the house or lies outside it; more than 2 ``extra_sources``; ``gas_type``
        without ``enose`` (or the reverse); or a component refuses its own arguments (the message names it).

    Examples
    --------
    >>> w = make_world(seed=0, warm_up=5.0)
    >>> w.source_object.class_name, round(w.time, 1)
    ('oven', 5.0)
    """
    if house is None:
        house = default_house(seed)
    if not isinstance(house, House):
        raise TypeError(f"house must be a House, got {type(house).__name__}")
    if localisation is not None and not isinstance(localisation, LocalisationError):
        raise TypeError(f"localisation must be a LocalisationError or None, got {type(localisation).__name__}")
    if not (np.isfinite(warm_up) and warm_up >= 0):
        raise ValueError(f"warm_up must be a non-negative number of seconds, got {warm_up!r}")
    ss = np.random.SeedSequence(int(seed))
    wind_seed, gas_seed = (int(s.generate_state(1)[0]) for s in ss.spawn(2))
    source, source_object = _source(house, source)
    if wind is None:
        wind = make_wind(house.grid, house.inlet, house.outlet, mean_speed=mean_speed, perturbation=perturbation,
                         duration=duration, seed=wind_seed)
    elif not isinstance(wind, WindSequence) or wind.grid.shape != house.grid.shape:
        raise ValueError(f"wind must be a WindSequence on the house's {house.grid.shape} grid, got {wind!r}")
    gas_grid, release = house.grid, source
    if gas_obstacles is not None:
        gas_grid, release = _blocked_for_gas(house, gas_obstacles, source)
    gas = FilamentModel(gas_grid, wind, release, params=params, outlet=house.outlet, seed=gas_seed)
    extra = _extra_sources(house, extra_sources, extra_gas_types, gas_type, wind, params, gas_obstacles, seed)
    if gas_sensor is not None and not isinstance(gas_sensor, (GasSensor, MOXSensor, PIDSensor)):
        raise TypeError(f"gas_sensor must be a GasSensor, MOXSensor or PIDSensor, got {type(gas_sensor).__name__}")
    world = World(
        house, wind, gas,
        camera=camera if camera is not None else Camera(),
        detector=detector if detector is not None else DetectorModel.default(house.classes),
        gas_sensor=gas_sensor if gas_sensor is not None else GasSensor(),
        anemometer=anemometer if anemometer is not None else Anemometer(),
        source_object=source_object,
        seed=seed,
        localisation=localisation,
        source=None if gas_obstacles is None else source,
        source_detector=source_detector,
        enose=enose,
        gas_type=gas_type,
        extra_sources=extra,
    )
    world.advance(warm_up)
    return world


#: Most further sources a world holds (1–3 sources in all).
MAX_EXTRA_SOURCES = 2


def _extra_sources(house, extra_sources, extra_gas_types, gas_type, wind, params, gas_obstacles, seed) -> tuple:
    """(FilamentModel, named point, emitting object, gas) of each further source (make_world's docstring)."""
    if isinstance(extra_sources, (str, bytes)) or not hasattr(extra_sources, "__len__"):
        raise TypeError(f"extra_sources must be a sequence of sources (class names, objects or (x, y)), got "
                        f"{extra_sources!r}")
    if len(extra_sources) > MAX_EXTRA_SOURCES:
        raise ValueError(f"extra_sources must hold at most {MAX_EXTRA_SOURCES} sources (1-3 in all), got "
                         f"{len(extra_sources)}")
    if extra_gas_types is None:
        extra_gas_types = [gas_type] * len(extra_sources)
    elif gas_type is None or len(extra_gas_types) != len(extra_sources):
        raise ValueError(f"extra_gas_types must give one gas per further source ({len(extra_sources)}) with an "
                         f"e-nose's gas_type, got {extra_gas_types!r} (gas_type={gas_type!r})")
    out = []
    for i, (spec, g) in enumerate(zip(extra_sources, extra_gas_types)):
        xy, obj = _source(house, spec)
        gas_grid, release = house.grid, xy
        if gas_obstacles is not None:
            gas_grid, release = _blocked_for_gas(house, gas_obstacles, xy)
        s = int(np.random.SeedSequence([int(seed), 0x5EC0, i]).generate_state(1)[0])
        model = FilamentModel(gas_grid, wind, release, params=params, outlet=house.outlet, seed=s)
        out.append((model, np.asarray(xy, dtype=np.float64).copy(), obj, None if g is None else str(g)))
    return tuple(out)
