"""Finite-volume discretisation of the steady advection-diffusion-decay plume model on the occupancy grid.

The mean concentration c(r) of a continuously emitting source at r0 obeys (Vergassola et al. 2007, Methods)

    0 = D ∇²c − ∇·(w c) − c/τ + R δ(r − r0),

with eddy diffusivity D, wind w(r), finite particle lifetime τ and emission rate R. On the grid every free,
non-outlet cell is one unknown (cell average); the balance over cell i of side h reads, after division by h²,

    Σ_faces F_i→j / h + c_i/τ = R_i / h²,       F_i→j = (D/h) [a(Pe) c_i − b(Pe) c_j],   Pe = u_f h / D,

where u_f is the wind's normal component on the face (mean of the two cell values, positive out of i). Walls
(occupied cells) have no-flux faces; outlet cells and, with ``boundary="open"``, the outside of the map are
absorbing (c = 0 one cell away). Two face-flux schemes are provided:

* ``"exponential"`` (default): the exponentially fitted (Il'in / Allen–Southwell / Scharfetter–Gummel) flux,
  a(Pe) = B(−Pe), b(Pe) = B(Pe) with the Bernoulli function B(x) = x / (eˣ − 1). It is exact for 1-D steady
  advection-diffusion, reduces to central differencing for Pe → 0 (second order) and to pure upwinding for
  |Pe| → ∞; both coefficients stay positive, so the matrix remains an M-matrix (non-negative Green's
  function) at any Péclet number.
* ``"upwind"``: first-order upwinding, a(Pe) = 1 + max(Pe, 0), b(Pe) = 1 + max(−Pe, 0). Monotone too, but it
  adds a numerical diffusion |u| h / 2 that biases the plume (see the analytic-match test).

The resulting matrix A (1/s) is a Z-matrix whose columns are strictly diagonally dominant (the face fluxes are
conservative and 1/τ > 0), hence a non-singular M-matrix: A⁻¹ ≥ 0 entrywise.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .._shared._validate import as_float_array
from ..geometry._grid import GridMap

__all__ = ["advection_diffusion_operator", "bernoulli"]

_SCHEMES = ("exponential", "upwind")
_BOUNDARIES = ("wall", "open")


def bernoulli(x) -> np.ndarray:
    """Bernoulli function B(x) = x / (eˣ − 1), with B(0) = 1, evaluated without overflow.

    Parameters
    ----------
    x : (...) array_like of float

    Returns
    -------
    b : (...) ndarray of float64
        Positive; B(x) − B(−x) = −x.

    Raises
    ------
    ValueError
        ``x`` holds NaN or inf.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.allclose(bernoulli([0.0, 1.0, -1.0, 800.0]), [1.0, 1 / (np.e - 1), np.e / (np.e - 1), 0.0]))
    True
    """
    x = as_float_array(x, "x", dtype=np.float64)
    if not np.isfinite(x).all():
        raise ValueError(f"x must be finite, got {x[~np.isfinite(x)][0]} among its entries")
    out = np.empty_like(x)
    small = np.abs(x) < 1e-3
    xs = x[small]
    out[small] = 1.0 - xs / 2.0 + xs**2 / 12.0 - xs**4 / 720.0  # Taylor series, error O(x⁶)
    pos = (~small) & (x > 0)
    xp = x[pos]
    out[pos] = xp * np.exp(-xp) / -np.expm1(-xp)  # x e^{-x} / (1 - e^{-x}): no overflow for large x
    neg = (~small) & (x < 0)
    xn = x[neg]
    out[neg] = xn / np.expm1(xn)
    return out


def _flux_coefficients(pe: np.ndarray, scheme: str) -> tuple[np.ndarray, np.ndarray]:
    """(a, b) of the face flux F = (D/h)(a c_i − b c_j) for outward Péclet numbers ``pe``."""
    if scheme == "exponential":
        return bernoulli(-pe), bernoulli(pe)
    return 1.0 + np.maximum(pe, 0.0), 1.0 + np.maximum(-pe, 0.0)


def advection_diffusion_operator(
    geometry: GridMap,
    wind: np.ndarray,
    *,
    outlets=None,
    diffusivity: float,
    lifetime: float,
    boundary: str = "wall",
    scheme: str = "exponential",
) -> tuple[sp.csc_matrix, np.ndarray]:
    """Sparse matrix A with A c = q / h² for the steady plume on the active (free, non-outlet) cells.

    Parameters
    ----------
    geometry : psgsl_pgm.GridMap
        Occupancy and resolution h.
    wind : (H, W, 2) ndarray of float64
        Cell-centred wind (u_x, u_y) in m/s (validated; zero on occupied cells).
    outlets : (H, W) ndarray of bool, optional
        Free cells that absorb gas (c = 0 there); none by default.
    diffusivity : float
        Eddy diffusivity D in m²/s (> 0).
    lifetime : float
        Particle lifetime τ in s (> 0, finite).
    boundary : {"wall", "open"}
        The map border: no-flux wall, or absorbing free space beyond the last cell.
    scheme : {"exponential", "upwind"}
        Face-flux scheme (see the module docstring).

    Returns
    -------
    A : (n, n) scipy.sparse.csc_matrix of float64
        n = number of active cells, unit 1/s. The concentration (s/m² per unit emission rate) due to a unit
        source in active cell j is ``A⁻¹ e_j / h²``.
    index : (H, W) ndarray of int64
        Active-cell number of every grid cell, −1 for occupied and outlet cells.

    Raises
    ------
    ValueError
        ``scheme`` or ``boundary`` is not one of its names.

    Examples
    --------
    Still air on a free 2 x 3 map of 0.5 m cells, D = 0.1 m²/s, τ = 10 s: each cell loses c/τ and exchanges
    D/h² = 0.4 /s with each neighbour:

    >>> import numpy as np
    >>> from psgsl_pgm import GridMap
    >>> from psgsl_pgm.olfaction import advection_diffusion_operator
    >>> A, index = advection_diffusion_operator(GridMap(np.zeros((2, 3), bool), 0.5), np.zeros((2, 3, 2)),
    ...                                         diffusivity=0.1, lifetime=10.0)
    >>> index.tolist()
    [[0, 1, 2], [3, 4, 5]]
    >>> A.toarray()[0].round(3)                                # corner cell 0: 1/τ + 2 · 0.4 on the diagonal
    array([ 0.9, -0.4,  0. , -0.4,  0. ,  0. ])
    """
    if scheme not in _SCHEMES:
        raise ValueError(f"scheme must be one of {_SCHEMES}, got {scheme!r}")
    if boundary not in _BOUNDARIES:
        raise ValueError(f"boundary must be one of {_BOUNDARIES}, got {boundary!r}")
    h = geometry.resolution
    outlet = np.zeros(geometry.shape, dtype=bool) if outlets is None else np.asarray(outlets, dtype=bool)
    active = geometry.free & ~outlet
    index = np.full(geometry.shape, -1, dtype=np.int64)
    n = int(active.sum())
    index[active] = np.arange(n)
    k = diffusivity / h**2  # D / h², 1/s
    diag = np.full(n, 1.0 / lifetime)  # decay c/τ
    rows, cols, vals = [], [], []
    diag_parts_idx, diag_parts_val = [], []

    # interior faces: axis 1 -> between (r, c) and (r, c+1) with u_x; axis 0 -> (r, c) and (r+1, c) with u_y
    for axis, comp in ((1, 0), (0, 1)):
        lo = (slice(None), slice(None, -1)) if axis == 1 else (slice(None, -1), slice(None))
        hi = (slice(None), slice(1, None)) if axis == 1 else (slice(1, None), slice(None))
        u_face = 0.5 * (wind[lo + (comp,)] + wind[hi + (comp,)])  # normal velocity, positive lo -> hi
        pe = u_face * h / diffusivity
        a_lo, b_lo = _flux_coefficients(pe, scheme)  # outward from the lo cell; from hi: a(-pe)=b_lo, b(-pe)=a_lo
        act_lo, act_hi = active[lo], active[hi]
        both = act_lo & act_hi
        i_lo, i_hi = index[lo][both], index[hi][both]
        rows += [i_lo, i_hi]
        cols += [i_hi, i_lo]
        vals += [-k * b_lo[both], -k * a_lo[both]]  # F_i->j = k (a c_i - b c_j)
        diag_parts_idx += [i_lo, i_hi]
        diag_parts_val += [k * a_lo[both], k * b_lo[both]]
        # faces to an absorbing outlet cell (c = 0 there): only the outgoing part remains
        lo_to_out = act_lo & outlet[hi]
        hi_to_out = act_hi & outlet[lo]
        diag_parts_idx += [index[lo][lo_to_out], index[hi][hi_to_out]]
        diag_parts_val += [k * a_lo[lo_to_out], k * b_lo[hi_to_out]]

    if boundary == "open":
        # absorbing exterior: outward Péclet number from the cell's own normal wind component
        edges = (
            ((slice(None), 0), 0, -1.0),
            ((slice(None), -1), 0, 1.0),
            ((0, slice(None)), 1, -1.0),
            ((-1, slice(None)), 1, 1.0),
        )
        for sl, comp, sign in edges:
            pe = sign * wind[sl + (comp,)] * h / diffusivity
            a_out, _ = _flux_coefficients(pe, scheme)
            m = active[sl]
            diag_parts_idx.append(index[sl][m])
            diag_parts_val.append(k * a_out[m])

    if diag_parts_idx:
        diag += np.bincount(np.concatenate(diag_parts_idx), weights=np.concatenate(diag_parts_val), minlength=n)
    rows.append(np.arange(n))
    cols.append(np.arange(n))
    vals.append(diag)
    A = sp.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n), dtype=np.float64
    )
    return A, index
