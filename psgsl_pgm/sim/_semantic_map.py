"""``SemanticMap``: the core's class-belief map (:class:`psgsl_pgm.ClassBeliefMap`) under its simulator name.

Kept for users of ``psgsl_pgm.sim``: it *is* a :class:`~psgsl_pgm.ClassBeliefMap` (same constructors,
``probs``, ``most_likely``, ``source_probability``); only :meth:`SemanticMap.update` differs, taking one
simulated :class:`~psgsl_pgm.sim.Frame` (the core's ``update(cells, likelihood)`` is
:meth:`~psgsl_pgm.ClassBeliefMap.observe` with a frame). The simulator only emits frames; the beliefs live
in the core.
"""

from __future__ import annotations

from ..core._class_beliefs import ClassBeliefMap
from ._camera import Frame

__all__ = ["SemanticMap"]


class SemanticMap(ClassBeliefMap):
    """Per-cell (or per-voxel) class beliefs, updated with simulated camera frames.

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

    def update(self, frame: Frame) -> None:  # noqa: D401 — the simulator's frame-at-a-time update
        """Apply one frame's likelihoods to the observed cells (voxels): p ∝ p · p(z | o)."""
        if not isinstance(frame, Frame):
            raise TypeError(f"frame must be a Frame, got {type(frame).__name__}")
        self.observe(frame)
