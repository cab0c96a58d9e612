"""``psgsl search``: outputs, summary.json layout, resumability, the open-space benchmark, bad input."""

import json

import pytest

from psgsl_pgm.cli._main import main


def test_search_grid_writes_summary_csv_figures_and_resumes(tmp_path, capsys):
    out = tmp_path / "s"
    argv = ["search", "--sources", "oven", "--policies", "tour", "greedy", "--variants", "olfaction",
            "--seeds", "2", "--budget", "12", "--workers", "1", "--quiet", "--out", str(out)]
    assert main(argv) == 0
    top = json.loads((out / "summary.json").read_text())
    group = json.loads((out / "oven-infotaxis" / "summary.json").read_text())
    assert top == {"oven/infotaxis": group}
    assert set(group) == {"tour/olfaction", "greedy/olfaction"}
    entry = group["greedy/olfaction"]
    assert set(entry["success_rate"]) == {"value", "ci95"}
    assert {"median", "not_found", "budget"} <= set(entry["time_to_find"]) and "mean" not in entry["time_to_find"]
    assert set(entry["rmst"]) == {"value", "ci95", "tau"} and set(entry["km"]) == {"t", "survival", "lower", "upper"}
    assert set(entry["path_ratio"]) == {"mean", "ci95"}
    assert set(entry["coverage90"]) == {"quarter", "half", "three_quarters", "final"}
    assert set(entry["region_area90"]) == {"mean", "ci95"} and set(entry["hpd_level"]) == {"median", "mean"}
    assert entry["n_runs"] == 2 and 0.0 <= entry["coverage90"]["final"] <= 1.0
    rows = (out / "runs.csv").read_text().splitlines()
    assert len(rows) == 1 + 4 and rows[0].startswith("source,estimator,policy,variant,seed,found")
    for name in ("survival.png", "paths.png", "paired.json", "runs.csv"):
        assert (out / "oven-infotaxis" / name).stat().st_size > 0
    stamps = {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()}
    assert len(stamps) == 4
    assert main(argv) == 0  # resumed: nothing recomputed
    assert {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()} == stamps
    assert "tour/olfaction" in capsys.readouterr().out


def test_open_space_from_the_command_line(tmp_path, capsys):
    argv = ["search", "--open-space", "--setting", "1", "1", "--episodes", "3", "--out", str(tmp_path)]
    assert main(argv) == 0
    rows = json.loads((tmp_path / "open_space.json").read_text())
    assert [r["policy"] for r in rows] == ["infotaxis", "space-aware-infotaxis"]
    assert all(r["n"] == 19 and len(r["steps"]) == 3 for r in rows)
    assert "mean T" in capsys.readouterr().out


@pytest.mark.parametrize("argv", [
    ["search", "--sources", "piano", "--seeds", "1", "--budget", "5", "--policies", "tour"],
    ["search", "--sources", "99,99", "--seeds", "1"],
    ["search", "--sources", "1,2,3"],
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, argv):
    assert main(argv + ["--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("psgsl search: error:")


@pytest.mark.parametrize("option", [["--budget", "-1"], ["--seeds", "10001"], ["--workers", "1025"],
                                    ["--episodes", "0"]])
def test_bad_option_values_are_refused(capsys, option):
    """Counts and budgets are checked as psgsl experiment checks them, with the same size guards."""
    with pytest.raises(SystemExit) as exc:
        main(["search"] + option)
    assert exc.value.code == 2
    assert f"argument {option[0]}: expected a positive" in capsys.readouterr().err


def test_table_of_a_single_run_has_no_interval(tmp_path):
    """One seed (the demo's): the summary's intervals are null and the table says n/a instead of failing."""
    from psgsl_pgm.cli._search import format_search_table

    entry = {"success_rate": {"value": 1.0, "ci95": [0.21, 1.0]}, "rmst": {"value": 161.4, "ci95": [None, None]},
             "time_to_find": {"median": None}, "coverage90": {"final": 1.0}, "n_runs": 1}
    text = format_search_table({"infotaxis/semantics+rooms": entry})
    assert "n/a" in text and "161.4" in text


def test_the_scoring_rule_is_stored_with_the_runs_and_a_grid_of_the_other_rule_is_refused(tmp_path, capsys):
    from psgsl_pgm.search import load_search_run

    out = tmp_path / "s"
    argv = ["search", "--sources", "oven", "--policies", "infotaxis", "--variants", "olfaction", "--seeds", "1",
            "--budget", "12", "--workers", "1", "--quiet", "--no-figures", "--out", str(out)]
    assert main(argv + ["--score", "gain"]) == 0
    (path,) = (out / "runs").iterdir()
    assert load_search_run(path).config["search"]["score"] == "gain"
    capsys.readouterr()
    assert main(argv) == 2  # the default rule, per-time, into the same directory
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "computed with other settings" in err[0]
    assert "search.score: gain → per-time" in err[0]  # the setting and both values
    with pytest.raises(SystemExit) as exc:
        main(argv + ["--score", "fastest"])
    assert exc.value.code == 2


@pytest.mark.parametrize("command", ["search", "experiment"])
@pytest.mark.parametrize("value", ["-1", "1.5", "two", ""])
def test_a_bad_first_seed_is_one_line_and_exit_2_before_any_output(tmp_path, capsys, command, value):
    out = tmp_path / "o"
    assert main([command, "--first-seed", value, "--seeds", "1", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"psgsl {command}: error: --first-seed must be an integer >= 0, got {value!r}"]
    assert not out.exists()


def test_first_seed_runs_the_held_out_seeds_and_resumes(tmp_path):
    from psgsl_pgm.search import load_search_run

    out = tmp_path / "s"
    argv = ["search", "--sources", "oven", "--policies", "tour", "--variants", "olfaction", "--seeds", "2",
            "--first-seed", "7", "--budget", "5", "--workers", "1", "--quiet", "--no-figures", "--out", str(out)]
    assert main(argv) == 0
    files = sorted((out / "runs").iterdir())
    assert [load_search_run(f).seed for f in files] == [7, 8]
    assert json.loads((out / "summary.json").read_text())["oven/infotaxis"]["tour/olfaction"]["seeds"] == [7, 8]
    stamps = {p.name: p.stat().st_mtime_ns for p in files}
    assert main(argv) == 0  # resumed: nothing recomputed
    assert {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()} == stamps
    assert main(argv[:-2] + ["--first-seed", "8", "--seeds", "2", "--out", str(out)]) == 0  # 8 reused, 9 added
    assert {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir() if p.name in stamps} == stamps
    assert json.loads((out / "summary.json").read_text())["oven/infotaxis"]["tour/olfaction"]["seeds"] == [7, 8, 9]


@pytest.mark.parametrize("extra, needle", [
    (["--split", "test", "--first-seed", "0"], "--first-seed does not apply with --split test"),
    (["--split", "test", "--seeds", "21"], "at most 20"),
    (["--first-seed", "19999", "--seeds", "2"], "are the test split's"),
])
def test_a_split_with_explicit_seeds_is_one_line_and_exit_2(tmp_path, capsys, extra, needle):
    out = tmp_path / "o"
    assert main(["search", "--out", str(out), "--quiet"] + extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("psgsl search: error: ") and needle in err[0], err
    assert not out.exists()


def test_an_unknown_split_exits_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["search", "--split", "holdout", "--out", str(tmp_path / "o")])
    assert exc.value.code == 2
    assert "invalid choice: 'holdout'" in capsys.readouterr().err


def test_the_test_split_runs_its_own_seeds_and_says_so(tmp_path, capsys):
    out = tmp_path / "s"
    argv = ["search", "--sources", "oven", "--policies", "tour", "--variants", "olfaction", "--seeds", "2",
            "--budget", "5", "--workers", "1", "--quiet", "--no-figures", "--out", str(out)]
    assert main(argv + ["--split", "test"]) == 0
    assert "split test: seeds 20000-20001; world model ideal" in capsys.readouterr().out
    s = json.loads((out / "summary.json").read_text())["oven/infotaxis"]["tour/olfaction"]
    assert s["seeds"] == [20000, 20001] and s["split"] == "test"
    dev = tmp_path / "d"
    assert main(argv[:-1] + [str(dev)]) == 0  # no --split: dev, seeds 0 and 1 as before
    s = json.loads((dev / "summary.json").read_text())["oven/infotaxis"]["tour/olfaction"]
    assert s["seeds"] == [0, 1] and s["split"] == "dev"


def test_the_nearest_object_baseline_runs_from_the_command_line(tmp_path):
    """``--policies nearest-object`` is accepted; with ``olfaction`` among the variants that pair is left out, as
    for ``semantic-modes`` (semantics alone); on seed 0 the baseline finds the oven within the 100-s budget."""
    out = tmp_path / "s"
    assert main(["search", "--sources", "oven", "--policies", "nearest-object", "--variants", "olfaction",
                 "semantics+rooms", "--seeds", "1", "--budget", "100", "--workers", "1", "--quiet",
                 "--out", str(out)]) == 0
    group = json.loads((out / "oven-infotaxis" / "summary.json").read_text())
    assert set(group) == {"nearest-object/semantics+rooms"}
    assert group["nearest-object/semantics+rooms"]["success_rate"]["value"] == 1.0


def test_how_runs_end_is_stored_and_a_grid_of_the_other_rule_is_refused(tmp_path, capsys):
    from psgsl_pgm.search import load_search_run

    out = tmp_path / "s"
    argv = ["search", "--sources", "oven", "--policies", "nearest-object", "--variants", "semantics+rooms",
            "--seeds", "1", "--budget", "200", "--workers", "1", "--quiet", "--no-figures", "--out", str(out)]
    assert main(argv) == 0
    (path,) = (out / "runs").iterdir()
    run = load_search_run(path)
    assert run.config["search"]["end"] == "declare" and run.declared and run.declared_correct
    s = json.loads((out / "summary.json").read_text())["oven/infotaxis"]["nearest-object/semantics+rooms"]
    assert s["end"] == "declare" and s["declared_success"]["value"] == 1.0 and s["declared"] == 1
    assert s["false_declaration_rate"]["value"] == 0.0 and s["declared_error"]["median"] <= 1.0
    capsys.readouterr()
    assert main(argv + ["--end", "reach"]) == 2  # runs of the other rule never resume into this grid
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "computed with other settings" in err[0]
    reach = tmp_path / "r"
    assert main(argv[:-1] + [str(reach), "--end", "reach"]) == 0
    s = json.loads((reach / "summary.json").read_text())["oven/infotaxis"]["nearest-object/semantics+rooms"]
    assert s["end"] == "reach" and s["declared_success"] is None and s["success_rate"]["value"] == 1.0
    with pytest.raises(SystemExit) as exc:
        main(argv + ["--end", "found"])
    assert exc.value.code == 2
