"""``psgsl live``: the estimators and a policy on a robot's live ROS 2 topics (over DDS, :mod:`psgsl_pgm.ros._dds`).

The live node is the offline replay (:mod:`psgsl_pgm.experiment._replay`) run as the messages come:

* the messages received so far are decoded by the bag reader's own conversion
  (:func:`psgsl_pgm.ros._read.decode_messages`), and become the replay's steps (:func:`replay_frames`,
  :func:`replay_steps`): one step per gas reading, at the robot's position at its stamp, the wind interpolated
  to it, the detection arrays stamped from it up to the next reading as its camera frames;
* gas reading k becomes a step when reading k + 1 has arrived (its frames are then complete), the pose and wind
  streams hold a sample stamped at or after it and after its frames (the interpolation has both neighbours),
  and ``latency`` seconds of wall time have passed since reading k + 1 arrived (for detections still on their
  way). At the end (duration, declaration, interrupt) the last reading becomes a step if its pose and wind are
  covered. A detection array that arrives after its step was taken is dropped and counted. Only the messages
  the new steps need are decoded (from twice the tolerance before them), so a step costs the same at any point
  of a long run;
* :class:`LiveSession` assimilates each step exactly as the replay does (:class:`VariantPosteriors`, no "not
  found here" update: the robot is driven by its own navigation, and a replay of the same messages gives the
  same posteriors), then asks the policy (:func:`psgsl_pgm.search.choose`, on the robot's map,
  :class:`FreeSpace`) for the next pose of the camera;
* after each step the node publishes that pose as ``geometry_msgs/msg/PoseStamped`` (Nav2's ``/goal_pose``) and
  the variant's posterior as ``nav_msgs/msg/OccupancyGrid`` (:func:`psgsl_pgm.ros._dds.posterior_grid`).

The session never sees the simulator: its house is the world file's map and objects (what the robot knows), its
detector model the one the replay uses to read detections.
"""

from __future__ import annotations

import bisect
import json
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from ..experiment._config import ESTIMATORS, VARIANTS, ExperimentConfig
from ..experiment._metrics import credible_region
from ..experiment._replay import replay_frames, replay_steps
from ..experiment._step import VariantPosteriors
from ..ros._read import META_TOPIC, ROLES, TF, decode_messages
from ..ros._time import DEFAULT_TOLERANCE
from ..sim import Camera, DetectorModel, GasSensor, default_world, load_world
from ._declare import propose_declaration
from ._detection import DetectionModel
from ._settings import SearchConfig
from ._choose import choose
from ._policies import POLICIES, Situation, check_semantics_alone
from ._space import FreeSpace

__all__ = ["DEFAULT_TOPICS", "LiveSession", "LiveStep", "live_subscriptions", "run_live", "write_live"]

#: Role -> (ROS 2 topic, message type) the node subscribes to unless told otherwise.
DEFAULT_TOPICS = {
    "pose": ("/tf", TF),
    "gas": ("/gas", "olfaction_msgs/msg/GasSensor"),
    "wind": ("/wind", "geometry_msgs/msg/Vector3Stamped"),
    "detections": ("/detections", "vision_msgs/msg/Detection3DArray"),
}


class LiveStep(SimpleNamespace):
    """One step of a live session: ``t_ns``, ``position`` (2,), ``heading`` (rad, the robot's at the reading),
    ``hit``, ``value`` (ppm), ``posteriors`` (V, H, W) float64 of every variant, ``goal`` (3,) = (x, y, yaw) the
    policy chose next, ``region_area`` (m², the session variant's credible region), ``declaration`` (the
    :class:`psgsl_pgm.search._declare.Declaration` the closed loop's rule would make now: point and mass) and
    ``declared`` (its mass reached ``search.declare_mass``)."""


class LiveSession:
    """The robot's beliefs and policy on a stream of replay steps.

    Parameters
    ----------
    world : str or Path, optional, keyword-only
        World file of the house (:func:`psgsl_pgm.load_world`); default: the embedded house.
    seed : int, keyword-only
        Furniture layout of the embedded house (a world file's house is fixed).
    estimator : {"infotaxis", "analytic-plume", "particle-filter", "pmfs", "grgsl"}, keyword-only
    config : ExperimentConfig, optional, keyword-only
    policy : str, keyword-only
        One of :data:`psgsl_pgm.search.POLICIES` but ``tour``.
    variant : {"olfaction", "semantics", "semantics+rooms"}, keyword-only
        The posterior the policy uses and the node publishes.
    search : SearchConfig, optional, keyword-only
        Candidate lattice, horizon, found radius and credible mass of the policy, and the declaration rule's
        ``declare_mass`` and ``declare_radius`` (:mod:`psgsl_pgm.search._declare`, as in the closed loop).
    threshold : float, optional, keyword-only
        Gas hit threshold, ppm (default: the sensor model's, 1 ppm).
    sense_time : float, keyword-only
        s the robot dwells per gas reading (the policy's cost of a stop).
    """

    def __init__(self, *, world=None, seed: int = 0, estimator: str = "infotaxis",
                 config: ExperimentConfig | None = None, policy: str = "infotaxis", variant: str = "semantics+rooms",
                 search: SearchConfig | None = None, threshold: float | None = None, sense_time: float = 1.0):
        if estimator not in ESTIMATORS:
            raise ValueError(f"estimator must be one of {ESTIMATORS}, got {estimator!r}")
        if policy not in POLICIES or policy == "tour":
            raise ValueError(f"policy must be one of {POLICIES[1:]} (the tour is planned, not chosen), got {policy!r}")
        if variant not in VARIANTS:
            raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")
        check_semantics_alone(policy, variant)
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
        config = ExperimentConfig() if config is None else config
        if not isinstance(config, ExperimentConfig):
            raise TypeError(f"config must be an ExperimentConfig, got {type(config).__name__}")
        search = SearchConfig() if search is None else search
        if not isinstance(search, SearchConfig):
            raise TypeError(f"search must be a SearchConfig, got {type(search).__name__}")
        threshold = float(GasSensor().threshold if threshold is None else threshold)
        if not (np.isfinite(threshold) and threshold > 0):
            raise ValueError(f"threshold must be a positive number of ppm, got {threshold!r}")
        if not (isinstance(sense_time, (int, float)) and np.isfinite(sense_time) and sense_time > 0):
            raise ValueError(f"sense_time must be a positive number of seconds, got {sense_time!r}")
        # the replay's own set-up: the world's house, the simulator's detector labels, the experiment's beliefs
        setting = default_world() if world is None else load_world(world)
        house = setting.house(int(seed))
        self.detector = DetectorModel.default(house.classes)
        self.beliefs = VariantPosteriors(SimpleNamespace(house=house, detector=self.detector), estimator, config,
                                         setting=setting)
        self.camera = Camera()
        self.house, self.config, self.search = house, config, search
        self.world, self.seed, self.estimator = world, int(seed), estimator
        self.policy, self.variant, self.threshold, self.sense_time = policy, variant, threshold, float(sense_time)
        self.space = FreeSpace(house, self.camera, clearance=search.clearance, spacing=search.spacing,
                               n_headings=search.n_headings)
        miss = 0.0 if search.miss_probability is None else search.miss_probability  # no detector estimate here
        self.detection = DetectionModel.from_house(house, search.found_radius, miss_probability=miss)
        self.space.cover(self.detection)
        self._cache: dict = {}
        self._v = VARIANTS.index(variant)
        self.steps: list = []

    def frames(self, detections) -> tuple:
        """The camera frames of detection arrays (:func:`replay_frames`): ``([(t_ns, Frame)], skipped)``; none
        when the class beliefs come from a mapper."""
        frames, skipped = replay_frames(SimpleNamespace(detections=list(detections)), self.house, self.detector,
                                        self.camera)
        return ([] if self.beliefs.mapped else frames), skipped

    def observe(self, step, heading: float) -> LiveStep:
        """Assimilate one replay step ``(t_ns, stop, hit, value, wind, frames)`` with the robot's ``heading``
        (rad) at it; returns the :class:`LiveStep` with the policy's next pose."""
        t, stop, hit, value, wind, fr = step
        stop = np.asarray(stop, dtype=np.float64)
        self.beliefs.observe(stop, SimpleNamespace(hit=hit), wind, fr)
        post = self.beliefs.posteriors(VARIANTS)
        mine = post[self._v]
        s = self.search
        sit = Situation(mine, self.beliefs, self.variant, self.space, self.space.snap(stop), float(heading),
                        self.config.speed, self.config.turn_time, self.sense_time, s.horizon, s.found_radius,
                        self._cache, s.score, self.detection, s.far_spacing)
        dec = choose(self.policy, sit)
        xy = self.space.position(np.array([dec.cell]))[0]
        goal = np.array([xy[0], xy[1], float(dec.headings[0])])
        area = float(credible_region(mine, s.credible).sum()) * self.house.grid.resolution**2
        dec_now = propose_declaration(mine, self.detection, radius=s.declare_radius)
        out = LiveStep(t_ns=int(t), position=stop, heading=float(heading), hit=bool(hit), value=float(value),
                       posteriors=post, goal=goal, region_area=area, declaration=dec_now,
                       declared=dec_now.mass >= s.declare_mass)
        self.steps.append(out)
        return out

    def meta(self) -> dict:
        """The session's settings as a recorded bag's episode metadata (:data:`psgsl_pgm.ros.META_TOPIC`)."""
        return {"world": None if self.world is None else str(Path(self.world).resolve()), "seed": self.seed,
                "estimator": self.estimator, "config": self.config.to_dict(), "threshold": self.threshold}


def live_subscriptions(topics: dict | None = None, types: dict | None = None) -> tuple:
    """``(role -> topic, topic -> message type)`` of the node: :data:`DEFAULT_TOPICS` with ``topics`` (role ->
    topic) and ``types`` (role -> message type, one of :data:`psgsl_pgm.ros.ROLES`' for the role) applied;
    ``/tf_static`` is always read."""
    topics, types = dict(topics or {}), dict(types or {})
    for what, table in (("topics", topics), ("types", types)):
        bad = sorted(set(table) - set(DEFAULT_TOPICS))
        if bad:
            raise ValueError(f"{what}: unknown role(s) {bad}; the live roles are {list(DEFAULT_TOPICS)}")
    roles, subs = {}, {}
    for role, (topic, msgtype) in DEFAULT_TOPICS.items():
        topic = topics.get(role, topic)
        msgtype = types.get(role, msgtype)
        if msgtype not in ROLES[role]:
            raise ValueError(f"{role}: unknown topic type {msgtype!r}; {role} needs one of {list(ROLES[role])}")
        if not isinstance(topic, str) or not topic.startswith("/"):
            raise ValueError(f"topics: the {role} topic must be a name starting with '/', got {topic!r}")
        if topic in subs and subs[topic] != msgtype:
            raise ValueError(f"topic {topic} given for two roles with different types, {subs[topic]} and {msgtype}")
        roles[role] = topic
        subs[topic] = msgtype
    subs.setdefault("/tf_static", TF)  # places the sensors and the camera on the robot, whatever gives its pose
    return roles, subs


def _stamp(msg) -> int:
    return int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)


class _Topic:
    """One topic's messages in arrival order, with the running maximum of their stamps (searchable: the first
    message at or after a time is found by bisection even when a stamp goes back)."""

    def __init__(self):
        self.items: list = []  # (receive stamp, message)
        self.top: list = []  # running maximum of the stamps

    def add(self, t_recv: int, msg, stamp: int) -> None:
        self.items.append((t_recv, msg))
        self.top.append(stamp if not self.top else max(self.top[-1], stamp))

    def first_at(self, t: int) -> int:
        """Index of the first message whose stamp (running maximum) is at or after ``t``."""
        return bisect.bisect_left(self.top, t)

    def first_after(self, t: int) -> int:
        return bisect.bisect_right(self.top, t)


class _Stream:
    """What the node has received, and which gas readings are ready to become steps (module docstring)."""

    def __init__(self, roles: dict, subs: dict, tolerance: float):
        self.roles, self.subs = roles, subs
        self.topics = {t: _Topic() for t in subs}
        self.order: list = []  # (topic, index) in arrival order, for the record
        self.gas_arrived: list = []  # wall time of each gas reading's arrival
        self.tf_topics = {t for t, m in subs.items() if m == TF}
        self.tol = round(float(tolerance) * 1e9)
        self.closed = None  # detection arrays stamped before this belong to steps already taken
        self.late = 0

    def add(self, topic: str, t_recv: int, msg, now: float) -> None:
        r = self.roles
        if topic == r["gas"]:
            stamp = _stamp(msg) if hasattr(msg, "header") else t_recv
            self.gas_arrived.append(now)
        elif hasattr(msg, "transforms"):
            stamp = max((_stamp(tr) for tr in msg.transforms), default=0)
        else:
            stamp = _stamp(msg)
            if topic == r["detections"] and self.closed is not None and stamp < self.closed:
                self.late += 1  # its step is taken: dropped, counted
                return
        self.order.append((topic, len(self.topics[topic].items)))
        self.topics[topic].add(t_recv, msg, stamp)

    @property
    def raw(self) -> list:
        """Every message received, ``[(topic, receive stamp, message)]`` in arrival order."""
        return [(topic, *self.topics[topic].items[i]) for topic, i in self.order]

    @property
    def n_gas(self) -> int:
        return len(self.topics[self.roles["gas"]].items)

    def stamp_of_gas(self, k: int):
        """The stamp of gas reading ``k``, or None when it has not come."""
        return self._stamp_of(self.roles["gas"], k) if k < self.n_gas else None

    def _stamp_of(self, topic, k):
        t_recv, msg = self.topics[topic].items[k]
        return _stamp(msg) if hasattr(msg, "header") else t_recv

    def ready(self, done: int, now: float, latency: float, final: bool) -> int:
        """How many gas readings may be steps now (≥ ``done``)."""
        r = self.roles
        pose = self.topics[r["pose"]]
        wind, dets = self.topics[r["wind"]], self.topics[r["detections"]]
        k = done
        while k < self.n_gas:
            last = k + 1 >= self.n_gas
            if not final and (last or now - self.gas_arrived[k + 1] < latency):
                break
            t = self._stamp_of(r["gas"], k)
            right = wind.first_at(t)  # the wind's right neighbour of the reading
            if right >= len(wind.items) or not pose.top:
                break
            # the pose is looked up at the reading, its frames and the wind samples kept (messages())
            n_frames = len(dets.items) if last else dets.first_at(self._stamp_of(r["gas"], k + 1))
            need = max(t, wind.top[right], dets.top[n_frames - 1] if n_frames else t)
            if pose.top[-1] < need:
                break
            k += 1
        return k

    def messages(self, done: int, n: int) -> list:
        """The messages that steps ``done`` … ``n - 1`` need: gas readings ``done`` … ``n - 1``; the detection
        arrays from reading ``done`` up to reading ``n`` (from the first, for the first step); wind samples from
        the tolerance before reading ``done`` to the first at or after reading ``n - 1``; poses and transforms from
        twice the tolerance before reading ``done`` (the lookups at those wind samples have their left neighbour);
        every static transform."""
        r = self.roles
        gas = self.topics[r["gas"]]
        t_first = self._stamp_of(r["gas"], done)
        t_last = self._stamp_of(r["gas"], n - 1)
        after = self._stamp_of(r["gas"], n) if n < self.n_gas else None
        window = None if done == 0 else t_first - self.tol
        out = [(r["gas"], *gas.items[i]) for i in range(done, n)]
        for topic, top in self.topics.items():
            if topic == r["gas"]:
                continue
            lo, hi = 0, len(top.items)
            if topic == "/tf_static":
                pass
            elif topic == r["detections"]:
                lo = 0 if done == 0 else top.first_at(t_first)
                hi = hi if after is None else top.first_at(after)
            elif topic == r["wind"]:
                lo = 0 if window is None else top.first_at(window)
                hi = min(top.first_at(t_last) + 1, hi)
            elif window is not None:  # the pose and the transforms
                lo = top.first_at(window - self.tol)
            out.extend((topic, *top.items[i]) for i in range(lo, hi))
        return out


def run_live(endpoint, session: LiveSession, *, roles: dict, subs: dict, duration: float | None = None,
             until_declared: bool = False, latency: float = 0.2, tolerance: float = DEFAULT_TOLERANCE,
             map_frame: str = "map", robot_frame: str = "base_link", goal_topic: str = "/goal_pose",
             posterior_topic: str = "/psgsl/posterior", poll: float = 0.02, stop=None, on_step=None) -> dict:
    """Run the node (see the module docstring) until ``duration``, a declaration, or ``stop()``.

    Parameters
    ----------
    endpoint : psgsl_pgm.ros._dds.DdsEndpoint
        Subscribed to ``subs``, publishing ``goal_topic`` (PoseStamped) and ``posterior_topic`` (OccupancyGrid).
    session : LiveSession
    roles : dict, keyword-only
        Role -> topic (:func:`live_subscriptions`).
    subs : dict, keyword-only
        Topic -> message type.
    duration : float, optional, keyword-only
        Wall-clock seconds to run; None: until declared or stopped.
    until_declared : bool, keyword-only
        Stop at the first step whose declaration reaches ``search.declare_mass`` (the closed loop's rule,
        :mod:`psgsl_pgm.search._declare`).
    latency : float, keyword-only
        Wall seconds a gas reading waits after the next one arrives, for late detection arrays.
    tolerance : float, keyword-only
        Seconds (:mod:`psgsl_pgm.ros._time`).
    map_frame, robot_frame, goal_topic, posterior_topic : str, keyword-only
    poll : float, keyword-only
        Wall seconds between polls of the readers.
    stop : callable, optional, keyword-only
        ``stop() -> bool``: end the run when true (checked every poll).
    on_step : callable, optional, keyword-only
        Called with each :class:`LiveStep` after it is published.

    Returns
    -------
    dict
        ``steps`` (list of LiveStep), ``declared`` (bool), ``messages`` (every (topic, stamp, message) kept),
        ``skipped_detections`` (of classes the detector does not know), ``late_detections`` (arrays that came
        after their step was taken: dropped), ``pending`` (gas readings received but not assimilated: no pose or
        wind after them).

    Raises
    ------
    ValueError
        No end is given (``duration``, ``until_declared`` or ``stop``), ``duration`` is not a positive number, or
        a message cannot be decoded (see :func:`psgsl_pgm.ros.read_bag`).

    Examples
    --------
    A 4-reading episode in the default house's hallway, written as a bag and handed to the node one message per
    poll by a stand-in for the DDS endpoint (``psgsl live`` uses :class:`psgsl_pgm.ros._dds.DdsEndpoint`):

    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from rosbags.rosbag2 import Reader
    >>> from psgsl_pgm.ros import Episode, write_bag
    >>> from psgsl_pgm.ros._dds import message_types
    >>> from psgsl_pgm.search import LiveSession, run_live
    >>> from psgsl_pgm.sim import default_house
    >>> class Feed:                                            # take() what came in, publish() what the node sends
    ...     def __init__(self, messages):
    ...         self.messages, self.published = list(messages), []
    ...     def take(self):
    ...         return [self.messages.pop(0)] if self.messages else []
    ...     def publish(self, topic, message):
    ...         self.published.append(topic)
    >>> t = np.arange(4.0)                                     # s
    >>> pose = np.stack([1.0 + 0.5 * t, np.full(4, 6.0), np.zeros(4)], axis=-1)
    >>> episode = Episode(grid=default_house(0).grid, pose_t=t, pose=pose, gas_t=t, gas=[2.0, 0.5, 2.0, 0.5],
    ...                   wind_t=t, wind=np.tile([0.2, 0.0], (4, 1)), frame_t=[], frame_cells=[], frame_labels=[])
    >>> roles = {"pose": "/tf", "gas": "/gas", "wind": "/wind", "detections": "/detections"}
    >>> subs = {"/tf": "tf2_msgs/msg/TFMessage", "/gas": "olfaction_msgs/msg/GasSensor",
    ...         "/wind": "geometry_msgs/msg/Vector3Stamped", "/detections": "vision_msgs/msg/Detection3DArray"}
    >>> T = message_types()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     with Reader(write_bag(Path(folder) / "hall.bag", episode)) as bag:
    ...         messages = [(c.topic, s, T[c.msgtype].deserialize(raw)) for c, s, raw in bag.messages()
    ...                     if c.topic in subs]
    >>> feed = Feed(messages)
    >>> result = run_live(feed, LiveSession(policy="greedy", variant="olfaction"), roles=roles, subs=subs,
    ...                   latency=0.0, poll=0.0, stop=lambda: not feed.messages)
    >>> len(result["steps"]), feed.published[:2]               # a goal and a posterior per gas reading
    (4, ['/goal_pose', '/psgsl/posterior'])
    """
    from ..ros._dds import pose_stamped, posterior_grid

    if duration is None and not until_declared and stop is None:
        raise ValueError("run_live needs an end: duration, until_declared or stop")
    if duration is not None and not (isinstance(duration, (int, float)) and np.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be a positive number of seconds, got {duration!r}")
    stream = _Stream(roles, subs, tolerance)
    skipped = 0
    done, declared = 0, False
    t_end = None if duration is None else time.monotonic() + float(duration)
    name = "live (DDS)"

    def advance(final: bool) -> bool:
        nonlocal skipped, done
        k = stream.ready(done, time.monotonic(), latency, final)
        if k == done:
            return False
        data = decode_messages(name, roles | {"map": None}, stream.messages(done, k), tf_topics=stream.tf_topics,
                               map_frame=map_frame, robot_frame=robot_frame, tolerance=tolerance)
        frames, s = session.frames(data.detections)  # the arrays of steps done … k - 1 only
        skipped += s
        steps = replay_steps(data, frames, threshold=session.threshold, tolerance=tolerance)
        yaw = dict(zip(data.pose_t.tolist(), data.pose[:, 2].tolist()))
        for step in steps:
            out = session.observe(step, yaw[step[0]])
            endpoint.publish(goal_topic, pose_stamped(out.t_ns, map_frame, out.goal))
            endpoint.publish(posterior_topic, posterior_grid(out.t_ns, map_frame, session.house.grid,
                                                             out.posteriors[VARIANTS.index(session.variant)]))
            if on_step is not None:
                on_step(out)
            done += 1
            stream.closed = stream.stamp_of_gas(done)
            if until_declared and out.declared:
                return True
        return False

    while True:
        now = time.monotonic()
        for topic, t, msg in endpoint.take():
            stream.add(topic, t, msg, now)
        if advance(False):
            declared = True
            break
        if (t_end is not None and time.monotonic() >= t_end) or (stop is not None and stop()):
            for topic, t, msg in endpoint.take():
                stream.add(topic, t, msg, time.monotonic())
            declared = advance(True)
            break
        time.sleep(poll)
    return {"steps": session.steps, "declared": declared, "messages": stream.raw, "skipped_detections": skipped,
            "late_detections": stream.late, "pending": stream.n_gas - done}


def write_live(result: dict, session: LiveSession, out, *, subs: dict, goal_topic: str = "/goal_pose",
               posterior_topic: str = "/psgsl/posterior") -> list:
    """Record a live run into ``out``: ``live.bag`` (every message received, the published goals and posteriors,
    and the session's settings on :data:`psgsl_pgm.ros.META_TOPIC`: ``psgsl replay`` replays it), ``steps.csv``
    (per step: seconds since the first reading, position, hit, value, goal, credible-region area) and
    ``posterior-<variant>.npy`` (final posteriors, (H, W) float64). Every file whole or not at all.

    Parameters
    ----------
    result : dict
        What :func:`run_live` returned: ``{"steps": [...], "messages": [(topic, t_ns, message), ...], ...}``.
    session : LiveSession
        The session that made the steps (its house, variant and settings).
    out : path-like
        The folder to write into (created if missing).
    subs : dict, keyword-only
        Topic -> ROS 2 message type of every subscribed topic (the types the bag records).
    goal_topic, posterior_topic : str, keyword-only
        The topics the goals (``geometry_msgs/msg/PoseStamped``) and posteriors (``nav_msgs/msg/OccupancyGrid``)
        were published on.

    Returns
    -------
    list of Path
        The files written.

    Examples
    --------
    The run of :func:`run_live`'s example, recorded:

    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from rosbags.rosbag2 import Reader
    >>> from psgsl_pgm.ros import Episode, write_bag
    >>> from psgsl_pgm.ros._dds import message_types
    >>> from psgsl_pgm.search import LiveSession, run_live, write_live
    >>> from psgsl_pgm.sim import default_house
    >>> class Feed:
    ...     def __init__(self, messages):
    ...         self.messages = list(messages)
    ...     def take(self):
    ...         return [self.messages.pop(0)] if self.messages else []
    ...     def publish(self, topic, message):
    ...         pass
    >>> t = np.arange(4.0)
    >>> pose = np.stack([1.0 + 0.5 * t, np.full(4, 6.0), np.zeros(4)], axis=-1)
    >>> episode = Episode(grid=default_house(0).grid, pose_t=t, pose=pose, gas_t=t, gas=[2.0, 0.5, 2.0, 0.5],
    ...                   wind_t=t, wind=np.tile([0.2, 0.0], (4, 1)), frame_t=[], frame_cells=[], frame_labels=[])
    >>> roles = {"pose": "/tf", "gas": "/gas", "wind": "/wind", "detections": "/detections"}
    >>> subs = {"/tf": "tf2_msgs/msg/TFMessage", "/gas": "olfaction_msgs/msg/GasSensor",
    ...         "/wind": "geometry_msgs/msg/Vector3Stamped", "/detections": "vision_msgs/msg/Detection3DArray"}
    >>> T = message_types()
    >>> session = LiveSession(policy="greedy", variant="olfaction")
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     with Reader(write_bag(Path(folder) / "hall.bag", episode)) as bag:
    ...         feed = Feed([(c.topic, s, T[c.msgtype].deserialize(raw)) for c, s, raw in bag.messages()
    ...                      if c.topic in subs])
    ...     result = run_live(feed, session, roles=roles, subs=subs, latency=0.0, poll=0.0,
    ...                       stop=lambda: not feed.messages)
    ...     files = write_live(result, session, Path(folder) / "live", subs=subs)
    ...     lines = (Path(folder) / "live" / "steps.csv").read_text().splitlines()
    >>> [f.name for f in files][:2], len(lines)                # a header and one line per step
    (['live.bag', 'steps.csv'], 5)
    """
    from ..io._output import write_file_atomically
    from ..ros._dds import message_types, pose_stamped, posterior_grid
    from ..ros._types import typestore
    from ..ros._write import replace_folder

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    steps = result["steps"]
    T = message_types()
    frame = "map"
    rows = [(topic, t, subs[topic], msg) for topic, t, msg in result["messages"]]
    for s in steps:
        rows.append((goal_topic, s.t_ns, "geometry_msgs/msg/PoseStamped", pose_stamped(s.t_ns, frame, s.goal)))
        rows.append((posterior_topic, s.t_ns, "nav_msgs/msg/OccupancyGrid",
                     posterior_grid(s.t_ns, frame, session.house.grid, s.posteriors[VARIANTS.index(session.variant)])))
    t0 = min([t for _, t, _, _ in rows], default=0)
    rows.append((META_TOPIC, t0, "std_msgs/msg/String", T["std_msgs/msg/String"](data=json.dumps(session.meta()))))
    rows.sort(key=lambda r: r[1])

    def write(folder):
        from rosbags.rosbag2 import StoragePlugin, Writer

        store = typestore()
        with Writer(folder, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
            conns = {}
            for topic, t, msgtype, msg in rows:
                if topic not in conns:
                    conns[topic] = writer.add_connection(topic, msgtype, typestore=store)
                writer.write(conns[topic], int(t), bytes(msg.serialize()))

    written = [replace_folder(out / "live.bag", write)]
    start = steps[0].t_ns if steps else 0
    lines = ["t,x,y,hit,value,goal_x,goal_y,goal_yaw,region_area,declare_x,declare_y,declare_mass,declared"]
    for s in steps:
        d = s.declaration
        lines.append(",".join(f"{v:.9g}" for v in ((s.t_ns - start) * 1e-9, *s.position)) + f",{int(s.hit)},"
                     + ",".join(f"{v:.9g}" for v in (s.value, *s.goal, s.region_area, *d.xy, d.mass))
                     + f",{int(s.declared)}")
    text = "\n".join(lines) + "\n"
    written.append(write_file_atomically(out / "steps.csv", lambda fh: fh.write(text.encode())))
    if steps:
        for v, p in zip(VARIANTS, steps[-1].posteriors):
            written.append(write_file_atomically(out / f"posterior-{v}.npy", lambda fh, p=p: np.save(fh, p)))
    return written
