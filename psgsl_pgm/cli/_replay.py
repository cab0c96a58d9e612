"""``psgsl replay BAG``: a robot's ROS 2 bag (sqlite3 or MCAP storage) through the estimators.

``--list`` prints the bag's topics, their types and message counts, and the role each would fill. Otherwise the
bag is replayed (:func:`psgsl_pgm.experiment._replay.replay`) and OUT receives what ``psgsl experiment`` writes
for one run. A bad bag — not a bag, truncated, a missing topic, an unknown type, a reading no pose covers, times
going backwards — is one line naming the bag, topic and time, exit 2, and OUT is left untouched.
"""

from __future__ import annotations

import numpy as np

from ._usage import UsageError

__all__ = ["add_parser", "check_record_extra", "run"]


def check_record_extra() -> None:
    """``--record`` (experiment, search) needs the ros extra: a usage error naming it when missing, before any run."""
    try:
        from ..ros import require
        from ..ros._foxglove import _require

        require()
        _require()
    except ImportError as exc:
        raise UsageError(f"--record: {exc}") from None


def role_topic(text: str):
    role, sep, topic = text.partition("=")
    if not sep or not role or not topic:
        raise ValueError(f"expected ROLE=TOPIC, got {text!r}")
    return role.strip(), topic.strip()


def conversion(text: str):
    """``SCALE[,OFFSET]`` -> (scale, offset)."""
    parts = text.split(",")
    if len(parts) not in (1, 2):
        raise ValueError(f"expected SCALE[,OFFSET], got {text!r}")
    return float(parts[0]), float(parts[1]) if len(parts) == 2 else 0.0


def add_parser(subparsers):
    """Register ``psgsl replay``."""
    from ..experiment import ESTIMATORS

    p = subparsers.add_parser("replay", help="replay a robot's ROS 2 bag (sqlite3 or MCAP) through the estimators")
    p.add_argument("bag", metavar="BAG", help="the bag folder (metadata.yaml with .db3 or .mcap files)")
    p.add_argument("--list", action="store_true", help="list the bag's topics and the role each fills, then stop")
    p.add_argument("--world", default=None, help="world file of the house the bag was recorded in (default: the "
                   "embedded house, or the world a psgsl-recorded bag names)")
    p.add_argument("--source", default=None, help="the true source (class, 'x,y' or the world's source name), for "
                   "the error (default: none, or a psgsl-recorded bag's)")
    p.add_argument("--estimator", choices=ESTIMATORS, default=None,
                   help="olfactory estimator (default: a psgsl-recorded bag's, else infotaxis)")
    p.add_argument("--seed", type=int, default=None, help="furniture layout of the embedded house (default: a "
                   "psgsl-recorded bag's, else 0)")
    p.add_argument("--topics", nargs="+", type=role_topic, default=[], metavar="ROLE=TOPIC",
                   help="use these topics (roles: pose, gas, wind, detections, map) instead of finding them by type")
    p.add_argument("--map-frame", default="map", help="fixed frame (default: %(default)s)")
    p.add_argument("--robot-frame", default="base_link", help="robot frame (default: %(default)s)")
    p.add_argument("--tolerance", type=float, default=None, metavar="S",
                   help="seconds a pose, transform or wind sample may lie from a reading it is interpolated to "
                   "(default: 0.5)")
    p.add_argument("--threshold", type=float, default=None, metavar="PPM",
                   help="gas hit threshold, a hit when reading >= PPM (default: a psgsl-recorded bag's, else the "
                   "sensor model's 1 ppm)")
    p.add_argument("--gas-conversion", type=conversion, default=None, metavar="SCALE[,OFFSET]",
                   help="the gas readings in ppm are SCALE × raw + OFFSET (needed when the GasSensor messages are in "
                   "a unit other than ppm or ppb, e.g. a MOX sensor in ohms)")
    p.add_argument("--bag-map", action="store_true", help="use the bag's nav_msgs/OccupancyGrid as the house (no "
                   "rooms or objects; a source may be in any free cell) instead of the world's map")
    p.add_argument("--out", default=None, help="output directory (required unless --list)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    """Run ``psgsl replay``; returns the exit code."""
    try:
        from ..ros import require

        require()
    except ImportError as exc:
        raise UsageError(str(exc)) from None
    if args.list:
        return _list(args)
    if args.out is None:
        raise UsageError("--out is required (or --list)")
    from ..experiment._replay import replay, write_replay
    from ..io._output import check_output_dir

    check_output_dir(args.out)  # an unwritable --out fails now, before the bag is read; creates nothing
    bar = _Bar(not getattr(args, "quiet", False))
    try:
        res = replay(args.bag, world=args.world, source=args.source, estimator=args.estimator, seed=args.seed,
                     topics=dict(args.topics), map_frame=args.map_frame, robot_frame=args.robot_frame,
                     tolerance=args.tolerance, threshold=args.threshold, bag_map=args.bag_map,
                     gas_conversion=args.gas_conversion, progress=bar)
    finally:
        bar.close()
    run_ = res.run
    print(f"psgsl replay: {args.bag}: {run_.n_steps} gas readings ({int(run_.hit.sum())} hits at >= "
          f"{run_.config['threshold']:g} ppm), {res.n_frames} detection frames"
          + (f", {res.skipped} detections of unknown classes skipped" if res.skipped else "")
          + f"; topics {', '.join(f'{k}={v}' for k, v in res.bag.topics.items() if v)}")
    outside = {k: v for k, v in res.bag.skipped.items() if v}
    if outside:
        print("  skipped outside the overlap of the streams: "
              + ", ".join(f"{v} {k} message{'s' if v > 1 else ''}" for k, v in outside.items()))
    for text in res.assumptions:
        print(f"  {text}")
    from ..experiment import VARIANTS

    for v, name in enumerate(VARIANTS):
        err = f"error {run_.error[-1, v]:.2f} m, " if run_.error.size and np.isfinite(run_.error[-1, v]) else ""
        print(f"  {name:<16} final: {err}spread {run_.spread[-1, v]:.2f} m, 90 % region {run_.region_area[-1, v]:.1f} m²")
    written = write_replay(res, args.out)
    print(f"written to {args.out}: {', '.join(p.name for p in written)}")
    return 0


class _Bar:
    """``progress(done, total)`` for :func:`replay`: a tqdm bar on stderr over the gas readings (none when quiet)."""

    def __init__(self, show: bool):
        self._show, self._bar, self._done = show, None, 0

    def __call__(self, done: int, total: int) -> None:
        if self._bar is None:
            from ..runs._runner import _progress_bar

            self._bar = _progress_bar(total, "gas readings", self._show, unit="reading")
        self._bar.update(done - self._done)
        self._done = done

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


def _list(args) -> int:
    from ..ros import bag_topics

    rows = bag_topics(args.bag)
    width = max([len(r[0]) for r in rows] + [5])
    twidth = max([len(r[1]) for r in rows] + [4])
    print(f"{'topic':<{width}}  {'type':<{twidth}}  {'messages':>8}  role")
    for topic, typ, count, role in rows:
        print(f"{topic:<{width}}  {typ:<{twidth}}  {count:>8}  {role or '-'}")
    return 0
