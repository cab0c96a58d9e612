"""The one drawer of the paper's Bayesian networks (Fig. ``Bayes_net``): layered, with networkx + matplotlib.

Used by the notebooks (``psgsl_pgm.teaching.draw_network`` is :func:`draw_network`) and by
:func:`psgsl_pgm.networks.export` for the PNGs under ``networks/``. matplotlib and networkx are imported on
call.
"""

from __future__ import annotations

__all__ = ["draw_network", "network_layout"]

#: Fill colour of each node kind (S: source, O: object class, Z: semantic observation, G: olfaction,
#: C: counter of the exactly-one chain, alpha: the constraint α, gamma: gas type γ, zeta: classifier ζ).
KIND_COLOURS = {
    "S": "#4d908e", "O": "#577590", "Z": "#a8dadc", "G": "#90be6d", "C": "#bdbdbd",
    "alpha": "#e76f51", "gamma": "#f4a261", "zeta": "#e9c46a",
}


#: Legend text of each node kind.
KIND_NAMES = {
    "S": "S / S_i: source", "O": "O_c: object class", "Z": "Z_c_j: semantic observation", "G": "G / G_i: olfaction",
    "C": "C_i: exactly-one counter", "alpha": "α: constraint", "gamma": "γ: gas type", "zeta": "ζ_j: gas classifier",
}


def _kind(node: str) -> str:
    for prefix in ("alpha", "gamma", "zeta"):
        if node.startswith(prefix):
            return prefix
    kind = node.split("_", 1)[0]
    if kind not in KIND_COLOURS:
        raise ValueError(f"node {node!r} is not a node of psgsl_pgm.networks (expected S, O_, Z_, G, C_, alpha, "
                         "gamma, zeta_ names)")
    return kind


def network_layout(model) -> dict:
    """Positions {node: (x, y)}: one column per cell, node kinds in rows (γ, ζ, α, C above; Z below).

    Parameters
    ----------
    model : pgmpy.models.DiscreteBayesianNetwork
        Built by ``psgsl_pgm.networks.build_network_a`` or ``build_network_b``.

    Returns
    -------
    dict of str to (float, float)
    """
    nodes = list(model.nodes())
    cells = [v[2:] for v in nodes if v.startswith("O_")]  # networks add O_c in cell order
    column = {c: float(i) for i, c in enumerate(cells)}
    middle = (len(cells) - 1) / 2
    n_obs = {c: sum(1 for v in nodes if v.startswith(f"Z_{c}_")) for c in cells}
    pos = {}
    for v in nodes:
        kind = _kind(v)
        if kind == "S":
            pos[v] = (middle, 0.0) if v == "S" else (column[v[2:]], 0.0)
        elif kind == "G":  # Network B's G_i hangs below-right of S_i, off the S_i → α / C_i edges going up
            pos[v] = (middle + 0.8, 0.9) if v == "G" else (column[v[2:]] + 0.45, -0.5)
        elif kind == "O":
            pos[v] = (column[v[2:]], -1.0)
        elif kind == "Z":
            cell, j = v[2:].rsplit("_", 1)
            pos[v] = (column[cell] + 0.3 * (int(j) - (n_obs[cell] - 1) / 2), -2.0 - 0.15 * int(j))
        elif kind == "C":
            pos[v] = (column[v[2:]] + 0.5, 1.2)
        elif kind == "alpha":
            pos[v] = (len(cells) - 0.2, 2.0)
        elif kind == "gamma":
            pos[v] = (-1.2, -0.3)
        else:  # zeta_j
            pos[v] = (-1.2 + 0.5 * int(v.split("_")[1]), 1.0)
    return pos


def draw_network(model, *, ax=None, title=None, node_size=700, font_size=7, legend=True):
    """Draw a network of ``psgsl_pgm.networks`` as a layered directed graph.

    Observed (evidence) nodes — Z, G, G_i, ζ, and α = true in Network B (``network_evidence``) — get a thick
    black border; a legend names the node kinds and says which are observed.

    Parameters
    ----------
    model : pgmpy.models.DiscreteBayesianNetwork
        Network A or B (any constraint encoding), with or without γ/ζ.
    ax : matplotlib Axes, optional, keyword-only
        Drawn into; a new figure otherwise.
    title : str, optional, keyword-only
    node_size, font_size : int, keyword-only
    legend : bool, default True, keyword-only

    Returns
    -------
    matplotlib Axes

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.networks import SemanticGSLProblem, build_network_a
    >>> from psgsl_pgm.teaching import draw_network
    >>> model = build_network_a(SemanticGSLProblem([0.7, 0.3], [0.5, 0.5], cells=2))
    >>> ax = draw_network(model, title="Network A")
    >>> len(ax.collections) >= 1                       # the nodes were drawn
    True
    """
    import matplotlib.pyplot as plt
    import networkx as nx
    from matplotlib.lines import Line2D

    from ._inference import network_evidence

    pos = network_layout(model)
    graph = nx.DiGraph()
    graph.add_nodes_from(model.nodes())
    graph.add_edges_from(model.edges())
    observed = set(network_evidence(model))
    if ax is None:
        n_cols = max(x for x, _ in pos.values()) - min(x for x, _ in pos.values()) + 1
        _, ax = plt.subplots(figsize=(max(5.0, 1.1 * n_cols + 3.0), 4.5))
    nodes = list(graph.nodes())
    colours = [KIND_COLOURS[_kind(v)] for v in nodes]
    nx.draw_networkx_edges(graph, pos, ax=ax, arrows=True, arrowsize=10, edge_color="#555555", width=0.8,
                           node_size=node_size)
    nx.draw_networkx_nodes(graph, pos, ax=ax, nodelist=nodes, node_color=colours, node_size=node_size,
                           edgecolors=["black" if v in observed else "#777777" for v in nodes],
                           linewidths=[2.5 if v in observed else 0.8 for v in nodes])
    nx.draw_networkx_labels(graph, pos, labels={v: v.replace("_", "\n", 1) for v in nodes}, ax=ax,
                            font_size=font_size)
    if legend:
        kinds = sorted({_kind(v) for v in nodes}, key=list(KIND_COLOURS).index)
        handles = [Line2D([], [], ls="", marker="o", ms=9, mfc=KIND_COLOURS[k], mec="#777777",
                          label=KIND_NAMES[k]) for k in kinds]
        handles.append(Line2D([], [], ls="", marker="o", ms=9, mfc="white", mec="black", mew=2.5,
                              label="thick border: observed (evidence)"))
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=7, frameon=False)
    if title is not None:
        ax.set_title(title)
    ax.set_axis_off()
    return ax
