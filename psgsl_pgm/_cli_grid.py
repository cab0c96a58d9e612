"""Command-line side of the grid runner (:mod:`psgsl_pgm._grid_runner`): ``--scheduler`` and the Ctrl-C line.

Used by ``psgsl experiment`` and ``psgsl search``::

    add_scheduler_argument(parser)                      # --scheduler {local, tcp://HOST:PORT}
    try:
        run_experiment(..., scheduler=args.scheduler)
    except GridInterrupted as exc:
        return interrupted(args, exc, where=out / "runs")  # one line on stderr, exit code 130
"""

from __future__ import annotations

import shlex
import sys

__all__ = ["EXIT_INTERRUPTED", "add_scheduler_argument", "interrupted"]

#: Exit code after Ctrl-C (128 + SIGINT), as shells report it.
EXIT_INTERRUPTED = 130


def add_scheduler_argument(parser) -> None:
    """Add ``--scheduler`` (default: the local process pool of ``--workers`` processes)."""
    parser.add_argument(
        "--scheduler", default=None, metavar="ADDRESS",
        help="run on dask.distributed (extra psgsl-pgm[dask]): 'local' = a LocalCluster of --workers processes, "
             "or the address of a running 'dask scheduler' (e.g. tcp://127.0.0.1:8786); default: a local pool",
    )


def interrupted(args, exc, *, where) -> int:
    """Print the one-line Ctrl-C report (runs done, where, how to resume) on stderr; return 130."""
    argv = getattr(args, "argv", None)
    again = shlex.join(["psgsl", *argv]) if argv else f"psgsl {args.command} with the same arguments"
    how = "in-progress runs abandoned" if exc.immediate else "runs in progress were finished"
    print(f"psgsl {args.command}: interrupted: {exc.done} of {exc.total} runs done in {where} ({how}); "
          f"resume with: {again}", file=sys.stderr, flush=True)
    return EXIT_INTERRUPTED
