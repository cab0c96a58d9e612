"""Regenerate the canonical networks of this directory: XMLBIF, BIF and a PNG drawing of each graph.

Usage (from the repository root)::

    python -m networks.export_networks            # or: python networks/export_networks.py

The text files are what :func:`psgsl_pgm.networks._export.network_text` produces for
:data:`psgsl_pgm.networks._export.CANONICAL`; ``tests/test_networks_export.py`` checks that the committed
files equal a fresh export and load back in pgmpy with the same posteriors. The PNGs are drawn with
networkx + matplotlib (not compared byte-for-byte: renderers differ between versions).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

# Layer (row from the top) of each node kind in the drawings.
_LAYERS = {"gamma": 0, "zeta": 0, "alpha": 0, "C": 1, "G": 2, "S": 3, "O": 4, "Z": 5}
_COLOURS = {"gamma": "#f4a261", "zeta": "#e9c46a", "alpha": "#e76f51", "C": "#bdbdbd", "G": "#90be6d",
            "S": "#4d908e", "O": "#577590", "Z": "#a8dadc"}


def _kind(node: str) -> str:
    for prefix in ("gamma", "zeta", "alpha"):
        if node.startswith(prefix):
            return prefix
    return node.split("_")[0]


def _layout(model, problem) -> dict:
    """Layered positions: cells left to right, node kinds top to bottom, observations fanned below."""
    cells = {c: i for i, c in enumerate(problem.cell_names)}
    spacing = 2.0
    pos = {}
    for node in model.nodes():
        kind = _kind(node)
        y = -_LAYERS[kind]
        parts = node.split("_")
        if kind in ("S", "O", "C") and len(parts) > 1:
            x = cells[parts[1]] * spacing
        elif kind == "G" and len(parts) > 1:  # Network B's G_i: beside S_i, off the S_i → C_i edge
            x, y = cells[parts[1]] * spacing + 0.8, -2.5
        elif kind == "Z":
            x = cells[parts[1]] * spacing + 0.5 * int(parts[2]) - 0.25
            y -= 0.35 * int(parts[2])
        elif kind == "S" or kind == "G":  # Network A's single S and G
            x = (problem.n - 1) * spacing / 2 + (1.5 if kind == "G" else 0.0)
            y = -3 if kind == "S" else -2
        elif kind == "gamma":
            x = -spacing
            y = -2
        elif kind == "zeta":
            x = -spacing + 0.9 * (int(parts[1]) + 1)
            y = -1
        else:  # alpha
            x = problem.n * spacing
            y = -1
        pos[node] = (x, y)
    return pos


def draw(model, problem, path: Path, title: str) -> None:
    """Draw the graph of ``model`` to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import networkx as nx

    graph = nx.DiGraph(model.edges())
    graph.add_nodes_from(model.nodes())
    pos = _layout(model, problem)
    width = max(8.0, 1.3 * problem.n + 3)
    fig, ax = plt.subplots(figsize=(width, 6.5), dpi=100)
    colours = [_COLOURS[_kind(v)] for v in graph.nodes()]
    nx.draw_networkx_edges(graph, pos, ax=ax, arrows=True, arrowsize=10, edge_color="#555555", width=0.8,
                           node_size=900)
    nx.draw_networkx_nodes(graph, pos, ax=ax, node_color=colours, node_size=900, edgecolors="#333333")
    labels = {v: v.replace("_", "\n", 1) for v in graph.nodes()}
    nx.draw_networkx_labels(graph, pos, labels=labels, ax=ax, font_size=6)
    ax.set_title(title, fontsize=10)
    ax.set_axis_off()
    fig.tight_layout()
    fig.savefig(path, metadata={"Software": None})
    plt.close(fig)


def export(directory: Path = HERE, *, drawings: bool = True) -> list[Path]:
    """Write every canonical network to ``directory``; return the written paths."""
    from psgsl_pgm.networks._export import CANONICAL, canonical_network, network_text

    written = []
    for name, (_, _, description) in CANONICAL.items():
        problem, model = canonical_network(name)
        for fmt in ("xmlbif", "bif"):
            path = directory / f"{name}.{fmt}"
            path.write_text(network_text(model, fmt), encoding="utf-8")
            written.append(path)
        if drawings:
            path = directory / f"{name}.png"
            draw(model, problem, path, f"{name}: {description}")
            written.append(path)
    return written


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE, help="output directory (default: networks/)")
    parser.add_argument("--no-drawings", action="store_true", help="skip the PNG drawings")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    for path in export(args.out, drawings=not args.no_drawings):
        print(path)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(HERE.parent))  # run as a file from anywhere: the repository root is importable
    sys.exit(main())
