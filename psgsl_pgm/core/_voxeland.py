"""The semantic term of a Voxeland instance map's columns without its dense voxel array.

A voxel map read onto a fine grid is large: house B's 1-cm map with furniture up to 2 m has 870 × 1140 × 200 voxels,
tens of GB at a dozen classes. Its columns' semantic term needs far less: the voxels no box reaches all hold the class
prior, and the rest can be taken a block of rows at a time.
"""

from __future__ import annotations

import numpy as np

from ..io._class_maps import VoxelMap
from ._semantic import semantic_source_probability

__all__ = ["voxeland_column_weights"]


def voxeland_column_weights(data, classes, *, grid, class_prior, source_likelihood, gas_probs=None,
                            where: str = "Voxeland map", other_classes: str = "error",
                            block_bytes: int = 64 << 20) -> np.ndarray:
    r"""The unnormalised semantic term of a Voxeland map's columns, in memory bounded by the grid.

    The column sum of Sec. "Voxelized Scene Representations", :math:`p(s_c \mid z) \propto \sum_{v \in c}
    \sum_i p(o_{vi} \mid z_v) / p(o_i)\, p(o_i \mid s_v)` (eq. (20) summed over a column, eq. (21)), equal to
    ``semantic_source_probability(voxeland_class_beliefs(...), ..., column_axis=2, normalize=False)`` without
    building the (H, W, L, k) array: columns no box reaches hold L prior voxels (one weight, computed once);
    the rows that boxes reach are computed a block of rows at a time.

    Parameters
    ----------
    data, classes, grid, class_prior, where, other_classes
        As for :func:`voxeland_class_beliefs`.
    source_likelihood : (k,) or (G, k) array_like, keyword-only
        p(o_i | s), as for :func:`psgsl_pgm.semantic_source_probability`.
    gas_probs : (G,) array_like, optional, keyword-only
        p(γ | ζ) when ``source_likelihood`` has one row per gas.
    block_bytes : int, keyword-only
        Largest voxel block built at once (default 64 MiB); memory stays near 3 × ``block_bytes`` plus the grid.

    Returns
    -------
    (H, W) ndarray of float64
        Column weights, to be normalised over cells (divide by their sum).

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.geometry import GridMap
    >>> grid = GridMap(np.zeros((4, 5), bool), 0.5)
    >>> data = {"instances": {"0": {"bbox": {"center": [0.75, 0.75, 0.25], "size": [1.0, 1.0, 0.5]},
    ...                             "results": {"oven": 6.0}, "n_observations": 5}}}
    >>> w = voxeland_column_weights(data, ["oven", "other"], grid=grid, class_prior=[0.1, 0.9],
    ...                             source_likelihood=[0.9, 0.1])
    >>> w.shape, bool(w[1, 1] > w[3, 4])
    ((4, 5), True)
    """
    vox = VoxelMap.parse(data, classes, grid=grid, class_prior=class_prior, where=where,
                         other_classes=other_classes)
    h, w = grid.shape

    def weights(block):
        return semantic_source_probability(block, source_likelihood, class_prior, gas_probs=gas_probs,
                                           column_axis=2, normalize=False)

    column = np.broadcast_to(vox.prior, (1, 1, vox.layers, len(vox.prior)))
    out = np.full((h, w), weights(column)[0, 0], dtype=np.float64)  # L prior voxels: Σ_v of one weight
    r0, r1, c0, c1 = vox.reach()
    if r1 > r0 and c1 > c0:
        step = max(1, block_bytes // max(1, (c1 - c0) * vox.layers * len(vox.prior) * 8))
        for a in range(r0, r1, step):
            b = min(a + step, r1)
            out[a:b, c0:c1] = weights(vox.rows(a, b, c0, c1))
    return out
