r"""Reactive baselines of the closed loop: ``surge-cast`` and ``spiral``, no map of the source, no p(s | g).

Both policies read only what the robot itself has measured: its gas hits and its anemometer readings (the
estimator's :attr:`~psgsl_pgm.olfaction.OlfactoryEstimator.observations`, each a stop's position, hit and wind),
and its own map to drive. They ignore the posterior the loop keeps beside them. Their state (the current
spiral centre, the cast leg, …) is a function of those readings, kept per run in the situation's cache.

A decision is one stop: the robot drives along the geodesic path towards the current *waypoint* (the reachable
drivable cell nearest it: walls and furniture clip a leg), at most :data:`STEP` metres (and at most the horizon)
per stop, so that it takes one gas reading every metre or so. A waypoint counts as reached when the robot stands
on that cell; the next one follows.

* ``spiral`` — Archimedean spiral search (Hayes, Martinoli & Goodman 2002, Auton. Robots 12:63–80, "spiral
  surge"; Lochmatter, Raemy & Martinoli 2008, ICRA, "spiral"): waypoints along

  .. math:: \mathbf x(\theta) = \mathbf c + \frac{b\,\theta}{2\pi}\,(\cos\theta, \sin\theta),

  consecutive ones :data:`STEP` apart in arc length (s(θ) = a/2 (θ √(1 + θ²) + asinh θ), a = b/2π),
  b = :data:`GAP` the distance between turns, starting at the robot's start. A hit re-centres the spiral on the stop where it was
  read (θ = 0): the next turns circle the place where the plume was met, widening until the next hit. Once the
  radius passes the map's diagonal the spiral starts again from its centre.
* ``surge-cast`` — the moth's upwind surge and crosswind cast (Kennedy & Marsh 1974, Science 184:999–1001;
  on robots, Lochmatter & Martinoli 2008, "Tracking odor plumes in a laminar wind field with bio-inspired
  algorithms", ISER). On a hit at x with anemometer reading u the robot *surges*: its next waypoint is
  x − :data:`SURGE` · u/‖u‖ (upwind). When the stop after a surge reads no gas, at x_l, it *casts*: crosswind
  legs about x_l, alternating sides and widening,

  .. math:: \mathbf w_k = \mathbf x_l + (-1)^k\,(k + 1)\,w_0\,\hat{\mathbf c}, \qquad k = 0, 1, 2, \ldots,

  with ĉ ⟂ the upwind direction of the last hit and w_0 = :data:`CAST_LEG` (a surge that cannot go further
  upwind, against a wall, casts about its end). A hit at any stop starts a new surge; when a leg would pass
  :data:`CAST_MAX` metres from x_l the plume counts as lost and the robot searches with the spiral above,
  centred on x_l. Before the first hit it searches with the spiral from its start (plume
  acquisition, as Hayes et al.). The wind direction is the anemometer reading of the hit; a reading below
  :data:`CALM` m/s gives none, and then the mean of the robot's readings so far, and failing that the last
  upwind direction (+x before any).

**How a run ends.** These policies choose their moves without p(s | g). The loop still keeps the estimator's
posterior beside them (the ``olfaction`` variant, conditioned on the detector's detections and misses), and a run
ends as every run does: at the robot's first declaration by the one rule (:mod:`psgsl_pgm.search._declare`; with
``end="reach"``, at the first detection), or at the time budget. The moves never read that posterior.

**Variants.** ``olfaction`` only. They cannot use the semantic term, and a semantic variant would record a
fused posterior the path does not depend on: :func:`check_reactive` refuses ``semantics`` and
``semantics+rooms`` in one line.
"""

from __future__ import annotations

import numpy as np

from ._policies import REACTIVE, Decision, _reachable_nearest, check_reactive

__all__ = ["CALM", "CAST_LEG", "CAST_MAX", "GAP", "REACTIVE", "STEP", "SURGE", "check_reactive", "reactive_step"]

#: m, the longest drive between two readings.
STEP = 1.0
#: m, the distance between the turns of the spiral (twice the default found radius: the turns' found discs touch).
GAP = 1.0
#: m, the upwind surge after a hit.
SURGE = 1.0
#: m, the first cast leg's offset w_0 from the line of the last hit.
CAST_LEG = 0.5
#: m, the widest cast before the plume counts as lost.
CAST_MAX = 4.0
#: m/s, anemometer readings below this give no wind direction.
CALM = 0.02

_STATE = "reactive: state"  # Situation.cache key


def _unit(v):
    n = float(np.hypot(v[0], v[1]))
    return None if n < CALM else np.array([v[0] / n, v[1] / n])


class _Spiral:
    """Waypoints of an Archimedean spiral about ``centre``, :data:`STEP` apart in arc length."""

    def __init__(self, centre, limit: float):
        self.centre = np.asarray(centre, dtype=np.float64)
        self.theta = 0.0
        self.limit = limit

    def point(self) -> np.ndarray:
        rho = GAP * self.theta / (2 * np.pi)
        return self.centre + rho * np.array([np.cos(self.theta), np.sin(self.theta)])

    @staticmethod
    def arc(theta):
        """Arc length from the centre to angle θ, a/2 (θ √(1 + θ²) + asinh θ), a = b/2π (m)."""
        return GAP / (4 * np.pi) * (theta * np.hypot(1.0, theta) + np.arcsinh(theta))

    def advance(self) -> None:
        """θ of the point :data:`STEP` further along the spiral (Newton on s(θ), ds/dθ = a √(1 + θ²))."""
        target = self.arc(self.theta) + STEP
        theta = self.theta + STEP / (GAP / (2 * np.pi) * np.hypot(1.0, self.theta))
        for _ in range(50):
            theta_next = theta - (self.arc(theta) - target) / (GAP / (2 * np.pi) * np.hypot(1.0, theta))
            if abs(theta_next - theta) < 1e-12:
                break
            theta = theta_next
        self.theta = theta_next
        if GAP * self.theta / (2 * np.pi) > self.limit:
            self.theta = 0.0


class _State:
    """A reactive policy's memory: what it has read so far and where it is going."""

    def __init__(self, policy: str, start, limit: float):
        self.policy = policy
        self.seen = 0  # observations processed
        self.limit = limit
        self.mode = "spiral"
        self.spiral = _Spiral(start, limit)
        self.spiral.advance()  # the start itself is read already
        self.upwind = np.array([1.0, 0.0])
        self.wind_sum = np.zeros(2)
        self.anchor = None  # where the cast is centred, m
        self.leg = 0
        self.surge_to = None

    def read(self, observations) -> None:
        """Take in the readings since the last decision (normally one)."""
        for obs in observations[self.seen :]:
            if obs.wind is not None:
                self.wind_sum += np.asarray(obs.wind, dtype=np.float64)
            if obs.hit:
                self._hit(np.asarray(obs.position, dtype=np.float64), obs.wind)
            elif self.policy == "surge-cast" and self.mode == "surge":  # lost the plume: cast about this stop
                self.mode, self.leg, self.anchor = "cast", 0, np.asarray(obs.position, dtype=np.float64)
        self.seen = len(observations)

    def _hit(self, position, wind) -> None:
        if self.policy == "spiral":
            self.spiral = _Spiral(position, self.limit)  # re-centre; θ = 0 is the hit's own stop
            self.spiral.advance()
            return
        u = None if wind is None else _unit(-np.asarray(wind, dtype=np.float64))
        if u is None:
            u = _unit(-self.wind_sum)
        if u is not None:
            self.upwind = u
        self.anchor = position
        self.mode = "surge"
        self.surge_to = position + SURGE * self.upwind

    def waypoint(self) -> np.ndarray:
        if self.mode == "surge":
            return self.surge_to
        if self.mode == "cast":
            cross = np.array([-self.upwind[1], self.upwind[0]])
            return self.anchor + (-1) ** self.leg * (self.leg + 1) * CAST_LEG * cross
        return self.spiral.point()

    def advance(self) -> None:
        """The waypoint is reached (or cannot be approached further): the next one."""
        if self.mode == "surge":  # no way upwind from here: cast about the surge's end
            self.mode, self.leg, self.anchor = "cast", 0, self.surge_to
        elif self.mode == "cast":
            self.leg += 1
            if (self.leg + 1) * CAST_LEG > CAST_MAX:
                self.mode = "spiral"  # the plume is lost: search about the last hit
                self.spiral = _Spiral(self.anchor, self.limit)
                self.spiral.advance()
        else:
            self.spiral.advance()


def _goal(sit, point) -> int:
    """The reachable drivable cell nearest (straight line) to ``point`` (m), clipped to the map."""

    grid = sit.space.grid
    h, w = sit.space.nav.shape
    lo = np.asarray(grid.origin, dtype=np.float64) + 0.5 * grid.resolution
    hi = lo + grid.resolution * (np.array([w, h]) - 1)
    return _reachable_nearest(sit, sit.space.cell_of(np.clip(point, lo, hi)))


def reactive_step(policy: str, sit):
    """The next stop of the reactive ``policy`` (:data:`REACTIVE`) in the situation ``sit`` (module docstring).

    Returns a :class:`psgsl_pgm.search.Decision` whose ``score`` is the drive's remaining distance to the
    waypoint, negated (m). The camera keeps its heading.
    """

    if policy not in REACTIVE:
        raise ValueError(f"policy must be one of {REACTIVE}, got {policy!r}")
    space = sit.space
    state = sit.cache.get(_STATE)
    if state is None or state.policy != policy:
        extent = np.asarray(space.nav.shape, dtype=np.float64) * space.resolution
        state = sit.cache[_STATE] = _State(policy, space.position(sit.cell), float(np.hypot(*extent)))
    state.read(sit.beliefs.estimator.observations)
    dist, pred = space.reach(sit.cell, np.inf)
    goal = sit.cell
    for _ in range(10_000):  # waypoints the robot stands on (or cannot approach) are skipped
        goal = _goal(sit, state.waypoint())
        if goal != sit.cell:
            break
        state.advance()
    if goal == sit.cell:  # nowhere to go (a robot boxed in a single cell): stay and read again
        return Decision(int(sit.cell), (float(sit.heading),), np.array([int(sit.cell)]), 0.0, 0.0)
    path = space.path(pred, goal)
    along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(space.position(path), axis=0), axis=1))])
    k = int(np.searchsorted(along, min(STEP, sit.horizon), side="right")) - 1
    k = max(k, 1)  # always move at least one cell
    path = path[: k + 1]
    return Decision(int(path[-1]), (float(sit.heading),), path, float(along[k]), -float(dist[goal] - along[k]))
