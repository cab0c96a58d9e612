"""Checked reading of the small YAML / image files that the loaders accept.

Every failure is a :class:`ValueError` (or :class:`FileNotFoundError`) whose message names the file and the
field, so that a user with a hand-edited map knows what to fix.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._shared._validate import file_field
from ..io._yaml import load_yaml_mapping

__all__ = ["MAX_IMAGE_PIXELS", "read_yaml_mapping", "number", "number_list", "read_grey_image", "resolve"]


def read_yaml_mapping(path) -> tuple[Path, dict]:
    """Read a YAML file whose top level must be a mapping (the project's safe loader, :mod:`psgsl_pgm.io._yaml`)."""
    return load_yaml_mapping(path)


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


#: Largest image a loader reads, pixels (50 million, e.g. 7000 × 7000: a 350 m square house at 5 cm per cell).
#: Checked on the header, before any pixel is decoded, so a "decompression bomb" header costs nothing.
MAX_IMAGE_PIXELS = 50_000_000


def read_grey_image(path: Path, *, where: str, field: str) -> np.ndarray:
    """(rows, cols) uint8 grey levels of an image file, image row 0 = top (as stored).

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        Not an image, truncated (shorter than its header says, or a PNG without its end), more than
        :data:`MAX_IMAGE_PIXELS` pixels, an empty image or a 16-bit / float mode — naming ``where``, ``field``
        and the image.
    """
    import warnings

    from PIL import Image, UnidentifiedImageError

    if not path.is_file():
        if path.exists():
            raise ValueError(f"{where}: field '{field}' names {path}, which is not a file")
        raise FileNotFoundError(f"{where}: field '{field}' names image {path}, which does not exist")
    at = f"{where}: field '{field}': image {path}"
    try:
        with warnings.catch_warnings():  # our own limit below replaces PIL's warning (an error under pytest)
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(path) as im:
                w, h = im.size
                _check_pixels(w, h, at)
                if im.format == "PNG":
                    im.verify()  # chunk CRCs and the final IEND: a cut PNG is refused even if its pixels decode
            with Image.open(path) as im:
                if im.mode in ("L", "1", "P"):
                    return np.asarray(im.convert("L"), dtype=np.uint8).copy()
                if im.mode in ("I;16", "I;16B", "I;16L", "I", "F"):
                    raise ValueError(f"{at} has mode {im.mode}; expected an 8-bit image")
                arr = np.asarray(im.convert("RGB"), dtype=np.float64).mean(axis=-1)  # map_server averages channels
                return np.rint(arr).astype(np.uint8)
    except Image.DecompressionBombError:
        raise ValueError(f"{at} has more pixels than the {MAX_IMAGE_PIXELS} pixels an image may have") from None
    except UnidentifiedImageError:
        raise ValueError(f"{at} is not a readable image") from None
    except (OSError, SyntaxError, EOFError) as exc:  # PIL: truncated data, bad header, bad chunk (SyntaxError)
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise ValueError(f"{at} is truncated or corrupt ({reason})") from None
    except ValueError as exc:
        if str(exc).startswith(where):
            raise
        raise ValueError(f"{at} is not a readable image ({' '.join(str(exc).split())})") from None


def _check_pixels(w: int, h: int, at: str) -> None:
    if w < 1 or h < 1:
        raise ValueError(f"{at} is empty ({w} x {h} pixels)")
    if w * h > MAX_IMAGE_PIXELS:
        raise ValueError(f"{at} is {w} x {h} = {w * h} pixels, more than the {MAX_IMAGE_PIXELS} pixels an image may have")
