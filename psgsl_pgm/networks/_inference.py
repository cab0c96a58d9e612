"""Exact queries on Networks A and B with pgmpy's VariableElimination (its contraction, or fixed orders)."""

from __future__ import annotations

import numpy as np
from pgmpy.inference import VariableElimination
from pgmpy.models import DiscreteBayesianNetwork

from ..core._problem import SemanticGSLProblem
from ._names import (
    ALPHA,
    ALPHA_STATES,
    EVIDENCE_STATES,
    GAMMA,
    OBSERVED,
    SOURCE,
    SOURCE_STATES,
    counter_node,
    object_node,
    source_node,
)
from ._underflow import check_result, check_scale

__all__ = [
    "exact_gas_posterior",
    "exact_information_gain",
    "exact_source_posterior",
    "network_evidence",
    "network_kind",
]


def network_evidence(model: DiscreteBayesianNetwork) -> dict[str, str]:
    """The evidence of a built (or loaded) network: every evidence node ``observed``, α ``true``.

    Evidence nodes are recognised by their states ``("observed", "other")`` (Z, G, G_i, ζ).

    Parameters
    ----------
    model : pgmpy.models.DiscreteBayesianNetwork
        Network A or B (:func:`build_network_a`, :func:`build_network_b`, or read back from XMLBIF/BIF).

    Returns
    -------
    evidence : dict of str to str
        Node name → observed state, sorted by node name; what pgmpy's queries take as ``evidence``.

    Raises
    ------
    ValueError
        A node of ``model`` has no CPD (pgmpy's ``get_cpds`` raises).

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.networks import SemanticGSLProblem, build_network_b
    >>> p = SemanticGSLProblem([0.7, 0.3], [0.5, 0.5], cells=2, observation_cells=[1],
    ...                        observation_likelihoods=[[1.0, 0.2]])
    >>> network_evidence(build_network_b(p))
    {'G_c0': 'observed', 'G_c1': 'observed', 'Z_c1_0': 'observed', 'alpha': 'true'}
    """
    evidence = {}
    for node in sorted(model.nodes()):
        states = tuple(model.get_cpds(node).state_names[node])
        if states == EVIDENCE_STATES:
            evidence[node] = OBSERVED
        elif node == ALPHA:
            evidence[node] = ALPHA_STATES[1]
    return evidence


def network_kind(model: DiscreteBayesianNetwork) -> str:
    """Which of the paper's networks ``model`` is.

    Parameters
    ----------
    model : pgmpy.models.DiscreteBayesianNetwork
        A network built by :func:`build_network_a` or :func:`build_network_b` (or read back from a file).

    Returns
    -------
    kind : {"A", "B-chain", "B-table"}
        ``"A"`` (a node S), ``"B-chain"`` (α with one counter parent) or ``"B-table"`` (α over all S_i).

    Raises
    ------
    TypeError
        ``model`` is not a pgmpy ``DiscreteBayesianNetwork``.
    ValueError
        It has neither a node ``S`` nor a node ``alpha``.

    Examples
    --------
    >>> from psgsl_pgm.networks import build_network_b, canonical_network, network_kind
    >>> problem, model = canonical_network("kitchen_a")
    >>> network_kind(model), network_kind(build_network_b(problem, "chain")), network_kind(build_network_b(problem, "table"))
    ('A', 'B-chain', 'B-table')
    """
    if not isinstance(model, DiscreteBayesianNetwork):
        raise TypeError(f"model must be a pgmpy DiscreteBayesianNetwork, got {type(model).__name__}")
    nodes = set(model.nodes())
    if SOURCE in nodes:
        return "A"
    if ALPHA in nodes:
        parents = model.get_parents(ALPHA)
        return "B-chain" if len(parents) == 1 and parents[0].startswith("C_") else "B-table"
    raise ValueError("model is neither Network A (no node 'S') nor Network B (no node 'alpha')")


def _check_pair(model, problem) -> str:
    if not isinstance(problem, SemanticGSLProblem):
        raise TypeError(f"problem must be a SemanticGSLProblem, got {type(problem).__name__}")
    kind = network_kind(model)
    expected = {SOURCE} if kind == "A" else {source_node(c) for c in problem.cell_names}
    cells = set(model.get_cpds(SOURCE).state_names[SOURCE]) if kind == "A" else set(model.nodes()) & expected
    if kind == "A" and cells != set(problem.cell_names) or kind != "A" and cells != expected:
        raise ValueError(f"model and problem disagree on the cells (network {kind}, problem n = {problem.n})")
    return kind


def _query(infer: VariableElimination, variables, evidence, order, what: str):
    """One VariableElimination query; floating-point warnings are replaced by :func:`check_result`."""
    order = order if isinstance(order, str) else list(order)
    with np.errstate(invalid="ignore", divide="ignore", under="ignore"):
        factor = infer.query(list(variables), evidence=evidence, elimination_order=order, joint=True,
                             show_progress=False)
    check_result(factor.values, what)
    return factor


def _object_nodes(problem, exclude=()) -> list[str]:
    return [object_node(c) for c in problem.cell_names if c not in exclude]


def _chain_order(problem, t: int) -> list[str]:
    """Elimination order for S_t in Network B (chain): forward and backward messages along the counters.

    O_i first (each leaves a factor on S_i [, γ]); then S_1, then (S_i, C_{i−1}) for i < t; then (S_i, C_i)
    from the last cell down to t + 1; then C_{t−1}, C_t; then γ. No factor ever has more than C_{i−1}, C_i,
    S_i and γ in scope.
    """
    cells = problem.cell_names
    s = [source_node(c) for c in cells]
    c = [counter_node(x) for x in cells]
    n = len(cells)
    order = _object_nodes(problem)
    if t > 0:
        order.append(s[0])
        for i in range(1, t):
            order += [s[i], c[i - 1]]
    for i in range(n - 1, t, -1):
        order += [s[i], c[i]]
    if t > 0:
        order.append(c[t - 1])
    order.append(c[t])
    if problem.m > 1:
        order.append(GAMMA)
    return order


def _states(factor, variable) -> list:
    return list(factor.state_names[variable])


def _aligned(factor, variables) -> np.ndarray:
    """The factor's values with axes in ``variables`` order."""
    return np.transpose(factor.values, [factor.variables.index(v) for v in variables])


def exact_source_posterior(
    model: DiscreteBayesianNetwork, problem: SemanticGSLProblem, *, elimination_order: str = "auto"
) -> np.ndarray:
    """p(s_c | all evidence) by exact variable elimination in pgmpy, over cells in cell order.

    Network A: one query of S. Network B: one query per S_i (its marginal p(S_i = yes | evidence, α));
    never a joint over all S_i.

    Parameters
    ----------
    model : pgmpy.models.DiscreteBayesianNetwork
        Built by :func:`build_network_a` / :func:`build_network_b` from ``problem`` (or loaded from their
        exported files).
    problem : SemanticGSLProblem
    elimination_order : {"auto", "fixed", "greedy"}, default "auto"
        ``"greedy"``: pgmpy 1.1's default — one tensor contraction of the pruned network (opt_einsum, greedy
        path). ``"fixed"``: classic variable elimination with orders computed here — all O_c first, then
        (Network B, chain) forward and backward messages along the counters, so no factor holds more than
        C_{i−1}, C_i, S_i, γ; for the table encoding O_c then S_i (each step touches the 2^n-entry α
        factor). ``"auto"`` = ``"greedy"``: measured faster in every case of ``benchmarks/bench_networks.py``
        (pgmpy's per-query network pruning dominates either way; the list path also re-checks the pruned
        model and multiplies pgmpy factors in Python). Both give the same posterior to round-off.

    Returns
    -------
    posterior : (n,) ndarray

    Raises
    ------
    ValueError
        When the evidence probability of the network is below the float64 normal range (the query would
        return NaN or lose precision), or the query returns NaN.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.networks import SemanticGSLProblem, build_network_a, build_network_b
    >>> p = SemanticGSLProblem.random(np.random.default_rng(1), 5, 3)
    >>> a = exact_source_posterior(build_network_a(p), p)
    >>> b = exact_source_posterior(build_network_b(p), p)
    >>> bool(np.allclose(a, b, rtol=1e-12, atol=0)), bool(np.allclose(a, p.closed_form_posterior(), rtol=1e-10))
    (True, True)
    """
    kind = _check_pair(model, problem)
    if elimination_order not in ("auto", "fixed", "greedy"):
        raise ValueError(f"elimination_order must be 'auto', 'fixed' or 'greedy', got {elimination_order!r}")
    greedy = elimination_order != "fixed"
    check_scale(problem, kind[0])
    infer = VariableElimination(model)
    evidence = network_evidence(model)
    if kind == "A":
        order = "greedy" if greedy else _object_nodes(problem) + ([GAMMA] if problem.m > 1 else [])
        factor = _query(infer, [SOURCE], evidence, order, "S")
        index = {cell: i for i, cell in enumerate(_states(factor, SOURCE))}
        return factor.values[[index[c] for c in problem.cell_names]]
    posterior = np.empty(problem.n)
    for t, cell in enumerate(problem.cell_names):  # one query per target S_t
        s_t = source_node(cell)
        if greedy:
            order = "greedy"
        elif kind == "B-chain":
            order = _chain_order(problem, t)
        else:
            order = _object_nodes(problem) + [source_node(c) for c in problem.cell_names if c != cell]
            order += [GAMMA] if problem.m > 1 else []
        factor = _query(infer, [s_t], evidence, order, s_t)
        posterior[t] = factor.values[_states(factor, s_t).index(SOURCE_STATES[1])]  # p(S_t = yes | ...)
    return posterior


def exact_gas_posterior(model: DiscreteBayesianNetwork, problem: SemanticGSLProblem) -> np.ndarray:
    """p(γ | all evidence) by exact inference in pgmpy (Network A or B; pgmpy's contraction), in gas order.

    For a single-gas problem this is ``array([1.0])``.

    Parameters
    ----------
    model : pgmpy.models.DiscreteBayesianNetwork
        Network A or B built from ``problem`` (:func:`build_network_a`, :func:`build_network_b`), or loaded from a
        file written from it.
    problem : SemanticGSLProblem
        The problem the network was built from: it names the cells and the gases (the order of the result).

    Returns
    -------
    posterior : (m,) ndarray of float64
        p(γ | z, g, ζ) for the problem's m gases, summing to 1.

    Raises
    ------
    TypeError
        ``model`` is not a pgmpy ``DiscreteBayesianNetwork`` or ``problem`` not a :class:`SemanticGSLProblem`.
    ValueError
        ``model`` is neither Network A nor B, the two disagree on the cells, or the evidence is so improbable that
        exact inference would underflow float64 (use the problem's closed form then).

    Examples
    --------
    >>> from psgsl_pgm.networks import build_network_a, canonical_network, exact_gas_posterior
    >>> problem, model = canonical_network("gas_type_a")
    >>> bool(abs(exact_gas_posterior(model, problem) - problem.closed_form_gas_posterior()).max() < 1e-10)
    True
    """
    kind = _check_pair(model, problem)
    if problem.m == 1:
        return np.ones(1)
    check_scale(problem, kind[0])
    infer = VariableElimination(model)
    factor = _query(infer, [GAMMA], network_evidence(model), "greedy", GAMMA)
    index = {gas: i for i, gas in enumerate(_states(factor, GAMMA))}
    return factor.values[[index[g] for g in problem.gas_names]]


def _mutual_information(joint: np.ndarray) -> float:
    """I(X; Y) in nats of a joint table p(x, y) (normalised), 0 log 0 = 0."""
    px = joint.sum(axis=1, keepdims=True)
    py = joint.sum(axis=0, keepdims=True)
    positive = joint > 0
    ratio = np.where(positive, joint, 1.0) / np.where(positive, px * py, 1.0)
    mi = float(np.sum(joint * np.log(ratio)))  # Σ p(s,o) log p(s,o)/(p(s)p(o)) = H(S) − H(S | O_n)
    return max(mi, 0.0)  # I ≥ 0; a negative value is round-off of order eps (terms cancel when I = 0)


def exact_information_gain(model: DiscreteBayesianNetwork, problem: SemanticGSLProblem, *, cells=None) -> np.ndarray:
    """I(S; O_n | evidence) in nats, from the exact joint p(S, O_n | evidence) of Network A (pgmpy).

    I(S; O_n) = H(S) − Σ_i p(o_ni | ev) H(S | o_ni, ev) (Sec. "Information Gain Optimization"), with every
    entropy taken under the exact posterior given all evidence (z, g, ζ).

    Parameters
    ----------
    model : pgmpy.models.DiscreteBayesianNetwork
        Network A (the joint over S needs the single source variable).
    problem : SemanticGSLProblem
    cells : sequence of int, optional
        Cell indices n to evaluate; all cells when omitted.

    Returns
    -------
    information_gain : (len(cells),) ndarray

    Raises
    ------
    TypeError
        ``model`` and ``problem`` are not a network of this package and its problem.
    ValueError
        ``model`` is Network B (no joint over S), its likelihoods fall outside pgmpy's float64 range
        (:func:`check_scale`), or ``cells`` are not indices of the problem's cells.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.networks import SemanticGSLProblem, build_network_a, exact_information_gain
    >>> problem = SemanticGSLProblem.random(np.random.default_rng(0), 4, 3)
    >>> gain = exact_information_gain(build_network_a(problem), problem, cells=[0, 1])
    >>> gain.shape, bool((gain >= 0).all())
    ((2,), True)
    """
    kind = _check_pair(model, problem)
    if kind != "A":
        raise ValueError(f"exact_information_gain needs Network A (a joint over S), got Network {kind}")
    check_scale(problem, "A")
    idx = np.arange(problem.n) if cells is None else np.asarray(cells, dtype=np.intp).reshape(-1)
    if idx.size and (idx.min() < 0 or idx.max() >= problem.n):
        raise ValueError(f"cells must index the {problem.n} cells, got {idx.tolist()}")
    infer = VariableElimination(model)
    evidence = network_evidence(model)
    gains = np.empty(idx.size)
    for out, c in enumerate(idx):  # one joint query (S, O_c) per cell
        o_node = object_node(problem.cell_names[c])
        factor = _query(infer, [SOURCE, o_node], evidence, "greedy", f"(S, {o_node})")
        joint = _aligned(factor, [SOURCE, o_node])
        gains[out] = _mutual_information(joint / joint.sum())
    return gains
