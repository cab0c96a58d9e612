"""The command line's usage error: every command module raises it, :func:`psgsl_pgm.cli.main` reports it."""

__all__ = ["LIBRARY_ERRORS", "UsageError", "reporting_usage_errors"]

#: What a command's library calls raise on bad input: their messages name what was expected and what arrived.
LIBRARY_ERRORS = (ValueError, TypeError)


class UsageError(ValueError):
    """A bad argument or input file: reported by :func:`psgsl_pgm.cli.main` in one line, exit code 2."""


def reporting_usage_errors(command, args, *, errors=LIBRARY_ERRORS) -> int:
    """Run ``command(args)``, turning each of ``errors`` it raises into a :class:`UsageError` with its message.

    The command's ``run()`` calls this around its body, so that bad input found anywhere below it reaches
    :func:`psgsl_pgm.cli.main` as one line ``psgsl <command>: error: <message>`` and exit code 2, without the
    library's traceback (``from None``).

    Parameters
    ----------
    command : callable
        The command's body, ``command(args) -> int`` (its exit code).
    args : argparse.Namespace
        The parsed command line.
    errors : tuple of exception types, keyword-only
        What counts as bad input (default: :class:`ValueError` and :class:`TypeError`).

    Returns
    -------
    int
        ``command``'s exit code.
    """
    try:
        return command(args)
    except errors as exc:
        raise UsageError(str(exc)) from None
