"""Every Python block in README.md runs; the two fresh-machine commands are present."""

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)


def test_readme_shows_the_two_fresh_machine_commands():
    text = README.read_text()
    assert 'pip install -e ".[test]" && python -m pytest -q' in text
    assert 'python -m venv .venv && . .venv/bin/activate && pip install ".[all]" && psgsl' in text
    ci = (README.parent / ".ci" / "run").read_text()  # CI runs exactly the commands README shows
    for line in ci.splitlines():
        if line.startswith(("TEST_CMD=", "MAIN_CMD=")):
            assert line.split("=", 1)[1].strip("'") in text, line


@pytest.mark.parametrize("block", BLOCKS, ids=[f"block{i}" for i in range(len(BLOCKS))])
def test_readme_python_block_runs(block):
    exec(compile(block, str(README), "exec"), {"__name__": "readme"})


def test_readme_is_short_and_describes_the_software_not_its_history():
    text = README.read_text()
    assert len(text.splitlines()) <= 200, "README holds what a newcomer needs; the rest lives in docs/"
    assert not re.search(r"load average|\bissue \d+|`[0-9a-f]{7,40}`", text, flags=re.I), \
        "no load averages, issue numbers or commit hashes in user-facing text"


def test_readme_links_point_at_files_that_exist():
    for target in re.findall(r"\]\(((?!https?:)[^)#]+)(?:#[^)]*)?\)", README.read_text()):
        assert (README.parent / target).exists(), f"README links to {target}, which does not exist"


def test_readme_names_every_command():
    """Every command ``psgsl --help`` lists is named in README (as `name`, a world action as `world <action>`)."""
    import argparse

    from psgsl_pgm.cli._main import build_parser

    text = README.read_text()
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    missing = []
    for name, parser in sub.choices.items():
        actions = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        names = [f"{name} {action}" for a in actions for action in a.choices] or [name]
        missing += [n for n in names if f"`{n}`" not in text]
    assert missing == []
