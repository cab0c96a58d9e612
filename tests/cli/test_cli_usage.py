"""The one wrapper that turns a command's bad-input errors into a :class:`UsageError` (one line, exit code 2)."""

import pytest

from psgsl_pgm.cli._usage import UsageError, reporting_usage_errors


def _raising(exc):
    def command(args):
        raise exc

    return command


@pytest.mark.parametrize("exc", [ValueError("--x must be > 0, got -1"), TypeError("--x must be a number, got 'a'")])
def test_library_errors_become_usage_errors_with_their_message(exc):
    with pytest.raises(UsageError) as info:
        reporting_usage_errors(_raising(exc), None)
    assert str(info.value) == str(exc)
    assert info.value.__cause__ is None and info.value.__suppress_context__  # no library traceback attached


def test_exit_code_and_args_pass_through():
    assert reporting_usage_errors(lambda args: args + 1, 6) == 7


def test_other_errors_are_not_reported_as_usage():
    with pytest.raises(KeyError):  # a bug keeps its traceback
        reporting_usage_errors(_raising(KeyError("k")), None)
    with pytest.raises(FileNotFoundError):  # only when the command asks for it
        reporting_usage_errors(_raising(FileNotFoundError("a.yaml")), None)
    with pytest.raises(UsageError, match="a.yaml"):
        reporting_usage_errors(_raising(FileNotFoundError("a.yaml")), None, errors=(ValueError, FileNotFoundError))


def test_quiet_before_the_command_is_the_commands_quiet(monkeypatch):
    """``psgsl --quiet`` runs the demo without a progress bar; ``psgsl --quiet COMMAND`` passes it on."""
    import argparse

    import psgsl_pgm.cli._main as cli

    seen = []

    def fake(args):
        seen.append((args.command, args.quiet))
        return 0

    build = cli.build_parser

    def parser():
        p = build()
        sub = next(a for a in p._actions if isinstance(a, argparse._SubParsersAction))
        for name in ("demo", "replay"):
            sub.choices[name].set_defaults(func=fake)
        return p

    monkeypatch.setattr(cli, "build_parser", parser)
    assert cli.main(["--quiet"]) == 0 and cli.main([]) == 0
    assert cli.main(["--quiet", "replay", "bag"]) == 0 and cli.main(["replay", "bag"]) == 0
    assert seen == [("demo", True), ("demo", False), ("replay", True), ("replay", False)]
