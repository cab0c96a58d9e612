"""A mapper's class beliefs p(o_c | z_c) from files: dense arrays (.npy / .npz) and Voxeland instance maps (.json).

These replace the simulated camera when a real semantic map exists (paper Sec. "Model": any observation that
gives p(O_c | z) will do):

* ``.npy`` — one float array (..., k) whose last axis is the ontology's classes, in its order;
* ``.npz`` — arrays ``probs`` (..., k') and ``classes`` (k' names): columns are matched to the ontology's
  classes by name (COCO alias table, :func:`psgsl_pgm.io._coco.canonical_class`). A class the ontology does not
  list is an error naming it and the closest known names (a typo such as ``ovne`` would otherwise move its
  mass to ``other`` without a word); with ``other_classes="lump"`` such columns are added to ``other``
  knowingly (the lab's rule). A detector's ``background`` column always belongs to ``other``;
* ``.json`` — Voxeland's saved instance map (``voxeland_instanceMap.json``)::

      {"instances": {"<id>": {"bbox": {"center": [x, y, z], "size": [sx, sy, sz]},
                              "results": {"<class>": alpha, ...}, "n_observations": n}, ...}}

  Each instance's ``results`` are the concentration parameters α of a Dirichlet over classes (names matched as
  for ``.npz``, ``other_classes`` likewise); its belief is the Dirichlet mean α / Σα. Voxels of the world's grid
  (cell size = the grid's resolution in x, y and z, layers from the lowest to the highest box) inside an
  instance's box take that mean; where boxes overlap their α are added (independent evidence about one voxel);
  voxels in no box — and instances with ``n_observations`` 0 —
  carry no evidence and stay at the class prior. The result is a voxel map (H, W, L, k): the semantic term
  reduces columns, p(s_c | z) = Σ_{v ∈ c} p(s_v | z) (Sec. "Voxelized Scene Representations",
  ``semantic_source_probability(..., column_axis=2)``).
"""

from __future__ import annotations

import difflib
import json
import math
from pathlib import Path

import numpy as np

from .._shared._validate import check_distribution
from ._coco import canonical_class
from ._npyfile import READ_ERRORS, load_npy

__all__ = ["MAX_VOXEL_BYTES", "read_class_beliefs", "VoxelMap", "voxeland_class_beliefs"]

OTHER = "other"
#: A detector's "no object" class: always part of ``other``.
BACKGROUND = "background"
#: What to do with a class the ontology does not list: refuse it (default) or add it to ``other``.
OTHER_CLASSES = ("error", "lump")


def check_other_classes(value) -> str:
    """The ``other_classes`` option: ``"error"`` or ``"lump"`` (TypeError / ValueError otherwise)."""
    if not isinstance(value, str):
        raise TypeError(f"other_classes must be one of {list(OTHER_CLASSES)}, got {type(value).__name__} {value!r}")
    if value not in OTHER_CLASSES:
        raise ValueError(f"other_classes must be one of {list(OTHER_CLASSES)}, got {value!r}")
    return value


def read_class_beliefs(path, classes, *, grid=None, class_prior=None, other_classes: str = "error") -> np.ndarray:
    """Class beliefs from a ``.npy``, ``.npz`` or Voxeland ``.json`` file, in the order of ``classes``.

    Parameters
    ----------
    path : str or Path
    classes : sequence of str
        The ontology's classes (``"other"`` among them for name matching).
    grid : GridMap, optional, keyword-only
        The working grid (``shape``, ``resolution``, ``origin``); required for Voxeland files.
    class_prior : (k,) array_like, optional, keyword-only
        p(o) for voxels without evidence; required for Voxeland files.
    other_classes : {"error", "lump"}, keyword-only
        A class name of the file that the ontology lacks: an error naming it and the closest known names
        (default), or added to ``other`` (``"lump"``, the lab's rule, for a mapper with more classes).

    Returns
    -------
    (..., k) ndarray of float64
        Every cell (voxel) a distribution over ``classes``; (H, W, L, k) for Voxeland files.

    Raises
    ------
    ValueError
        Unreadable files, wrong shapes, unknown classes, beliefs that are not distributions — naming the file.
    """
    p = Path(path)
    classes = tuple(classes)
    other_classes = check_other_classes(other_classes)
    if not p.is_file():
        raise ValueError(f"{p}: no such class-belief file")
    suffix = p.suffix.lower()
    if suffix == ".json":
        if grid is None or class_prior is None:
            raise ValueError(f"{p}: a Voxeland instance map needs the grid it is read onto (a world or a map)")
        try:
            data = json.loads(p.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise ValueError(f"{p}: not a readable JSON file ({exc})") from None
        return voxeland_class_beliefs(data, classes, grid=grid, class_prior=class_prior, where=str(p),
                                      other_classes=other_classes)
    try:
        loaded = load_npy(p, str(p))
    except READ_ERRORS as exc:
        raise ValueError(f"{p}: not a .npy/.npz array file ({' '.join(str(exc).split())})") from None
    if suffix == ".npz" or not isinstance(loaded, np.ndarray):
        with loaded as z:
            missing = [k for k in ("probs", "classes") if k not in z.files]
            if missing:
                raise ValueError(f"{p}: an .npz of class beliefs needs arrays 'probs' and 'classes'; missing {missing}"
                                 f" (has {z.files})")
            try:
                probs, names = z["probs"], z["classes"]
            except READ_ERRORS as exc:
                raise ValueError(f"{p}: not a readable .npz array file ({' '.join(str(exc).split())})") from None
        if names.ndim != 1 or names.dtype.kind not in "US":
            raise ValueError(f"{p}: array 'classes' must be a 1-D array of names, got {names.dtype} {names.shape}")
        return _by_name(p, _real(p, probs), [str(n) for n in names], classes, other_classes)
    probs = _real(p, loaded)
    if probs.ndim < 2 or probs.shape[-1] != len(classes):
        raise ValueError(f"{p}: class beliefs must have shape (..., {len(classes)}) for the classes {list(classes)}, "
                         f"got {probs.shape} (an .npz with a 'classes' array may list its own classes)")
    return _checked(p, probs)


def _real(p: Path, arr) -> np.ndarray:
    a = np.asarray(arr)
    if a.dtype.kind not in "fiu" or a.dtype == bool:
        raise ValueError(f"{p}: class beliefs must be a real numeric array, got dtype {a.dtype}")
    return a.astype(np.float64)


def _checked(p: Path, probs: np.ndarray) -> np.ndarray:
    try:
        check_distribution(probs, f"class beliefs in {p}")
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{p}: {exc}") from None
    return probs


def _by_name(p: Path, probs: np.ndarray, names, classes, other_classes: str) -> np.ndarray:
    if probs.ndim < 2 or probs.shape[-1] != len(names):
        raise ValueError(f"{p}: 'probs' must have shape (..., {len(names)}) for its {len(names)} 'classes', got "
                         f"{probs.shape}")
    index = _class_index(f"{p}: array 'classes'", names, classes, other_classes)
    out = np.zeros(probs.shape[:-1] + (len(classes),))
    for j, i in enumerate(index):  # k' columns, not cells
        out[..., i] += probs[..., j]
    return _checked(p, out)


def _class_index(where, names, classes, other_classes: str = "error") -> list:
    """Column of each name among ``classes`` (COCO aliases matched); unknown names refused or sent to ``other``."""
    lookup = {canonical_class(c): i for i, c in enumerate(classes)}
    if OTHER not in lookup:
        raise ValueError(f"{where}: the ontology's classes {list(classes)} have no '{OTHER}'")
    lookup.setdefault(BACKGROUND, lookup[OTHER])  # a detector's background is part of "other" (the lab's rule)
    out, seen = [], set()
    for n in names:
        c = canonical_class(n)
        if c in seen and c in lookup and c != OTHER:
            raise ValueError(f"{where}: class {n!r} appears twice (aliases included)")
        seen.add(c)
        out.append(lookup.get(c, lookup[OTHER]))
    unknown = [n for n in names if canonical_class(n) not in lookup]
    if unknown and other_classes == "error":
        text = unknown_names(unknown, classes, "class", "the ontology does not list")
        raise ValueError(f"{where}: {text}; to add such classes to '{OTHER}' knowingly, pass "
                         "other_classes=\"lump\" (psgsl estimate --other-classes; world file: other_classes: lump)")
    return out


def unknown_names(unknown, known, what: str, clause: str, *, listed: str | None = None) -> str:
    """``"class the ontology does not list: 'ovne' — did you mean 'oven'? (known: ...)"`` for names absent from
    ``known`` (difflib's closest, then the same ignoring case and spaces); ``listed`` replaces the known list."""
    known = [str(k) for k in known]
    parts = []
    for n in unknown:
        close = difflib.get_close_matches(str(n), known, n=2, cutoff=0.6)
        if not close:  # case and spacing: "living room" vs "LivingRoom"
            key = {"".join(ch for ch in k.lower() if ch.isalnum()): k for k in known}
            close = difflib.get_close_matches("".join(ch for ch in str(n).lower() if ch.isalnum()), list(key), n=2,
                                              cutoff=0.6)
            close = [key[c] for c in close]
        hint = f" — did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
        parts.append(f"{n!r}{hint}")
    plural = ("es" if what.endswith("s") else "s") if len(unknown) > 1 else ""
    return f"{what}{plural} {clause}: " + "; ".join(parts) + f" (known: {listed or ', '.join(known)})"


#: Largest dense voxel array :func:`voxeland_class_beliefs` builds (bytes of the (H, W, L, k) float64 result).
MAX_VOXEL_BYTES = 1 << 30


def voxeland_class_beliefs(data, classes, *, grid, class_prior, where: str = "Voxeland map",
                           other_classes: str = "error", max_bytes: int = MAX_VOXEL_BYTES) -> np.ndarray:
    """Voxel class beliefs (H, W, L, k) from a parsed Voxeland instance map (see the module docstring).

    Parameters
    ----------
    data : dict
        ``{"instances": {id: {"bbox": {"center", "size"}, "results": {class: alpha}, "n_observations"}}}``.
    classes : sequence of str
    grid : GridMap, keyword-only
        Voxels are ``grid.resolution`` on a side; columns are the grid's cells.
    class_prior : (k,) array_like, keyword-only
    where : str, keyword-only
        Name for messages.
    other_classes : {"error", "lump"}, keyword-only
        A class the ontology lacks: refused, naming the closest known names (default), or added to ``other``.
    max_bytes : int, keyword-only
        Largest result allowed (default :data:`MAX_VOXEL_BYTES`, 1 GiB). A finer grid is refused before anything
        is allocated: at 1 cm a house's voxel map runs to tens of GB. :func:`psgsl_pgm.core._voxeland.voxeland_column_weights`
        gives the semantic term of any grid in bounded memory.

    Returns
    -------
    (H, W, L, k) ndarray of float64
        Dirichlet means inside boxes, the prior elsewhere. Cost: O(H · W · L · k) memory, one slice update per
        instance.

    Raises
    ------
    ValueError
        A malformed map (naming ``where`` and the key), or a voxel array above ``max_bytes`` (naming the
        resolution that would fit).
    """
    vox = VoxelMap.parse(data, classes, grid=grid, class_prior=class_prior, where=where,
                         other_classes=other_classes)
    need = vox.nbytes()
    if need > max_bytes:
        raise ValueError(
            f"{where}: read onto {grid.shape[0]} x {grid.shape[1]} cells of {grid.resolution:g} m with "
            f"{vox.layers} layers, the voxel map needs {need / 2**30:.1f} GiB (limit {max_bytes / 2**30:.1f} GiB); "
            f"use a coarser resolution (>= {vox.resolution_within(max_bytes):.3g} m)")
    return vox.rows(0, grid.shape[0])


class VoxelMap:
    """A parsed Voxeland map on a grid: instance boxes and their α, the layers, and voxel rows on demand."""

    def __init__(self, boxes, prior, grid, z0, layers):
        self.boxes, self.prior, self.grid, self.z0, self.layers = boxes, prior, grid, z0, layers

    @classmethod
    def parse(cls, data, classes, *, grid, class_prior, where: str, other_classes: str) -> "VoxelMap":
        other_classes = check_other_classes(other_classes)
        prior = np.asarray(class_prior, dtype=np.float64)
        if prior.shape != (len(classes),):
            raise ValueError(f"class_prior must have shape ({len(classes)},), got {prior.shape}")
        if not isinstance(data, dict):
            raise ValueError(f"{where}: expected a JSON object with key 'instances', got {type(data).__name__}")
        if "instances" not in data:
            raise ValueError(f"{where}: missing key 'instances'")
        inst = data["instances"]
        if not isinstance(inst, dict):
            raise ValueError(f"{where}: key 'instances' must map instance ids to instances, got {type(inst).__name__}")
        boxes = [box for iid, it in inst.items()
                 if (box := _instance_box(where, f"instances.{iid}", it, classes, other_classes)) is not None]
        step = float(grid.resolution)
        if boxes:
            z0 = min(c[2] - s[2] / 2 for c, s, _ in boxes)
            z1 = max(c[2] + s[2] / 2 for c, s, _ in boxes)
        else:
            z0, z1 = 0.0, step
        layers = max(1, int(math.ceil((z1 - z0) / step - 1e-9)))
        return cls(boxes, prior, grid, z0, layers)

    def nbytes(self) -> int:
        """Bytes of the dense (H, W, L, k) float64 voxel map."""
        h, w = self.grid.shape
        return h * w * self.layers * len(self.prior) * 8

    def resolution_within(self, max_bytes: int) -> float:
        """The resolution at which the dense voxel map would fit ``max_bytes`` (cells and layers scale as 1/r³)."""
        return float(self.grid.resolution) * (self.nbytes() / max_bytes) ** (1 / 3)

    def _spans(self, centre, size):
        h, w = self.grid.shape
        step = float(self.grid.resolution)
        ox, oy = self.grid.origin
        lo, hi = centre - size / 2, centre + size / 2
        return (_span(lo[1], hi[1], oy, step, h), _span(lo[0], hi[0], ox, step, w),
                _span(lo[2], hi[2], self.z0, step, self.layers))

    def reach(self) -> tuple[int, int, int, int]:
        """Rows [r0, r1) and columns [c0, c1) of the grid that some box reaches (empty when none does)."""
        h, w = self.grid.shape
        r0, r1, c0, c1 = h, 0, w, 0
        for centre, size, _ in self.boxes:
            (a, b), (c, d), _ = self._spans(centre, size)
            if b > a and d > c:
                r0, r1, c0, c1 = min(r0, a), max(r1, b), min(c0, c), max(c1, d)
        return r0, r1, c0, c1

    def rows(self, r0: int, r1: int, c0: int = 0, c1: int | None = None) -> np.ndarray:
        """Voxel beliefs of grid rows [r0, r1) and columns [c0, c1): (r1 - r0, c1 - c0, L, k) float64."""
        c1 = self.grid.shape[1] if c1 is None else c1
        alpha = np.zeros((r1 - r0, c1 - c0, self.layers, len(self.prior)))
        for centre, size, a in self.boxes:  # one slice per instance: voxels whose centre lies in the box
            (ra, rb), (ca, cb), (la, lb) = self._spans(centre, size)
            ra, rb, ca, cb = max(ra, r0), min(rb, r1), max(ca, c0), min(cb, c1)
            if rb > ra and cb > ca:
                alpha[ra - r0:rb - r0, ca - c0:cb - c0, la:lb] += a
        total = alpha.sum(axis=-1, keepdims=True)
        np.divide(alpha, total, out=alpha, where=total > 0)  # Dirichlet mean, in place
        alpha[total[..., 0] == 0] = self.prior  # no evidence: p(o)
        return alpha


def _instance_box(where, key, it, classes, other_classes):
    """(centre, size, α) of one instance, or None when it carries no evidence."""
    if not isinstance(it, dict):
        raise ValueError(f"{where}: key '{key}' must be an object, got {it!r}")
    for req in ("bbox", "results", "n_observations"):
        if req not in it:
            raise ValueError(f"{where}: key '{key}' lacks '{req}'")
    bbox = it["bbox"]
    if not isinstance(bbox, dict) or "center" not in bbox or "size" not in bbox:
        raise ValueError(f"{where}: key '{key}.bbox' must have 'center' and 'size', got {bbox!r}")
    centre = _vec3(where, f"{key}.bbox.center", bbox["center"])
    size = _vec3(where, f"{key}.bbox.size", bbox["size"])
    if min(size) <= 0:
        raise ValueError(f"{where}: key '{key}.bbox.size' must be positive, got {bbox['size']!r}")
    nobs = it["n_observations"]
    if isinstance(nobs, bool) or not isinstance(nobs, int) or nobs < 0:
        raise ValueError(f"{where}: key '{key}.n_observations' must be a whole number >= 0, got {nobs!r}")
    res = it["results"]
    if not isinstance(res, dict):
        raise ValueError(f"{where}: key '{key}.results' must map classes to Dirichlet alphas, got {res!r}")
    names = list(res)
    alphas = np.zeros(len(classes))
    for j, name in zip(_class_index(f"{where}: key '{key}.results'", names, classes, other_classes), names):
        a = res[name]
        if isinstance(a, bool) or not isinstance(a, (int, float)) or not math.isfinite(a) or a < 0:
            raise ValueError(f"{where}: key '{key}.results.{name}' must be a finite alpha >= 0, got {a!r}")
        alphas[j] += float(a)
    if nobs == 0 or alphas.sum() == 0:
        return None  # no evidence
    return np.array(centre), np.array(size), alphas


def _span(lo: float, hi: float, origin: float, step: float, n: int) -> tuple[int, int]:
    """Indices [a, b) of cells whose centre origin + (i + 0.5) step lies in [lo, hi] (at least the centre's)."""
    a = int(math.ceil((lo - origin) / step - 0.5 - 1e-9))
    b = int(math.floor((hi - origin) / step - 0.5 + 1e-9)) + 1
    if b <= a:  # a box thinner than a cell: the cell of its centre
        a = int(math.floor(((lo + hi) / 2 - origin) / step))
        b = a + 1
    return max(a, 0), min(max(b, 0), n)


def _vec3(where: str, key: str, value) -> list:
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise ValueError(f"{where}: key '{key}' must be [x, y, z], got {value!r}")
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ValueError(f"{where}: key '{key}' must hold finite numbers, got {value!r}")
        out.append(float(v))
    return out
