"""The voxel column sum shared by the numpy and dask paths of the semantic term."""

import numpy as np

__all__ = ["column_sum"]


def column_sum(values: np.ndarray, column_axis, ndim: int) -> np.ndarray:
    """Sum over one cell axis (Sec. "Voxelized Scene Representations": p(s_c | z) = Σ_{v ∈ c} p(s_v | z))."""
    if column_axis is None:
        return values
    if isinstance(column_axis, (bool, np.bool_)) or not isinstance(column_axis, (int, np.integer)):
        raise TypeError(f"column_axis must be an int (a cell axis) or None, got {column_axis!r}")
    if not -ndim <= column_axis < ndim or ndim < 2:
        raise ValueError(
            f"column_axis must index one of the {ndim} cell axes (class axis excluded) and leave at least one, "
            f"got {column_axis}"
        )
    axis = int(column_axis) % ndim
    if isinstance(values, np.ndarray):  # each column summed in order along the axis, in one compiled pass
        from ..kernels._belief import column_sums  # compiled (numba), loaded on first use

        return column_sums(np.ascontiguousarray(values, dtype=np.float64), axis)
    return values.sum(axis=axis)  # a dask array: a lazy reduction over its chunks
