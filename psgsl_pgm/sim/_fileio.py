"""Checked reading of the small YAML / image files that the loaders accept.

Every failure is a :class:`ValueError` (or :class:`FileNotFoundError`) whose message names the file and the
field, so that a user with a hand-edited map knows what to fix.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._yaml import load_yaml_mapping

from .._validate import file_field

__all__ = ["read_yaml_mapping", "check_keys", "number", "number_list", "read_grey_image", "resolve"]


def read_yaml_mapping(path) -> tuple[Path, dict]:
    """Read a YAML file whose top level must be a mapping (the project's safe loader, :mod:`psgsl_pgm._yaml`)."""
    return load_yaml_mapping(path)


def check_keys(where: str, data: dict, *, required=(), optional=()) -> None:
    """Refuse unknown and missing keys of a mapping read from ``where``."""
    if not isinstance(data, dict):
        raise ValueError(f"{where}: expected a mapping, got {type(data).__name__} {data!r}")
    unknown = sorted(str(k) for k in data if k not in required and k not in optional)
    if unknown:
        raise ValueError(
            f"{where}: unknown key(s) {unknown}; allowed keys are {sorted(set(required) | set(optional))}"
        )
    missing = [k for k in required if k not in data]
    if missing:
        raise ValueError(f"{where}: missing required key(s) {missing}")


number = file_field  # the shared vocabulary's reader of a number from a file field


def number_list(where: str, field: str, value, *, length=None, min_length=None) -> list[float]:
    """A list of finite numbers from a YAML field."""
    if not isinstance(value, (list, tuple)):
        raise ValueError(f"{where}: field '{field}' must be a list of numbers, got {type(value).__name__} {value!r}")
    if length is not None and len(value) not in (length if isinstance(length, tuple) else (length,)):
        raise ValueError(f"{where}: field '{field}' must have {length} entries, got {len(value)}: {value!r}")
    if min_length is not None and len(value) < min_length:
        raise ValueError(f"{where}: field '{field}' must have at least {min_length} entries, got {value!r}")
    return [number(where, f"{field}[{i}]", v) for i, v in enumerate(value)]


def resolve(yaml_path: Path, name, field: str) -> Path:
    """Resolve a file name given in a YAML field relative to the YAML's folder."""
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"{yaml_path}: field '{field}' must be a file name, got {name!r}")
    p = Path(name)
    return p if p.is_absolute() else yaml_path.parent / p


def read_grey_image(path: Path, *, where: str, field: str) -> np.ndarray:
    """(rows, cols) uint8 grey levels of an image file, image row 0 = top (as stored)."""
    from PIL import Image, UnidentifiedImageError

    if not path.is_file():
        raise FileNotFoundError(f"{where}: field '{field}' names image {path}, which does not exist")
    try:
        with Image.open(path) as im:
            if im.mode in ("L", "1", "P"):
                im = im.convert("L")
            elif im.mode in ("I;16", "I;16B", "I", "F"):
                raise ValueError(f"{where}: field '{field}': image {path} has mode {im.mode}; expected 8-bit")
            else:  # colour: map_server averages the channels
                arr = np.asarray(im.convert("RGB"), dtype=np.float64).mean(axis=-1)
                return np.rint(arr).astype(np.uint8)
            return np.asarray(im, dtype=np.uint8).copy()
    except UnidentifiedImageError:
        raise ValueError(f"{where}: field '{field}': {path} is not a readable image") from None
