"""Online estimate of the mean wind field from the robot's own anemometer readings.

The plume model needs the *mean* flow u(x) over the whole map; the robot measures the instantaneous flow at its
stops only, with sensor noise and the eddies of the moment. :class:`MeanWindEstimator` writes the mean flow as
a linear combination of K known basis fields,

    u(x) = Σ_k a_k φ_k(x),     φ_k : (H, W, 2) in m/s per unit coefficient,

(for a house: the potential flow between its windows, whose shape follows from the map alone, so the single
coefficient is the unknown strength and direction of the through-flow; without windows: uniform flows along x
and y) and estimates the coefficients a by least squares from the readings w_n at positions x_n,

    â = argmin_a Σ_n |w_n − Φ(x_n) a|²  =  (Σ_n Φ_nᵀ Φ_n)⁻¹ Σ_n Φ_nᵀ w_n,      Φ_n = Φ(x_n) : (2, K),

kept as running normal equations (K × K and K numbers: O(K²) per reading, no reading stored). The anemometer
of the simulator (:class:`psgsl_pgm.sim.Anemometer`) reports (u_x, u_y) in the map frame plus isotropic
Gaussian noise, and the eddies of the moment add a zero-mean (over time) perturbation: both are noise of the
regression, and the least-squares estimate is unbiased for the mean flow's coefficients whatever their
variance. With an isotropic residual variance σ² its covariance is σ² (Σ Φ_nᵀ Φ_n)⁻¹; σ² is estimated from the
residual sum of squares (:attr:`MeanWindEstimator.covariance`).
"""

from __future__ import annotations

import numpy as np

from .._shared._validate import as_float_array, real_pair
from ..geometry._grid import GridMap

__all__ = ["MeanWindEstimator"]


class MeanWindEstimator:
    """Least-squares mean flow u = Σ_k a_k φ_k from anemometer readings (see the module docstring).

    Parameters
    ----------
    basis : (K, H, W, 2) array_like of float
        Basis fields φ_k (u_x, u_y) in m/s per unit coefficient; zero on walls.
    grid : GridMap
        The map (readings are looked up in the cell holding their position).

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm import GridMap
    >>> g = GridMap(np.zeros((4, 5), bool), 0.5)
    >>> basis = np.zeros((1, 4, 5, 2)); basis[0, ..., 0] = 1.0      # a uniform flow along x
    >>> est = MeanWindEstimator(basis, g)
    >>> est.add((1.0, 1.0), (0.3, 0.1)); est.add((2.0, 0.4), (0.1, -0.1))
    >>> est.coefficients.round(12).tolist(), est.field()[0, 0].round(12).tolist()
    ([0.2], [0.2, 0.0])
    """

    def __init__(self, basis, grid: GridMap):
        if not isinstance(grid, GridMap):
            raise TypeError(f"grid must be a GridMap, got {type(grid).__name__}")
        phi = as_float_array(basis, "basis", dtype=np.float64)
        if phi.ndim != 4 or phi.shape[1:] != grid.shape + (2,) or phi.shape[0] < 1:
            raise ValueError(f"basis must have shape (K, {grid.shape[0]}, {grid.shape[1]}, 2) with K >= 1, got {phi.shape}")
        if not np.isfinite(phi).all():
            raise ValueError("basis must be finite")
        self.grid = grid
        self.basis = np.array(phi, dtype=np.float64)
        self.basis.flags.writeable = False
        self.reset()

    def reset(self) -> None:
        """Forget every reading."""
        k = self.basis.shape[0]
        self._gram = np.zeros((k, k))  # Σ Φ_nᵀ Φ_n
        self._rhs = np.zeros(k)  # Σ Φ_nᵀ w_n
        self._ww = 0.0  # Σ |w_n|²
        self.n_readings = 0

    def add(self, position, reading) -> None:
        """Assimilate one anemometer reading (u_x, u_y) in m/s, map frame, taken at ``position`` (x, y) m."""
        r, c = self.grid.cell_of(position)
        w = np.asarray(real_pair(reading, "reading", "a (u_x, u_y)", "m/s"), dtype=np.float64)
        phi = self.basis[:, r, c, :].T  # Φ_n : (2, K)
        self._gram += phi.T @ phi
        self._rhs += phi.T @ w
        self._ww += float(w @ w)
        self.n_readings += 1

    @property
    def coefficients(self) -> np.ndarray:
        """(K,) â (zeros before any reading; the minimum-norm solution while the readings do not fix every a_k)."""
        if self.n_readings == 0:
            return np.zeros(self.basis.shape[0])
        return np.linalg.lstsq(self._gram, self._rhs, rcond=None)[0]

    @property
    def covariance(self) -> np.ndarray:
        """(K, K) σ̂² (Σ Φ_nᵀ Φ_n)⁺ with σ̂² = RSS / (2N − K), the residual variance per axis (NaN without
        enough readings)."""
        k = self.basis.shape[0]
        dof = 2 * self.n_readings - k
        if dof <= 0:
            return np.full((k, k), np.nan)
        a = self.coefficients
        rss = max(self._ww - 2 * float(a @ self._rhs) + float(a @ self._gram @ a), 0.0)
        return rss / dof * np.linalg.pinv(self._gram)

    def field(self, coefficients=None) -> np.ndarray:
        """(H, W, 2) Σ_k a_k φ_k for ``coefficients`` (default: the current estimate)."""
        a = self.coefficients if coefficients is None else np.asarray(coefficients, dtype=np.float64)
        return np.tensordot(a, self.basis, axes=1)
