"""World files with implausible values are refused naming the key: wind beyond an indoor bound, cells coarser
than the rooms, a start beyond int64 (without a warning first), unknown sources listing the world's own, too many
free cells for the runs; world check warns when the camera variants have nothing to see."""

from __future__ import annotations

import warnings

import pytest
import yaml

from psgsl_pgm import load_world
from psgsl_pgm.cli._main import main
from psgsl_pgm.sim import MAX_WIND_SPEED, check_free_cells
from tests.sim.test_sim_worldfile import flat, world_dict  # noqa: F401 - the fixture

WINDOWS = world_dict()["wind"]["windows"]


def _write(flat, **change):
    path = flat / "w.yaml"
    path.write_text(yaml.safe_dump(world_dict(**change)))
    return path


def test_wind_beyond_an_indoor_bound_is_refused(flat):
    assert load_world(_write(flat, wind={"speed": MAX_WIND_SPEED, "windows": WINDOWS}))
    with pytest.raises(ValueError, match=r"w\.yaml: key 'wind\.speed': 20 m/s is no indoor wind \(at most 5 m/s"):
        load_world(_write(flat, wind={"speed": 20, "windows": WINDOWS}))


def test_cells_coarser_than_the_rooms_name_resolution_not_a_window(flat):
    with pytest.raises(ValueError, match=r"w\.yaml: key 'resolution': cells of 4 m are coarser than the rooms: "
                                         r"LivingRoom keeps no cell .*use a resolution of at most 1 m"):
        load_world(_write(flat, resolution=4.0))


def test_a_start_beyond_int64_is_one_error_and_no_warning(flat):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning before the error would fail here
        with pytest.raises(ValueError, match=r"key 'start' \(1e\+30, 0\) is outside the map"):
            load_world(_write(flat, start=[1e30, 0.0]))


def test_an_unknown_source_lists_the_worlds_sources(flat, tmp_path, capsys):
    path = _write(flat)
    assert main(["search", "--world", str(path), "--sources", "S7", "--seeds", "1", "--quiet",
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "source 'S7' is neither a source of the world nor an object class of the house" in err
    assert "the world's sources: ['S1', 'oven']" in err and "object classes present: ['couch', 'oven', 'refrigerator']" in err


def test_world_check_warns_when_the_camera_has_no_objects_to_see(flat, capsys):
    data = world_dict(sources={"S1": [4.0, 1.0]})
    del data["objects"]
    (flat / "bare.yaml").write_text(yaml.safe_dump(data))
    assert main(["world", "check", str(flat / "bare.yaml")]) == 0
    assert "warning: the world lists no objects: the camera variants (semantics, semantics+rooms) will see nothing" \
        in capsys.readouterr().out
    assert main(["world", "check", str(_write(flat))]) == 0
    assert "lists no objects" not in capsys.readouterr().out


def test_too_many_free_cells_is_refused_naming_resolution(flat, tmp_path, capsys, monkeypatch):
    """The flat at its map's 5-cm cells: 8 000 free cells; with a limit below that the runs refuse, world check
    warns."""
    import functools

    import psgsl_pgm.sim as sim

    path = _write(flat, resolution=0.05)
    spec = load_world(path)
    check_free_cells(spec)  # within the default limit
    with pytest.raises(ValueError, match=r"w\.yaml: key 'resolution': 8,\d{3} free cells of 0\.05 m are more than "
                                         r"the 1,000 .*set 'resolution: 0\.15' \(or coarser\)"):
        check_free_cells(spec, limit=1_000)
    monkeypatch.setattr(sim, "check_free_cells", functools.partial(check_free_cells, limit=1_000))
    monkeypatch.setattr(sim, "MAX_FREE_CELLS", 1_000)
    assert main(["search", "--world", str(path), "--seeds", "1", "--quiet", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "key 'resolution'" in err[0] and not (tmp_path / "o").exists()
    assert main(["world", "check", str(path)]) == 0
    assert "warning: 8," in capsys.readouterr().out
