"""``psgsl live``: a ROS 2 node without rclpy, over DDS (Cyclone DDS), running the estimators and a policy.

It subscribes to the robot's ``/tf`` (with ``/tf_static``), gas sensor, anemometer and detections under ROS 2's
DDS names and types (:mod:`psgsl_pgm.ros._dds`), assimilates each gas reading as ``psgsl replay`` would
(:mod:`psgsl_pgm.search._live`), and publishes the policy's next pose on ``/goal_pose``
(``geometry_msgs/msg/PoseStamped``, what Nav2 drives to) and the posterior on ``/psgsl/posterior``
(``nav_msgs/msg/OccupancyGrid``). It runs for ``--duration`` seconds, until the robot declares the source
(``--until-declared``, the closed loop's rule), or until Ctrl-C. ``--out`` records the run (a ROS 2 bag ``psgsl replay`` replays, the
steps, the final posteriors); ``--foxglove`` streams it to Foxglove (:mod:`psgsl_pgm.ros._stream`). Without the
``ros`` extra it says in one line what to install (exit 2).
"""

from __future__ import annotations

import os
import signal
import threading

from ._replay import role_topic
from ._usage import UsageError, reporting_usage_errors

__all__ = ["add_parser", "run"]


def add_parser(subparsers):
    """Register ``psgsl live``."""
    from ..experiment import ESTIMATORS, VARIANTS
    from ..search import POLICIES

    p = subparsers.add_parser("live", help="a ROS 2 node over DDS (no ROS install): the estimators and a policy on "
                              "the robot's live topics, goals on /goal_pose")
    p.add_argument("--world", default=None, help="world file of the robot's house (default: the embedded house)")
    p.add_argument("--seed", type=int, default=0, help="furniture layout of the embedded house (default: 0)")
    p.add_argument("--topics", nargs="+", type=role_topic, default=[], metavar="ROLE=TOPIC",
                   help="ROS 2 topics per role (pose, gas, wind, detections; default: /tf, /gas, /wind, /detections)")
    p.add_argument("--types", nargs="+", type=role_topic, default=[], metavar="ROLE=TYPE",
                   help="message type per role (default: tf2_msgs/msg/TFMessage, olfaction_msgs/msg/GasSensor, "
                   "geometry_msgs/msg/Vector3Stamped, vision_msgs/msg/Detection3DArray)")
    p.add_argument("--domain-id", type=int, default=None,
                   help="DDS domain (default: $ROS_DOMAIN_ID, else 0)")
    p.add_argument("--best-effort", action="store_true", help="subscribe best effort (matches sensor-data QoS "
                   "publishers too) instead of reliable")
    p.add_argument("--estimator", choices=ESTIMATORS, default="infotaxis", help="olfactory estimator")
    p.add_argument("--policy", choices=[q for q in POLICIES if q != "tour"], default="infotaxis",
                   help="how the next goal is chosen (default: %(default)s)")
    p.add_argument("--variant", choices=VARIANTS, default="semantics+rooms",
                   help="the posterior the policy uses and the node publishes (default: %(default)s)")
    p.add_argument("--threshold", type=float, default=None, metavar="PPM",
                   help="gas hit threshold, a hit when reading >= PPM (default: 1 ppm)")
    p.add_argument("--tolerance", type=float, default=0.5, metavar="S",
                   help="seconds a pose or wind sample may lie from a reading it is interpolated to (default: 0.5)")
    p.add_argument("--map-frame", default="map", help="fixed frame (default: %(default)s)")
    p.add_argument("--robot-frame", default="base_link", help="robot frame (default: %(default)s)")
    p.add_argument("--goal-topic", default="/goal_pose", help="where the next goal goes (default: %(default)s)")
    p.add_argument("--posterior-topic", default="/psgsl/posterior",
                   help="where the posterior goes (default: %(default)s)")
    p.add_argument("--duration", type=float, default=None, metavar="S", help="run this many seconds")
    p.add_argument("--until-declared", action="store_true",
                   help="stop at the first declaration (the closed loop's rule: the most probable hypothesis once "
                   "the posterior mass within 0.5 m of its found region reaches --declare-mass)")
    p.add_argument("--declare-mass", type=float, default=0.9, metavar="KAPPA",
                   help="the mass at which the robot declares (default: %(default)s)")
    p.add_argument("--out", default=None, help="record the run here (live.bag, steps.csv, posterior-*.npy)")
    p.add_argument("--foxglove", type=int, nargs="?", const=8765, default=None, metavar="PORT",
                   help="stream the run to Foxglove over a WebSocket server on PORT (default 8765; 0: a free port)")
    p.add_argument("--foxglove-host", default="127.0.0.1",
                   help="address the Foxglove server binds (default: %(default)s, this machine only)")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    """Run ``psgsl live``; returns the exit code."""
    try:
        from ..ros._dds import require_dds

        require_dds()
    except ImportError as exc:
        raise UsageError(str(exc)) from None
    return reporting_usage_errors(_run, args)


def _run(args) -> int:
    from ..ros._dds import DdsEndpoint
    from ..search._live import LiveSession, live_subscriptions, run_live, write_live

    roles, subs = live_subscriptions(dict(args.topics), dict(args.types))
    domain = args.domain_id
    if domain is None:
        text = os.environ.get("ROS_DOMAIN_ID", "0") or "0"
        if not text.strip().isdigit():
            raise UsageError(f"ROS_DOMAIN_ID must be an integer 0..232, got {text!r}")
        domain = int(text)
    if args.out is not None:
        from ..io._output import check_output_dir

        check_output_dir(args.out)
    from ..search import SearchConfig

    session = LiveSession(world=args.world, seed=args.seed, estimator=args.estimator, policy=args.policy,
                          variant=args.variant, threshold=args.threshold,
                          search=SearchConfig(declare_mass=args.declare_mass))
    pubs = {args.goal_topic: "geometry_msgs/msg/PoseStamped", args.posterior_topic: "nav_msgs/msg/OccupancyGrid"}
    clash = sorted(set(pubs) & set(subs))
    if clash:
        raise UsageError(f"topics {clash} are both subscribed to and published")
    stream = None
    if args.foxglove is not None:
        from ..experiment import VARIANTS
        from ..ros._stream import FoxgloveStream

        try:
            stream = FoxgloveStream(session.house.grid, VARIANTS, host=args.foxglove_host, port=args.foxglove)
        except ImportError as exc:
            raise UsageError(str(exc)) from None
        except RuntimeError as exc:  # foxglove-sdk: the address is taken or cannot be bound
            raise UsageError(f"--foxglove: {exc}") from None
        print(f"psgsl live: Foxglove on ws://{args.foxglove_host}:{stream.port}", flush=True)
    endpoint = DdsEndpoint(subs, pubs, domain_id=domain, reliable=not args.best_effort)
    print(f"psgsl live: domain {domain}, listening to {', '.join(f'{r}={t}' for r, t in roles.items())}; goals on "
          f"{args.goal_topic}, posterior on {args.posterior_topic}" + ("" if args.duration
                                                                      else "; Ctrl-C ends"), flush=True)

    def report(step):
        print(f"  {step.t_ns * 1e-9:.3f}: at ({step.position[0]:.2f}, {step.position[1]:.2f}) "
              f"{'hit' if step.hit else 'miss'} {step.value:g}; goal ({step.goal[0]:.2f}, {step.goal[1]:.2f}, "
              f"{step.goal[2]:.2f} rad); 90 % region {step.region_area:.1f} m²; declaration "
              f"({step.declaration.xy[0]:.2f}, {step.declaration.xy[1]:.2f}) at mass {step.declaration.mass:.2f}"
              + (", declared" if step.declared else ""), flush=True)
        if stream is not None:
            stream.step(step.t_ns, step.position, step.heading, step.posteriors, step.goal)

    interrupted = []  # Ctrl-C ends the run like --duration: the last reading is assimilated, --out is written
    previous = signal.getsignal(signal.SIGINT) if _main_thread() else None
    if previous is not None:
        signal.signal(signal.SIGINT, lambda *_: interrupted.append(True))
    try:
        result = run_live(endpoint, session, roles=roles, subs=subs, duration=args.duration,
                          until_declared=args.until_declared, tolerance=args.tolerance, map_frame=args.map_frame,
                          robot_frame=args.robot_frame, goal_topic=args.goal_topic,
                          posterior_topic=args.posterior_topic, stop=lambda: bool(interrupted), on_step=report)
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
        endpoint.close()
        if stream is not None:
            stream.close()
    n = len(result["steps"])
    print(f"psgsl live: {n} steps" + (", declared" if result["declared"] else "")
          + (f", {result['pending']} readings without pose or wind after them" if result["pending"] else "")
          + (f", {result['skipped_detections']} detections of unknown classes skipped"
             if result["skipped_detections"] else "")
          + (f", {result['late_detections']} detection arrays came after their step and were dropped"
             if result["late_detections"] else ""))
    if args.out is not None:
        written = write_live(result, session, args.out, subs=subs, goal_topic=args.goal_topic,
                             posterior_topic=args.posterior_topic)
        print(f"written to {args.out}: {', '.join(p.name for p in written)}")
    return 0


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()
