"""The closed loop's settings (:class:`SearchConfig`) and what one run leaves (:class:`SearchRun`); the loop
itself is :func:`psgsl_pgm.search.run_closed_loop` (:mod:`._loop`, :mod:`._stepper`)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields

import numpy as np

from .._shared._validate import index, one_of, positive, real_pair, unit_interval
from ._policies import check_score

__all__ = ["ENDS", "SearchConfig", "SearchRun"]

#: How a run may end (:class:`SearchConfig` ``end``).
ENDS = ("declare", "reach")


@dataclass(frozen=True)
class SearchConfig:
    """Settings of the closed loop (the physics — speed, turn time, sensors — are the experiment's).

    Parameters
    ----------
    found_radius : float
        m; the source is found when the robot comes this close (the lab's benchmark rule).
    time_budget : float
        s of simulated time.
    horizon : float
        m of geodesic distance within which candidate positions are considered.
    spacing : float
        m, lattice spacing of candidate positions.
    n_headings : int
        Camera headings per candidate position.
    clearance : float
        m, the robot's distance from walls, furniture and windows (the tour's).
    start : (2,) tuple
        Start position, m (the tour's).
    credible : float
        Mass of the declared credible region.
    score : {"per-time", "gain"}
        How ``infotaxis`` and ``space-aware-infotaxis`` score a candidate pose: its gain per second of driving,
        turning and sensing (the default), or its gain alone (:mod:`psgsl_pgm.search._policies`).
    far_spacing : float or None
        m, lattice spacing of the candidate positions beyond ``horizon``, over the whole reachable free space
        (:mod:`psgsl_pgm.search._policies`); None: no candidates beyond the horizon.
    miss_probability : float or None
        In [0, 1): the robot's probability that a move within ``found_radius`` of the source's found region does
        not detect it (:class:`DetectionModel`). None: the robot's estimate counted on reference passes of its
        detector (``psgsl_pgm.experiment._robot_models.robot_source_miss_probability``) with ``end="declare"``, 0 (the
        deterministic rule) with ``end="reach"``.
    end : {"declare", "reach"}
        How a run ends. ``"declare"``: at the robot's first declaration (:mod:`psgsl_pgm.search._declare`),
        right when it lies within ``success_radius`` of the source; passing near the source is evidence, not the
        end. ``"reach"``: when the robot's path first passes within ``found_radius`` of the source and the
        detector fires (the rule of earlier results, kept to reproduce them; no declaration is made).
    declare_mass : float
        κ in (0, 1): the posterior mass within ``declare_radius`` of the most probable hypothesis's found region
        at which the robot declares it.
    declare_radius : float
        m, the reach of the declared region around the declared hypothesis's found region.
    success_radius : float
        m: a declaration is right when it lies this close to the source (to the source object's footprint).
    source_count_prior : (3,) tuple of float or None
        p(N) on N ∈ {1, 2, 3}, the robot's prior over how many sources emit. None (the default): the robot
        believes in one source and the run ends at its first declaration. Given: it declares sources one by one
        — after each declaration the declared region is removed from its hypothesis space — and stops when its
        probability that a further source exists falls below ``more_sources_level`` (or at the budget)
        (:mod:`psgsl_pgm.search._several`). Needs ``end="declare"``.
    more_sources_level : float
        In (0, 1): the robot stops declaring when p(another source | what it saw) falls below this.
    """

    found_radius: float = 0.5
    time_budget: float = 1000.0
    horizon: float = 2.0
    spacing: float = 0.5
    n_headings: int = 8
    clearance: float = 0.25
    start: tuple = (0.8, 6.0)
    credible: float = 0.9
    score: str = "per-time"
    far_spacing: float | None = 1.0
    miss_probability: float | None = None
    end: str = "declare"
    declare_mass: float = 0.9
    declare_radius: float = 0.5
    success_radius: float = 1.0
    source_count_prior: tuple | None = None
    more_sources_level: float = 0.1

    def __post_init__(self):
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "score":
                v = check_score(v)
            elif f.name == "start":
                v = tuple(real_pair(v, "start", "an (x, y)", "metres").tolist())
            elif f.name == "n_headings":
                v = index(v, "n_headings", minimum=1)
            elif f.name == "credible":
                v = unit_interval(v, "credible", low_open=True, high_open=True)
            elif f.name == "miss_probability":
                v = None if v is None else unit_interval(v, "miss_probability", high_open=True)
            elif f.name == "end":
                v = one_of(v, "end", ENDS)
            elif f.name == "declare_mass":
                v = unit_interval(v, "declare_mass", low_open=True, high_open=True)
            elif f.name == "far_spacing" and v is None:
                pass
            elif f.name == "source_count_prior":
                v = None if v is None else _count_prior(v)
            elif f.name == "more_sources_level":
                v = unit_interval(v, "more_sources_level", low_open=True, high_open=True)
            else:
                v = positive(v, f.name, "metres" if f.name != "time_budget" else "seconds")
            object.__setattr__(self, f.name, v)
        if self.source_count_prior is not None and self.end != "declare":
            raise ValueError(f"source_count_prior needs end='declare' (sources are declared one by one), got "
                             f"end={self.end!r}")

    def to_dict(self) -> dict:
        """The settings as JSON types. The default ``score`` is left out (as runs stored before the option
        existed have it); ``far_spacing`` and ``miss_probability`` are always written, so that runs stored
        before the "not found" update and the far candidates — other searches — never resume into a new grid.
        The declaration settings are written with ``end="declare"`` only: a ``"reach"`` run's settings are those
        of runs stored before declarations."""
        d = asdict(self)
        d["start"] = list(self.start)
        if d["score"] == "per-time":
            del d["score"]
        if self.source_count_prior is None:  # a one-source robot: the settings of runs stored before, unchanged
            del d["source_count_prior"], d["more_sources_level"]
        else:
            d["source_count_prior"] = list(self.source_count_prior)
        if self.end == "reach":  # the settings of runs stored before declarations, unchanged
            for k in ("end", "declare_mass", "declare_radius", "success_radius"):
                del d[k]
            d["miss_probability"] = 0.0 if self.miss_probability is None else self.miss_probability
        return d


def _count_prior(v) -> tuple:
    """p(N) on {1, 2, 3} as a checked tuple (ValueError naming ``source_count_prior`` otherwise)."""
    a = np.asarray(v, dtype=np.float64) if not isinstance(v, (str, bytes)) else np.zeros(0)
    if a.shape != (3,) or not np.isfinite(a).all() or (a < 0).any() or abs(a.sum() - 1.0) > 1e-9 or a[0] == 1.0:
        raise ValueError(f"source_count_prior must be p(N) for N = 1, 2, 3: three non-negative numbers summing to "
                         f"1 with some mass on N > 1, got {v!r}")
    return tuple(float(x) for x in a)


@dataclass(frozen=True, eq=False)
class SearchRun:
    """One closed-loop search (step 0 = before the first stop).

    Attributes
    ----------
    source, seed, policy, variant, estimator : identification
    source_xy : (2,) ndarray
        True source position, m.
    found : bool
        Whether the robot's true path passed within ``found_radius`` of the source's found region (with
        ``end="reach"``: and the detector fired — the run's end).
    time_to_find : float
        s of simulated time of that first pass; ``time_budget`` when there was none (``found`` says so).
    geodesic : float
        Geodesic distance from the start to the nearest drivable point within ``found_radius`` of the source, m.
    driven : float
        Path length driven until found (or the budget), m.
    time : (n + 1,) ndarray
        s since the start, at each stop (step 0: 0).
    position : (n + 1, 2) ndarray
        Robot position at each stop (step 0: the start).
    heading : (n + 1,) ndarray
        Camera heading of the stop's last frame, rad.
    hit : (n + 1,) ndarray of bool
    path_length : (n + 1,) ndarray
        m driven up to each stop.
    error, map_error, spread : (n + 1,) ndarray
        ‖E[s] − s‖, ‖s_MAP − s‖ and √E‖s − E[s]‖² of the variant's posterior, m.
    region_area : (n + 1,) ndarray
        Area of the credible region (smallest set of cells holding ``credible`` of the mass), m².
    region_hit : (n + 1,) ndarray of bool
        Whether that region contains the true source's cell.
    hpd_level : (n + 1,) ndarray
        HPD level of the true source's cell (:func:`psgsl_pgm.search.hpd_level`): the posterior mass of every cell
        at least as probable as it.
    path : (p, 2) ndarray
        Every cell centre driven through, m (for drawing).
    final_posterior : (H, W) ndarray of float32
    config : dict
        ``{"experiment": ExperimentConfig dict, "search": SearchConfig dict}``.
    declared : bool
        Whether the robot declared a source within the budget (``end="declare"``).
    declared_xy : (2,) ndarray
        The declared point, m (NaN without a declaration).
    time_to_declare : float
        s of simulated time of the declaration (NaN without one).
    declared_error : float
        m, distance from the declared point to the source (its object's footprint); NaN without a declaration.
    declared_correct : bool
        Whether the declaration lies within ``success_radius`` of the source.
    declared_mass : float
        The posterior mass M that backed the declaration (:mod:`psgsl_pgm.search._declare`); NaN without one.
    gas : str
        The episode's true gas when the robot was not told it (``gas: unknown``); "" otherwise.
    gas_names : tuple of str
        The gases of the robot's belief p(γ | ζ_1:t), in the order of ``gas_probs``'s columns; () when told.
    gas_probs : (n + 1, m) ndarray
        p(γ | ζ_1:t) at each stop (step 0: the uniform prior); (0, 0) when the gas was told.
    sources_xy : (N, 2) ndarray
        Every true source, m, in an episode with several (the first is ``source_xy``); (0, 2) for one source.
    declarations : (k, 4) ndarray
        Every declaration of a robot that declares sources one by one (``source_count_prior``): rows (x m, y m,
        time s, mass M); (0, 4) otherwise (its one declaration is in ``declared_*``).
    declared_source : (k,) ndarray of int
        The true source each declaration names (index into ``sources_xy``, each source matched at most once, in
        declaration order, within ``success_radius``), −1 for a false declaration.
    more_probability : (n + 1,) ndarray
        p(another source | what the robot saw) at each stop (NaN before the first declaration); empty for a
        one-source robot.
    """

    source: str
    seed: int
    policy: str
    variant: str
    estimator: str
    source_xy: np.ndarray
    found: bool
    time_to_find: float
    geodesic: float
    driven: float
    time: np.ndarray
    position: np.ndarray
    heading: np.ndarray
    hit: np.ndarray
    path_length: np.ndarray
    error: np.ndarray
    map_error: np.ndarray
    spread: np.ndarray
    region_area: np.ndarray
    region_hit: np.ndarray
    path: np.ndarray
    final_posterior: np.ndarray
    config: dict = field(default_factory=dict)
    hpd_level: np.ndarray = field(default_factory=lambda: np.zeros(0))
    declared: bool = False
    declared_xy: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    time_to_declare: float = float("nan")
    declared_error: float = float("nan")
    declared_correct: bool = False
    declared_mass: float = float("nan")
    gas: str = ""
    gas_names: tuple = ()
    gas_probs: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    sources_xy: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    declarations: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    declared_source: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    more_probability: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def several(self) -> bool:
        """Whether the run has several sources or a robot that declares them one by one."""
        return bool(len(self.sources_xy) or len(self.more_probability))

    @property
    def n_sources(self) -> int:
        """How many sources emitted."""
        return max(len(self.sources_xy), 1)

    def source_times(self) -> tuple[np.ndarray, np.ndarray]:
        """((N,) s until each source was rightly declared or the budget, (N,) bool whether it was): the event
        times of the per-source survival statistics, censored at the budget."""
        budget = float(self.config["search"]["time_budget"])
        t, ok = np.full(self.n_sources, budget), np.zeros(self.n_sources, bool)
        if len(self.declarations):
            for (_, _, when, _), j in zip(self.declarations, self.declared_source):
                if j >= 0 and when <= budget:
                    t[j], ok[j] = when, True
        elif self.declared_correct:  # a one-source robot: its one declaration names the first source
            t[0], ok[0] = float(self.time_to_declare), True
        return t, ok

    def time_to_all(self) -> tuple[float, bool]:
        """(s until every source was rightly declared — the last of them —, whether all were); the budget when
        not all were (censored)."""
        t, ok = self.source_times()
        return (float(t.max()), True) if ok.all() else (float(self.config["search"]["time_budget"]), False)

    @property
    def n_false_declarations(self) -> int:
        """Declarations that named no source (or one already declared)."""
        if len(self.declarations):
            return int((self.declared_source < 0).sum())
        return int(self.false_declaration)

    @property
    def gas_unknown(self) -> bool:
        """Whether the robot searched without being told the gas."""
        return bool(self.gas_names)

    @property
    def gas_identified(self) -> bool:
        """Whether the most probable gas at the run's end is the true one, alone (a tie — e.g. the uniform prior of a
        run that ended before any classified reading — is not an identification); False when the gas was told."""
        if not self.gas_unknown:
            return False
        p = self.gas_probs[-1]
        i = self.gas_names.index(self.gas)
        return bool(p[i] > np.max(np.delete(p, i), initial=-np.inf))

    def time_to_gas(self, level: float = 0.9) -> tuple[float, bool]:
        """(s until p(true γ | ζ_1:t) first reached ``level``, whether it did): the first such stop's time, or the
        time budget without one — also for a run that ended (declared) before: it never names the gas (censored
        at the budget). A run whose gas was told has no such time: ValueError."""
        if not self.gas_unknown:
            raise ValueError("time_to_gas needs a run whose gas the robot was not told (gas: unknown)")
        p_true = self.gas_probs[:, self.gas_names.index(self.gas)]
        reached = np.flatnonzero(p_true >= level)
        budget = float(self.config["search"]["time_budget"])
        if reached.size == 0 or self.time[reached[0]] > budget:
            return budget, False
        return float(self.time[reached[0]]), True

    @property
    def n_steps(self) -> int:
        return len(self.time) - 1

    @property
    def end(self) -> str:
        """How the run ended (:class:`SearchConfig` ``end``; runs stored before declarations: ``"reach"``)."""
        return str(self.config.get("search", {}).get("end", "reach"))

    @property
    def succeeded(self) -> bool:
        """The run's success: a right declaration (``end="declare"``), or the find (``end="reach"``)."""
        return bool(self.declared_correct) if self.end == "declare" else bool(self.found)

    @property
    def time_to_success(self) -> float:
        """s until the success (:attr:`succeeded`), or the time budget without one: the event time of the
        survival statistics, censored at the budget."""
        if self.end == "reach":
            return float(self.time_to_find)
        budget = float(self.config["search"]["time_budget"])
        return float(self.time_to_declare) if self.declared_correct else budget

    @property
    def false_declaration(self) -> bool:
        """Whether the run ended in a wrong declaration."""
        return bool(self.declared and not self.declared_correct)

    @property
    def path_ratio(self) -> float:
        """Path length driven until found (or the budget) / geodesic distance from the start to the source."""
        return float(self.driven / self.geodesic) if self.geodesic > 0 else float("nan")
