"""An object detector as a probabilistic sensor: p(label | true class, distance).

The detector reports, for every cell (or voxel) in view, one label: an object class or ``"nothing"``.

* a cell holding an object of class i is *detected* with probability p_d(d), falling with the distance d
  (p_d(d) = p_max · exp(−max(d − d_near, 0) / d_scale)); a detection is labelled j with the confusion
  probability C[i, j] (similar classes are confused: oven ↔ microwave ↔ toaster, sink ↔ toilet, ...);
  otherwise the label is ``"nothing"``;
* a cell of class ``"other"`` (empty floor) yields a false positive with probability ``false_positive``,
  labelled j with C[other, j]; otherwise ``"nothing"`` ("seen, nothing detected").

The same model is the observation likelihood p(z | o) of the Bayes update of the class beliefs (one column
of the table per observed label): no clamping, no filler scores.

Opt-in realism (all off by default; :meth:`DetectorModel.realistic` turns it on with stated values):

* **range** — with ``half_range`` set, p_d falls logistically instead:
  p_d(d) = p_max / (1 + exp((d − half_range) / range_width));
* **viewing angle** — with ``angle_power`` n > 0 and the bearing β of the cell off the optical axis,
  p_d(d, β) = p_d(d) · cos(β)^n (n = 4: the cos⁴ law of natural vignetting);
* **errors that persist per object instance** — with ``persistence`` ρ > 0, every object instance of a world
  gets one label m drawn once from its class's confusion row C[i, ·]; in each frame, with probability ρ (one
  draw per instance and frame) every detection of the instance reads m, otherwise each detection draws a fresh
  label from C[i, ·]. The label distribution over instances and frames is still C[i, ·]; a mislabelled
  instance (m ≠ i) reads m again in a later frame with probability ρ + (1 − ρ) C[i, m];
* **recurring false positives** — ``distractors`` sites per world (e.g. a reflective surface read as an oven):
  the floor cells within ``distractor_radius`` of a uniformly drawn floor cell, each site with a label drawn once
  from the false-positive row C[other, ·]; a site cell in view reads the site's label with probability
  p_d(d, β), as an object of that class would, otherwise it is an ordinary floor cell.

The per-world draws (:class:`DetectorErrors`) come from the world's seed (:class:`psgsl_pgm.sim.World`).
:meth:`DetectorModel.table` and :meth:`DetectorModel.likelihood` stay the per-cell marginal model: the
instance and site errors are what a robot's model of independent errors does not know.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._classes import HOUSE_CLASSES, OTHER

__all__ = ["DetectorErrors", "DetectorModel", "DEFAULT_CONFUSION_GROUPS", "NOTHING"]

#: The label of "seen, nothing detected".
NOTHING = "nothing"

#: Groups of classes that a detector confuses with each other.
DEFAULT_CONFUSION_GROUPS = (
    ("oven", "microwave", "toaster"),
    ("sink", "toilet"),
    ("countertop", "dining table"),
    ("couch", "bed", "chair"),
    ("refrigerator",),
    ("tv",),
    ("potted plant",),
)


@dataclass(frozen=True, eq=False)
class DetectorModel:
    """p(label | class, distance) of an object detector.

    Parameters
    ----------
    classes : tuple of str
        The k classes (must include ``"other"``). Labels are the k − 1 object classes, in this order, then
        ``"nothing"`` (index k − 1).
    confusion : (k, k - 1) ndarray
        Row i: p(label j | class i, a detection happened); the row of ``"other"`` is the label distribution
        of false positives. Rows sum to 1.
    p_max : float
        Detection probability of an object up to ``near`` metres.
    near, scale : float
        Distance (m) up to which p_d = p_max, and the e-folding length (m) of its decay beyond.
    false_positive : float
        Probability that an ``"other"`` cell in view is reported as some object.
    half_range : float or None
        Distance (m) at which a logistic p_d falls to p_max / 2 (None: the exponential curve of ``near`` and
        ``scale``).
    range_width : float
        Width (m) of the logistic fall (used with ``half_range``).
    angle_power : float
        n of the cos(β)^n factor of the bearing β off the optical axis (0: none).
    persistence : float
        ρ, the probability per frame that an instance's detections read its persistent label (0: independent).
    distractors : int
        Number of recurring false-positive sites per world.
    distractor_radius : float
        Radius (m) of a site.
    """

    classes: tuple
    confusion: np.ndarray
    p_max: float = 0.9
    near: float = 1.0
    scale: float = 3.0
    false_positive: float = 0.02
    half_range: float | None = None
    range_width: float = 0.5
    angle_power: float = 0.0
    persistence: float = 0.0
    distractors: int = 0
    distractor_radius: float = 0.15

    def __post_init__(self):
        classes = tuple(str(c) for c in self.classes)
        if OTHER not in classes or len(set(classes)) != len(classes) or len(classes) < 2:
            raise ValueError(f"classes must be distinct, at least 2, and include {OTHER!r}, got {classes}")
        k = len(classes)
        conf = np.array(self.confusion, dtype=np.float64)
        if conf.shape != (k, k - 1):
            raise ValueError(f"confusion must have shape ({k}, {k - 1}) (classes x object labels), got {conf.shape}")
        if not np.all(np.isfinite(conf)) or conf.min() < 0 or not np.allclose(conf.sum(axis=1), 1.0, rtol=0, atol=1e-9):
            raise ValueError("confusion rows must be probability distributions (non-negative, summing to 1)")
        for name in ("p_max", "false_positive"):
            v = getattr(self, name)
            if not (np.isfinite(v) and 0 <= v <= 1):
                raise ValueError(f"{name} must be a probability in [0, 1], got {v!r}")
        for name in ("near", "scale"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0) or (name == "scale" and v == 0):
                raise ValueError(f"{name} must be {'> 0' if name == 'scale' else '>= 0'} metres, got {v!r}")
        if self.half_range is not None and not (isinstance(self.half_range, (int, float, np.floating, np.integer))
                                                and not isinstance(self.half_range, bool)
                                                and np.isfinite(self.half_range) and self.half_range > 0):
            raise ValueError(f"half_range must be a positive number of metres or None, got {self.half_range!r}")
        for name, lo in (("range_width", 0.0), ("angle_power", None), ("distractor_radius", None)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not (
                    np.isfinite(v) and (v > 0 if lo is not None else v >= 0)):
                raise ValueError(f"{name} must be a {'positive' if lo is not None else 'non-negative'} number "
                                 f"({'metres' if 'angle' not in name else 'an exponent'}), got {v!r}")
        if isinstance(self.persistence, bool) or not (np.isfinite(self.persistence) and 0 <= self.persistence <= 1):
            raise ValueError(f"persistence must be a probability in [0, 1], got {self.persistence!r}")
        if isinstance(self.distractors, bool) or not isinstance(self.distractors, (int, np.integer)) or \
                self.distractors < 0:
            raise ValueError(f"distractors must be a non-negative whole number of sites, got {self.distractors!r}")
        conf.flags.writeable = False
        object.__setattr__(self, "classes", classes)
        object.__setattr__(self, "confusion", conf)
        obj = np.array([c != OTHER for c in classes])
        object.__setattr__(self, "_object_classes", np.flatnonzero(obj))

    @classmethod
    def default(cls, classes=HOUSE_CLASSES, *, groups=DEFAULT_CONFUSION_GROUPS, correct: float = 0.85,
                leak: float = 0.02, **kwargs) -> "DetectorModel":
        """A detector that confuses classes within ``groups``.

        Row of class i: ``leak`` spread evenly over the labels outside i's group, the within-group confusion
        ``1 − correct − leak`` spread evenly over i's group mates, the rest on i itself (a class without mates
        keeps ``1 − leak``). False positives are labelled uniformly. Other keywords go to the constructor.
        """
        classes = tuple(classes)
        if OTHER not in classes:
            raise ValueError(f"classes must include {OTHER!r}, got {classes}")
        if not (0 <= leak and 0 <= correct and correct + leak <= 1):
            raise ValueError(f"need 0 <= correct, leak and correct + leak <= 1, got correct={correct}, leak={leak}")
        labels = [c for c in classes if c != OTHER]
        m = len(labels)
        group_of = {}
        for g_i, g in enumerate(groups):
            for c in g:
                group_of[c] = g_i
        conf = np.zeros((len(classes), m))
        for i, c in enumerate(classes):
            if c == OTHER:
                conf[i] = 1.0 / m
                continue
            j = labels.index(c)
            mates = [labels.index(o) for o in labels if o != c and c in group_of and group_of.get(o) == group_of[c]]
            rest = [x for x in range(m) if x != j and x not in mates]
            if rest:
                conf[i, rest] = leak / len(rest)
            if mates:  # without labels outside the group, the leak stays within it
                conf[i, mates] = (1.0 - correct - (leak if rest else 0.0)) / len(mates)
                conf[i, j] = correct
            else:
                conf[i, j] = 1.0 - (leak if rest else 0.0)
        return cls(classes, conf, **kwargs)

    @classmethod
    def realistic(cls, classes=HOUSE_CLASSES, *, p_max: float = 0.9, half_range: float = 4.0,
                  range_width: float = 0.8, angle_power: float = 4.0, persistence: float = 0.7,
                  distractors: int = 3, distractor_radius: float = 0.15, correct: float = 0.8, leak: float = 0.03,
                  false_positive: float = 0.01, groups=DEFAULT_CONFUSION_GROUPS) -> "DetectorModel":
        """A detector with the range and angle fall-off, persistent per-instance errors and recurring false
        positives of the module docstring, with these values (every one a keyword):

        * ``half_range`` = 4.0 m, ``range_width`` = 0.8 m: a 0.25-m object spans 32 px on a 640-px, 70° image
          at 4.1 m — the COCO boundary between small and medium objects (Lin et al., "Microsoft COCO", ECCV
          2014), where a one-stage detector's average precision halves (YOLOv3-608: AP_S 18.3 against AP_M 35.4,
          Redmon & Farhadi, arXiv:1804.02767, 2018); at 1.6 m, where it spans 80 px, p_d is within 5 % of
          ``p_max``;
        * ``angle_power`` = 4: p_d follows the image brightness at bearing β, cos⁴β (natural vignetting;
          e.g. Kang & Weiss, ECCV 2000), 0.45 at the 35° edge of the default camera;
        * ``persistence`` = 0.7, ``distractors`` = 3 sites of ``distractor_radius`` = 0.15 m: stated
          assumptions (no published rate for a house robot's detector); a mislabelled instance then stays
          mislabelled in at least 70 % of the frames that see it;
        * ``correct`` = 0.8, ``leak`` = 0.03, ``false_positive`` = 0.01, ``p_max`` = 0.9: the confusion of
          :meth:`default` with a weaker diagonal, and the per-cell false-positive rate lowered since the sites
          add recurring ones.

        Examples
        --------
        >>> det = DetectorModel.realistic()
        >>> [round(float(p), 3) for p in det.detection_probability([1.0, 4.0], bearing=[0.0, 0.0])]
        [0.879, 0.45]
        """
        base = cls.default(classes, groups=groups, correct=correct, leak=leak)
        return cls(base.classes, base.confusion, p_max=p_max, false_positive=false_positive, half_range=half_range,
                   range_width=range_width, angle_power=angle_power, persistence=persistence,
                   distractors=distractors, distractor_radius=distractor_radius)

    @property
    def correlated(self) -> bool:
        """Whether frames of one world share errors (persistent instance labels or distractor sites)."""
        return self.persistence > 0 or self.distractors > 0

    @classmethod
    def from_counts(cls, classes, true_classes, labels, distance, *, pseudo_count: float = 1.0) -> "DetectorModel":
        """The detector model estimated from labelled observations (class truth known, e.g. reference houses).

        * confusion C[i, j]: Dirichlet-smoothed frequencies, (n_ij + α) / (n_i + (k − 1) α), of label j among
          the detections on class i (α = ``pseudo_count``; the row of ``"other"`` from its false positives);
        * ``false_positive``: (n_fp + α) / (n_other + 2α), detections among the ``"other"`` observations;
        * (p_max, near, scale) of p_d(d): maximum likelihood on the detected / not-detected events of the object
          cells (Bernoulli with p_d(d_n); Nelder–Mead on (logit p_max, log near, log scale), from the
          moment-like start p_max = detection rate below the median distance).

        Parameters
        ----------
        classes : tuple of str
            The k classes (with ``"other"``), in the order ``true_classes`` indexes.
        true_classes, labels : (n,) array_like of int
            True class of each observation, and the reported label (index into the labels, ``"nothing"`` = k − 1).
        distance : (n,) array_like of float
            Camera–cell distances, metres.
        pseudo_count : float, keyword-only
            α > 0.

        Returns
        -------
        DetectorModel
        """
        from scipy.optimize import minimize

        classes = tuple(str(c) for c in classes)
        if OTHER not in classes:
            raise ValueError(f"classes must include {OTHER!r}, got {classes}")
        k = len(classes)
        c = np.asarray(true_classes)
        z = np.asarray(labels)
        d = np.asarray(distance, dtype=np.float64)
        if not (np.issubdtype(c.dtype, np.integer) and np.issubdtype(z.dtype, np.integer)) or not (
                c.shape == z.shape == d.shape) or c.ndim != 1:
            raise ValueError(f"true_classes, labels (int) and distance must be (n,) arrays of one length, got "
                             f"{c.shape}, {z.shape}, {d.shape}")
        if c.size and (c.min() < 0 or c.max() >= k or z.min() < 0 or z.max() >= k):
            raise ValueError(f"true_classes and labels must lie in [0, {k}), got [{c.min()}, {c.max()}] and "
                             f"[{z.min()}, {z.max()}]")
        if not (np.isfinite(pseudo_count) and pseudo_count > 0):
            raise ValueError(f"pseudo_count must be a positive number, got {pseudo_count!r}")
        nothing = k - 1
        det = z != nothing
        counts = np.zeros((k, k - 1))
        np.add.at(counts, (c[det], z[det]), 1.0)
        confusion = (counts + pseudo_count) / (counts + pseudo_count).sum(axis=1, keepdims=True)
        other = classes.index(OTHER)
        is_other = c == other
        false_positive = (det[is_other].sum() + pseudo_count) / (is_other.sum() + 2 * pseudo_count)
        obj_d, obj_det = d[~is_other], det[~is_other]
        if obj_d.size == 0:
            raise ValueError("true_classes must include observations of object cells to fit the detection curve")

        def unpack(x):
            return 1.0 / (1.0 + np.exp(-x[0])), float(np.exp(x[1])), float(np.exp(x[2]))

        def nll(x):
            p_max, near, scale = unpack(x)
            p = np.clip(p_max * np.exp(-np.maximum(obj_d - near, 0.0) / scale), 1e-15, 1 - 1e-15)
            return -float(np.where(obj_det, np.log(p), np.log1p(-p)).sum())

        med = float(np.median(obj_d))
        rate = float(np.clip(obj_det[obj_d <= med].mean(), 0.01, 0.99))
        x0 = np.array([np.log(rate / (1 - rate)), np.log(max(med / 2, 0.05)), np.log(max(med, 0.1))])
        res = minimize(nll, x0, method="Nelder-Mead", options={"xatol": 1e-6, "fatol": 1e-8, "maxiter": 4000})
        p_max, near, scale = unpack(res.x)
        return cls(classes, confusion, p_max=float(p_max), near=near, scale=scale,
                   false_positive=float(false_positive))

    @property
    def labels(self) -> tuple:
        """Label names: the object classes then ``"nothing"``."""
        return tuple(c for c in self.classes if c != OTHER) + (NOTHING,)

    @property
    def nothing(self) -> int:
        """Index of the ``"nothing"`` label."""
        return len(self.classes) - 1

    def detection_probability(self, distance, bearing=None) -> np.ndarray:
        """p_d(d) = p_max · exp(−max(d − near, 0) / scale), or the logistic of ``half_range``; times cos(β)^n
        for a ``bearing`` β (radians off the optical axis, shaped as ``distance``) when ``angle_power`` n > 0."""
        d = np.asarray(distance, dtype=np.float64)
        if self.half_range is None:
            p = self.p_max * np.exp(-np.maximum(d - self.near, 0.0) / self.scale)
        else:
            p = self.p_max / (1.0 + np.exp((d - self.half_range) / self.range_width))
        if bearing is not None and self.angle_power > 0:
            b = np.asarray(bearing, dtype=np.float64)
            if b.shape != d.shape:
                raise ValueError(f"bearing must have the shape of distance {d.shape}, got {b.shape}")
            p = p * np.maximum(np.cos(b), 0.0) ** self.angle_power
        return p

    def table(self, distance, bearing=None) -> np.ndarray:
        """(..., k, k) p(label | class, d[, β]): rows are true classes, columns labels (``"nothing"`` last)."""
        pd = self.detection_probability(distance, bearing)[..., None]  # (..., 1)
        k = len(self.classes)
        other = self.classes.index(OTHER)
        rate = np.where(np.arange(k) == other, self.false_positive, pd)  # (..., k): p(some label | class)
        out = np.empty(rate.shape + (k,))
        out[..., :-1] = rate[..., None] * self.confusion  # p(label j | i) = rate_i · C[i, j]
        out[..., -1] = 1.0 - rate  # p(nothing | i)
        return out

    def likelihood(self, labels, distance, bearing=None) -> np.ndarray:
        """(n, k) p(z_n | o, d_n[, β_n]) over the classes o, for observed labels z_n at distances d_n (and
        bearings β_n, radians off the optical axis).

        This is the factor for :func:`psgsl_pgm.update_class_probs`.
        """
        z = np.asarray(labels)
        d = np.asarray(distance, dtype=np.float64)
        if not np.issubdtype(z.dtype, np.integer) or z.shape != d.shape:
            raise ValueError(f"labels (int) and distance must have the same shape, got {z.shape} and {d.shape}")
        k = len(self.classes)
        if z.size and (z.min() < 0 or z.max() >= k):
            raise ValueError(f"labels must index {self.labels}, got values in [{z.min()}, {z.max()}]")
        pd = self.detection_probability(d, bearing)[..., None]
        other = self.classes.index(OTHER)
        rate = np.where(np.arange(k) == other, self.false_positive, pd)  # (n, k)
        det = z != self.nothing
        conf_cols = self.confusion.T[np.where(det, z, 0)]  # (n, k): C[o, z_n]
        return np.where(det[..., None], rate * conf_cols, 1.0 - rate)

    def sample(self, true_classes, distance, rng, bearing=None) -> np.ndarray:
        """(n,) labels drawn from p(label | true class, d[, β]) (inverse-CDF, vectorised)."""
        c = np.asarray(true_classes)
        d = np.asarray(distance, dtype=np.float64)
        if not np.issubdtype(c.dtype, np.integer) or c.shape != d.shape:
            raise ValueError(f"true_classes (int) and distance must have the same shape, got {c.shape}, {d.shape}")
        k = len(self.classes)
        pd = self.detection_probability(d, bearing)
        other = self.classes.index(OTHER)
        rate = np.where(c == other, self.false_positive, pd)
        rows = np.empty(c.shape + (k,))
        rows[..., :-1] = rate[..., None] * self.confusion[c]
        rows[..., -1] = 1.0 - rate
        cdf = np.cumsum(rows, axis=-1)
        u = rng.random(c.shape)[..., None] * cdf[..., -1:]
        return np.minimum((u >= cdf).sum(axis=-1), k - 1).astype(np.int64)


def _draw_rows(rows, rng) -> np.ndarray:
    """One index per row of the (n, m) probability table ``rows`` (inverse CDF)."""
    cdf = np.cumsum(rows, axis=-1)
    u = rng.random(rows.shape[0])[:, None] * cdf[:, -1:]
    return np.minimum((u >= cdf).sum(axis=-1), rows.shape[1] - 1).astype(np.int64)


@dataclass(frozen=True, eq=False)
class DetectorErrors:
    """The errors of one detector fixed for one world: each instance's persistent label and the distractor sites.

    Build it with :meth:`draw` (the world does, from its seed).

    Attributes
    ----------
    instance_label : (n_objects,) ndarray of int
        The label (index into ``detector.labels``) each of ``house.objects`` reads as when its error persists.
    site_map : (H, W) ndarray of int
        The label each distractor cell reads as (−1 off the sites).
    """

    instance_label: np.ndarray
    site_map: np.ndarray

    @property
    def site_cells(self) -> np.ndarray:
        """(m, 2) (row, col) of the distractor cells."""
        return np.argwhere(self.site_map >= 0)

    @classmethod
    def draw(cls, detector: DetectorModel, house, rng) -> "DetectorErrors":
        """Draw the per-world errors of ``detector`` in ``house`` (module docstring).

        Parameters
        ----------
        detector : DetectorModel
        house : House
        rng : numpy.random.Generator

        Returns
        -------
        DetectorErrors
        """
        from ._classes import match_names
        from ._house import House

        if not isinstance(detector, DetectorModel):
            raise TypeError(f"detector must be a DetectorModel, got {type(detector).__name__}")
        if not isinstance(house, House):
            raise TypeError(f"house must be a House, got {type(house).__name__}")
        other = detector.classes.index(OTHER)
        idx = match_names(tuple(o.class_name for o in house.objects), detector.classes)
        idx = np.where(idx < 0, other, idx)
        instance_label = _draw_rows(detector.confusion[idx].reshape(-1, len(detector.classes) - 1), rng)
        floor = house.grid.free & ~house.furniture & ~house.inlet & ~house.outlet
        cand = np.argwhere(floor)
        n = min(int(detector.distractors), len(cand))
        centres = cand[rng.choice(len(cand), n, replace=False)] if n else np.zeros((0, 2), np.int64)
        labels = _draw_rows(np.broadcast_to(detector.confusion[other], (n, len(detector.classes) - 1)), rng)
        radius = detector.distractor_radius / house.grid.resolution  # cells
        site_map = np.full(house.shape, -1, dtype=np.int64)
        for (r, c), z in zip(centres, labels):  # a later site wins where two overlap
            near = cand[np.hypot(cand[:, 0] - r, cand[:, 1] - c) <= radius]
            site_map[near[:, 0], near[:, 1]] = z
        for a in (instance_label, site_map):
            a.flags.writeable = False
        return cls(instance_label, site_map)
