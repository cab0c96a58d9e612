"""``psgsl export-networks DIR``: the paper's canonical networks as XMLBIF, BIF and PNG files.

Calls :func:`psgsl_pgm.networks.export` (the files committed under ``networks/`` are its output) and prints
each path written, one a line.
"""

from __future__ import annotations

__all__ = ["add_parser", "run"]


def add_parser(subparsers) -> None:
    """Register ``export-networks`` on an ``argparse`` sub-parser collection."""
    p = subparsers.add_parser("export-networks", help="write the canonical networks (XMLBIF, BIF, PNG) to DIR",
                              description="Write the canonical networks of psgsl_pgm.networks to DIR as XMLBIF "
                              "(.xmlbif), BIF (.bif) and a PNG drawing of each graph.")
    p.add_argument("directory", metavar="DIR", help="output directory (created if missing)")
    p.add_argument("--no-drawings", action="store_true", help="skip the PNG drawings (no matplotlib needed)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Export into ``args.directory``; print the written paths; return 0."""
    from ..networks import export

    for path in export(args.directory, drawings=not args.no_drawings):
        print(path)
    return 0
