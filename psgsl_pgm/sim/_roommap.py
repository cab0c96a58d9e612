"""Room-category maps: one mask per category, or a segmented image with a grey-level -> room table.

Two YAML layouts are accepted (images resolved relative to the YAML's folder, same pixel frame as the
occupancy map, flipped so that row 0 is the lowest y — as the lab's code reads them):

*Masks* (the layout of MAPIRlab's ``roomMasks.yaml``)::

    categories:
      - name: Kitchen
        mask: Kitchen.png        # pixels > 127 belong to the room
      - name: Bathroom
        mask: Bathroom.png

*Segmented image*::

    image: segmented.pgm
    rooms:                       # grey level -> room name (several levels may share a name)
      50: LivingRoom
      91: Kitchen
    background: [0]              # optional: grey levels that are no room (default [0])
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from .._shared._validate import check_keys
from ..geometry._grid import GridMap
from ._fileio import number, read_grey_image, read_yaml_mapping, resolve

__all__ = ["load_room_map", "save_room_map"]


def load_room_map(yaml_path, *, like: GridMap) -> tuple[np.ndarray, list[str]]:
    """Load a room-category map in the frame of a grid map.

    Parameters
    ----------
    yaml_path : str or Path
        Masks layout (``categories``) or segmented layout (``image`` + ``rooms``), see the module docstring.
    like : GridMap, keyword-only
        The map whose frame the images share; every image must have its shape (W x H pixels).

    Returns
    -------
    room_labels : (H, W) ndarray of int64
        Index into ``room_names`` of every cell; -1 = no room.
    room_names : list of str
        Room categories in order of first appearance in the file.

    Raises
    ------
    FileNotFoundError
        The YAML or an image does not exist.
    ValueError
        Unknown/missing keys, an image of the wrong size, overlapping masks, grey levels missing from the
        table, non-numeric levels — naming the file and the field.

    Examples
    --------
    A round trip through :func:`save_room_map`:

    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from psgsl_pgm.sim import GridMap, load_room_map, save_room_map
    >>> labels = np.array([[0, 0, 1], [-1, 1, 1]])
    >>> with tempfile.TemporaryDirectory() as d:
    ...     path = save_room_map(labels, ["kitchen", "hall"], Path(d) / "rooms.yaml")
    ...     back, names = load_room_map(path, like=GridMap(np.zeros((2, 3), bool), 0.1))
    >>> bool(np.array_equal(back, labels)), names
    (True, ['kitchen', 'hall'])
    """
    if not isinstance(like, GridMap):
        raise TypeError(f"like must be the GridMap whose frame the room images share, got {type(like).__name__}")
    path, data = read_yaml_mapping(yaml_path)
    if "categories" in data:
        return _load_masks(path, data, like)
    if "image" in data or "rooms" in data:
        return _load_segmented(path, data, like)
    raise ValueError(
        f"{path}: expected either a 'categories' list (one mask per room) or 'image' + 'rooms' (segmented "
        f"image), got keys {sorted(map(str, data))}"
    )


def _image_in_frame(path: Path, where: str, field: str, like: GridMap) -> np.ndarray:
    grey = read_grey_image(path, where=where, field=field)
    if grey.shape != like.shape:
        h, w = like.shape
        raise ValueError(
            f"{where}: field '{field}': image {path} is {grey.shape[1]} x {grey.shape[0]} pixels, but the map is "
            f"{w} x {h}"
        )
    return grey[::-1]  # image row 0 is the top (max y)


def _load_masks(path: Path, data: dict, like: GridMap):
    where = str(path)
    check_keys(where, data, required=("categories",))
    cats = data["categories"]
    if not isinstance(cats, list) or not cats:
        raise ValueError(f"{where}: field 'categories' must be a non-empty list, got {cats!r}")
    labels = np.full(like.shape, -1, dtype=np.int64)
    names: list[str] = []
    for i, entry in enumerate(cats):
        field = f"categories[{i}]"
        check_keys(f"{where}: {field}", entry, required=("name", "mask"))
        name = entry["name"]
        if not isinstance(name, str) or not name:
            raise ValueError(f"{where}: field '{field}.name' must be a non-empty string, got {name!r}")
        mask = _image_in_frame(resolve(path, entry["mask"], f"{field}.mask"), where, f"{field}.mask", like) > 127
        if name not in names:
            names.append(name)
        idx = names.index(name)
        clash = mask & (labels >= 0) & (labels != idx)
        if clash.any():
            other = names[labels[clash][0]]
            raise ValueError(
                f"{where}: field '{field}.mask': room '{name}' overlaps room '{other}' on {int(clash.sum())} cells"
            )
        labels[mask] = idx
    return labels, names


def _load_segmented(path: Path, data: dict, like: GridMap):
    where = str(path)
    check_keys(where, data, required=("image", "rooms"), optional=("background",))
    rooms = data["rooms"]
    if not isinstance(rooms, dict) or not rooms:
        raise ValueError(f"{where}: field 'rooms' must be a non-empty mapping grey level -> room name, got {rooms!r}")
    background = data.get("background", [0])
    if not isinstance(background, list):
        background = [background]
    bg = set()
    for i, v in enumerate(background):
        lv = number(where, f"background[{i}]", v, integer=True, nonnegative=True)
        if lv > 255:
            raise ValueError(f"{where}: field 'background[{i}]': grey level must lie in [0, 255], got {v!r}")
        bg.add(int(lv))
    table: dict[int, str] = {}
    for level, name in rooms.items():
        lv = number(where, f"rooms.{level}", level, integer=True, nonnegative=True)
        if lv > 255:
            raise ValueError(f"{where}: field 'rooms.{level}': grey level must lie in [0, 255], got {level!r}")
        if not isinstance(name, str) or not name:
            raise ValueError(f"{where}: field 'rooms.{level}' must be a room name, got {name!r}")
        if int(lv) in bg:
            raise ValueError(f"{where}: field 'rooms.{level}': grey level {int(lv)} is also listed as background")
        table[int(lv)] = name
    grey = _image_in_frame(resolve(path, data["image"], "image"), where, "image", like)
    names = list(dict.fromkeys(table.values()))
    lut = np.full(256, -2, dtype=np.int64)
    for lv, name in table.items():
        lut[lv] = names.index(name)
    for lv in bg:
        lut[lv] = -1
    labels = lut[grey]
    if (labels == -2).any():
        stray = sorted(int(v) for v in np.unique(grey[labels == -2]))
        raise ValueError(
            f"{where}: field 'rooms': the image holds grey levels {stray[:10]} that are neither rooms nor "
            f"background {sorted(bg)}"
        )
    return labels, names


def save_room_map(room_labels, room_names, yaml_path) -> Path:
    """Write a room-category map in the masks layout (one PNG per room next to the YAML).

    Parameters
    ----------
    room_labels : (H, W) array_like of int
        Index into ``room_names`` per cell, -1 = no room; row 0 at the lowest y.
    room_names : sequence of str
    yaml_path : str or Path

    Returns
    -------
    Path
        The YAML path.

    Raises
    ------
    ValueError
        ``room_labels`` is not a 2-D integer array, holds an index outside ``[-1, len(room_names) - 1]``, or
        ``room_names`` repeats a name.

    Examples
    --------
    >>> import tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from psgsl_pgm.sim import save_room_map
    >>> with tempfile.TemporaryDirectory() as d:
    ...     path = save_room_map(np.array([[0, 1]]), ["kitchen", "hall"], Path(d) / "rooms.yaml")
    ...     print(sorted(p.name for p in Path(d).iterdir()))
    ['rooms.yaml', 'rooms_0_kitchen.png', 'rooms_1_hall.png']
    """
    from PIL import Image

    labels = np.asarray(room_labels)
    names = [str(n) for n in room_names]
    if labels.ndim != 2 or not np.issubdtype(labels.dtype, np.integer):
        raise ValueError(f"room_labels must be an (H, W) integer array, got shape {labels.shape}, dtype {labels.dtype}")
    if labels.size and (labels.min() < -1 or labels.max() >= len(names)):
        raise ValueError(f"room_labels must lie in [-1, {len(names) - 1}] for {len(names)} room names")
    if len(set(names)) != len(names):
        raise ValueError(f"room_names must be distinct, got {names}")
    yp = Path(yaml_path)
    cats = []
    for i, name in enumerate(names):
        fname = f"{yp.stem}_{i}_{''.join(ch if ch.isalnum() else '_' for ch in name)}.png"
        Image.fromarray(np.where(labels[::-1] == i, 255, 0).astype(np.uint8)).save(yp.parent / fname)
        cats.append({"name": name, "mask": fname})
    yp.write_text(yaml.safe_dump({"categories": cats}, sort_keys=False))
    return yp
