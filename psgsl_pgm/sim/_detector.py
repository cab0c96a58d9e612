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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._classes import HOUSE_CLASSES, OTHER

__all__ = ["DetectorModel", "DEFAULT_CONFUSION_GROUPS", "NOTHING"]

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
    """

    classes: tuple
    confusion: np.ndarray
    p_max: float = 0.9
    near: float = 1.0
    scale: float = 3.0
    false_positive: float = 0.02

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

    def detection_probability(self, distance) -> np.ndarray:
        """p_d(d) = p_max · exp(−max(d − near, 0) / scale)."""
        d = np.asarray(distance, dtype=np.float64)
        return self.p_max * np.exp(-np.maximum(d - self.near, 0.0) / self.scale)

    def table(self, distance) -> np.ndarray:
        """(..., k, k) p(label | class, d): rows are true classes, columns labels (``"nothing"`` last)."""
        pd = self.detection_probability(distance)[..., None]  # (..., 1)
        k = len(self.classes)
        other = self.classes.index(OTHER)
        rate = np.where(np.arange(k) == other, self.false_positive, pd)  # (..., k): p(some label | class)
        out = np.empty(rate.shape + (k,))
        out[..., :-1] = rate[..., None] * self.confusion  # p(label j | i) = rate_i · C[i, j]
        out[..., -1] = 1.0 - rate  # p(nothing | i)
        return out

    def likelihood(self, labels, distance) -> np.ndarray:
        """(n, k) p(z_n | o, d_n) over the classes o, for observed labels z_n at distances d_n.

        This is the factor for :func:`psgsl_pgm.update_class_probs`.
        """
        z = np.asarray(labels)
        d = np.asarray(distance, dtype=np.float64)
        if not np.issubdtype(z.dtype, np.integer) or z.shape != d.shape:
            raise ValueError(f"labels (int) and distance must have the same shape, got {z.shape} and {d.shape}")
        k = len(self.classes)
        if z.size and (z.min() < 0 or z.max() >= k):
            raise ValueError(f"labels must index {self.labels}, got values in [{z.min()}, {z.max()}]")
        pd = self.detection_probability(d)[..., None]
        other = self.classes.index(OTHER)
        rate = np.where(np.arange(k) == other, self.false_positive, pd)  # (n, k)
        det = z != self.nothing
        conf_cols = self.confusion.T[np.where(det, z, 0)]  # (n, k): C[o, z_n]
        return np.where(det[..., None], rate * conf_cols, 1.0 - rate)

    def sample(self, true_classes, distance, rng) -> np.ndarray:
        """(n,) labels drawn from p(label | true class, d) (inverse-CDF, vectorised)."""
        c = np.asarray(true_classes)
        d = np.asarray(distance, dtype=np.float64)
        if not np.issubdtype(c.dtype, np.integer) or c.shape != d.shape:
            raise ValueError(f"true_classes (int) and distance must have the same shape, got {c.shape}, {d.shape}")
        k = len(self.classes)
        pd = self.detection_probability(d)
        other = self.classes.index(OTHER)
        rate = np.where(c == other, self.false_positive, pd)
        rows = np.empty(c.shape + (k,))
        rows[..., :-1] = rate[..., None] * self.confusion[c]
        rows[..., -1] = 1.0 - rate
        cdf = np.cumsum(rows, axis=-1)
        u = rng.random(c.shape)[..., None] * cdf[..., -1:]
        return np.minimum((u >= cdf).sum(axis=-1), k - 1).astype(np.int64)
