"""``psgsl replay``: a robot's ROS 2 bag through the estimators, with the experiment's own per-step code.

The bag (:func:`psgsl_pgm.ros.read_bag`) gives gas readings, wind readings, the robot's pose and camera
detections on one clock. They become the steps of one run:

* every gas reading is one step, at the robot's position at its stamp, in ppm: a ``GasSensor`` message's unit is
  read from its ``raw_units`` (ppm as it is, ppb divided by 1000; any other unit — volt, ohm, … — is refused
  unless the user gives a linear conversion ``ppm = scale × raw + offset``); a Float has no unit and is taken as
  ppm (said in ``assumptions``). It is a hit by the gas sensor's own
  threshold rule (``value >= threshold``, :class:`psgsl_pgm.sim.GasSensor`; the world's sensor unless
  ``threshold`` is given);
* its wind is the anemometer's reading interpolated to the same stamp (exact at an equal stamp; otherwise
  linear between the readings around it, within the tolerance). A bag without wind readings replays with none:
  the estimators then assume still air (:data:`NO_WIND`, said in the result's ``assumptions``);
* readings outside the overlap of the streams are skipped and counted (:attr:`psgsl_pgm.ros.BagData.skipped`);
* the detection arrays stamped from this gas reading up to the next (those before the first reading go to the
  first step) are the step's camera frames: the camera looks from the array's frame; every free cell in its
  field of view (:class:`psgsl_pgm.sim.Camera`, the same as the simulator's) is "seen", labelled "nothing"
  unless a detection box covers its centre (the cell holding a box's centre always counts), then labelled by
  the detection's class. Detections of classes the detector does not know are skipped and counted;
* :class:`VariantPosteriors` assimilates the steps exactly as in :func:`run_search`, and every step is measured
  with :func:`step_metrics` (the error only when the true source is given).

A simulated episode written by ``--record`` replays to the same posteriors (the project's round-trip test).
Unlike the closed loop, a replay applies no "not found here" update: it estimates along the driven path.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ..sim import (
    Camera,
    DetectorModel,
    GasSensor,
    House,
    default_world,
    load_world,
    match_names,
)
from ..sim._camera import Frame
from ._config import ESTIMATORS, VARIANTS, ExperimentConfig, parse_source, stored_estimator_name
from ._run import RunResult, run_config, step_metrics
from ._step import VariantPosteriors

__all__ = ["NO_WIND", "ReplayResult", "replay", "replay_figure", "replay_frames", "replay_steps", "write_replay"]

#: What the estimators assume when the bag holds no wind reading.
NO_WIND = ("no wind readings: the estimators assume still air (the plume model's mean wind stays zero, so the "
           "plume spreads by diffusion alone, and the analytic-plume estimator's hit kernel is round)")


class ReplayResult(SimpleNamespace):
    """What :func:`replay` returns: ``run`` (RunResult), ``posteriors`` (list of (3, H, W) per step, when kept),
    ``final`` (3, H, W), ``bag`` (BagData), ``house``, ``skipped`` (detections of unknown classes),
    ``assumptions`` (list of str: what the estimators assumed for missing streams)."""


def replay_frames(bag, house, detector: DetectorModel, camera: Camera):
    """The camera frames of ``bag``'s detections (see the module docstring): ``(frames, skipped)``."""
    grid = house.grid
    w = grid.shape[1]
    labels = detector.labels
    nothing = detector.nothing
    frames, skipped = [], 0
    for d in bag.detections:
        pose = np.asarray(d.camera, dtype=np.float64)
        flat = np.array(camera._visible_flat(grid, pose))  # row-major, as the simulator's frame
        lab = np.full(len(flat), nothing, dtype=np.int64)
        idx = match_names(list(d.class_id), labels[:-1]) if len(d.class_id) else np.zeros(0, np.int64)
        skipped += int((idx < 0).sum())
        extra_cells, extra_labels = [], []
        for i in np.flatnonzero(idx >= 0):
            cells = _covered(grid, d.centre[i], d.half_size[i], d.yaw[i])
            if len(cells) == 0:
                continue
            f = cells[:, 0] * w + cells[:, 1]
            pos = np.searchsorted(flat, f)
            inside = (pos < len(flat)) & (flat[np.minimum(pos, len(flat) - 1)] == f)
            lab[pos[inside]] = idx[i]
            extra_cells.append(f[~inside])
            extra_labels.append(np.full(int((~inside).sum()), idx[i]))
        if extra_cells and sum(len(e) for e in extra_cells):  # boxes outside the modelled view are seen too
            f = np.concatenate(extra_cells)
            f, first = np.unique(f, return_index=True)
            flat = np.concatenate([flat, f])
            lab = np.concatenate([lab, np.concatenate(extra_labels)[first]])
        cells = np.stack(np.divmod(flat, w), axis=-1)
        dist = np.linalg.norm(grid.cell_to_world(cells) - pose[:2], axis=-1)
        frames.append((d.t_ns, Frame(pose, cells, None, dist, lab, detector.likelihood(lab, dist), detector.classes)))
    return frames, skipped


def _covered(grid, centre, half, yaw) -> np.ndarray:
    """(n, 2) cells (row, col) of the map whose centres lie in the box, always including the cell of its centre."""
    h, w = grid.shape
    res = grid.resolution
    rc = np.asarray(grid.world_to_cell(np.asarray(centre, dtype=np.float64)[None]))[0]
    out = [rc] if (0 <= rc[0] < h and 0 <= rc[1] < w) else []
    reach = float(np.hypot(*half))
    if reach > res / 2:
        lo = grid.world_to_cell(np.asarray(centre) - reach)
        hi = grid.world_to_cell(np.asarray(centre) + reach)
        rows = np.arange(max(lo[0], 0), min(hi[0], h - 1) + 1)
        cols = np.arange(max(lo[1], 0), min(hi[1], w - 1) + 1)
        rr, cc = np.meshgrid(rows, cols, indexing="ij")
        cand = np.stack([rr.ravel(), cc.ravel()], axis=-1)
        xy = grid.cell_to_world(cand) - centre
        c, s = np.cos(yaw), np.sin(yaw)
        u, v = c * xy[:, 0] + s * xy[:, 1], -s * xy[:, 0] + c * xy[:, 1]
        out.extend(cand[(np.abs(u) <= half[0]) & (np.abs(v) <= half[1])])
    return np.unique(np.array(out, dtype=np.int64).reshape(-1, 2), axis=0)


def replay_steps(bag, frames, *, threshold: float, tolerance: float):
    """``[(t_ns, stop (2,), hit, value, wind (2,), [Frame, ...])]``, one per gas reading (module docstring)."""
    from ..ros._time import interpolate

    if len(bag.wind_t):
        where = f"{bag.path}: topic {bag.topics['wind']}"
        wind = interpolate(bag.wind_t, bag.wind, bag.gas_t, tolerance=tolerance, where=where, describe=bag.describe)
    else:  # no anemometer: no wind per step (the estimators' assumption is :data:`NO_WIND`)
        wind = [None] * len(bag.gas_t)
    ft = np.array([t for t, _ in frames], dtype=np.int64)
    # frames stamped in [t_k, t_{k+1}) go to step k; frames before the first reading to step 0
    owner = np.maximum(np.searchsorted(bag.gas_t, ft, side="right") - 1, 0)
    steps = []
    for k, (t, xy, value) in enumerate(zip(bag.gas_t, bag.gas_xy, bag.gas)):
        steps.append((int(t), xy, bool(value >= threshold), float(value), wind[k],
                      [frames[i][1] for i in np.flatnonzero(owner == k)]))
    return steps


def replay(bag, *, world=None, source=None, estimator: str | None = None, config: ExperimentConfig | None = None,
           seed: int | None = None, topics=None, map_frame: str = "map", robot_frame: str = "base_link",
           tolerance: float | None = None, threshold: float | None = None, bag_map: bool = False,
           keep_posteriors: bool = False, gas_conversion=None, progress=None) -> ReplayResult:
    """Replay a ROS 2 bag through the estimators (see the module docstring).

    Parameters
    ----------
    bag : str or Path
        The bag folder (sqlite3 or MCAP storage).
    world : str or Path, optional, keyword-only
        World file (:func:`psgsl_pgm.load_world`) of the house the bag was recorded in; default: the embedded
        house (or the world the project's recorder names in the bag).
    source : str or (2,), optional, keyword-only
        The true source (class, ``"x,y"`` or a world source name), for the error; default: none (or the
        recorded episode's).
    estimator : {"infotaxis", "analytic-plume", "particle-filter", "pmfs", "grgsl"}, optional, keyword-only
        Default: the recorded episode's, else ``"infotaxis"``.
    config : ExperimentConfig, optional, keyword-only
    seed : int, optional, keyword-only
        Seed of the embedded house's furniture layout (a world file's house is fixed); default: the recorded
        episode's, else 0.
    topics : dict, optional, keyword-only
        Role -> topic overrides (:data:`psgsl_pgm.ros.ROLES`).
    map_frame, robot_frame : str, keyword-only
    tolerance : float, optional, keyword-only
        Seconds; see :mod:`psgsl_pgm.ros._time` (default :data:`psgsl_pgm.ros.DEFAULT_TOLERANCE`).
    threshold : float, optional, keyword-only
        Gas hit threshold, ppm (default: the recorded episode's, else the sensor model's, 1 ppm).
    bag_map : bool, keyword-only
        Use the bag's ``nav_msgs/msg/OccupancyGrid`` as the house (occupied: ≥ 50 or unknown) instead of the world
        file's map: no rooms, no objects, no windows, so the room variant starts from the class prior, the source
        may be in any free cell, and the wind estimate uses uniform flows along x and y. The world still gives the
        ontology and the gas.
    keep_posteriors : bool, keyword-only
        Keep every step's posteriors (float64) in the result.
    gas_conversion : (2,) sequence of float, optional, keyword-only
        ``(scale, offset)``: the readings in ppm are ``scale * raw + offset`` whatever the message's unit (needed
        for a unit other than ppm or ppb, e.g. a MOX sensor's resistance in ohms); scale non-zero, both finite.
    progress : callable, optional, keyword-only
        ``progress(done, total)`` after every step (the command's progress bar).

    Returns
    -------
    ReplayResult

    Raises
    ------
    FileNotFoundError
        ``bag`` or ``world`` does not exist.
    ValueError
        ``bag`` is not a readable ROS 2 bag or holds bad messages (see :func:`psgsl_pgm.ros.read_bag`); ``world`` is
        refused by :func:`psgsl_pgm.sim.load_world`; an unknown ``estimator``, a negative ``seed``, a
        ``threshold`` that is not positive, ``bag_map`` without a map in the bag, a ``source`` outside the map, or
        a bad ``gas_conversion``.
    TypeError
        ``config`` is not an :class:`ExperimentConfig`, or ``gas_conversion`` does not hold two numbers.
    ImportError
        The ``ros`` extra is not installed.

    Examples
    --------
    A 4-reading episode in the default house's hallway, written as a bag and replayed:

    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from psgsl_pgm.experiment import replay
    >>> from psgsl_pgm.ros import Episode, write_bag
    >>> from psgsl_pgm.sim import default_house
    >>> t = np.arange(4.0)                                                  # s
    >>> pose = np.stack([1.0 + 0.5 * t, np.full(4, 6.0), np.zeros(4)], axis=-1)  # along the hallway, m
    >>> episode = Episode(grid=default_house(0).grid, pose_t=t, pose=pose, gas_t=t, gas=[2.0, 0.5, 2.0, 0.5],
    ...                   wind_t=t, wind=np.tile([0.2, 0.0], (4, 1)), frame_t=[], frame_cells=[], frame_labels=[])
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     result = replay(write_bag(Path(folder) / "hall.bag", episode), source="oven")
    >>> result.run.n_steps, result.run.hit.tolist()          # step 0 is the start; gas above 1 ppm at readings 1, 3
    (4, [False, True, False, True, False])
    """
    from ..ros import DEFAULT_TOLERANCE, read_bag

    tolerance = DEFAULT_TOLERANCE if tolerance is None else tolerance
    conversion = _conversion(gas_conversion)
    data = read_bag(bag, topics=topics, map_frame=map_frame, robot_frame=robot_frame, tolerance=tolerance)
    data, assumptions = _in_ppm(data, conversion)
    meta = data.meta
    if world is None and meta.get("world"):
        world = meta["world"]
    setting = default_world() if world is None else load_world(world)
    if estimator is None:  # a bag recorded before "estimator_naming" names the analytic-plume estimator "pmfs"
        estimator = stored_estimator_name(meta.get("estimator", "infotaxis"), meta.get("estimator_naming"))
    if estimator not in ESTIMATORS:
        raise ValueError(f"estimator must be one of {ESTIMATORS}, got {estimator!r}")
    if seed is None:
        seed = int(meta.get("seed", 0))
    elif isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    if config is None:  # the recorded run's settings (what the estimators were tuned with), else the defaults
        recorded = meta.get("config") or {}
        config = ExperimentConfig(**{k: v for k, v in recorded.items() if k in ExperimentConfig.__dataclass_fields__})
    elif not isinstance(config, ExperimentConfig):
        raise TypeError(f"config must be an ExperimentConfig, got {type(config).__name__}")
    if threshold is None:
        threshold = float(meta.get("threshold", GasSensor().threshold))
    if not (np.isfinite(threshold) and threshold > 0):
        raise ValueError(f"threshold must be a positive number of ppm, got {threshold!r}")
    if bag_map:
        if data.grid is None:
            raise ValueError(f"{data.path}: the bag has no nav_msgs/msg/OccupancyGrid topic to use as the map")
        grid = data.grid
        empty = np.zeros(grid.shape, dtype=bool)
        house = House(grid, np.full(grid.shape, -1, dtype=np.int64), (), (), empty, empty)
        setting = dataclasses.replace(setting, fixed_house=house, source_region="free", class_beliefs=None,
                                      start=None, sources={})
    house = setting.house(int(seed))
    if world is not None and not bag_map:
        from ..sim import check_free_cells

        check_free_cells(setting, int(seed))
    if source is None and meta.get("source") is not None:
        source = meta["source"]
    truth = None if source is None else setting.resolve_source(parse_source(source), house)
    detector = DetectorModel.default(house.classes)  # the simulator's detector: labels, and its likelihoods
    robot = SimpleNamespace(house=house, detector=detector)
    beliefs = VariantPosteriors(robot, estimator, config, setting=setting)
    frames, skipped = replay_frames(data, house, detector, Camera())
    if beliefs.mapped:
        frames = []  # a mapper's beliefs replace the camera, as in the experiment
    steps = replay_steps(data, frames, threshold=threshold, tolerance=tolerance)
    n = len(steps)
    g = house.grid
    centres = g.cell_centres()
    truth_xy = np.full(2, np.nan) if truth is None else np.asarray(truth, dtype=np.float64)
    truth_cell = None
    if truth is not None:
        rc = tuple(int(v) for v in g.world_to_cell(truth_xy))
        if not (0 <= rc[0] < g.shape[0] and 0 <= rc[1] < g.shape[1]):
            raise ValueError(f"source {source!r} at {tuple(truth_xy)} lies outside the map")
        truth_cell = int(np.ravel_multi_index(rc, g.shape))
    V = len(VARIANTS)
    err, spr, area, level = (np.empty((n + 1, V)) for _ in range(4))
    region_hit = np.zeros((n + 1, V), dtype=bool)
    times, pos, hits = np.zeros(n + 1), np.empty((n + 1, 2)), np.zeros(n + 1, dtype=bool)
    kept = []
    post = None

    def record(step):
        nonlocal post
        post = beliefs.posteriors(VARIANTS)
        err[step], spr[step], region_hit[step], area[step], level[step] = step_metrics(
            post, centres, truth_xy, truth_cell, g.resolution**2)
        if keep_posteriors:
            kept.append(post)

    pos[0] = steps[0][1] if steps else np.nan
    record(0)
    t0 = steps[0][0] if steps else 0
    for k, (t, stop, hit, _, wind, fr) in enumerate(steps):
        beliefs.observe(np.asarray(stop, dtype=np.float64), SimpleNamespace(hit=hit), wind, fr)
        pos[k + 1], hits[k + 1], times[k + 1] = stop, hit, (t - t0) * 1e-9
        record(k + 1)
        if progress is not None:
            progress(k + 1, n)
    label = "unknown" if source is None else (source if isinstance(source, str) else f"{truth_xy[0]:g},{truth_xy[1]:g}")
    cfg = run_config(config, setting if world is not None else None)
    cfg.update(bag=str(data.path), topics=data.topics, threshold=threshold, tolerance=tolerance)
    run = RunResult(label, int(seed), estimator, truth_xy, times, pos, hits, err, spr, {n: post}, cfg, region_hit,
                    area, level)
    if not len(data.wind_t):
        assumptions.append(NO_WIND)
    return ReplayResult(run=run, posteriors=kept, final=post, bag=data, house=house, skipped=skipped,
                        n_frames=len(frames), assumptions=assumptions)


def _conversion(value):
    """Validated ``(scale, offset)`` of ``gas_conversion`` (None: none given)."""
    if value is None:
        return None
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise ValueError(f"gas_conversion must be (scale, offset), ppm = scale * raw + offset, got {value!r}")
    try:
        scale, offset = float(value[0]), float(value[1])
    except (TypeError, ValueError):
        raise TypeError(f"gas_conversion must hold two numbers (scale, offset), got {value!r}") from None
    if not (np.isfinite(scale) and np.isfinite(offset) and scale != 0):
        raise ValueError(f"gas_conversion must be a finite non-zero scale and a finite offset, got {value!r}")
    return scale, offset


def _in_ppm(data, conversion):
    """``(data with its gas readings in ppm, assumptions)`` (see the module docstring)."""
    units = data.gas_units
    where = f"{data.path}: topic {data.topics['gas']}"
    if conversion is not None:
        scale, offset = conversion
        gas = scale * data.gas + offset
        if not np.isfinite(gas).all():
            raise ValueError(f"{where}: the gas conversion {scale:g} × raw + {offset:g} gives a non-finite ppm")
        return dataclasses.replace(data, gas=gas), []
    if units == "ppm":
        return data, []
    if units == "ppb":
        return dataclasses.replace(data, gas=data.gas / 1000.0), []
    if units is None:
        return data, [f"the gas topic's {data.topics['gas']} messages carry no unit: their values are taken as ppm"]
    raise ValueError(f"{where}: the readings are in {units} (the GasSensor's raw_units), not ppm; give the "
                     "conversion to ppm: --gas-conversion SCALE[,OFFSET] (ppm = SCALE × raw + OFFSET)")


def write_replay(result: ReplayResult, out) -> list:
    """What ``psgsl experiment`` writes for one replayed run, into ``out``.

    The files: ``run.npz`` (:func:`save_run`), ``metrics.csv``, ``summary.json``, ``posterior-<variant>.npy``
    (final, (H, W) float64), ``posterior.png`` (the final posteriors with the path and the 90 % region,
    ``replay_figure``) and, with a known source, ``error-chart.png``. Every file atomically.

    Parameters
    ----------
    result : ReplayResult
        What :func:`replay` returns for a robot's bag.
    out : str or path-like
        The output folder (made if missing).

    Returns
    -------
    list of pathlib.Path
        The files written.

    Raises
    ------
    OSError
        ``out`` cannot be made or written.

    Examples
    --------
    A 4-reading episode in the default house's hallway, replayed and written (``psgsl replay BAG --out DIR`` does
    the same with a bag recorded on the robot):

    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from psgsl_pgm.experiment import replay, write_replay
    >>> from psgsl_pgm.ros import Episode, write_bag
    >>> from psgsl_pgm.sim import default_house
    >>> t = np.arange(4.0)
    >>> pose = np.stack([1.0 + 0.5 * t, np.full(4, 6.0), np.zeros(4)], axis=-1)
    >>> episode = Episode(grid=default_house(0).grid, pose_t=t, pose=pose, gas_t=t, gas=[2.0, 0.5, 2.0, 0.5],
    ...                   wind_t=t, wind=np.tile([0.2, 0.0], (4, 1)), frame_t=[], frame_cells=[], frame_labels=[])
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     result = replay(write_bag(Path(folder) / "hall.bag", episode), source="oven")
    ...     files = write_replay(result, Path(folder) / "replay-out")
    ...     names = sorted(f.name for f in files if f.exists())
    >>> names[:3], len(names)
    (['error-chart.png', 'metrics.csv', 'posterior-olfaction.npy'], 8)
    """
    from ..io._output import write_file_atomically
    from ._figures import plot_error_chart
    from ._store import save_run
    from ._summary import summarize, write_csv, write_summary

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    run = result.run
    written = [save_run(run, out / "run.npz"), write_csv([run], out / "metrics.csv")]
    summary = summarize([run]) if np.isfinite(run.source_xy).all() else {}
    summary.update(bag=str(result.bag.path), steps=run.n_steps, frames=result.n_frames,
                   skipped_detections=result.skipped, outside_overlap=dict(result.bag.skipped),
                   assumptions=list(result.assumptions), final_spread=dict(zip(VARIANTS, map(float, run.spread[-1]))),
                   final_region_area=dict(zip(VARIANTS, map(float, run.region_area[-1]))))
    written.append(write_summary(summary, out / "summary.json"))
    for v, p in zip(VARIANTS, result.final):
        written.append(write_file_atomically(out / f"posterior-{v}.npy", lambda fh, p=p: np.save(fh, p)))
    written.append(out / "posterior.png")
    _savefig(replay_figure(result), written[-1])
    if np.isfinite(run.source_xy).all():
        fig = plot_error_chart([run])
        written.append(out / "error-chart.png")
        _savefig(fig, written[-1])
    return written


def replay_figure(result: ReplayResult):
    """The final posterior of every variant over the map: axes in metres, one colour bar per panel (p(s | …) per
    cell), the 90 % credible region, the walls, the driven path, the start and, when known, the true source, with
    a legend. Returns the matplotlib Figure."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    from ._metrics import credible_region

    run, house = result.run, result.house
    extent = house.grid.extent
    fig, axes = plt.subplots(1, len(VARIANTS), figsize=(4.6 * len(VARIANTS), 4.4), constrained_layout=True)
    for ax, v, p in zip(np.atleast_1d(axes), VARIANTS, result.final):
        im = ax.imshow(p, origin="lower", extent=extent, cmap="magma")
        fig.colorbar(im, ax=ax, shrink=0.8, label="p(s | …) per cell")
        ax.contour(credible_region(p, 0.9), levels=[0.5], colors="cyan", linewidths=0.8, origin="lower",
                   extent=extent)
        ax.imshow(np.ma.masked_where(~house.grid.occupancy, house.grid.occupancy), origin="lower",
                  extent=extent, cmap="Greys", vmin=0, vmax=1.5, alpha=0.8)
        ax.plot(run.position[1:, 0], run.position[1:, 1], "w-", lw=0.8)
        if run.n_steps:
            ax.plot(*run.position[1], "wo", ms=5)
        if np.isfinite(run.source_xy).all():
            ax.plot(*run.source_xy, "g*", ms=12)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(f"{v}: final p(s | …)")
    handles = [Line2D([], [], color="cyan", lw=0.8, label="90 % credible region"),
               Line2D([], [], color="w", lw=0.8, marker="o", ms=5, markevery=[0], label="path (from its start)"),
               Line2D([], [], color="0.6", lw=6, label="walls and furniture")]
    if np.isfinite(run.source_xy).all():
        handles.append(Line2D([], [], color="g", marker="*", ms=12, ls="", label="true source"))
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), facecolor="0.85")
    return fig


def _savefig(fig, path) -> None:
    import matplotlib.pyplot as plt

    from ..runs._runner import atomic_write

    try:
        atomic_write(path, lambda f, fh: f.savefig(fh, format="png", dpi=110), fig)
    finally:
        plt.close(fig)
