"""Content keys of stored runs: what a resumed grid compares before it reuses a run file.

A run's result depends on the world (the world file's settings and the bytes of every file it names), on every
option of the run (the experiment's and the search's settings) and on the code (the package version). The
*run key* holds all of it, as a flat mapping from a setting's name to its value::

    {"command": "search", "version": "0.1.0",
     "experiment.speed": 0.25, ..., "search.time_budget": 1000.0, ...,
     "world.wind.speed": 0.2, "world.start": [1.5, 1.5], "world.sources.stove": "oven",
     "world.map": "sha256 9f8e…", "world.map/image": "sha256 1a2b…", "world.rooms/categories[0].mask": …}

A file named by the world file enters by its SHA-256, not by its name, so a copied or moved world with the same
content has the same key, and one changed byte gives another. The world file itself enters by its parsed
content (comments and key order do not matter; ``1`` and ``1.0`` are one number). Every stored run carries its
key, and :func:`key_differences` names each differing setting with both values::

    world.wind.speed: 0.2 → 0.6; world.objects: sha256 1a2b3c4d5e6f… → (none)

Used by :func:`psgsl_pgm.experiment.run_experiment` and :func:`psgsl_pgm.search.run_search_grid` through
:func:`psgsl_pgm.runs._runner.grid_folder`, which refuses a grid whose key differs from its stored runs'.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path

__all__ = ["OMIT_DEFAULT", "digest", "file_sha256", "key_differences", "run_key", "world_key"]

_CHUNK = 1 << 20


def file_sha256(path) -> str:
    """``"sha256 <64 hex digits>"`` of a file's bytes; ``"missing file"`` when there is none."""
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(_CHUNK), b""):
                h.update(block)
    except (FileNotFoundError, IsADirectoryError, NotADirectoryError):
        return "missing file"
    return f"sha256 {h.hexdigest()}"


def _plain(value):
    """JSON types, numbers as float (YAML's ``1`` and ``1.0`` are one setting)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, (int, float)):
        return float(value)
    return str(value)  # dates and other YAML scalars: by their text


def _flatten(value, prefix: str, out: dict) -> dict:
    """``{"a": {"b": [1, {"c": 2}]}}`` -> ``{"a.b": ...}``: mappings by ``.``, lists of mappings by ``[i]``;
    a list of plain values is one value."""
    if isinstance(value, dict):
        if not value:
            out[prefix] = {}
        for k, v in value.items():
            _flatten(v, f"{prefix}.{k}" if prefix else str(k), out)
    elif isinstance(value, list) and any(isinstance(v, (dict, list)) for v in value):
        for i, v in enumerate(value):
            _flatten(v, f"{prefix}[{i}]", out)
    else:
        out[prefix] = value
    return out


def world_key(path=None) -> dict:
    """The world's part of a run key: ``{"world.<setting>": value}`` (see the module docstring).

    Parameters
    ----------
    path : str or Path, optional
        A world file; None: the embedded house (``psgsl_pgm/data/worlds/house.yaml``).

    Raises
    ------
    FileNotFoundError, ValueError
        The world file cannot be read as a YAML mapping (the files it names are hashed as they are; a missing
        one is ``"missing file"``, and :func:`psgsl_pgm.load_world` names the problem).
    """
    from ..io._yaml import load_yaml_mapping
    from ..sim._worldfile import default_world_path, world_files

    path = default_world_path() if path is None else Path(path)
    _, data = load_yaml_mapping(path)
    files = world_files(path)
    data = _plain(data)
    wind = data.get("wind")
    if isinstance(wind, dict) and isinstance(wind.get("gaden_csv"), list):
        del wind["gaden_csv"]  # listed file by file below
    flat = _flatten(data, "", {})
    for label, p in files.items():
        flat[label] = file_sha256(p)
    return {f"world.{k}": v for k, v in flat.items()}


#: a dataclass field with this metadata flag is left out of a key while it holds its default: an option added to
#: a config keys its runs only when used, and the folders stored before it existed still resume
OMIT_DEFAULT = "omit_from_key_when_default"


def _settings(prefix: str, config) -> dict:
    if dataclasses.is_dataclass(config):
        values = dataclasses.asdict(config)
        for f in dataclasses.fields(config):
            if f.metadata.get(OMIT_DEFAULT) and values[f.name] == f.default:
                del values[f.name]
        config = values
    return {f"{prefix}.{k}": v for k, v in _flatten(_plain(dict(config)), "", {}).items()}


def run_key(command: str, world: dict, **configs) -> dict:
    """The run key of a grid (see the module docstring).

    Parameters
    ----------
    command : str
        The grid's kind (``"experiment"``, ``"search"``): runs of different commands never share a folder.
    world : dict
        The world's part, :func:`world_key`.
    **configs
        Every option group of the runs, by name: a dataclass (``experiment=ExperimentConfig(...)``) or a
        mapping of plain values.

    Returns
    -------
    dict
        Flat ``{setting: value}`` of JSON types (the same after a JSON round trip).
    """
    from .. import __version__

    key = {"command": str(command), "version": __version__}
    for name, config in configs.items():
        key.update(_settings(name, config))
    key.update(world)
    return key


def digest(key: dict) -> str:
    """SHA-256 (hex) of a key's canonical JSON."""
    text = json.dumps(key, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _show(value) -> str:
    if value is _ABSENT:
        return "(none)"
    if isinstance(value, str):
        return value[:19] + "…" if value.startswith("sha256 ") else value
    if value is None:
        return "null"
    if isinstance(value, float):
        return repr(int(value)) if value.is_integer() and abs(value) < 1e15 else repr(value)
    return json.dumps(value, separators=(", ", ": "))


_ABSENT = object()


def key_differences(stored: dict, wanted: dict) -> list:
    """Every setting whose value differs, as ``"name: stored → wanted"`` (``(none)`` where a key lacks it),
    in the order of ``wanted`` then the names only ``stored`` has."""
    names = list(wanted) + [k for k in stored if k not in wanted]
    out = []
    for name in names:
        a, b = stored.get(name, _ABSENT), wanted.get(name, _ABSENT)
        if a is _ABSENT or b is _ABSENT or _plain(a) != _plain(b):
            out.append(f"{name}: {_show(a)} → {_show(b)}")
    return out
