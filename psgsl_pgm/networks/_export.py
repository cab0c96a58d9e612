"""The canonical networks as XMLBIF / BIF text and PNG drawings: :func:`export` writes the files of ``networks/``."""

from __future__ import annotations

import io
import os
import tempfile
from pathlib import Path

from pgmpy.readwrite import BIFWriter, XMLBIFWriter

from ._canonical import gas_type_problem, grid_problem, kitchen_problem
from ._draw import draw_network
from ._network_a import build_network_a
from ._network_b import build_network_b

__all__ = ["CANONICAL", "canonical_network", "export", "network_text"]

#: name → (problem factory, network builder, one-line description)
CANONICAL = {
    "kitchen_a": (kitchen_problem, build_network_a, "the paper's kitchen ontology on 4 illustrative cells, Network A"),
    "grid3x3_a": (grid_problem, build_network_a, "a 3×3 kitchen grid, Network A"),
    "grid3x3_b_chain": (grid_problem, lambda p: build_network_b(p, "chain"), "the 3×3 grid, Network B (chain)"),
    "gas_type_a": (gas_type_problem, build_network_a, "gas classification (γ, ζ) on the kitchen, Network A"),
}


def canonical_network(name: str):
    """The problem and the pgmpy model of one of the package's canonical networks (the files of ``networks/``).

    Parameters
    ----------
    name : str
        A key of :data:`CANONICAL`: ``"kitchen_a"``, ``"grid3x3_a"``, ``"grid3x3_b_chain"`` or ``"gas_type_a"``.

    Returns
    -------
    problem : SemanticGSLProblem
        The problem the network is built from.
    model : pgmpy.models.DiscreteBayesianNetwork
        Its network (A or B as the name says), with ``model.name == name``.

    Raises
    ------
    ValueError
        ``name`` is not a canonical network (the message lists the names).

    Examples
    --------
    >>> from psgsl_pgm.networks import canonical_network, network_kind
    >>> problem, model = canonical_network("kitchen_a")
    >>> model.name, network_kind(model), problem.n
    ('kitchen_a', 'A', 4)
    """
    if name not in CANONICAL:
        raise ValueError(f"unknown canonical network {name!r}; expected one of {sorted(CANONICAL)}")
    factory, builder, _ = CANONICAL[name]
    problem = factory()
    model = builder(problem)
    model.name = name
    return problem, model


def network_text(model, fmt: str) -> str:
    """The model serialised as ``"xmlbif"`` or ``"bif"`` text by pgmpy's writers (full float precision)."""
    if fmt == "xmlbif":
        return str(XMLBIFWriter(model))
    if fmt == "bif":
        return str(BIFWriter(model))
    raise ValueError(f"fmt must be 'xmlbif' or 'bif', got {fmt!r}")


def _write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file in the same directory and ``os.replace``."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _png(model, title: str) -> bytes:
    """The drawing of ``model`` by :func:`draw_network`, as PNG bytes (Agg canvas, no pyplot state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ._draw import network_layout

    pos = network_layout(model)
    width = max(x for x, _ in pos.values()) - min(x for x, _ in pos.values()) + 1
    fig = Figure(figsize=(max(7.0, 1.3 * width + 3.5), 5.0), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    draw_network(model, ax=fig.add_subplot(), title=title)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    return buf.getvalue()


def export(directory, *, drawings: bool = True) -> list:
    """Write every canonical network to ``directory``: ``<name>.xmlbif``, ``<name>.bif`` and ``<name>.png``.

    The text files are :func:`network_text` of :func:`canonical_network` (pgmpy's writers, full float
    precision); the PNGs are drawn by :func:`psgsl_pgm.networks.draw_network`. Every file is written
    atomically (a temporary file, then ``os.replace``). ``psgsl export-networks DIR`` calls this.

    Parameters
    ----------
    directory : str or os.PathLike
        Created if missing (with its parents).
    drawings : bool, default True, keyword-only
        Also write the PNG drawings (matplotlib + networkx).

    Returns
    -------
    list of pathlib.Path
        The files written, in order.

    Raises
    ------
    ValueError
        ``directory`` exists and is not a directory.

    Examples
    --------
    >>> import tempfile
    >>> from psgsl_pgm.networks import export
    >>> with tempfile.TemporaryDirectory() as d:
    ...     sorted(p.name for p in export(d, drawings=False))[:2]
    ['gas_type_a.bif', 'gas_type_a.xmlbif']
    """
    directory = Path(directory)
    if directory.exists() and not directory.is_dir():
        raise ValueError(f"directory must be a directory, got the file {str(directory)!r}")
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    for name, (_, _, description) in CANONICAL.items():
        _, model = canonical_network(name)
        for fmt in ("xmlbif", "bif"):
            path = directory / f"{name}.{fmt}"
            _write_atomic(path, network_text(model, fmt).encode("utf-8"))
            written.append(path)
        if drawings:
            path = directory / f"{name}.png"
            _write_atomic(path, _png(model, f"{name}: {description}"))
            written.append(path)
    return written
