"""One problem description from which the closed form and both Bayesian networks are built.

The generative model (the paper's Network A, Sec. "Model"; Sec. "Probabilistic Gas Classification"):

* S ~ p(s) over n cells (``source_prior``);
* γ ~ p(γ) over m gases (``gas_prior``), ζ_j | γ ~ p(ζ_j | γ) (``gas_observations``);
* O_c | S = c, γ ~ p(o | s, γ) = L_γ (``source_likelihood``, the ontology), O_c | S ≠ c ~ p(o | ¬s) = β
  (``background``, independent of γ);
* Z_cj | O_c with likelihood vectors p(z_cj | o) (``observation_likelihoods``, cell ``observation_cells``);
* G | S with p(g | S = c) (``olfactory_likelihood``).

Pure numpy (it lives in the core, so a core-only install can build and solve problems in closed form); the
pgmpy networks of ``psgsl_pgm.networks`` are built from it, and ``psgsl_pgm.networks.SemanticGSLProblem``
is this class. Inputs go through the core's validation vocabulary (same types and tolerances as
:func:`psgsl_pgm.semantic_source_probability`).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import logsumexp

from .._shared._validate import as_array, as_float_array, check_nonnegative, check_sums
from .._shared._validate import identifier as check_identifier
from .._shared._validate import index as as_index
from ._beliefs import update_class_probs
from ._fusion import fuse
from ._semantic import semantic_source_probability

__all__ = ["MAX_CELLS", "SemanticGSLProblem"]

#: Largest number of cells n a problem may have: 2 000 000 (a 1414 × 1414 grid). The problem holds (n, k)
#: arrays and n cell names; beyond this size guard, ``cells=10**9`` would run for ever building the names.
#: (The exact networks are far smaller in practice: their inference is exponential in what they couple.)
MAX_CELLS = 2_000_000

def _array(x, name: str, ndim: int | None, *, keep_float32: bool = False) -> np.ndarray:
    """Validated real array (the shared vocabulary's type contract) with ``ndim`` dimensions (any: None), finite and
    non-negative; float64 unless ``keep_float32`` and ``x`` is float32 (so that its sums are judged with
    float32's tolerance)."""
    arr = as_float_array(x, name, ndim=ndim) if keep_float32 else as_float_array(x, name, dtype=np.float64, ndim=ndim)
    if arr.size:
        check_nonnegative(arr, name)
    return arr


def _distribution(x: np.ndarray, name: str) -> np.ndarray:
    """Require rows of ``x`` to sum to 1 within the core's tolerance for its dtype (:data:`SUM_RTOL`: 1e-6
    in float64, 1e-4 in float32) and renormalise them in float64 to round-off."""
    if x.size:
        check_sums(np.sum(x, axis=-1, dtype=np.float64), name, x.dtype)
    x = x.astype(np.float64)
    return x / x.sum(axis=-1, keepdims=True)


def _names(names, count: int, prefix: str, argument: str) -> tuple[str, ...]:
    """Default or validated identifiers, one per item; messages name ``argument`` (and the entry)."""
    if names is None:
        width = len(str(count - 1))
        return tuple(f"{prefix}{i:0{width}d}" for i in range(count))
    if isinstance(names, (str, bytes, dict)) or not hasattr(names, "__iter__"):
        raise TypeError(f"{argument} must be a sequence of {count} names, got {type(names).__name__} {names!r}")
    names = tuple(check_identifier(name, f"{argument}[{i}]") for i, name in enumerate(names))
    if len(names) != count:
        raise ValueError(f"{argument} must have {count} names, got {len(names)}: {names}")
    if len(set(names)) != count:
        raise ValueError(f"{argument} must be unique, got {names}")
    return names


class SemanticGSLProblem:
    """A semantic gas-source-localisation problem: ontology, background, evidence and priors.

    Parameters
    ----------
    source_likelihood : (k,) or (m, k) array_like
        The ontology p(o | s, γ): class distribution of the source cell, one row per gas.
    background : (k,) array_like
        p(o | ¬s), the class distribution of a cell without the source; strictly positive (the closed
        form divides by it). Does not depend on γ.
    cells : int or sequence of str
        The number of cells n, or their names (identifiers; default ``c0 … c{n-1}``, zero-padded).
    observation_cells : (N,) array_like of int, optional
        The cell of each semantic observation (any number per cell, including none).
    observation_likelihoods : (N, k) array_like, optional
        p(z | o) of each observation (a likelihood over classes: camera detection, room evidence, ...).
        Each row must have a positive entry.
    olfactory_likelihood : (n,) array_like, optional
        p(g | S = c), the olfactory evidence; ones (no olfactory information) when omitted.
    source_prior : (n,) array_like, optional
        p(s); uniform when omitted.
    gas_prior : (m,) array_like, optional
        p(γ); uniform when omitted.
    gas_observations : (N_ζ, m) array_like, optional
        p(ζ_j | γ) of each gas-classifier observation.
    class_names, gas_names : sequence of str, optional
        Identifiers of the k classes and the m gases (defaults ``o0 …``, ``gas0 …``).
    shape : tuple of int, optional
        Grid shape of the cells (C order, ``prod(shape) == n``): 2-D cells or 3-D voxels.

    Raises
    ------
    ValueError, TypeError
        Shapes that do not agree, negative/non-finite numbers, distributions that do not sum to 1, a
        non-positive background, an all-zero likelihood, or evidence that has probability zero.

    Examples
    --------
    The paper's kitchen ontology, four cells each seen once by a detector that is right 70 % of the time:

    >>> import numpy as np
    >>> problem = SemanticGSLProblem(
    ...     [0.4, 0.25, 0.3, 0.05], np.full(4, 0.25), cells=4,
    ...     observation_cells=[0, 1, 2, 3],
    ...     observation_likelihoods=np.where(np.eye(4, dtype=bool), 0.7, 0.1),
    ...     class_names=["oven", "microwave", "refrigerator", "countertop"])
    >>> problem.n, problem.k, problem.m
    (4, 4, 1)
    >>> problem.closed_form_posterior().round(6)
    array([0.34, 0.25, 0.28, 0.13])
    """

    def __init__(
        self,
        source_likelihood,
        background,
        *,
        cells,
        observation_cells=(),
        observation_likelihoods=None,
        olfactory_likelihood=None,
        source_prior=None,
        gas_prior=None,
        gas_observations=None,
        class_names=None,
        gas_names=None,
        shape=None,
    ):
        lik = _array(source_likelihood, "source_likelihood", None, keep_float32=True)
        if lik.ndim == 1:
            lik = lik[None, :]
        if lik.ndim != 2 or lik.shape[1] < 2 or lik.shape[0] < 1:
            raise ValueError(
                f"source_likelihood must be (k,) or (m, k) with m >= 1 gases and k >= 2 classes, got shape {lik.shape}"
            )
        self.source_likelihood = _distribution(lik, "source_likelihood")  # p(o | s, γ), (m, k)
        m, k = lik.shape
        beta = _array(background, "background", 1, keep_float32=True)
        if beta.shape != (k,):
            raise ValueError(f"background must have shape ({k},) like the ontology rows, got {beta.shape}")
        if np.any(beta <= 0):
            raise ValueError(f"background p(o | ¬s) must be strictly positive, got {beta}")
        self.background = _distribution(beta, "background")  # β = p(o | ¬s), (k,)

        if isinstance(cells, (int, np.integer)) and not isinstance(cells, bool):
            if not 1 <= cells <= MAX_CELLS:
                shown = cells if abs(cells) < 10**24 else f"an integer of {int(cells).bit_length()} bits"
                raise ValueError(f"cells must be a positive count of at most {MAX_CELLS} (the size guard MAX_CELLS), got {shown}")
            n, cell_names = int(cells), None
        elif isinstance(cells, str):
            raise TypeError(f"cells must be an int or a sequence of names, got the str {cells!r}")
        else:
            if not hasattr(cells, "__len__") or isinstance(cells, (dict, bytes)):
                raise TypeError(f"cells must be an int or a sequence of names, got {type(cells).__name__}")
            if len(cells) > MAX_CELLS:
                raise ValueError(f"cells must name at most {MAX_CELLS} cells (the size guard MAX_CELLS), got {len(cells)}")
            cell_names = tuple(cells)
            n = len(cell_names)
            if n < 1:
                raise ValueError("cells must name at least one cell")
        self.cell_names = _names(cell_names, n, "c", "cells")
        self.class_names = _names(class_names, k, "o", "class_names")
        self.gas_names = _names(gas_names, m, "gas", "gas_names")
        if shape is not None:
            entries = shape.tolist() if isinstance(shape, np.ndarray) and shape.ndim == 1 else shape
            if not isinstance(entries, (tuple, list)) or not all(np.ndim(s) == 0 for s in entries):
                raise TypeError(f"shape must be a tuple of ints, got {type(shape).__name__} {shape!r}")
            shape = tuple(as_index(s, "shape entries", minimum=1) for s in entries)
            if math.prod(shape) != n:  # exact, no int64 overflow
                raise ValueError(f"shape {shape} must have positive sides whose product is the number of cells "
                                 f"(cells gives n = {n})")
        self.shape = shape

        cells_idx = as_array(observation_cells, "observation_cells", "a 1-D integer array")
        if cells_idx.size == 0:
            cells_idx = np.zeros(0, dtype=np.intp)
        if cells_idx.ndim != 1 or not np.issubdtype(cells_idx.dtype, np.integer):
            raise TypeError(f"observation_cells must be a 1-D integer array, got {cells_idx.dtype} {cells_idx.shape}")
        if np.any((cells_idx < 0) | (cells_idx >= n)):
            raise ValueError(f"observation_cells must index the {n} cells (cells gives n = {n}), got values outside "
                             f"[0, {n})")
        obs = np.zeros((0, k)) if observation_likelihoods is None else _array(
            observation_likelihoods, "observation_likelihoods", 2
        )
        if obs.shape[0] != cells_idx.size:
            given = "" if observation_likelihoods is not None else " (observation_likelihoods not given)"
            raise ValueError(
                f"observation_cells and observation_likelihoods must have one entry per observation, got "
                f"{cells_idx.size} observation cell(s) and {obs.shape[0]} likelihood row(s){given}"
            )
        if obs.shape != (cells_idx.size, k):
            raise ValueError(
                f"observation_likelihoods must have shape ({cells_idx.size}, {k}) (one row per observation "
                f"cell, one column per class), got {obs.shape}"
            )
        if obs.size and np.any(obs.max(axis=1) <= 0):
            raise ValueError("observation_likelihoods: every row p(z | o) needs a positive entry; got an all-zero row")
        self.observation_cells = cells_idx.astype(np.intp)
        self.observation_likelihoods = obs
        impossible = np.flatnonzero(~np.isfinite(self.log_class_likelihood().max(axis=1)))
        if impossible.size:
            raise ValueError(
                f"the observations of cell(s) {impossible[:5].tolist()} exclude every class together "
                "(Π_j p(z_cj | o) = 0 for all o): that evidence has probability zero"
            )

        g = np.ones(n) if olfactory_likelihood is None else _array(olfactory_likelihood, "olfactory_likelihood", 1)
        if g.shape != (n,):
            raise ValueError(f"olfactory_likelihood must have shape ({n},), one entry per cell (cells gives n = {n}), "
                             f"got {g.shape}")
        self.olfactory_likelihood = g  # p(g | S = c), (n,)
        prior = np.full(n, 1.0 / n) if source_prior is None else _array(source_prior, "source_prior", 1, keep_float32=True)
        if prior.shape != (n,):
            raise ValueError(f"source_prior must have shape ({n},), one entry per cell (cells gives n = {n}), got "
                             f"{prior.shape}")
        self.source_prior = _distribution(prior, "source_prior")  # π_s, (n,)
        gp = np.full(m, 1.0 / m) if gas_prior is None else _array(gas_prior, "gas_prior", 1, keep_float32=True)
        if gp.shape != (m,):
            raise ValueError(f"gas_prior must have shape ({m},), got {gp.shape}")
        self.gas_prior = _distribution(gp, "gas_prior")  # p(γ), (m,)
        zeta = np.zeros((0, m)) if gas_observations is None else _array(gas_observations, "gas_observations", 2)
        if zeta.shape[1:] != (m,):
            raise ValueError(f"gas_observations must have shape (N_zeta, {m}), got {zeta.shape}")
        if zeta.size and np.any(zeta.max(axis=1) <= 0):
            raise ValueError("gas_observations: every row p(ζ | γ) needs a positive entry; got an all-zero row")
        self.gas_observations = zeta
        if not np.isfinite(logsumexp(self.log_joint_weights())):
            raise ValueError(
                "the evidence has probability zero under this problem: no cell and gas has a positive product of "
                "source_prior, olfactory_likelihood, gas_prior, gas_observations and observation_likelihoods"
            )

    # ------------------------------------------------------------------ sizes
    @property
    def n(self) -> int:
        """Number of cells (states of S)."""
        return len(self.cell_names)

    @property
    def k(self) -> int:
        """Number of object classes."""
        return self.source_likelihood.shape[1]

    @property
    def m(self) -> int:
        """Number of gas types."""
        return self.source_likelihood.shape[0]

    def observations_of(self, cell: int) -> np.ndarray:
        """(N_c, k) likelihood vectors of the observations of cell index ``cell``, in input order."""
        return self.observation_likelihoods[self.observation_cells == cell]

    # ------------------------------------------------------------ evidence terms
    def log_class_likelihood(self) -> np.ndarray:
        """(n, k) log Π_j p(z_cj | o): all observations of each cell combined (zeros → -inf)."""
        logs = np.zeros((self.n, self.k))
        with np.errstate(divide="ignore"):
            np.add.at(logs, self.observation_cells, np.log(self.observation_likelihoods))
        return logs

    def class_likelihood(self) -> np.ndarray:
        """(n, k) Π_j p(z_cj | o) per cell, scaled so each row's maximum is 1 (posteriors are invariant)."""
        logs = self.log_class_likelihood()
        return np.exp(logs - logs.max(axis=1, keepdims=True))  # rows with a positive entry: checked in __init__

    def gas_probs(self) -> np.ndarray:
        """(m,) p(γ | ζ) ∝ p(γ) Π_j p(ζ_j | γ) — the gas classifier's belief."""
        with np.errstate(divide="ignore"):
            logs = np.log(self.gas_prior) + np.log(self.gas_observations).sum(axis=0)
        if not np.isfinite(logs.max()):
            raise ValueError("the gas observations have probability zero under every gas of positive prior")
        return np.exp(logs - logsumexp(logs))

    def olfactory_posterior(self) -> np.ndarray:
        """(n,) p(s | g) ∝ p(s) p(g | s) — what a pure-olfaction method reports."""
        w = self.source_prior * self.olfactory_likelihood
        return w / w.sum()

    def marginal_class_prior(self) -> np.ndarray:
        """(k,) p(o) averaged over cells: (1/n) Σ_γ p(γ) L_γ + (1 − 1/n) β (the paper's p(o_ni)).

        Since Σ_c p(s_c) = 1 this is the cell average of p(o_c) = p(s_c) L̄ + (1 − p(s_c)) β for any
        source prior; it is p(o_c) itself for a uniform prior.
        """
        mean_source = self.gas_prior @ self.source_likelihood  # L̄ = Σ_γ p(γ) L_γ
        return mean_source / self.n + (1.0 - 1.0 / self.n) * self.background

    def log_joint_weights(self) -> np.ndarray:
        """(n, m) log of p(S = c, γ, evidence) up to one constant, computed exactly in log space.

        log p(s_c) + log p(g | c) + log p(γ) + Σ_j log p(ζ_j | γ) + log[Σ_i L_γi Λ_ci / Σ_i β_i Λ_ci],
        where Λ_c = Π_j p(z_cj | o); the dropped constant is Σ_n log Σ_i β_i Λ_ni.
        """
        lam = self.class_likelihood()  # Λ_c scaled to max 1: positive somewhere
        with np.errstate(divide="ignore"):
            log_ratio = np.log(lam @ self.source_likelihood.T) - np.log(lam @ self.background)[:, None]
            log_gas = np.log(self.gas_prior) + np.log(self.gas_observations).sum(axis=0)
            log_cell = np.log(self.source_prior) + np.log(self.olfactory_likelihood)
        return log_cell[:, None] + log_gas[None, :] + log_ratio

    # ------------------------------------------------------------- closed forms
    def class_probs(self, class_prior=None) -> np.ndarray:
        """(n, k) p(o_c | z_c) under ``class_prior`` (default β), by the core's :func:`update_class_probs`."""
        prior = self.background if class_prior is None else np.asarray(class_prior, dtype=np.float64)
        return update_class_probs(np.broadcast_to(prior, (self.n, self.k)), self.class_likelihood())

    def _class_prior(self, class_prior) -> np.ndarray:
        if isinstance(class_prior, str):
            if class_prior == "background":
                return self.background
            if class_prior == "marginal":
                return self.marginal_class_prior()
            raise ValueError(f"class_prior must be 'background', 'marginal' or a (k,) array, got {class_prior!r}")
        rho = _array(class_prior, "class_prior", 1, keep_float32=True)
        if rho.shape != (self.k,):
            raise ValueError(f"class_prior must have shape ({self.k},), got {rho.shape}")
        return _distribution(rho, "class_prior")

    def closed_form_posterior(self, *, class_prior="background") -> np.ndarray:
        """(n,) p(s_c | g, z, ζ) by the paper's closed form, through the core library.

        ``fuse(p(s | g), p(s | z, ζ), prior=p(s))`` (eq. (11)) with
        p(s | z, ζ) = ``semantic_source_probability(q, L, ρ, gas_probs=p(γ | ζ), source_prior=p(s))``
        (eq. (20) and its gas mixture), q = p(o_c | z_c) computed under ρ.

        Parameters
        ----------
        class_prior : {"background", "marginal"} or (k,) array_like, default "background"
            ρ = p(o_ci) of the formula. ``"background"`` (ρ = β) is exact for this model; ``"marginal"``
            (:meth:`marginal_class_prior`) is the paper's approximation p(o_ni | s_c) ≈ p(o_ni).

        Returns
        -------
        posterior : (n,) ndarray
            Over cells in cell order, summing to 1.
        """
        rho = self._class_prior(class_prior)
        semantic = semantic_source_probability(
            self.class_probs(rho),
            self.source_likelihood,
            rho,
            gas_probs=self.gas_probs(),
            source_prior=self.source_prior,
        )  # p(s_c | z, ζ) ∝ p(s_c) Σ_γ p(γ|ζ) Σ_i q_ci/ρ_i L_γi
        return fuse(self.olfactory_posterior(), semantic, prior=self.source_prior)  # ∝ p(s|g) p(s|z) / p(s)

    def closed_form_gas_posterior(self) -> np.ndarray:
        """(m,) p(γ | g, z, ζ) ∝ p(γ | ζ) Σ_c p(s_c) p(g | c) Σ_i q_ci/β_i L_γi, exactly (log space)."""
        logs = logsumexp(self.log_joint_weights(), axis=0)  # marginalise S
        return np.exp(logs - logsumexp(logs))

    # ------------------------------------------------------------ random tests
    @classmethod
    def random(
        cls,
        rng: np.random.Generator,
        n: int,
        k: int,
        m: int = 1,
        *,
        max_observations: int = 3,
        zero_fraction: float = 0.2,
        uniform_prior: bool = False,
        n_gas_observations: int = 2,
        shape=None,
    ) -> SemanticGSLProblem:
        """A random valid problem for tests (seed ``rng``; every draw comes from it).

        Parameters
        ----------
        rng : numpy.random.Generator
        n, k, m : int
            Cells, classes, gases.
        max_observations : int, default 3
            Each cell gets 0 … ``max_observations`` observations.
        zero_fraction : float, default 0.2
            Fraction of zeros put into the ontology rows, the observation likelihoods and the olfactory
            likelihood (never a whole row). The source prior stays positive.
        uniform_prior : bool, default False
            Uniform source prior instead of a random one.
        n_gas_observations : int, default 2
            Number of ζ observations (only when m > 1).
        shape : tuple of int, optional
            Passed through (grid shape of the cells).

        Examples
        --------
        >>> import numpy as np
        >>> p = SemanticGSLProblem.random(np.random.default_rng(0), 6, 3, m=2)
        >>> p.closed_form_posterior().shape
        (6,)
        """
        if not isinstance(rng, np.random.Generator):
            raise TypeError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")

        def sparse(shape_, floor=0.0):
            x = rng.uniform(floor, 1.0, size=shape_)
            x[rng.random(shape_) < zero_fraction] = 0.0
            rows = x.reshape(-1, shape_[-1])
            empty = np.flatnonzero(rows.max(axis=1) <= 0)  # never an all-zero row
            rows[empty, rng.integers(shape_[-1], size=empty.size)] = rng.uniform(0.5, 1.0, size=empty.size)
            return rows.reshape(shape_)

        for _ in range(100):  # redraw (from the same rng) when zeros make the evidence impossible
            lik = sparse((m, k))
            lik /= lik.sum(axis=1, keepdims=True)
            beta = np.maximum(rng.dirichlet(np.ones(k)), 1e-3)
            beta /= beta.sum()
            counts = rng.integers(0, max_observations + 1, size=n)
            obs_cells = np.repeat(np.arange(n), counts)
            obs = sparse((obs_cells.size, k), floor=0.05)
            truth = rng.integers(k, size=n)  # one class every observation of a cell allows: p(z_c) > 0
            obs[np.arange(obs_cells.size), truth[obs_cells]] = rng.uniform(0.5, 1.0, size=obs_cells.size)
            olf = sparse((1, n), floor=0.01)[0]
            prior = np.full(n, 1.0 / n) if uniform_prior else rng.uniform(0.05, 1.0, size=n)
            prior /= prior.sum()
            gas_prior = rng.dirichlet(np.ones(m) * 2.0)
            zeta = rng.uniform(0.05, 1.0, size=(n_gas_observations if m > 1 else 0, m))
            try:
                return cls(
                    lik, beta, cells=n, observation_cells=obs_cells, observation_likelihoods=obs,
                    olfactory_likelihood=olf, source_prior=prior, gas_prior=gas_prior, gas_observations=zeta,
                    shape=shape,
                )
            except ValueError as exc:
                if "probability zero" not in str(exc):
                    raise
        raise ValueError(
            f"could not draw a problem with possible evidence in 100 attempts (zero_fraction={zero_fraction})"
        )

    def __repr__(self) -> str:
        return (
            f"SemanticGSLProblem(n={self.n}, k={self.k}, m={self.m}, "
            f"observations={self.observation_cells.size}, gas_observations={self.gas_observations.shape[0]})"
        )
