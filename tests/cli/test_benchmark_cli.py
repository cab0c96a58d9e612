"""``psgsl benchmark``: a tiny benchmark end to end (runs, report, the primary ratio by hand, resume, a refused
resume with other settings) and bad input as one line with exit code 2, nothing written."""

import json

import numpy as np
import pytest

from psgsl_pgm.cli._main import main


@pytest.mark.parametrize("extra, needle", [
    (["--conditions", "right-ontology", "sideways"], "condition must be one of"),
    (["--rooms", "2"], "n_rooms must be in [3, 8], got 2"),
    (["--rooms", "2", "--room-types", "Kitchen", "Bathroom", "Bedroom", "LivingRoom", "Hallway", "Bedroom",
      "Bedroom", "Bathroom"], "n_rooms must be in [3, 8], got 2"),
    (["--rooms", "3", "--room-types", "Kitchen", "Bathroom", "Bedroom", "LivingRoom"], "one type per room"),
    (["--area", "-20"], "area must be in [40, 200] m², got -20"),
    (["--rooms", "8", "--area", "50"], "per room"),
    (["--room-types", "Kitchen", "Garage", "Bedroom"], "room_types must name types"),
    (["--policies", "teleport"], "policies must be among"),
    (["--policies", "nearest-object", "--variants", "olfaction"], "needs a semantic variant"),
    (["--variants", "smell"], "variants must be among"),
    (["--conditions", "no-rooms"], "must include 'right-ontology'"),
    (["--off-rate", "1.5"], "off_rate"),
    (["--gases", "chlorine"], "gases must be gases of the ontology"),
    (["--first-house", "1000000"], "reference seeds"),
    (["--policies", "infotaxis", "pmfs-nav"], "policy 'pmfs-nav' runs with estimator 'pmfs' only, got 'infotaxis'"),
])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys, extra, needle):
    out = tmp_path / "b"
    assert main(["benchmark", "--houses", "2", "--seeds", "1", "--out", str(out), "--quiet"] + extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("psgsl benchmark: error: ") and needle in err[0], err
    assert not out.exists()


def test_world_and_houses_together_are_refused(tmp_path, capsys):
    from psgsl_pgm.sim import generate_house

    world = generate_house(1).write(tmp_path / "w")
    out = tmp_path / "b"
    assert main(["benchmark", "--houses", "2", "--world", str(world), "--out", str(out)]) == 2
    assert "not both" in capsys.readouterr().err
    assert main(["benchmark", "--world", str(world), "--rooms", "4", "--out", str(out)]) == 2
    assert "do not apply with --world" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.slow
def test_tiny_benchmark_report_primary_ratio_and_resume(tmp_path, capsys):
    out = tmp_path / "b"
    argv = ["benchmark", "--houses", "2", "--seeds", "2", "--rooms", "3", "--area", "45", "--policies", "infotaxis",
            "--variants", "olfaction", "semantics+rooms", "--conditions", "right-ontology", "wrong-ontology",
            "--budget", "40", "--workers", "1", "--quiet", "--out", str(out)]
    assert main(argv) == 0
    runs = sorted(p.name for p in (out / "runs").iterdir())
    # per episode: right (olfaction, semantics+rooms) + wrong (semantics+rooms; olfaction shared) = 3 runs
    assert len(runs) == 2 * 2 * 3
    assert not any("wrong-ontology__infotaxis__olfaction" in r for r in runs)
    summary = json.loads((out / "summary.json").read_text())
    report = (out / "report.md").read_text()
    assert "## Primary comparison (declared before the runs)" in report and "psgsl benchmark --houses 2" in report
    for name in ("survival.png", "rmst.png", "episodes.json", "houses/h00000/world.yaml", "houses/h00001/world.yaml"):
        assert (out / name).stat().st_size > 0
    # the primary ratio by hand from the stored runs: mean capped time to success of A over that of B, same episodes
    from psgsl_pgm.search import load_search_run

    def capped(policy_variant, condition="right-ontology"):
        return np.array([min(load_search_run(out / "runs" / f"h{h:05d}__{condition}__{policy_variant}__infotaxis__seed{s}.npz")
                             .time_to_success, 40.0) for h in (0, 1) for s in (0, 1)])

    a, b = capped("infotaxis__semantics+rooms"), capped("infotaxis__olfaction")
    prim = summary["primary"]["result"]
    assert prim["value"] == pytest.approx(a.mean() / b.mean(), rel=1e-12)
    assert prim["n"] == 4 and prim["houses"] == 2 and prim["ci95"][0] <= prim["value"] <= prim["ci95"][1]
    arm = summary["arms"]["wrong-ontology"]["infotaxis/semantics+rooms"]
    assert arm["rmst"]["value"] == pytest.approx(capped("infotaxis__semantics+rooms", "wrong-ontology").mean(), rel=1e-12)
    found = [load_search_run(out / "runs" / f"h{h:05d}__wrong-ontology__infotaxis__semantics+rooms__infotaxis__seed{s}.npz")
             .found for h in (0, 1) for s in (0, 1)]
    assert arm["success_rate"]["value"] == pytest.approx(np.mean(found), rel=1e-12)
    lo, hi = arm["success_rate"]["ci95"]
    assert 0.0 <= lo <= arm["success_rate"]["value"] <= hi <= 1.0
    shared = summary["arms"]["wrong-ontology"]["infotaxis/olfaction"]
    assert shared["rmst"]["value"] == pytest.approx(b.mean(), rel=1e-12)  # shared with right-ontology
    cost = summary["costs"]["infotaxis/semantics+rooms: RMST wrong-ontology / right-ontology"]
    assert cost["value"] == pytest.approx(capped("infotaxis__semantics+rooms", "wrong-ontology").mean() / a.mean(),
                                          rel=1e-12)
    # every generated house is a world file `psgsl world check` accepts
    capsys.readouterr()
    assert main(["world", "check", str(out / "houses" / "h00001" / "world.yaml")]) == 0
    assert ": OK" in capsys.readouterr().out
    # resumed: nothing recomputed, the same report numbers
    stamps = {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()}
    assert main(argv) == 0
    assert {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()} == stamps
    assert json.loads((out / "summary.json").read_text())["primary"] == summary["primary"]
    # another budget is another benchmark: refused before anything runs, naming the setting
    capsys.readouterr()
    assert main(argv[:-7] + ["--budget", "50", "--workers", "1", "--quiet", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "search.time_budget" in err and len(err.strip().splitlines()) == 1
    assert {p.name: p.stat().st_mtime_ns for p in (out / "runs").iterdir()} == stamps


def test_a_relative_out_folder_gives_condition_worlds_that_load(tmp_path, monkeypatch, capsys):
    """The condition worlds (wrong ontology, no rooms) are copies in OUT/worlds naming the home's files by absolute
    paths, so the documented `--out bench-50x5`, a folder relative to the working directory, runs them."""
    monkeypatch.chdir(tmp_path)
    argv = ["benchmark", "--houses", "1", "--seeds", "1", "--rooms", "3", "--area", "45", "--policies", "infotaxis",
            "--variants", "semantics+rooms", "--conditions", "right-ontology", "wrong-ontology", "no-rooms",
            "--budget", "10", "--workers", "1", "--quiet", "--out", "rel"]
    assert main(argv) == 0, capsys.readouterr().err
    worlds = sorted((tmp_path / "rel" / "worlds").glob("h00000__*-*.yaml"))
    worlds = [w for w in worlds if not w.name.endswith("__ontology.yaml")]
    assert len(worlds) == 2
    from psgsl_pgm.sim import load_world

    for w in worlds:
        load_world(w)  # every file it names exists
    assert len(list((tmp_path / "rel" / "runs").glob("*.npz"))) == 3


@pytest.mark.parametrize("extra, needle", [
    (["--split", "test", "--first-house", "0"], "--first-house does not apply with --split test"),
    (["--split", "test", "--seeds", "21"], "at most 20"),
    (["--split", "test", "--houses", "101"], "at most 100"),
    (["--first-house", "9999"], "are the test split's"),
])
def test_a_split_with_explicit_homes_is_one_line_and_exit_2(tmp_path, capsys, extra, needle):
    out = tmp_path / "b"
    assert main(["benchmark", "--houses", "2", "--out", str(out), "--quiet"] + extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("psgsl benchmark: error: ") and needle in err[0], err
    assert not out.exists()


def test_an_unknown_benchmark_split_exits_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["benchmark", "--split", "holdout", "--out", str(tmp_path / "b")])
    assert exc.value.code == 2
    assert "invalid choice: 'holdout'" in capsys.readouterr().err


def test_the_test_split_runs_test_homes_and_seeds_and_records_it(tmp_path, capsys):
    out = tmp_path / "b"
    argv = ["benchmark", "--split", "test", "--houses", "1", "--seeds", "1", "--rooms", "3", "--area", "45",
            "--policies", "tour", "--variants", "olfaction", "--conditions", "right-ontology", "--budget", "5",
            "--workers", "1", "--quiet", "--no-figures", "--out", str(out)]
    assert main(argv) == 0
    assert "(test split), seeds 20000-20000" in capsys.readouterr().out
    assert [p.name for p in (out / "runs").iterdir()] == [
        "h10000__right-ontology__tour__olfaction__infotaxis__seed20000.npz"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["settings"]["split"] == "test" and summary["settings"]["houses"] == ["h10000"]
    assert summary["settings"]["seeds"] == [20000]
    assert "Split: **test**" in (out / "report.md").read_text()


def test_the_nearest_object_baseline_runs_in_the_benchmark(tmp_path):
    out = tmp_path / "b"
    assert main(["benchmark", "--houses", "1", "--seeds", "1", "--rooms", "3", "--area", "45", "--policies",
                 "nearest-object", "--variants", "olfaction", "semantics+rooms", "--conditions", "right-ontology",
                 "--budget", "40", "--workers", "1", "--quiet", "--out", str(out)]) == 0
    runs = sorted(p.name for p in (out / "runs").iterdir())
    assert runs == ["h00000__right-ontology__nearest-object__semantics+rooms__infotaxis__seed0.npz"]


def test_the_estimator_option_runs_every_arm_on_that_estimator(tmp_path):
    out = tmp_path / "b"
    assert main(["benchmark", "--houses", "1", "--seeds", "1", "--rooms", "3", "--area", "45", "--policies",
                 "infotaxis", "--variants", "olfaction", "--conditions", "right-ontology", "--estimator", "grgsl",
                 "--budget", "40", "--workers", "1", "--quiet", "--no-figures", "--out", str(out)]) == 0
    runs = sorted(p.name for p in (out / "runs").iterdir())
    assert runs == ["h00000__right-ontology__infotaxis__olfaction__grgsl__seed0.npz"]
    assert json.loads((out / "summary.json").read_text())["settings"]["estimator"] == "grgsl"
