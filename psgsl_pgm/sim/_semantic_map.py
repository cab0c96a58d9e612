"""Dense class-belief map p(o_c | z_c) over all cells (or voxels), updated frame by frame.

Beliefs start from the class prior p(o) — optionally already conditioned on the room-category map through
:func:`psgsl_pgm.room_evidence` — and every camera frame multiplies in the detector's likelihood p(z | o)
with :func:`psgsl_pgm.update_class_probs` (Bayes' rule; paper Sec. "Model"). A voxel map (H, W, L, k)
reduces to 2-D cells with ``semantic_source_probability(..., column_axis=2)``.
"""

from __future__ import annotations

import numpy as np

from ._camera import Frame

__all__ = ["SemanticMap"]


class SemanticMap:
    """Per-cell (or per-voxel) class beliefs.

    Parameters
    ----------
    class_probs : (H, W, k) or (H, W, L, k) array_like
        Initial beliefs; every cell sums to 1.
    classes : sequence of str
        The k class names.

    Examples
    --------
    >>> import numpy as np
    >>> m = SemanticMap.from_prior((2, 3), [0.2, 0.8], ("oven", "other"))
    >>> m.probs.shape
    (2, 3, 2)
    """

    def __init__(self, class_probs, classes):
        p = np.array(class_probs, dtype=np.float64)
        classes = tuple(str(c) for c in classes)
        if p.ndim not in (3, 4) or p.shape[-1] != len(classes):
            raise ValueError(
                f"class_probs must have shape (H, W, k) or (H, W, L, k) with k = {len(classes)} classes, got {p.shape}"
            )
        if not np.all(np.isfinite(p)) or p.min() < 0 or not np.allclose(p.sum(axis=-1), 1.0, rtol=0, atol=1e-9):
            raise ValueError("class_probs must hold a probability distribution over the classes in every cell")
        self.probs = p
        self.classes = classes
        self.n_frames = 0

    @classmethod
    def from_prior(cls, shape, class_prior, classes) -> "SemanticMap":
        """Every cell (voxel) at the class prior; ``shape`` is (H, W) or (H, W, L)."""
        prior = np.asarray(class_prior, dtype=np.float64)
        if prior.ndim != 1:
            raise ValueError(f"class_prior must be a (k,) distribution, got shape {prior.shape}")
        return cls(np.broadcast_to(prior, tuple(shape) + prior.shape), classes)

    @classmethod
    def from_rooms(cls, room_labels, room_table, class_prior, classes, *, layers: int | None = None) -> "SemanticMap":
        """Beliefs conditioned on the room-category map: p(o | room_c) (prior where the label is -1).

        Parameters
        ----------
        room_labels : (H, W) array_like of int
            Room index into the rows of ``room_table``; -1 = none.
        room_table : (r, k) array_like
            p(o | room) (e.g. ``Ontology.room_table``; rows in the order of the labels).
        class_prior : (k,) array_like
        classes : sequence of str
        layers : int, optional, keyword-only
            Give a voxel map with this many layers (the same room evidence in every layer).
        """
        from psgsl_pgm import room_evidence, update_class_probs

        factor = room_evidence(room_labels, room_table, class_prior)  # p(o | r) / p(o)
        probs = update_class_probs(np.asarray(class_prior, dtype=np.float64), factor)
        if layers is not None:
            if not isinstance(layers, (int, np.integer)) or layers < 1:
                raise ValueError(f"layers must be a positive integer, got {layers!r}")
            probs = np.repeat(probs[:, :, None, :], layers, axis=2)
        return cls(probs, classes)

    @property
    def is_voxel(self) -> bool:
        return self.probs.ndim == 4

    def update(self, frame: Frame) -> None:
        """Apply one frame's likelihoods to the observed cells (voxels): p ∝ p · p(z | o)."""
        from psgsl_pgm import update_class_probs

        if not isinstance(frame, Frame):
            raise TypeError(f"frame must be a Frame, got {type(frame).__name__}")
        if tuple(frame.classes) != self.classes:
            raise ValueError(f"frame classes {frame.classes} differ from the map's {self.classes}")
        if (frame.layers is not None) != self.is_voxel:
            raise ValueError("voxel frames need a voxel map and 2-D frames a 2-D map")
        if frame.cells.shape[0] == 0:
            self.n_frames += 1
            return
        r, c = frame.cells[:, 0], frame.cells[:, 1]
        if self.is_voxel:
            idx = (r, c, frame.layers)
        else:
            idx = (r, c)
        # repeated observations of one voxel in a frame (not produced by take_frame) would need sequential
        # application; take_frame observes each cell/voxel once per frame.
        self.probs[idx] = update_class_probs(self.probs[idx], frame.likelihood)  # p(o|z,z') ∝ p(o|z) p(z'|o)
        self.n_frames += 1

    def most_likely(self) -> np.ndarray:
        """(H, W) or (H, W, L) int: arg max class per cell (voxel)."""
        return self.probs.argmax(axis=-1)
