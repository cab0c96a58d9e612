"""The ``psgsl`` command line: one module per command (``_main`` kitchen, demo, experiment, semantic, fuse;
``_search``; ``_world``; ``_export``), shared options (``_grid``) and the usage error all of them raise
(``_usage``). :func:`main` prints every bad argument or input as one line and exits with 2.

May import every other layer; nothing imports it.
"""

from ._main import build_parser, error_line, main

__all__ = ["build_parser", "error_line", "main"]
