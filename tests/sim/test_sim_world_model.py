"""World models: the names, the world-file key, the config option and what each component puts in the world."""

import numpy as np
import pytest
import yaml

from psgsl_pgm import load_world
from psgsl_pgm.cli._main import main
from psgsl_pgm.experiment import ExperimentConfig
from psgsl_pgm.sim import WORLD_COMPONENTS, WorldModel, default_world
from tests.sim.test_sim_worldfile import world_dict, write_house


@pytest.mark.parametrize(("name", "components", "canonical"), [
    ("ideal", (), "ideal"),
    ("realistic", WORLD_COMPONENTS, "realistic"),
    (" Realistic ", WORLD_COMPONENTS, "realistic"),
    ("ideal+pose+mox", ("mox", "pose"), "ideal+mox+pose"),
    ("ideal+cfd-wind+mox+camera+pose", WORLD_COMPONENTS, "realistic"),
])
def test_names_parse_to_components_in_one_canonical_spelling(name, components, canonical):
    model = WorldModel.parse(name)
    assert model.components == components and model.name == canonical
    assert WorldModel.parse(model.name) == model


@pytest.mark.parametrize(("name", "words"), [
    ("ideel", "did you mean 'ideal'"),
    ("ideal+wind", "did you mean 'cfd-wind'"),
    ("ideal+mox+mox", "names a component twice"),
    ("realistic+pose", "expected ideal, realistic"),
    ("", "unknown world model"),
])
def test_bad_names_say_what_was_expected(name, words):
    with pytest.raises(ValueError, match=words):
        WorldModel.parse(name)


def test_a_name_must_be_a_string():
    with pytest.raises(TypeError, match="a world model must be a name"):
        WorldModel.parse(1)
    with pytest.raises(TypeError, match="tuple of names"):
        WorldModel("mox")


def test_the_ideal_model_adds_nothing_to_the_world():
    assert WorldModel().world_kwargs(default_world().house(0)) == {}


def test_config_keeps_the_run_key_of_the_ideal_world_and_stores_the_canonical_name():
    assert "world_model" not in ExperimentConfig().to_dict()  # stored runs of the ideal world still resume
    assert ExperimentConfig(world_model="ideal+pose+mox").to_dict()["world_model"] == "ideal+mox+pose"
    with pytest.raises(ValueError, match="unknown world model"):
        ExperimentConfig(world_model="perfect")


def test_ideal_by_name_is_the_default_world_bit_for_bit():
    spec = default_world()
    a = spec.make_world(3, "oven", warm_up=20.0)
    b = spec.make_world(3, "oven", warm_up=20.0, model="ideal")
    pts = a.house.grid.cell_centres().reshape(-1, 2)[::37]
    assert np.array_equal(a.concentration(pts), b.concentration(pts))
    assert a.sense_gas((3.0, 6.0)) == b.sense_gas((3.0, 6.0))


def test_world_file_key_model(tmp_path):
    write_house(tmp_path)
    (tmp_path / "world.yaml").write_text(yaml.safe_dump(world_dict(model="ideal+pose")))
    spec = load_world(tmp_path / "world.yaml")
    assert spec.model == "ideal+pose" and spec.summary()["model"] == "ideal+pose"
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(world_dict(model="lifelike")))
    with pytest.raises(ValueError, match=r"bad\.yaml: key 'model': unknown world model 'lifelike'"):
        load_world(tmp_path / "bad.yaml")
    (tmp_path / "plain.yaml").write_text(yaml.safe_dump(world_dict()))
    assert load_world(tmp_path / "plain.yaml").model == "ideal"


@pytest.mark.parametrize("command", [["search", "--seeds", "1"], ["experiment", "--seeds", "1"],
                                     ["benchmark", "--houses", "1", "--seeds", "1"]])
def test_cli_refuses_a_bad_world_model_in_one_line(command, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(command + ["--world-model", "ideal+wind", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--world-model" in err[0] and "cfd-wind" in err[0]
    assert not out.exists()  # nothing written


def test_cli_names_the_missing_solver_in_one_line(monkeypatch, tmp_path, capsys):
    import builtins

    real_import = builtins.__import__

    def no_lbmpy(name, *args, **kwargs):
        if name.split(".")[0] == "lbmpy":
            raise ImportError("No module named 'lbmpy'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_lbmpy)
    out = tmp_path / "out"
    code = main(["search", "--seeds", "1", "--world-model", "realistic", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and 'pip install "psgsl-pgm[cfd]"' in err[0]
    assert not out.exists()
    assert WorldModel.parse("ideal+mox+camera+pose").check_available() is None  # no solver without the CFD wind


def test_each_component_puts_its_part_in_the_world():
    from psgsl_pgm.sim import Anemometer, LocalisationError, MOXSensor, SourceDetector

    house = default_world().house(0)
    assert WorldModel.parse("ideal+mox+pose").source_detector().miss_probability == 0.0  # camera's part
    kwargs = WorldModel.parse("ideal+mox+camera+pose").world_kwargs(house)
    assert set(kwargs) == {"gas_sensor", "anemometer", "camera", "detector", "localisation", "source_detector"}
    assert kwargs["source_detector"].miss_probability == SourceDetector.realistic().miss_probability > 0
    assert isinstance(kwargs["gas_sensor"], MOXSensor) and kwargs["anemometer"] == Anemometer.datasheet()
    assert kwargs["camera"].occlusion == "furniture" and kwargs["detector"].correlated
    assert isinstance(kwargs["localisation"], LocalisationError)
    world = default_world().make_world(0, "oven", warm_up=2.0, model="ideal+mox+camera+pose")
    assert world.detector_errors is not None and world.localisation is not None
    assert world.sense_gas(world.source).hit is None  # the robot decides a MOX sensor's hits


@pytest.mark.slow
def test_the_realistic_world_runs_a_closed_loop_on_the_cfd_wind(tmp_path):
    pytest.importorskip("lbmpy")
    from psgsl_pgm.search import SearchConfig, run_closed_loop

    config = ExperimentConfig(world_model="realistic")
    run = run_closed_loop("oven", 0, "infotaxis", "semantics+rooms", config=config,
                          search=SearchConfig(time_budget=120.0))
    assert run.config["experiment"]["world_model"] == "realistic"
    assert np.isfinite(run.error).all() and run.hit.dtype == bool
