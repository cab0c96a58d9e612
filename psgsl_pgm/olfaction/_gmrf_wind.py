"""Wind map from the anemometer readings with a Gaussian Markov random field over the map's free cells.

PMFS (Ojeda, Monroy & Gonzalez-Jimenez, "Robotic Gas Source Localization with Probabilistic Mapping and Online
Dispersion Simulation", IEEE T-RO 2024, arXiv:2304.08879) simulates filaments on a wind map estimated from the
robot's own readings with a GMRF (Gonzalez-Jimenez et al.'s GMRF wind mapping). Here each component of the
mean wind u = (u_x, u_y) on the free cells is the maximum a posteriori estimate of a GMRF, the sparse least
squares problem

    û = argmin_u  Σ_n |w_n − u_{c_n}|² / σ_z²  +  Σ_{i~j} |u_i − u_j|² / σ_r²  +  Σ_i |u_i|² / σ_0²,

with w_n the readings (m/s) at the cells c_n, i~j the pairs of 4-neighbouring free cells (a wall is a missing
edge, so readings do not leak through it), σ_z the reading noise, σ_r the change of the wind between
neighbouring cells and σ_0 a weak prior towards still air that keeps cells no reading reaches defined (their
connected region has no data: they stay at zero). The normal equations (D/σ_z² + L/σ_r² + I/σ_0²) û = b/σ_z²,
D the diagonal count of readings per cell, L the graph Laplacian of the free cells, are solved with a sparse
LU factorisation (scipy.sparse), one per refresh for both components. Cost: the factorisation of an N × N
matrix with 5 non-zeros per row, N free cells (about 6000 for the embedded house: a few milliseconds).

A uniform flow sampled anywhere is recovered exactly up to the prior's shrinkage (its Laplacian term is zero);
a field with curl or divergence is smoothed.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .._shared._validate import positive, real_pair
from ..geometry._grid import GridMap

__all__ = ["GMRFWind"]


class GMRFWind:
    """GMRF estimate of the mean wind field from anemometer readings (see the module docstring).

    Parameters
    ----------
    grid : psgsl_pgm.GridMap
        The map; the field lives on its free cells.
    reading_std : float, default 0.1, keyword-only
        σ_z in m/s: noise of one reading about the mean wind (sensor noise and the eddies of the moment).
    smoothness_std : float, default 0.05, keyword-only
        σ_r in m/s: change of the mean wind between neighbouring cells.
    prior_std : float, default 100.0, keyword-only
        σ_0 in m/s: the prior towards still air (weak: it only fixes cells no reading reaches).

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm import GridMap
    >>> gmrf = GMRFWind(GridMap(np.zeros((6, 8), bool), 0.25))
    >>> gmrf.add((0.3, 0.3), (0.4, -0.1)); gmrf.add((1.6, 1.2), (0.4, -0.1))
    >>> gmrf.field()[5, 7].round(3).tolist()          # the far corner: the uniform flow of the readings
    [0.4, -0.1]
    """

    def __init__(self, grid: GridMap, *, reading_std: float = 0.1, smoothness_std: float = 0.05,
                 prior_std: float = 100.0):
        if not isinstance(grid, GridMap):
            raise TypeError(f"grid must be a psgsl_pgm.GridMap, got {type(grid).__name__}")
        self.grid = grid
        self.reading_std = positive(reading_std, "reading_std", "m/s")
        self.smoothness_std = positive(smoothness_std, "smoothness_std", "m/s")
        self.prior_std = positive(prior_std, "prior_std", "m/s")
        free = grid.free
        h, w = grid.shape
        self._index = np.full(h * w, -1, np.int64)
        self._cells = np.flatnonzero(free.ravel())
        self._index[self._cells] = np.arange(self._cells.size)
        idx = self._index.reshape(h, w)
        pairs = [np.stack([idx[:, :-1][free[:, :-1] & free[:, 1:]], idx[:, 1:][free[:, :-1] & free[:, 1:]]]),
                 np.stack([idx[:-1][free[:-1] & free[1:]], idx[1:][free[:-1] & free[1:]]])]
        i, j = np.concatenate(pairs, axis=1)
        n = self._cells.size
        adj = sp.coo_matrix((np.ones(i.size), (i, j)), shape=(n, n))
        adj = (adj + adj.T).tocsr()
        self._laplacian = (sp.diags(np.asarray(adj.sum(axis=1)).ravel()) - adj).tocsc()
        self.reset()

    def reset(self) -> None:
        """Forget every reading (the field returns to still air)."""
        n = self._cells.size
        self._count = np.zeros(n)  # readings per free cell
        self._sum = np.zeros((n, 2))  # Σ w_n per free cell
        self.n_readings = 0
        self._field = None

    def add(self, position, reading) -> None:
        """Assimilate one reading (u_x, u_y) in m/s, map frame, taken at ``position`` (x, y) in metres (a free cell)."""
        r, c = self.grid.cell_of(position)  # ValueError outside the map or in an occupied cell
        k = self._index[r * self.grid.shape[1] + c]
        w = np.asarray(real_pair(reading, "reading", "a (u_x, u_y)", "m/s"), dtype=np.float64)
        self._count[k] += 1.0
        self._sum[k] += w
        self.n_readings += 1
        self._field = None

    def field(self) -> np.ndarray:
        """(H, W, 2) float64 û in m/s on the free cells, zero on occupied ones (a fresh array)."""
        if self._field is None:
            a = (sp.diags(self._count / self.reading_std ** 2) + self._laplacian / self.smoothness_std ** 2
                 + sp.identity(self._cells.size) / self.prior_std ** 2).tocsc()
            u = spla.splu(a).solve(self._sum / self.reading_std ** 2) if self._cells.size else np.zeros((0, 2))
            out = np.zeros((self.grid.shape[0] * self.grid.shape[1], 2))
            out[self._cells] = u
            self._field = out.reshape(self.grid.shape + (2,))
        return self._field.copy()
