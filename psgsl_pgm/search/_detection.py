r"""The detection model of the closed loop: when does the robot *find* the source, and what does "not found"
say about where it is.

One model serves three purposes, so that they cannot disagree:

1. the **success rule** of a simulated search (the episode ends when the robot finds the true source),
2. the **"not found here"** update of the belief after every move (:meth:`DetectionModel.not_found_log_likelihood`),
3. the policies' **P_f**, the probability of finding the source at a candidate pose
   (:meth:`DetectionModel.found_probability`).

**Found regions.** Under the hypothesis "the source is in cell c", the robot at position x finds it iff

.. math:: \min_{y \in R(c)} \lVert x - y \rVert \le r, \qquad
          R(c) = \begin{cases} \text{footprint of the object that owns } c & c \text{ lies in a known object} \\
                               \{c\} & \text{otherwise,} \end{cases}

with r = ``found_radius`` and distances between cell centres (y runs over the centres of the footprint's cells).
A point source is found within a disc of radius r; an object source (an oven, a bed) anywhere within r of its
footprint — a robot cannot drive into an oven, and its nearest drivable cell may be farther than r from the
oven's centre.

**What the robot may know.** The footprints come from the robot's own map: the same object footprints that the
map marks as obstacles (:attr:`psgsl_pgm.sim.House.robot_obstacles` = walls | furniture | windows, with
furniture the union of the objects' footprints; a map that draws furniture as occupied, as the lab's occupancy
maps do, marks the same cells). A footprint is the object's whole outline on the grid, also where the map draws it
as occupied: a robot within r of any part of the oven has found the oven. A mapping robot segments its obstacles
into objects (each piece of furniture is one footprint); it does *not* learn their classes from the map (those come
only through the noisy camera and the class beliefs), nor which object emits. Where footprints overlap (an oven
on a countertop) a cell belongs to the object drawn last, the object the house's class map shows there. The
simulator's truth enters only through the success rule's one argument, the true source's hypothesis
(:meth:`DetectionModel.source_cell`).

**A detector that can miss.** With ``miss_probability`` m, a move whose path comes within r of R(c) finds a
source in c with probability 1 − m (one detection trial per move: the drive to a stop and the stop itself).
The likelihood of "not found" after a move with path points x_1 … x_p is therefore

.. math:: P(\bar F \mid s = c) = \begin{cases} m & \exists k: x_k \text{ within } r \text{ of } R(c) \\
                                             1 & \text{otherwise,} \end{cases}

(0 inside the region for the default m = 0, the deterministic rule), and P_f(x) = (1 − m) Σ_{c: x within r of
R(c)} p(c).
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np
import scipy.sparse as sp

from .._shared._memo import ContentCache, content_digest
from .._shared._validate import bool_mask, positive, unit_interval

__all__ = ["DetectionModel"]

_PATHS_MAX = 1024  # paths whose found hypotheses are kept (the drives between a run's stops: tens to hundreds)

#: Detection models of the houses met last in the process (DetectionModel.shared), keyed by content.
_SHARED_MODELS = ContentCache(maxsize=8)

#: Point-centre pairs compared at once: the (points, centres, 2) differences stay within 32 MiB however many
#: cells a map has (a 1-cm house has 10⁵-10⁶ cells and footprints of thousands of cells).
_PAIRS_AT_ONCE = 1 << 21


def _d2(points: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """Squared distances, broadcast; the one formula of every "within r" test of this module."""
    return ((points - centres) ** 2).sum(axis=-1)


def _near_any(points: np.ndarray, centres: np.ndarray, r2: float) -> np.ndarray:
    """(p,) bool: whether each point lies within √r2 of some centre (:func:`_d2`, in blocks of points so that
    memory is bounded by :data:`_PAIRS_AT_ONCE`, not by p × the number of centres)."""
    out = np.empty(len(points), dtype=bool)
    step = max(1, _PAIRS_AT_ONCE // max(len(centres), 1))
    for i in range(0, len(points), step):
        out[i : i + step] = (_d2(points[i : i + step, None, :], centres[None, :, :]) <= r2).any(axis=1)
    return out


class DetectionModel:
    """Found regions of every source hypothesis on a grid (see the module docstring).

    Parameters
    ----------
    grid : psgsl_pgm.GridMap
        The map; hypotheses are its H·W cells (row-major flat indices).
    found_radius : float
        r, m (0: only the hypothesis's own cell centre, or its footprint's cells).
    footprints : sequence of (H, W) bool, keyword-only
        Known object footprints, in drawing order (a later footprint owns shared cells).
    miss_probability : float, keyword-only
        m in [0, 1): probability that a move within reach of the source does not find it.

    Attributes
    ----------
    owner : (H·W,) ndarray of int
        Index of the footprint that owns each cell, −1 where none does.
    """

    def __init__(self, grid, found_radius: float, *, footprints=(), miss_probability: float = 0.0):
        self.grid = grid
        self.shape = tuple(grid.shape)
        self.found_radius = r = positive(found_radius, "found_radius", "metres", allow_zero=True)
        self.miss_probability = unit_interval(miss_probability, "miss_probability", high_open=True)
        self.centres = grid.cell_centres().reshape(-1, 2)
        n = self.centres.shape[0]
        masks = [bool_mask(m, f"footprints[{j}]", self.shape).ravel() for j, m in enumerate(footprints)]
        owner = np.full(n, -1, dtype=np.int64)
        for j, m in enumerate(masks):  # loop over objects (tens): later objects own shared cells
            owner[m] = j
        self.owner = owner
        self.owner.flags.writeable = False
        self.footprints = tuple(masks)
        cells = [np.flatnonzero(m) for m in masks]
        self._sizes = np.array([c.size for c in cells], dtype=np.int64)
        self._fp_points = self.centres[np.concatenate(cells)] if cells else np.empty((0, 2))
        self._fp_starts = np.concatenate([[0], np.cumsum(self._sizes)[:-1]]) if cells else np.empty(0, np.int64)
        # each footprint's bounding box of cell centres, widened by r (and, for rounding, by 1e-9 of the largest
        # length involved): a point outside it is farther than r from every centre of the footprint
        pad = r + 1e-9 * (1.0 + r + (float(np.abs(self.centres).max()) if n else 0.0))
        self._fp_boxes = np.array([[*(self.centres[c].min(axis=0) - pad), *(self.centres[c].max(axis=0) + pad)]
                                   if c.size else [np.inf, np.inf, -np.inf, -np.inf] for c in cells]).reshape(-1, 4)
        owned = owner >= 0
        self._owned = sp.csr_matrix((np.ones(int(owned.sum())), (owner[owned], np.flatnonzero(owned))),
                                    shape=(len(masks), n))  # (J, n) indicator of the cells each object owns
        reach = int(np.ceil(r / grid.resolution)) + 1
        dr, dc = np.mgrid[-reach : reach + 1, -reach : reach + 1]
        self._offsets = np.stack([dr.ravel(), dc.ravel()], axis=1)
        self._rows_cache: dict = {}
        self._paths: OrderedDict = OrderedDict()  # path points -> the hypotheses found along it (_found_along)

    @property
    def content_key(self) -> str:
        """A digest of what decides which hypotheses a point finds: the grid's frame, the found radius and the
        footprints (not the miss probability); equal models of equal houses have equal keys (a free space's
        finder cells and findable masks are cached under it, :class:`psgsl_pgm.search.FreeSpace`)."""
        key = self.__dict__.get("_content_key")
        if key is None:
            fp = np.packbits(np.stack(self.footprints)) if self.footprints else np.empty(0, np.uint8)
            key = self._content_key = content_digest(
                self.shape, float(self.grid.resolution),
                tuple(np.asarray(self.grid.origin, dtype=np.float64).ravel().tolist()), float(self.found_radius),
                len(self.footprints), fp)
        return key

    @classmethod
    def from_house(cls, house, found_radius: float, *, miss_probability: float = 0.0) -> "DetectionModel":
        """The model on a house's map with its objects' whole footprints (:meth:`SceneObject.mask`, the furniture
        of the robot's obstacle map, including cells the map draws as occupied)."""
        return cls(house.grid, found_radius, footprints=[o.mask(house.grid) for o in house.objects],
                   miss_probability=miss_probability)

    @classmethod
    def shared(cls, house, found_radius: float, *, miss_probability: float = 0.0) -> "DetectionModel":
        """:meth:`from_house`, one model per house content (grid, object footprints), radius and miss probability
        in the process, shared by every run there: its cached rows and paths are functions of that content alone,
        so a run gets the same numbers from a shared model as from a new one. Eight models are kept."""
        grid = house.grid
        key = content_digest(grid.occupancy, float(grid.resolution),
                             tuple(np.asarray(grid.origin, dtype=np.float64).ravel().tolist()), found_radius,
                             miss_probability, len(house.objects), *(o.footprint for o in house.objects))
        return _SHARED_MODELS.get(key, lambda: cls.from_house(house, found_radius,
                                                               miss_probability=miss_probability))

    def region_mask(self, source_cell: int) -> np.ndarray:
        """(H, W) bool: the found region R(c) of the hypothesis ``source_cell`` (module docstring): the footprint of
        the object that owns the cell, or the cell itself."""
        c = int(source_cell)
        j = int(self.owner[c])
        if j >= 0:
            return self.footprints[j].reshape(self.shape).copy()
        out = np.zeros(self.centres.shape[0], dtype=bool)
        out[c] = True
        return out.reshape(self.shape)

    # --- the rule ------------------------------------------------------------------------------------------
    def _points(self, points) -> np.ndarray:
        p = np.asarray(points, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 2:
            raise ValueError(f"points must have shape (p, 2) (x, y in metres), got shape {p.shape}")
        return p

    def near_footprints(self, points) -> np.ndarray:
        """(p, J) bool: whether each point lies within r of each footprint (of any of its cells' centres)."""
        p = self._points(points)
        out = np.zeros((len(p), len(self._sizes)), dtype=bool)
        if self._fp_points.shape[0] and len(p):
            b = self._fp_boxes
            inside = ((p[:, :1] >= b[:, 0]) & (p[:, :1] <= b[:, 2]) & (p[:, 1:] >= b[:, 1]) & (p[:, 1:] <= b[:, 3]))
            for j in np.flatnonzero(inside.any(axis=0)).tolist():  # the footprints within reach (a handful)
                k = np.flatnonzero(inside[:, j])
                fp = self._fp_points[self._fp_starts[j] : self._fp_starts[j] + self._sizes[j]]
                out[k, j] = _near_any(p[k], fp, self.found_radius**2)
        return out

    def found(self, points, source_cell: int) -> np.ndarray:
        """(p,) bool: whether a robot at each point finds a source in ``source_cell`` (a detector that never
        misses; a miss is drawn separately, see the module docstring)."""
        p = self._points(points)
        c = int(source_cell)
        j = int(self.owner[c])
        if j >= 0:  # the footprint's own points: the same comparisons as near_footprints()[:, j]
            fp = self._fp_points[self._fp_starts[j] : self._fp_starts[j] + self._sizes[j]]
            b = self._fp_boxes[j]  # only the points in its widened box can be within r
            k = np.flatnonzero((p[:, 0] >= b[0]) & (p[:, 0] <= b[2]) & (p[:, 1] >= b[1]) & (p[:, 1] <= b[3]))
            out = np.zeros(len(p), dtype=bool)
            out[k] = _near_any(p[k], fp, self.found_radius**2)
            return out
        return _d2(p, self.centres[c][None, :]) <= self.found_radius**2

    def _pairs(self, points):
        """(point index, hypothesis) pairs of every hypothesis found from each point, sorted by point (no
        duplicates: the disc part covers cells no object owns, and objects own disjoint cells). Points are taken
        in blocks, so that memory is bounded by :data:`_PAIRS_AT_ONCE` candidates, not by their number."""
        p = self._points(points)
        step = max(1, _PAIRS_AT_ONCE // len(self._offsets))
        if len(p) <= step:
            return self._block_pairs(p)
        ks, cs = [], []
        for i in range(0, len(p), step):
            k, c, _ = self._block_pairs(p[i : i + step])
            ks.append(k + i)
            cs.append(c)
        return np.concatenate(ks), np.concatenate(cs), len(p)

    def _block_pairs(self, p):
        """:meth:`_pairs` of one block of points."""
        h, w = self.shape
        rc = self.grid.world_to_cell(p)  # (p, 2)
        cand = rc[:, None, :] + self._offsets[None, :, :]  # (p, o, 2)
        inside = (cand[..., 0] >= 0) & (cand[..., 0] < h) & (cand[..., 1] >= 0) & (cand[..., 1] < w)
        flat = np.where(inside, cand[..., 0] * w + cand[..., 1], 0)
        disc = inside & (self.owner[flat] < 0) & (_d2(p[:, None, :], self.centres[flat]) <= self.found_radius**2)
        k, o = np.nonzero(disc)
        ks, cs = [k], [flat[k, o]]
        if len(self._sizes):
            kj, jj = np.nonzero(self.near_footprints(p))
            if kj.size:
                owned = self._owned[jj]  # (pairs, n) rows of the owned cells
                ks.append(np.repeat(kj, np.diff(owned.indptr)))
                cs.append(owned.indices.astype(np.int64))
        k, c = np.concatenate(ks), np.concatenate(cs)
        order = np.lexsort((c, k))
        return k[order], c[order], len(p)

    def rows(self, points) -> sp.csr_matrix:
        """(p, H·W) bool sparse: row k marks every hypothesis c that a robot at point k finds."""
        k, c, n_p = self._pairs(points)
        return sp.csr_matrix((np.ones(k.size, dtype=bool), (k, c)), shape=(n_p, self.centres.shape[0]))

    def cell_rows(self, cells, positions) -> list:
        """Per cell: the sorted flat hypotheses found from its ``positions`` row (cached by cell; the policies'
        candidates are cell centres)."""
        cells = [int(c) for c in np.asarray(cells).ravel()]
        missing = [k for k, c in enumerate(cells) if c not in self._rows_cache]
        if missing:
            k, c, n_p = self._pairs(np.asarray(positions, dtype=np.float64).reshape(-1, 2)[missing])
            for i, row in enumerate(np.split(c, np.searchsorted(k, np.arange(1, n_p)))):
                row.flags.writeable = False
                self._rows_cache[cells[missing[i]]] = row
        return [self._rows_cache[c] for c in cells]

    # --- what it says about the source ------------------------------------------------------------------------
    def source_cell(self, source_xy, source_object=None, house=None) -> int:
        """The hypothesis of the true source: a cell that ``source_object`` owns (its footprint is then the found
        region), or the cell holding ``source_xy`` for a point source.

        ``source_object`` must be one of ``house.objects`` (the same object, or one with the same class, name
        and footprint), the house whose footprints the model holds; ValueError otherwise, or when later objects
        cover all of its cells.
        """
        if source_object is None:
            xy = np.asarray(source_xy, dtype=np.float64)
            r, c = (int(v) for v in self.grid.world_to_cell(xy))
            if not (0 <= r < self.shape[0] and 0 <= c < self.shape[1]):
                x0, x1, y0, y1 = self.grid.extent
                raise ValueError(f"the source position ({xy[0]:g}, {xy[1]:g}) m lies off the map (x in [{x0:g}, "
                                 f"{x1:g}], y in [{y0:g}, {y1:g}])")
            return r * self.shape[1] + c
        j = next((i for i, o in enumerate(house.objects) if o is source_object), None)
        if j is None:  # an equal object (same class, name and footprint), e.g. read again from a world file
            j = next((i for i, o in enumerate(house.objects) if o.class_name == source_object.class_name
                      and o.name == source_object.name and o.footprint.shape == source_object.footprint.shape
                      and np.array_equal(o.footprint, source_object.footprint)), None)
        if j is None:
            raise ValueError(f"source_object must be one of the house's objects, got {source_object!r}")
        mine = np.flatnonzero(self.owner == j)
        if mine.size == 0:
            raise ValueError(f"the source object {source_object.name!r} is covered by later objects everywhere")
        return int(mine[0])

    def not_found_likelihood(self, points) -> np.ndarray:
        """(H·W,) P(not found along ``points`` | s = c): m on every hypothesis found from some point, 1 elsewhere
        (one detection trial for the whole path)."""
        out = np.ones(self.centres.shape[0])
        out[self._found_along(points)] = self.miss_probability
        return out

    def _found_along(self, points) -> np.ndarray:
        """The hypotheses found from some point of ``points`` (:meth:`_pairs`), cached per path: the robot
        drives the same few paths between its stops again and again."""
        p = np.ascontiguousarray(self._points(points))
        key = (p.shape, p.tobytes())
        hit = self._paths.get(key)
        if hit is not None:
            self._paths.move_to_end(key)
            return hit
        hit = self._paths[key] = self._pairs(p)[1]
        hit.flags.writeable = False
        if len(self._paths) > _PATHS_MAX:
            self._paths.popitem(last=False)
        return hit

    def not_found_log_likelihood(self, points) -> np.ndarray:
        """(H·W,) log of :meth:`not_found_likelihood` (−inf where a detector that never misses rules c out)."""
        with np.errstate(divide="ignore"):
            return np.log(self.not_found_likelihood(points))

    def found_log_likelihood(self, points) -> np.ndarray:
        """(H·W,) log P(found at the last of ``points`` | s = c), up to a constant: 0 on every hypothesis found from
        the last point and from no earlier one (the move's one detection trial fires at the first point within
        reach of the source), −inf elsewhere."""
        p = self._points(points)
        out = np.full(self.centres.shape[0], -np.inf)
        out[self._found_along(p[-1:])] = 0.0
        if len(p) > 1:
            out[self._found_along(p[:-1])] = -np.inf
        return out

    def found_probability(self, posterior, rows) -> np.ndarray:
        """(K,) P_f = (1 − m) Σ_{c ∈ row} p(c) for each row of hypotheses (from :meth:`cell_rows`)."""
        post = np.asarray(posterior, dtype=np.float64).ravel()
        sizes = np.array([len(r) for r in rows], dtype=np.int64)
        idx = np.concatenate(rows) if rows else np.empty(0, np.int64)
        sums = np.zeros(len(rows))
        if idx.size:
            starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
            nz = sizes > 0
            sums[nz] = np.add.reduceat(post[idx], starts[nz])
        return (1.0 - self.miss_probability) * sums
