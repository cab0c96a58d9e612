"""Calibration of the olfactory estimators on runs that the evaluation never sees.

A calibration run is the fixed exploration tour in a house whose source is known (seeds 1000+, sources other
than the evaluated ones). From its readings alone — gas hits and the anemometer, never the simulated wind
field — :func:`calibrate` fits

* the plume parameters (D, τ, κ) by maximum likelihood of the hit model
  (:func:`~psgsl_pgm.olfaction.fit_plume_parameters`), each run's plume solved with the mean wind the robot
  estimated from that run's anemometer readings (:class:`psgsl_pgm.olfaction.MeanWindEstimator`, all of its readings);
* the tempering β of :class:`psgsl_pgm.olfaction.GridInfotaxis` from the lag-1 autocorrelation of the hit
  model's Pearson residuals along each run at the fitted parameters (:func:`psgsl_pgm.olfaction.ar1_tempering`:
  β = n_eff / n = (1 − ρ̂)/(1 + ρ̂));
* the exponent λ of the analytic-plume estimator's PMFS-family score (:class:`psgsl_pgm.olfaction.PMFSEstimator`,
  a pseudo-likelihood without
  a reading-level model whose residuals could be used), by the log score of the known sources
  (:func:`pmfs_tempering`);
* the population weights of the plume-parameter grid that :class:`psgsl_pgm.olfaction.GridInfotaxis`
  marginalises over (:func:`parameter_grid_weights`): θ = (D, τ, κ) is a run-level unknown, and its
  distribution over runs is what the weights estimate, so they are fitted on more runs
  (:data:`GRID_CALIBRATION_RUNS`: the runs above, the same sources on eight more seeds, and four runs with
  floor sources in the hallway — whose fast, channelled flow keeps plumes narrower than in the rooms; the
  point estimate on rooms alone put D three times too high there).

The values stored as :class:`ExperimentConfig` defaults are this fit's, rounded to three significant digits;
``benchmarks/calibrate_olfaction.py`` re-makes it and a slow test re-derives them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..olfaction import (
    CalibrationRun,
    hit_log_likelihood,
    mixture_weights,
    MeanWindEstimator,
    PlumeFit,
    PlumeModel,
    PMFSEstimator,
    ar1_tempering,
    fit_plume_parameters,
    hit_residuals,
    profile_log_likelihood,
    score_tempering,
)
from ..sim import default_world
from ._config import ExperimentConfig, parse_source
from ._robot_models import wind_basis
from ._run import walk
from ._tour import exploration_tour

__all__ = ["CALIBRATION_RUNS", "CHECKPOINTS", "COVERAGE_RUNS", "TUNING_SEEDS", "Calibration", "CoverageTempering",
           "GRID_AXES", "GRID_CALIBRATION_RUNS", "calibrate", "calibrate_encounter_scale", "calibration_runs",
           "coverage_tempering", "coverage_threshold", "coverage_thresholds", "parameter_grid_weights",
           "pmfs_tempering", "tempered_posterior"]

#: (seed, source) of the calibration runs: seeds and sources disjoint from the evaluation's (oven, bed, the floor
#: point 5.0,6.0; seeds 0–999); two floor points in the bedrooms, where the dead-end rooms are.
CALIBRATION_RUNS = ((1000, "toilet"), (1001, "couch"), (1002, "tv"), (1003, "refrigerator"), (1004, "sink"),
                    (1005, "dining table"), (1006, "2.0,10.0"), (1007, "8.5,8.5"))

#: (seed, source) of the runs whose plume parameters give the grid's population weights: CALIBRATION_RUNS, its
#: sources again on seeds 1008–1015, and floor points in the hallway (away from the evaluated 5.0,6.0).
GRID_CALIBRATION_RUNS = CALIBRATION_RUNS + tuple((seed + 8, src) for seed, src in CALIBRATION_RUNS) + (
    (1016, "2.5,6.0"), (1017, "7.5,6.0"), (1018, "2.5,6.0"), (1019, "7.5,6.0"))

#: Seeds of the evaluated sources used for tuning (never for reported results).
TUNING_SEEDS = tuple(range(200, 220))

#: (seed, source) of a wider set of runs on which the tempering can be chosen for coverage
#: (``calibrate(coverage_runs=COVERAGE_RUNS)``): the calibration runs, and the evaluated sources on the tuning
#: seeds — the oven's stagnant corner and the bedroom's pooled gas, which no calibration source shows, are where
#: a steady plume is most wrong.
COVERAGE_RUNS = GRID_CALIBRATION_RUNS + tuple((seed, src) for src in ("oven", "bed", "5.0,6.0")
                                              for seed in TUNING_SEEDS)

#: The plume-parameter grid of :func:`parameter_grid_weights`: D (m²/s) a factor ≈ 3 either side of the
#: maximum-likelihood 0.0131, τ at its 284 s (the likelihood is flat in τ by comparison), κ (m²/s) halved and
#: doubled around 0.821 (κ costs no plume solve).
GRID_AXES = {"diffusivity": (0.004, 0.0131, 0.04), "lifetime": (284.0,), "encounter_scale": (0.4105, 0.821, 1.642)}


@dataclass(frozen=True)
class Calibration:
    """The fitted hit model: ``plume`` (D, τ, κ, log-likelihood), the residuals' pooled lag-1 autocorrelation
    ``rho`` and the tempering ``tempering`` = (1 − ρ)/(1 + ρ), the analytic-plume score exponent
    ``pmfs_tempering``, the
    number of readings ``n``, ``parameter_grid``, the rows (D, τ, κ, weight) of the grid Infotaxis
    marginalises over (None when not fitted), and ``coverage`` / ``pmfs_coverage``, the
    :class:`CoverageTempering` of Infotaxis (single fit) and the analytic-plume estimator on the calibration runs
    (None when not fitted)."""

    plume: PlumeFit
    rho: float
    tempering: float
    pmfs_tempering: float
    n: int
    parameter_grid: tuple | None = None
    coverage: "CoverageTempering | None" = None
    pmfs_coverage: "CoverageTempering | None" = None


def calibration_runs(runs=CALIBRATION_RUNS, *, config: ExperimentConfig | None = None) -> list:
    """The :class:`psgsl_pgm.olfaction.CalibrationRun` of each (seed, source) calibration run.

    Each run holds the tour's readings and a plume model carrying the mean wind estimated from that run's own
    anemometer readings. The runs are made in the embedded house of ``config.world_model`` (the ideal world by
    default), the hits decided as the robot decides them there (:func:`psgsl_pgm.experiment._run.walk`). A run
    walks the whole exploration tour without the camera: a few seconds each.

    Parameters
    ----------
    runs : sequence of (int, str or (float, float)), default CALIBRATION_RUNS
        (seed, source) pairs: the house's seed and a source (an object class, or ``"x,y"`` in metres; see
        :func:`parse_source`). The default, :data:`CALIBRATION_RUNS`, are seeds and sources the evaluation never
        uses.
    config : ExperimentConfig, optional, keyword-only
        The robot's settings (warm-up, world model, sensors); the defaults when None.

    Returns
    -------
    runs : list of psgsl_pgm.olfaction.CalibrationRun
        One per (seed, source), in the order given.

    Raises
    ------
    ValueError
        ``runs`` is empty, or a source names no object of the house or lies off its map.

    Examples
    --------
    A run walks the whole tour (seconds), so ``calibration_runs([(1000, "toilet")])`` is not run here; it gives one
    :class:`psgsl_pgm.olfaction.CalibrationRun` of 195 readings. A source the house lacks is refused before any
    run:

    >>> from psgsl_pgm.experiment import calibration_runs
    >>> try:
    ...     calibration_runs([(1000, "piano")])
    ... except ValueError as err:
    ...     print("piano" in str(err))
    True
    """
    config = ExperimentConfig() if config is None else config
    runs = list(runs)
    if not runs:
        raise ValueError("runs must name at least one (seed, source) calibration run")
    out = []
    for seed, source in runs:
        # made in the world the robot will search (its sensors, its wind)
        world = default_world().make_world(int(seed), parse_source(source), warm_up=config.warm_up,
                                           model=config.world_model)
        house = world.house
        wind = MeanWindEstimator(wind_basis(house), house.grid)
        positions, hits, winds = [], [], []
        for _, stop, reading, w, _ in walk(world, exploration_tour(house), config, camera=False):
            wind.add(stop, w)
            positions.append(stop)
            hits.append(reading.hit)
            winds.append(w)
        model = PlumeModel.from_grid_map(house.grid, wind.field(), outlets=house.outlet, cache_size=0)
        out.append(CalibrationRun(model, tuple(world.source), np.array(positions), np.array(hits), np.array(winds)))
    return out


def calibrate(runs=CALIBRATION_RUNS, *, config: ExperimentConfig | None = None, grid_runs=GRID_CALIBRATION_RUNS,
              coverage_runs=GRID_CALIBRATION_RUNS, **fit_options) -> Calibration:
    """Fit (D, τ, κ), the tempering and the grid's weights on calibration runs (module docstring).

    Parameters
    ----------
    runs : sequence of (int, str or (2,) array_like)
        (seed, source) pairs (default :data:`CALIBRATION_RUNS`).
    config : ExperimentConfig, optional, keyword-only
        ε, warm-up, robot timing and the world model the runs are made in; its plume parameters and tempering are
        ignored.
    grid_runs : sequence of (int, str or (2,) array_like), or None, keyword-only
        The runs of :func:`parameter_grid_weights` (default :data:`GRID_CALIBRATION_RUNS`); ``None`` skips it.
    coverage_runs : sequence of (int, str or (2,) array_like), or None, keyword-only
        The runs on which both estimators' tempering is chosen for coverage (:func:`coverage_tempering`;
        default :data:`GRID_CALIBRATION_RUNS`, sources never evaluated; :data:`COVERAGE_RUNS` adds the evaluated
        sources on the tuning seeds); ``None`` skips it.
    **fit_options
        Passed to :func:`psgsl_pgm.olfaction.fit_plume_parameters` (grids, ``refine``).

    Returns
    -------
    Calibration

    Examples
    --------
    The default call walks 20 calibration tours in the simulator and fits on them (minutes); the numbers it gives
    are in ``ExperimentConfig``'s defaults, and ``docs/guide/field-methods.md`` says how each was found. The fit
    it runs on the readings, shown on hand-made residuals, is :func:`psgsl_pgm.olfaction.ar1_tempering`'s:

    >>> from psgsl_pgm.experiment import CALIBRATION_RUNS
    >>> from psgsl_pgm.olfaction import ar1_tempering
    >>> CALIBRATION_RUNS[0]                                    # (seed, source) of the first calibration run
    (1000, 'toilet')
    >>> rho, beta = ar1_tempering([[1.0, 1.0, -1.0, -1.0, 1.0, 1.0, -1.0, -1.0]])
    >>> round(beta, 3)                                         # the tempering of correlated readings
    0.778
    """
    config = ExperimentConfig() if config is None else config
    data = calibration_runs(runs, config=config)
    fit = fit_plume_parameters(data, false_hit_rate=config.false_hit_rate, **fit_options)
    rho, beta = ar1_tempering(hit_residuals(data, fit, false_hit_rate=config.false_hit_rate))
    known = dict(zip(((int(s), str(src)) for s, src in runs), data))

    def runs_of(pairs):  # each (seed, source) walked once
        todo = [(int(s), str(src)) for s, src in pairs if (int(s), str(src)) not in known]
        known.update(zip(todo, calibration_runs(todo, config=config) if todo else []))
        return [known[(int(s), str(src))] for s, src in pairs]

    grid = None
    if grid_runs is not None:
        grid = parameter_grid_weights(runs_of(grid_runs), tempering=beta, false_hit_rate=config.false_hit_rate)
    cover = {}
    if coverage_runs is not None:
        runs_c = runs_of(coverage_runs)
        labels = np.repeat(np.arange(len(runs_c)), len(CHECKPOINTS))
        for name in ("infotaxis", "analytic-plume"):
            th = coverage_thresholds(runs_c, fit, name, false_hit_rate=config.false_hit_rate)
            cover[name] = coverage_tempering(th.ravel(), labels)
    return Calibration(fit, rho, beta, pmfs_tempering(data, fit), int(sum(len(r.hits) for r in data)), grid,
                       cover.get("infotaxis"), cover.get("analytic-plume"))


def parameter_grid_weights(data, *, tempering: float, false_hit_rate: float, axes=None, drop: float = 1e-3) -> tuple:
    """The rows (D, τ, κ, π) of the plume-parameter grid of :class:`psgsl_pgm.olfaction.GridInfotaxis`.

    For every run r and grid point θ_j, ℓ_rj = Σ_n log P_θj(g_n | s_r) at the run's known source (its plume
    with its own estimated wind); π maximises Σ_r log Σ_j π_j exp(β ℓ_rj)
    (:func:`psgsl_pgm.olfaction.mixture_weights`, β the tempering the estimator uses). Grid points below
    ``drop`` are left out (each distinct (D, τ) costs the estimator a plume solve per reading) and the rest
    renormalised.

    Parameters
    ----------
    data : sequence of CalibrationRun
    tempering : float, keyword-only
        β.
    false_hit_rate : float, keyword-only
        ε.
    axes : dict, optional, keyword-only
        ``{"diffusivity", "lifetime", "encounter_scale"}`` value tuples (default :data:`GRID_AXES`).
    drop : float, keyword-only
        Weights below it are dropped.

    Returns
    -------
    tuple of (D, τ, κ, weight)

    Raises
    ------
    ValueError
        ``data`` is empty, or :func:`psgsl_pgm.olfaction.mixture_weights` refuses the log-likelihoods (a run that
        no grid point explains) or ``tempering``.

    Examples
    --------
    One calibration run in a corridor (the source at its west end, the wind blowing east) and a grid of two
    diffusivities; the run's hits near the source and misses far from it leave the larger one a weight below
    ``drop``, so only the smaller one is kept:

    >>> import numpy as np
    >>> from psgsl_pgm.experiment import parameter_grid_weights
    >>> from psgsl_pgm.olfaction import CalibrationRun, PlumeModel
    >>> model = PlumeModel(np.zeros((3, 40), bool), resolution=0.25, wind=np.tile([0.2, 0.0], (3, 40, 1)),
    ...                    diffusivity=0.01, lifetime=30.0)
    >>> x = np.arange(0.6, 10.0, 0.5)
    >>> run = CalibrationRun(model, (0.4, 0.4), np.c_[x, np.full(x.size, 0.4)], x < 4.0)
    >>> rows = parameter_grid_weights([run], tempering=0.5, false_hit_rate=0.01,
    ...                               axes={"diffusivity": (0.01, 0.1), "lifetime": (30.0,), "encounter_scale": (0.2,)})
    >>> [(d, round(w, 3)) for d, _, _, w in rows]
    [(0.01, 1.0)]
    """
    axes = GRID_AXES if axes is None else axes
    data = list(data)
    if not data:
        raise ValueError("data must hold at least one calibration run")
    points = [(d, t, k) for d in axes["diffusivity"] for t in axes["lifetime"] for k in axes["encounter_scale"]]
    ell = np.empty((len(data), len(points)))
    for i, run in enumerate(data):
        for d in axes["diffusivity"]:
            for t in axes["lifetime"]:
                c = run.predicted(d, t)  # G(x_n | s_r): one factorisation and one forward solve
                for j, (dj, tj, kj) in enumerate(points):
                    if (dj, tj) == (d, t):
                        ell[i, j] = hit_log_likelihood(c, run.hits, kj, false_hit_rate)
    w = mixture_weights(ell, tempering=tempering)
    keep = w >= drop
    w = w[keep] / w[keep].sum()
    return tuple((float(d), float(t), float(k), float(v)) for (d, t, k), v in zip(np.array(points)[keep], w))


def _fitted_model(run: CalibrationRun, diffusivity: float, lifetime: float, encounter_scale: float) -> PlumeModel:
    """The run's plume (its estimated wind) with the given (D, τ, κ)."""
    m = run.model
    return PlumeModel(m.geometry.occupancy, resolution=m.geometry.resolution, origin=m.geometry.origin, wind=m.wind,
                      outlets=m.outlets, diffusivity=diffusivity, lifetime=lifetime, encounter_scale=encounter_scale)


def calibrate_encounter_scale(runs=CALIBRATION_RUNS, *, config: ExperimentConfig | None = None) -> float:
    """Maximum-likelihood κ alone, at the D and τ of ``config``, pooled over calibration runs.

    With c_k = G(x_k | s_true) from each run's plume (its wind estimated from its own anemometer readings), κ
    maximises Π_k P(g_k | κ c_k), P(hit) = ε + (1 − ε)(1 − exp(−κ c))
    (:func:`~psgsl_pgm.olfaction.profile_log_likelihood`). :func:`calibrate` fits (D, τ, κ) jointly; this is its
    profile in κ at fixed (D, τ).

    Parameters
    ----------
    runs : sequence of (int, str or (float, float)), default CALIBRATION_RUNS
        (seed, source) calibration runs, as :func:`calibration_runs` takes them.
    config : ExperimentConfig, optional, keyword-only
        Supplies D (``diffusivity``), τ (``lifetime``) and ε (``false_hit_rate``); the defaults when None.

    Returns
    -------
    kappa : float
        m²/s.

    Raises
    ------
    ValueError
        ``runs`` is empty or names a source the house lacks, or the pooled readings hold no hit (or no miss) where
        the plume predicts gas, so that κ̂ would be 0 (or infinite).

    Examples
    --------
    The default calibration runs take about a minute on one core, so the call is not run here. On the runs it
    makes, it profiles κ out of the likelihood at ``config``'s D and τ, as here on one hand-made corridor run:

    >>> import numpy as np
    >>> from psgsl_pgm.olfaction import CalibrationRun, PlumeModel, profile_log_likelihood
    >>> model = PlumeModel(np.zeros((3, 40), bool), resolution=0.25, wind=np.tile([0.2, 0.0], (3, 40, 1)),
    ...                    diffusivity=0.01, lifetime=30.0)
    >>> x = np.arange(0.6, 10.0, 0.5)
    >>> run = CalibrationRun(model, (0.4, 0.4), np.c_[x, np.full(x.size, 0.4)], x < 4.0)
    >>> kappa, _ = profile_log_likelihood([run], 0.01, 30.0, false_hit_rate=0.01)
    >>> bool(kappa > 0)
    True
    """
    config = ExperimentConfig() if config is None else config
    data = calibration_runs(runs, config=config)
    kappa, _ = profile_log_likelihood(data, config.diffusivity, config.lifetime, false_hit_rate=config.false_hit_rate)
    return kappa


def pmfs_tempering(data, fit: PlumeFit) -> float:
    """The analytic-plume score exponent λ (:class:`psgsl_pgm.olfaction.PMFSEstimator` ``tempering``, estimator
    ``analytic-plume``) that maximises the
    log posterior of the known source at ¼, ½, ¾ and the end of every calibration run
    (:func:`psgsl_pgm.olfaction.score_tempering`); the plume with the fitted (D, τ, κ) and each run's estimated
    wind, a uniform prior over the free cells."""
    scores, priors, truth = [], [], []
    for run in data:
        model = _fitted_model(run, fit.diffusivity, fit.lifetime, fit.encounter_scale)
        est = PMFSEstimator.from_model(model)
        r, c = model.cell_of(run.source)
        n = len(run.hits)
        keep = {int(round(f * n)) for f in (0.25, 0.5, 0.75, 1.0)}
        for j in range(n):
            est.update(run.positions[j], bool(run.hits[j]), None if run.winds is None else run.winds[j])
            if j + 1 in keep:
                scores.append(est.score.ravel())
                priors.append(est._log_prior)
                truth.append(r * model.shape[1] + c)
    return score_tempering(scores, priors, truth)


def tempered_posterior(log_prior, log_likelihoods, tempering: float, *, weights=None) -> np.ndarray:
    """p(s | g) ∝ p(s) Σ_j π_j exp(β L_j(s)) from untempered accumulated log-likelihoods L_j (flat, in log space).

    The posterior of :class:`psgsl_pgm.olfaction.GridInfotaxis` (L_j = Σ_k log P_θj(g_k | s), one row per
    component of its ``parameter_grid``, one row without) and of :class:`psgsl_pgm.olfaction.PMFSEstimator`
    (one row, L = the analytic-plume score S(s), β = λ) at any tempering.

    Parameters
    ----------
    log_prior : (N,) array_like of float
        log p(s), −inf off the support.
    log_likelihoods : (J, N) or (N,) array_like of float
        L_j(s), untempered.
    tempering : float
        β > 0.
    weights : (J,) array_like of float, optional, keyword-only
        π_j ≥ 0 (normalised here); default: equal.

    Returns
    -------
    (N,) ndarray of float64
        Sums to 1; 0 off the support.

    Raises
    ------
    ValueError
        ``log_likelihoods`` is not (J, N) with ``log_prior``'s N, ``tempering`` is not positive, or ``weights`` are
        not J non-negative values with a positive sum.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.experiment import tempered_posterior
    >>> log_prior = np.log([0.5, 0.5, 1e-300])                 # the third cell is all but ruled out
    >>> tempered_posterior(log_prior, [0.0, -2.0, 0.0], 0.5).round(4)     # β = 1/2: exp(-1) against 1
    array([0.7311, 0.2689, 0.    ])
    """
    from scipy.special import logsumexp

    lp = np.asarray(log_prior, dtype=np.float64).ravel()
    ell = np.asarray(log_likelihoods, dtype=np.float64)
    ell = ell.reshape(1, -1) if ell.ndim == 1 else ell
    if ell.ndim != 2 or ell.shape[1] != lp.size:
        raise ValueError(f"log_likelihoods must be (J, N) with N = {lp.size} like log_prior, got shape {ell.shape}")
    if not tempering > 0:
        raise ValueError(f"tempering must be positive, got {tempering!r}")
    w = np.full(ell.shape[0], 1.0) if weights is None else np.asarray(weights, dtype=np.float64).ravel()
    if w.shape != (ell.shape[0],) or (w < 0).any() or not w.sum() > 0:
        raise ValueError(f"weights must be {ell.shape[0]} non-negative values with a positive sum, got {weights!r}")
    with np.errstate(divide="ignore"):
        a = tempering * ell
        a = a[0] if ell.shape[0] == 1 else logsumexp(np.log(w / w.sum())[:, None] + a, axis=0)
        a = lp + a
    a -= logsumexp(a)
    return np.exp(a)


def coverage_threshold(log_prior, log_likelihoods, true_cell: int, *, level: float = 0.9, weights=None,
                       bounds=(1e-4, 10.0), iterations: int = 60) -> float:
    """β* of one calibration posterior: its ``level`` credible region holds the true cell for β below β*, not above.

    For one component and a prior uniform on its support, the cells more probable than the true cell t are
    {c : L(c) > L(t)} whatever β, and the posterior mass of that upper set of L grows with β
    (d/dβ E_β[1{L > L(t)}] = Cov_β(1{L > L(t)}, L) ≥ 0): the region
    (:func:`~psgsl_pgm.experiment._metrics.credible_region`) holds t exactly for β below one threshold, found by
    bisection on log β. With several components (a ``parameter_grid``) or a non-uniform prior the indicator is
    not proved monotone; the bisection then finds one crossing, and :func:`coverage_tempering` reports the
    coverage actually reached.

    Parameters
    ----------
    log_prior : (N,) array_like of float
        log p(s) over the N candidate cells (−inf off the support).
    log_likelihoods : (N,) or (J, N) array_like of float
        The accumulated log-likelihood L(s) of the readings, one row per component θ_j of a parameter grid.
    true_cell : int
        The flat index of the known source's cell.
    level : float, default 0.9, keyword-only
        The credible level of the region, in (0, 1).
    weights : (J,) array_like of float, optional, keyword-only
        The components' prior weights π_j (a mixture posterior ∝ p(s) Σ_j π_j exp(β L_j(s))); one component when
        None.
    bounds : (float, float), default (1e-4, 10.0), keyword-only
        The interval of β searched, both > 0.
    iterations : int, default 60, keyword-only
        Bisection steps on log β (60 halve the log-interval to far below float64's resolution).

    Returns
    -------
    float
        β* in [bounds[0], bounds[1]]: ``bounds[0]`` when t is outside the region already there, ``bounds[1]``
        when it is still inside there.

    Raises
    ------
    ValueError
        ``level`` outside (0, 1), or the arrays do not make a posterior (shapes that disagree, no finite
        log-prior, weights that do not match the rows).

    Examples
    --------
    Three cells, a flat prior, the readings favouring cell 0 while the source is in cell 1: the 90 % region holds
    cell 1 for β up to about 1.15 (untempered, β = 1, it still does; at β = 2 cell 0 alone holds 90 %).

    >>> import numpy as np
    >>> from psgsl_pgm.experiment import coverage_threshold
    >>> round(coverage_threshold(np.zeros(3), np.array([0.0, -2.0, -4.0]), 1), 3)
    1.147
    """
    from ._metrics import credible_region

    def covered(beta):
        return bool(credible_region(tempered_posterior(log_prior, log_likelihoods, beta, weights=weights),
                                    level).ravel()[true_cell])

    lo, hi = (float(np.log(b)) for b in bounds)
    if covered(np.exp(hi)):
        return float(bounds[1])
    if not covered(np.exp(lo)):
        return float(bounds[0])
    for _ in range(int(iterations)):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if covered(np.exp(mid)) else (lo, mid)
    return float(np.exp(0.5 * (lo + hi)))


@dataclass(frozen=True)
class CoverageTempering:
    """The tempering chosen for coverage: ``tempering`` (β̂), the per-item thresholds ``thresholds`` (β*_i) and
    their run labels ``groups``, the calibration coverage reached at β̂ ``coverage``, and ``interval``, the
    5–95 % bootstrap interval of β̂ over runs."""

    tempering: float
    thresholds: np.ndarray
    groups: np.ndarray
    coverage: float
    interval: tuple


def coverage_tempering(thresholds, groups, *, target: float = 0.9, n_boot: int = 2000,
                       seed: int = 0) -> CoverageTempering:
    """The learning rate (tempering) of a generalised posterior chosen so that its credible regions reach their
    nominal coverage on calibration runs with known sources (Syring & Martin 2019, Biometrika 106, 479).

    A posterior built on a misspecified model (a steady plume for a gas that meanders, eddies and pools) is
    over-confident however its readings' correlation is accounted for: the AR(1) rule of
    :func:`psgsl_pgm.olfaction.ar1_tempering` corrects the *variance* of an otherwise correct likelihood, not its
    bias. Syring & Martin choose the learning rate so that the generalised posterior's credible region has its
    nominal frequentist coverage, estimating coverage by bootstrap; with calibration runs whose source is known,
    coverage can be counted directly. Each calibration posterior i (a run at ¼, ½, ¾ and the end of its tour) has
    a threshold β*_i (:func:`coverage_threshold`): its region holds the source for β < β*_i. The coverage
    at β is the fraction of β*_i above β — a step function falling in β — so the largest β with coverage ≥
    ``target`` is the k-th largest threshold, k = ⌈target · n⌉; β̂ is the geometric midpoint of the k-th and
    (k+1)-th largest (coverage exactly k/n there).

    The estimate's own uncertainty: β̂ is an empirical quantile of correlated thresholds (four per run), so its
    spread is estimated by resampling *runs* (``groups``) with replacement (seeded); the 5–95 % interval is
    reported, not used: β̂ aims at the middle of the acceptable band of coverage rather than at an edge.

    Parameters
    ----------
    thresholds : (n,) array_like of float
        β*_i > 0.
    groups : (n,) array_like
        The run of each threshold (bootstrap unit).
    target : float, keyword-only
        Nominal coverage in (0, 1).
    n_boot : int, keyword-only
    seed : int, keyword-only

    Returns
    -------
    CoverageTempering

    Raises
    ------
    ValueError
        Fewer than 2 thresholds, a threshold that is not positive and finite, ``groups`` of another length, or
        ``target`` outside (0, 1).

    Examples
    --------
    Five calibration posteriors, one per run: the largest tempering that keeps 4 of their 5 regions on the source
    lies between the 4th and the 5th largest threshold:

    >>> from psgsl_pgm.experiment import coverage_tempering
    >>> fit = coverage_tempering([0.5, 1.0, 2.0, 4.0, 8.0], [0, 1, 2, 3, 4], target=0.8, n_boot=200)
    >>> round(fit.tempering, 4), fit.coverage
    (0.7071, 0.8)
    """
    b = np.asarray(thresholds, dtype=np.float64).ravel()
    g = np.asarray(groups).ravel()
    if b.size < 2 or g.shape != b.shape or not (np.isfinite(b).all() and (b > 0).all()):
        raise ValueError(f"thresholds must be at least 2 positive finite values with one group each, got {b.size} "
                         f"thresholds and {g.size} groups")
    if not 0 < target < 1:
        raise ValueError(f"target must lie in (0, 1), got {target!r}")

    def pick(x):
        s = np.sort(x)[::-1]
        k = min(int(np.ceil(target * s.size - 1e-12)), s.size - 1)
        return float(np.sqrt(s[k - 1] * s[k])) if k >= 1 else float(s[0])

    beta = pick(b)
    labels = np.unique(g)
    members = [np.flatnonzero(g == u) for u in labels]
    rng = np.random.default_rng(seed)
    boot = [pick(b[np.concatenate([members[i] for i in rng.integers(0, len(labels), len(labels))])])
            for _ in range(int(n_boot))]
    lo, hi = np.quantile(boot, [0.05, 0.95])
    return CoverageTempering(beta, b, g, float((b > beta).mean()), (float(lo), float(hi)))


#: Fractions of a calibration run's readings at which its posterior is scored (as the experiment's coverage).
CHECKPOINTS = (0.25, 0.5, 0.75, 1.0)


def coverage_thresholds(data, fit: PlumeFit, estimator: str, *, false_hit_rate: float = 0.01, level: float = 0.9,
                        parameter_grid=None) -> np.ndarray:
    """The thresholds β*_ri (:func:`coverage_threshold`) of each calibration run's posterior at ¼, ½, ¾ and the end.

    The checkpoints are ``CHECKPOINTS`` of this module. The estimator is replayed untempered on each run's readings
    (its plume with the fitted (D, τ, κ) and the run's estimated wind, a uniform prior over the free cells, as
    :func:`pmfs_tempering`): for ``"infotaxis"`` :class:`psgsl_pgm.olfaction.GridInfotaxis` with β = 1, whose
    accumulated log-likelihood is then L_j(s) = Σ_k log P_θj(g_k | s) per component (``parameter_grid``: rows
    (D, τ, κ, weight); None: the fit), for ``"analytic-plume"`` :class:`psgsl_pgm.olfaction.PMFSEstimator`'s
    untempered score S(s).

    The wind is the run's estimate from *all* of its readings (hindsight) and the prior covers every free cell;
    the experiment's estimator starts from a few anemometer readings and the source region's prior, so its early
    posteriors are wronger and its thresholds at ¼ and ½ lower (on run (1000, toilet): 0.15 and 0.16 against
    ≥ 10 here). ``benchmarks/calibration_record.py`` records the experiment's own per-step code for
    ``benchmarks/calibration_coverage.py``, which chooses the tempering from those records.

    Parameters
    ----------
    data : sequence of psgsl_pgm.olfaction.CalibrationRun
        The calibration runs (:func:`calibration_runs`).
    fit : psgsl_pgm.olfaction.PlumeFit
        The fitted plume parameters (D, τ, κ, δ).
    estimator : {"infotaxis", "analytic-plume"}
        Whose posterior is replayed.
    false_hit_rate : float, default 0.01, keyword-only
        ε in [0, 1) of the Infotaxis hit model.
    level : float, default 0.9, keyword-only
        The credible level, in (0, 1).
    parameter_grid : (J, 4) array_like of float, optional, keyword-only
        Rows (D, τ, κ, weight) of the Infotaxis mixture; the single fit when None (ignored for
        ``"analytic-plume"``).

    Returns
    -------
    thresholds : (len(data), 4) ndarray of float64
        β*, one row per run, one column per checkpoint.

    Raises
    ------
    ValueError
        ``estimator`` is neither ``"infotaxis"`` nor ``"analytic-plume"``, or ``fit``, ``false_hit_rate``,
        ``level`` or ``parameter_grid`` is out of range (the estimators check them).

    Examples
    --------
    On the default calibration runs (:func:`calibration_runs`) the runs take seconds each; here one hand-made
    corridor run (the source at its west end, the wind blowing east, readings near it hit):

    >>> import numpy as np
    >>> from psgsl_pgm.experiment import coverage_thresholds
    >>> from psgsl_pgm.olfaction import CalibrationRun, PlumeFit, PlumeModel
    >>> model = PlumeModel(np.zeros((3, 40), bool), resolution=0.25, wind=np.tile([0.2, 0.0], (3, 40, 1)),
    ...                    diffusivity=0.01, lifetime=30.0)
    >>> x = np.arange(0.6, 10.0, 0.5)
    >>> run = CalibrationRun(model, (0.4, 0.4), np.c_[x, np.full(x.size, 0.4)], x < 4.0)
    >>> coverage_thresholds([run], PlumeFit(0.01, 30.0, 0.2, 0.0), "infotaxis").round(2)
    array([[ 9.29, 10.  , 10.  , 10.  ]])
    """
    from ..olfaction import GridInfotaxis

    if estimator not in ("infotaxis", "analytic-plume"):
        raise ValueError(f"estimator must be 'infotaxis' or 'analytic-plume', got {estimator!r}")
    out = []
    for run in data:
        model = _fitted_model(run, fit.diffusivity, fit.lifetime, fit.encounter_scale)
        if estimator == "infotaxis":
            est = GridInfotaxis.from_model(model, tempering=1.0, false_hit_rate=false_hit_rate,
                                           missed_hit_rate=fit.missed_hit_rate,
                                           parameter_grid=parameter_grid)
            weights = None if parameter_grid is None else est.parameter_grid[:, 3]
        else:
            est = PMFSEstimator.from_model(model, tempering=1.0)
            weights = None
        r, c = model.cell_of(run.source)
        n = len(run.hits)
        keep = [int(round(f * n)) for f in CHECKPOINTS]
        row = []
        for j in range(n):
            est.update(run.positions[j], bool(run.hits[j]), None if run.winds is None else run.winds[j])
            for _ in range(keep.count(j + 1)):
                ell = est._loglik.copy() if estimator == "infotaxis" else est.score.ravel()
                row.append(coverage_threshold(est._log_prior, ell, r * model.shape[1] + c, level=level,
                                              weights=weights))
        out.append(row)
    return np.array(out, dtype=np.float64)
