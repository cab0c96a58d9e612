"""`psgsl estimate` uses the gas it is asked for (not the ontology's first)."""

from __future__ import annotations

import numpy as np

import psgsl_pgm.cli._main as cli
from psgsl_pgm import Ontology, fuse, semantic_source_probability

# Two gases whose sources sit on different classes: which gas is used moves the posterior.
_TWO_GASES = """\
classes: [oven, fridge, sink]
gases:
  smoke: {oven: 0.8, fridge: 0.1, sink: 0.05}
  ammonia: {oven: 0.05, fridge: 0.15, sink: 0.7}
"""


def test_estimate_uses_the_gas_named_by_gas_not_the_first(tmp_path, capsys):
    (tmp_path / "o.yaml").write_text(_TWO_GASES)
    ont = Ontology.from_yaml(tmp_path / "o.yaml")
    assert ont.gases == ("smoke", "ammonia")  # the asked gas is the second
    rng = np.random.default_rng(7)
    q = rng.dirichlet(np.full(len(ont.classes), 0.5), size=(3, 4))
    olf = rng.dirichlet(np.ones(12)).reshape(3, 4)
    np.save(tmp_path / "p.npy", q)
    np.save(tmp_path / "g.npy", olf)
    out = tmp_path / "post.npy"
    assert cli.main(["estimate", "--ontology", str(tmp_path / "o.yaml"), "--class-probs", str(tmp_path / "p.npy"),
                     "--olfactory", str(tmp_path / "g.npy"), "--gas", "ammonia", "--out", str(out)]) == 0
    assert "for 'ammonia'" in capsys.readouterr().out

    def expected(lik):  # p(s | g, z) ∝ p(s | g) Σ_i q_ci p(o_i | s, γ) / p(o_i), by hand
        w = olf * (q @ (lik / ont.class_prior))
        return w / w.sum()

    table = dict(zip(ont.gases, ont.source_likelihood(None)))
    got = np.load(out)
    np.testing.assert_allclose(got, expected(table["ammonia"]), rtol=1e-12)
    np.testing.assert_allclose(got, fuse(olf, semantic_source_probability(q, table["ammonia"], ont.class_prior)),
                               rtol=1e-12)
    assert np.max(np.abs(expected(table["smoke"]) / got - 1)) > 0.1  # the other gas would be visibly different


def _double(x):
    return 2 * x


def _write(result, fh):
    fh.write(str(result).encode())


def test_the_progress_bar_names_the_command(tmp_path, monkeypatch, capsys):
    import pytest

    pytest.importorskip("tqdm", reason="the sim extra is not installed (pip install 'psgsl-pgm[sim]')")
    from psgsl_pgm.runs._runner import GridJob, run_grid

    def command(args):  # a command that runs a grid with its bar on, as experiment/search/demo do
        run_grid([GridJob(tmp_path / "a.txt", _double, (1,))], write=_write,
                 workers=1, progress=True, desc="search runs")
        return 0

    parser = cli.build_parser()
    monkeypatch.setattr(cli, "build_parser", lambda: parser)
    parser._subparsers._group_actions[0].choices["kitchen"].set_defaults(func=command)
    assert cli.main(["kitchen"]) == 0
    assert "psgsl kitchen: search runs" in capsys.readouterr().err
    assert (tmp_path / "a.txt").read_text() == "2"
    # outside a command (the library), the bar keeps the caller's label
    run_grid([GridJob(tmp_path / "b.txt", _double, (2,))], write=_write, workers=1, progress=True,
             desc="search runs")
    err = capsys.readouterr().err
    assert "search runs" in err and "psgsl" not in err


def test_demo_help_gives_the_time_readme_gives():
    import re
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]  # README and the docs' pages (the results say how long the demo takes)
    readme = "\n".join(p.read_text() for p in [root / "README.md", *sorted((root / "docs").glob("*/*.md"))])
    said = set(re.findall(r"(\d+–\d+ s)\s+(?:wall\s+)?on\s+(?:the\s+)?2\s+idle\s+cores", readme))
    assert len(said) == 1, said  # README and the docs state the demo's time once, the same everywhere
    sub = cli.build_parser()._subparsers._group_actions[0]
    help_text = next(a.help for a in sub._choices_actions if a.dest == "demo")
    assert f"{said.pop()} on 2 idle cores" in help_text
