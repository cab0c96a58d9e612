"""``--record``: what a simulated episode looked like to the robot, written beside its stored run.

:class:`EpisodeRecorder` watches a world (:meth:`EpisodeRecorder.watch` wraps it: every gas reading, anemometer
reading and camera frame the per-step code asks for is logged with the simulation time) and takes the posteriors
after every step (:meth:`EpisodeRecorder.step`). Nothing of the run changes: the wrapped world hands back exactly
what the world returns. :meth:`EpisodeRecorder.write` then writes

* ``<run>.bag/`` — a ROS 2 bag (MCAP storage) with the messages a robot publishes (:func:`psgsl_pgm.ros.write_bag`),
  which ``psgsl replay`` reads back to the same posteriors;
* ``<run>.mcap`` — the episode in Foxglove's schemas (:func:`psgsl_pgm.ros.write_foxglove`).

Without ``--record`` none of this runs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["EpisodeRecorder"]


class _Watched:
    """A world whose readings and frames are logged (everything else is the world's own)."""

    def __init__(self, world, recorder):
        self._world = world
        self._recorder = recorder

    def __getattr__(self, name):
        return getattr(self._world, name)

    def sense_gas(self, xy, **kwargs):
        reading = self._world.sense_gas(xy, **kwargs)
        self._recorder._gas(self._world.time, xy, reading.value)
        return reading

    def sense_wind(self, xy):
        wind = self._world.sense_wind(xy)
        self._recorder._wind(self._world.time, xy, wind)
        return wind

    def camera_frame(self, pose, **kwargs):
        frame = self._world.camera_frame(pose, **kwargs)
        self._recorder._frame(self._world.time, pose, frame)
        return frame


class EpisodeRecorder:
    """Logs one episode (see the module docstring).

    Parameters
    ----------
    keep : {"float32", "float64"}, keyword-only
        Precision of the posteriors kept per step (float32 is what the Foxglove grids carry).
    """

    def __init__(self, *, keep: str = "float32"):
        self._dtype = np.dtype(keep)
        self._t0 = None
        self._poses: dict = {}  # time -> (x, y, yaw); a later sample at the same time replaces an earlier one
        self._heading = 0.0
        self.gas_t, self.gas, self.wind_t, self.wind = [], [], [], []
        self.frame_t, self.frame_cells, self.frame_labels = [], [], []
        self.step_t, self.posteriors, self.best_class, self.chosen = [], [], [], []
        self._world = None

    def watch(self, world):
        """``world`` wrapped so that its readings and frames are logged.

        Only a world with the thresholded :class:`psgsl_pgm.sim.GasSensor` can be recorded: the bag holds one value
        per reading and ``psgsl replay`` thresholds it; a sensor whose hits the robot decides from the window's
        samples (:class:`psgsl_pgm.sim.MOXSensor`, :class:`psgsl_pgm.sim.PIDSensor`) is a ValueError before
        anything is written. So is a world with an electronic nose (a run whose gas the robot is not told).
        """
        from ..sim import GasSensor

        if not isinstance(world.gas_sensor, GasSensor):
            kind = type(world.gas_sensor).__name__
            raise ValueError(f"--record needs the world's thresholded GasSensor, got a {kind} "
                             "(its hits are decided by the robot from each reading's samples, which a bag does not "
                             "hold)")
        if getattr(world, "enose", None) is not None:  # a bag has no message for the e-nose's classifications
            raise ValueError("--record cannot record a run whose gas is unknown to the robot: a bag holds no "
                             "electronic-nose readings, and its replay would not infer the gas")
        self._world = world
        self._t0 = world.time
        return _Watched(world, self)

    def _pose(self, t, xy, heading=None):
        if heading is not None:
            self._heading = float(heading)
        self._poses[float(t)] = (float(xy[0]), float(xy[1]), self._heading)

    def _gas(self, t, xy, value):
        self._pose(t, xy)
        self.gas_t.append(float(t))
        self.gas.append(float(value))

    def _wind(self, t, xy, wind):
        self._pose(t, xy)
        self.wind_t.append(float(t))
        self.wind.append(np.asarray(wind, dtype=np.float64).copy())

    def _frame(self, t, pose, frame):
        self._pose(t, pose[:2], pose[2])
        if frame.layers is not None:
            raise ValueError("--record writes 2-D camera frames only (a voxel frame arrived)")
        labels = self._world.detector.labels
        seen = frame.labels != self._world.detector.nothing  # cells reported as an object
        self.frame_t.append(float(t))
        self.frame_cells.append(np.asarray(frame.cells[seen], dtype=np.int64))
        self.frame_labels.append([labels[i] for i in frame.labels[seen]])

    def step(self, posteriors, beliefs, *, chosen=None) -> None:
        """After a step: the variants' posteriors (V, H, W), the most likely class per cell of the first
        class-belief map (none when the variants keep no class beliefs, as the olfaction variant alone), and the
        pose chosen next (3,) if any."""
        self.step_t.append(float(self._world.time))
        self.posteriors.append(np.asarray(posteriors, dtype=self._dtype))
        first = next(iter(beliefs.maps.values()), None)
        if first is None:
            self.best_class.append(None)
        else:
            probs = first.probs
            cells = probs if probs.ndim == 3 else probs.max(axis=2)  # a voxel column: its most certain voxel
            self.best_class.append(np.argmax(cells, axis=-1).astype(np.uint8))
        self.chosen.append(np.full(3, np.nan) if chosen is None else np.asarray(chosen, dtype=np.float64))

    def choose(self, pose) -> None:
        """The pose (x, y, heading) chosen after the last step (the closed loop's decision)."""
        if self.chosen:
            self.chosen[-1] = np.asarray(pose, dtype=np.float64)

    def episode(self, *, variants, meta: dict):
        """The log as a :class:`psgsl_pgm.ros.Episode` (times from the run's start)."""
        from ..ros import Episode

        world, t0 = self._world, self._t0
        times = np.array(sorted(self._poses))
        house = world.house
        objects = [(o.class_name, np.asarray(o.footprint), tuple(o.z_range)) for o in house.objects]
        return Episode(
            grid=house.grid, pose_t=times - t0, pose=np.array([self._poses[t] for t in times]).reshape(-1, 3),
            gas_t=np.array(self.gas_t) - t0, gas=np.array(self.gas), wind_t=np.array(self.wind_t) - t0,
            wind=np.array(self.wind).reshape(-1, 2), frame_t=np.array(self.frame_t) - t0,
            frame_cells=self.frame_cells, frame_labels=self.frame_labels, objects=objects,
            classes=tuple(world.detector.classes), variants=tuple(variants), step_t=np.array(self.step_t) - t0,
            posteriors=np.stack(self.posteriors) if self.posteriors else None,
            best_class=(np.stack(self.best_class) if self.best_class and all(b is not None for b in self.best_class)
                        else None),
            chosen=np.stack(self.chosen) if self.chosen else None,
            threshold=float(world.gas_sensor.threshold), meta=meta)

    def write(self, stem, *, variants, meta: dict) -> tuple:
        """``<stem>.bag/`` (ROS 2 bag, MCAP storage) and ``<stem>.mcap`` (Foxglove), each written atomically."""
        from ..ros import write_bag, write_foxglove

        ep = self.episode(variants=variants, meta=meta)
        stem = Path(stem)
        bag = write_bag(stem.with_name(stem.name + ".bag"), ep, storage="mcap")
        mcap = write_foxglove(stem.with_name(stem.name + ".mcap"), ep)
        return bag, mcap
