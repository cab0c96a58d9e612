"""The command line's usage error: every command module raises it, :func:`psgsl_pgm.cli.main` reports it."""

__all__ = ["UsageError"]


class UsageError(ValueError):
    """A bad argument or input file: reported by :func:`psgsl_pgm.cli.main` in one line, exit code 2."""
