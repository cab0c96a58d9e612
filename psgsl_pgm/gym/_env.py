r"""``psgsl/House-v0``: the closed-loop search as a gymnasium environment.

One episode is one closed-loop search (:func:`psgsl_pgm.search.run_closed_loop`) whose decisions come from the
agent: the environment drives the very stepping object of the loop (:class:`psgsl_pgm.search._stepper`), so the
world, the robot's beliefs, the success rule and the declaration rule are those of ``psgsl search``.

**Reset.** The common first stop (the look-around at the start) is part of the reset; the observation is the robot's
after it. ``reset(seed=...)`` seeds the environment's generator, which draws each episode: with
``world="generated"`` a generated home and an episode seed of the split
(:func:`psgsl_pgm.search._split.benchmark_sample`, development homes 0, 1, … by default) and the episode's gas and source as the benchmark draws them
(:func:`psgsl_pgm.search._episodes.draw_episode`, the world's own ontology); with ``world="house"`` the embedded
house, a seed of :func:`psgsl_pgm.search._split.house_seeds` and one of ``sources``. ``options={"house": h,
"seed": s}`` (and ``"source"`` in the embedded house) picks an episode instead. The world itself is seeded by the
episode seed, as every closed-loop run.

**Actions.** ``Discrete(N)``: a slot of the candidate table (:func:`psgsl_pgm.gym._features.candidate_table`), the
planner's candidate stops ranked by P_f per second of travel; the robot drives the geodesic path there and turns its
camera to the direction of its last step. ``info["action_mask"]`` says which slots hold a candidate; an action on an
empty slot a ≥ K takes the candidate a mod K.

**Reward.** −``time_cost`` per second of simulated time the step took (driving, turning, reading), plus
``correct_bonus`` at a right declaration or −``wrong_penalty`` at a wrong one. The episode terminates at the robot's
declaration (:mod:`psgsl_pgm.search._declare`, the rule of every policy) and is truncated at the time budget.
"""

from __future__ import annotations

from dataclasses import replace

import gymnasium
import numpy as np
from gymnasium import spaces

from ..experiment._config import ESTIMATORS, VARIANTS, ExperimentConfig
from ..search._settings import SearchConfig
from ..search._policies import Decision
from ..search._split import benchmark_sample, house_seeds
from ..search._stepper import ClosedLoopEpisode
from ._features import CANDIDATE_FEATURES, candidate_table, downsample_belief

__all__ = ["HouseEnv", "WORLDS"]

#: Where the episodes happen: generated homes, or the embedded house.
WORLDS = ("generated", "house")


def _positive_int(value, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


def _non_negative(value, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__}")
    if not np.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


class HouseEnv(gymnasium.Env):
    """The closed-loop gas source search in a house as a gymnasium environment (module docstring).

    Parameters
    ----------
    world : {"generated", "house"}, keyword-only
        Generated homes (:func:`psgsl_pgm.sim.generate_house`) or the embedded house.
    split : {"dev", "test"}, keyword-only
        The homes and seeds of the development or the test split (:mod:`psgsl_pgm.search._split`).
    houses : int, keyword-only
        How many generated homes (from ``first_house`` in the development split, the first test homes otherwise).
    seeds : int, keyword-only
        Episode seeds per home (generated) or in the embedded house.
    first_house : int, optional, keyword-only
        The first development home (default 0).
    sources : sequence, keyword-only
        The embedded house's sources (:func:`psgsl_pgm.experiment.parse_source`: an object name or (x, y) m), drawn
        uniformly.
    gases : sequence of str, keyword-only
        Gases a generated home's episode draws from.
    off_rate : float, keyword-only
        Probability of an off-ontology (floor) source in a generated home (:mod:`psgsl_pgm.search._episodes`).
    variant : {"olfaction", "semantics", "semantics+rooms"}, keyword-only
        The robot's posterior.
    estimator : {"infotaxis", "analytic-plume", "particle-filter", "pmfs", "grgsl"}, keyword-only
    search : SearchConfig, optional, keyword-only
        The loop's settings (budget, candidates, declaration rule); ``end`` must be ``"declare"``.
    config : ExperimentConfig, optional, keyword-only
        Physics and estimator settings (a generated home's episode replaces the gas).
    slots : int, keyword-only
        N, the candidate slots (the size of the action space).
    belief_size : int, keyword-only
        S, the side of the downsampled belief.
    time_cost : float, keyword-only
        Reward per second of simulated time, negated (1/s).
    correct_bonus, wrong_penalty : float, keyword-only
        Reward at a right declaration, and its negation at a wrong one.

    Notes
    -----
    The observation space is a ``Dict``:

    ========== ================ =============================================================================
    key        space            what
    ========== ================ =============================================================================
    gas        Box (1,)         the last stop's gas reading (the sensor's output: ppm, or relative conductance)
    hit        Discrete(2)      the robot's hit decision on it
    wind       Box (2,)         the anemometer's reading, m/s, map frame
    pose       Box (4,)         x / map width, y / map height, cos θ, sin θ of the camera heading
    time       Box (1,)         elapsed simulated time / the budget
    belief     Box (S, S)       the variant's posterior as the mass of S × S blocks of the map
    candidates Box (N, 5)       the candidate table: dx, dy, drive (over the map's diagonal), P_f, valid
    ========== ================ =============================================================================

    Everything in it is the robot's: its readings, its believed pose, its beliefs and its map. The info holds
    ``action_mask`` ((N,) bool), ``time`` (s) and the episode's ``house`` and ``seed``; once the episode is over also
    the true ``source``, and at a declaration ``declared_correct`` and ``declared_error`` (m).
    """

    metadata = {"render_modes": []}

    def __init__(self, *, world: str = "generated", split: str = "dev", houses: int = 50, seeds: int = 5,
                 first_house: int | None = None, sources=("oven", "bed"), gases=("smoke",), off_rate: float = 0.1,
                 variant: str = "semantics+rooms", estimator: str = "infotaxis", search: SearchConfig | None = None,
                 config: ExperimentConfig | None = None, slots: int = 32, belief_size: int = 32,
                 time_cost: float = 0.01, correct_bonus: float = 10.0, wrong_penalty: float = 10.0):
        if world not in WORLDS:
            raise ValueError(f"world must be one of {WORLDS}, got {world!r}")
        if variant not in VARIANTS:
            raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")
        if estimator not in ESTIMATORS:
            raise ValueError(f"estimator must be one of {ESTIMATORS}, got {estimator!r}")
        search = SearchConfig() if search is None else search
        if not isinstance(search, SearchConfig):
            raise TypeError(f"search must be a SearchConfig, got {type(search).__name__}")
        if search.end != "declare":
            raise ValueError(f"search.end must be 'declare' (the episode ends at the robot's declaration), "
                             f"got {search.end!r}")
        config = ExperimentConfig() if config is None else config
        if not isinstance(config, ExperimentConfig):
            raise TypeError(f"config must be an ExperimentConfig, got {type(config).__name__}")
        if world == "generated":
            self._houses, self._seeds = (list(r) for r in benchmark_sample(
                split, houses=_positive_int(houses, "houses"), seeds=_positive_int(seeds, "seeds"),
                first_house=first_house))
            self._gases = tuple(gases)
            if not self._gases or not all(isinstance(g, str) for g in self._gases):
                raise ValueError(f"gases must name at least one gas, got {gases!r}")
            self._off_rate = _non_negative(off_rate, "off_rate")
            if self._off_rate > 1:
                raise ValueError(f"off_rate must lie in [0, 1], got {off_rate!r}")
            self._sources = None
        else:
            self._houses = [None]
            self._seeds = list(house_seeds(split, seeds=_positive_int(seeds, "seeds")))
            self._sources = tuple(sources)
            if not self._sources:
                raise ValueError("sources must name at least one source")
        self.world_kind, self.split = world, split
        self.variant, self.estimator, self.search, self.config = variant, estimator, search, config
        self.slots = _positive_int(slots, "slots")
        self.belief_size = _positive_int(belief_size, "belief_size")
        self.time_cost = _non_negative(time_cost, "time_cost")
        self.correct_bonus = _non_negative(correct_bonus, "correct_bonus")
        self.wrong_penalty = _non_negative(wrong_penalty, "wrong_penalty")
        n, s = self.slots, self.belief_size
        inf = np.inf
        self.observation_space = spaces.Dict({
            "gas": spaces.Box(-inf, inf, (1,), np.float32),
            "hit": spaces.Discrete(2),
            "wind": spaces.Box(-inf, inf, (2,), np.float32),
            "pose": spaces.Box(-1.0, 1.0, (4,), np.float32),
            "time": spaces.Box(0.0, inf, (1,), np.float32),
            "belief": spaces.Box(0.0, 1.0, (s, s), np.float32),
            "candidates": spaces.Box(-inf, inf, (n, len(CANDIDATE_FEATURES)), np.float32),
        })
        self.action_space = spaces.Discrete(n)
        self._specs: dict = {}  # generated home -> (world, findable sources)
        self._spaces: dict = {}  # (house, seed) -> FreeSpace of the last episode
        self._episode = None
        self._candidates = None
        self._pending = False

    # --- episodes ---------------------------------------------------------------------------------------------

    def _generated(self, house: int):
        if house not in self._specs:
            from ..search._episodes import findable_sources
            from ..sim._generate import generate_house

            spec = generate_house(int(house)).world(gas=self._gases[0])
            self._specs = {house: (spec, findable_sources(spec, found_radius=self.search.found_radius))}
        return self._specs[house]

    def _draw(self, options: dict) -> dict:
        rng = self.np_random
        unknown = sorted(set(options) - {"house", "seed", "source"})
        if unknown:
            raise ValueError(f"options may hold house, seed and source, got {unknown}")
        house = options.get("house")
        if house is None:
            house = self._houses[int(rng.integers(len(self._houses)))]
        seed = options.get("seed")
        if seed is None:
            seed = self._seeds[int(rng.integers(len(self._seeds)))]
        if self.world_kind == "house":
            source = options.get("source")
            if source is None:
                source = self._sources[int(rng.integers(len(self._sources)))]
            return {"house": None, "seed": int(seed), "source": source, "spec": None, "config": self.config}
        from ..search._episodes import draw_episode
        from ..sim._generate import generate_house

        spec, found = self._generated(int(house))
        ep = draw_episode(spec, int(house), int(seed), gases=self._gases, off_rate=self._off_rate, sources=found)
        if ep["gas"] != spec.gas:
            spec = generate_house(int(house)).world(gas=ep["gas"])
        return {"house": int(house), "seed": int(seed), "source": tuple(ep["xy"]), "spec": spec,
                "config": replace(self.config, gas=ep["gas"])}

    def episode_setting(self, *, house: int | None = None, seed: int, source=None) -> dict:
        """The setting of the episode ``reset(options={"house": house, "seed": seed, "source": source})`` runs, to
        run another policy on it (:func:`psgsl_pgm.search.run_closed_loop`). What is not given (the embedded
        house's source, a generated home) is drawn with the environment's generator.

        Returns
        -------
        dict
            ``{"house", "seed", "source", "world_spec", "config"}``: ``source``, ``seed``, ``config`` and
            ``world_spec`` (None: the embedded house) as :func:`run_closed_loop` takes them.

        Examples
        --------
        >>> env = HouseEnv(world="house", sources=("bed",))
        >>> s = env.episode_setting(seed=3)
        >>> s["source"], s["seed"], s["world_spec"] is None
        ('bed', 3, True)
        """
        options = {k: v for k, v in (("house", house), ("seed", seed), ("source", source)) if v is not None}
        ep = self._draw(options)
        return {"house": ep["house"], "seed": ep["seed"], "source": ep["source"], "world_spec": ep["spec"],
                "config": ep["config"]}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode: draw it (or take the one ``options`` names) and run the first look-around.

        Parameters
        ----------
        seed : int, optional, keyword-only
            Seeds the environment's generator, which draws the episodes (gymnasium's convention: given once,
            then None).
        options : dict, optional, keyword-only
            ``{"house": h, "seed": s}`` (and ``"source"`` in the embedded house) picks that episode instead of
            drawing one.

        Returns
        -------
        observation : dict
            The robot's view after the look-around (the keys of the class's Notes).
        info : dict
            ``action_mask``, ``time`` (s), ``house`` and ``seed``.

        Raises
        ------
        ValueError
            ``options`` holds a key other than ``house``, ``seed`` and ``source``.
        """
        super().reset(seed=seed)
        ep = self._draw(dict(options or {}))
        key = (ep["house"], ep["seed"])  # the house's geometry: FreeSpace shares its caches between runs in it
        self._episode = ClosedLoopEpisode(ep["source"], ep["seed"], None, self.variant, self.estimator,
                                          config=ep["config"], search=self.search, world_spec=ep["spec"],
                                          space=self._spaces.get(key))
        self._spaces = {key: self._episode.space}  # the last episode's: a repeated episode reuses it
        self._label = {"house": ep["house"], "seed": ep["seed"], "source": ep["source"]}
        self._episode.take(self._episode.first_move())
        self._pending = self._episode.done  # ended at the look-around: the first step reports it
        return self._observe(), self._info()

    def step(self, action):
        """Drive to the candidate in slot ``action``, take its readings and frames, and report.

        Parameters
        ----------
        action : int
            A slot of the candidate table, in [0, N); an empty slot a >= K takes the candidate a mod K.

        Returns
        -------
        observation : dict
            The robot's view after the stop.
        reward : float
            −``time_cost`` per simulated second of the step, plus the declaration's bonus or penalty.
        terminated : bool
            The robot declared the source.
        truncated : bool
            The time budget ran out without a declaration.
        info : dict
            ``action_mask``, ``time``, ``house``, ``seed``; at the end also ``source`` and, at a declaration,
            ``declared_correct`` and ``declared_error`` (m).

        Raises
        ------
        TypeError
            ``action`` is not an integer.
        ValueError
            ``action`` is outside [0, N), or no episode is running (call :meth:`reset`).
        """
        if self._episode is None:
            raise ValueError("call reset() before step()")
        if isinstance(action, (bool, np.bool_)) or not isinstance(action, (int, np.integer)) and not (
                isinstance(action, np.ndarray) and action.shape == () and np.issubdtype(action.dtype, np.integer)):
            raise TypeError(f"action must be an integer slot in [0, {self.slots}), got {action!r}")
        a = int(action)
        if not 0 <= a < self.slots:
            raise ValueError(f"action must be a slot in [0, {self.slots}), got {a}")
        ep = self._episode
        if ep.done and not self._pending:
            raise ValueError("the episode has ended: call reset()")
        t_before = ep.time
        if not self._pending:
            cand = self._candidates
            k = a % int(cand.mask.sum())
            cell = int(cand.cells[k])
            path = ep.space.path(cand.pred, cell)
            pts = ep.space.position(path)
            step = pts[-1] - pts[-2] if len(pts) > 1 else np.zeros(2)
            heading = float(np.arctan2(step[1], step[0])) if np.hypot(*step) > 0 else float(ep.heading)
            ep.take(ep.move_to(Decision(cell, (heading,), path, float(cand.drive[k]))))
        self._pending = False
        reward = -self.time_cost * (ep.time - t_before)
        terminated = ep.declaration is not None
        if terminated:
            reward += self.correct_bonus if ep.declaration_outcome()["declared_correct"] else -self.wrong_penalty
        truncated = ep.done and not terminated
        return self._observe(), float(reward), bool(terminated), bool(truncated), self._info()

    # --- what the agent sees --------------------------------------------------------------------------------------

    def _observe(self) -> dict:
        ep = self._episode
        self._candidates = candidate_table(ep.situation(), slots=self.slots)
        space = ep.space
        half = 0.5 * space.resolution
        lo, hi = space.centres.min(axis=0) - half, space.centres.max(axis=0) + half  # the map's corners, m
        xy = (space.position(ep.cell) - lo) / (hi - lo)
        belief = np.clip(downsample_belief(ep.posterior, self.belief_size), 0.0, 1.0)
        return {
            "gas": np.array([ep.reading.value], dtype=np.float32),
            "hit": int(bool(ep.reading.hit)),
            "wind": np.asarray(ep.wind, dtype=np.float32).reshape(2),
            "pose": np.array([np.clip(xy[0], 0, 1), np.clip(xy[1], 0, 1),
                              np.cos(ep.heading), np.sin(ep.heading)], dtype=np.float32),
            "time": np.array([ep.time / ep.budget], dtype=np.float32),
            "belief": belief.astype(np.float32),
            "candidates": self._candidates.table,
        }

    def _info(self) -> dict:
        ep = self._episode
        info = {"action_mask": self._candidates.mask.copy(), "time": float(ep.time), "house": self._label["house"],
                "seed": self._label["seed"]}
        if ep.done:  # the truth, once the episode is over (for the evaluation, never for a decision)
            info["source"] = self._label["source"]
        if ep.declaration is not None:
            out = ep.declaration_outcome()
            info |= {"declared_correct": out["declared_correct"], "declared_error": out["declared_error"]}
        return info

    def episode_run(self):
        """The current episode as a :class:`psgsl_pgm.search.SearchRun` (policy ``"external"``)."""
        if self._episode is None:
            raise ValueError("call reset() first")
        return self._episode.result()
