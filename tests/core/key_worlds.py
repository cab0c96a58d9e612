"""A small world file that names every kind of file a world can name (for the run-key tests), and one-byte edits
that keep each file valid."""

from __future__ import annotations

import hashlib

import numpy as np
import yaml

ONTOLOGY = "Gases:\n  - gas: smoke\n    probs: {oven: 0.6, microwave: 0.3, other: 0.1}\n"
ROOM_CLASSES = "number_classes: 10\nroom_categories:\n  Kitchen: {oven: 0.3}\n  Bedroom: {oven: 0.01}\n"


def write_pgm(path, grey: np.ndarray) -> None:
    """A binary PGM (P5) of (rows, cols) uint8 grey levels, row 0 at the top."""
    h, w = grey.shape
    path.write_bytes(f"P5\n{w} {h}\n255\n".encode("ascii") + np.ascontiguousarray(grey, np.uint8).tobytes())


def write_full_world(d, *, beliefs: bool = True) -> tuple:
    """A 5 m x 3 m flat at 0.1 m (a kitchen with an oven, a bedroom with a bed, a door between them) whose world
    file names a map (+ its PGM), room masks (PGM), objects, a lab-format ontology, a room table, a source-region
    mask, a mapper's class beliefs (.npy) and two GADEN wind CSVs.

    Returns ``(world_path, {label: file})`` with the labels of :func:`psgsl_pgm.sim._worldfile.world_files`."""
    from psgsl_pgm import load_world
    from psgsl_pgm.sim import GridMap, SceneObject, box_footprint, save_objects, save_ros_map

    d.mkdir(parents=True, exist_ok=True)
    g = GridMap(np.zeros((30, 50), bool), 0.1)
    x, y = g.cell_centres()[..., 0], g.cell_centres()[..., 1]
    walls = (x < 0.2) | (x > 4.8) | (y < 0.2) | (y > 2.8) | ((x > 2.4) & (x < 2.6) & ~((y > 1.0) & (y < 2.0)))
    save_ros_map(g.with_occupancy(walls), d / "map.yaml")
    masks = {"Kitchen": ~walls & (x < 2.5), "Bedroom": ~walls & (x >= 2.5)}
    cats = []
    for name, m in masks.items():
        write_pgm(d / f"{name}.pgm", np.where(m, 255, 0)[::-1])  # image row 0 = the top (max y)
        cats.append({"name": name, "mask": f"{name}.pgm"})
    (d / "rooms.yaml").write_text(yaml.safe_dump({"categories": cats}, sort_keys=False))
    save_objects([SceneObject("oven", box_footprint((1.0, 0.5), (0.4, 0.4)), (0.0, 0.9)),
                  SceneObject("bed", box_footprint((4.0, 2.2), (1.0, 0.8)), (0.0, 0.6))], d / "objects.yaml")
    (d / "ontology.yaml").write_text(ONTOLOGY)
    (d / "rooms_p.yaml").write_text(ROOM_CLASSES)
    write_pgm(d / "region.pgm", np.where(~walls, 255, 0)[::-1])
    header = '"U:0","U:1","U:2","Points:0","Points:1","Points:2"\n'
    pts = g.cell_centres().reshape(-1, 2)
    for i, u in enumerate((0.3, 0.2)):
        (d / f"wind_{i}.csv").write_text(header + "".join(f"{u},0.05,0,{px:.2f},{py:.2f},0.5\n" for px, py in pts))
    world = {"map": "map.yaml", "rooms": "rooms.yaml", "objects": "objects.yaml", "ontology": "ontology.yaml",
             "room_classes": "rooms_p.yaml", "gas": "smoke", "source_region": "region.pgm",
             "wind": {"gaden_csv": ["wind_0.csv", "wind_1.csv"], "height": 0.5, "period": 2.0,
                      "windows": [{"role": "inlet", "from": [0.1, 1.0], "to": [0.1, 2.0]},
                                  {"role": "outlet", "from": [4.9, 1.0], "to": [4.9, 2.0]}]},
             "start": [1.5, 1.5], "sources": {"stove": "oven", "corner": [4.2, 0.6]}}
    (d / "world.yaml").write_text(yaml.safe_dump(world))
    files = {"map": d / "map.yaml", "map/image": d / "map.pgm", "rooms": d / "rooms.yaml",
             "rooms/categories[0].mask": d / "Kitchen.pgm", "rooms/categories[1].mask": d / "Bedroom.pgm",
             "objects": d / "objects.yaml", "ontology": d / "ontology.yaml", "room_classes": d / "rooms_p.yaml",
             "source_region": d / "region.pgm", "wind.gaden_csv[0]": d / "wind_0.csv",
             "wind.gaden_csv[1]": d / "wind_1.csv"}
    if beliefs:
        k = len(load_world(d / "world.yaml").ontology.classes)
        np.save(d / "beliefs.npy", np.random.default_rng(0).dirichlet(np.ones(k), size=(30, 50)))
        world["semantic_map"] = "beliefs.npy"
        (d / "world.yaml").write_text(yaml.safe_dump(world))
        files["semantic_map"] = d / "beliefs.npy"
    return d / "world.yaml", files


def one_byte_edit(path) -> bytes:
    """Change one byte of ``path`` so that the file stays valid and means nearly the same; returns the old bytes.

    YAML: one more newline at the end. PGM: one pixel one grey level darker (254 -> 253, or 255 -> 254: free stays
    free, a mask pixel stays in its mask). .npy: the lowest mantissa byte of the last float. CSV: one digit."""
    old = path.read_bytes()
    data = bytearray(old)
    suffix = path.suffix
    if suffix == ".yaml":
        data += b"\n"
    elif suffix == ".pgm":
        start = len(data) - int(np.prod([int(v) for v in old.split(b"\n")[1].split()]))
        pixels = np.frombuffer(bytes(data[start:]), np.uint8)
        i = int(np.flatnonzero(pixels >= 254)[len(pixels[pixels >= 254]) // 2])
        data[start + i] -= 1
    elif suffix == ".npy":
        data[-8] ^= 1
    elif suffix == ".csv":
        i = data.index(b"0.05")
        data[i + 3] = ord("6")
    else:
        raise ValueError(f"no one-byte edit for {path}")
    assert len(data) - len(old) in (0, 1) and sum(a != b for a, b in zip(old, data)) <= 1
    path.write_bytes(bytes(data))
    return old


def sha(path_or_bytes) -> str:
    data = path_or_bytes if isinstance(path_or_bytes, bytes) else path_or_bytes.read_bytes()
    return hashlib.sha256(data).hexdigest()
