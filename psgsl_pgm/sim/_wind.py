"""Wind fields: potential flow from inlet to outlet windows, with a slow divergence-free perturbation.

Potential flow (Sec. 2 of the simulation issue): Δφ = 0 on the free cells (finite volumes, 5-point stencil),
φ = 1 on inlet cells and φ = 0 on outlet cells (Dirichlet), no flux through walls or the map border
(Neumann). Velocities live on the cell faces of a staggered grid, u = -∂φ/∂n, so that the discrete
divergence of every interior cell is exactly the residual of the linear system (zero to solver precision).

The perturbation is the discrete curl of a smooth random stream function ψ defined on cell *corners*
(u_face = ∂ψ/∂y, v_face = -∂ψ/∂x): exactly divergence-free on every cell for any ψ, and with ψ = 0 on every
corner that touches a wall, a window or the border it adds no flux through them. ψ evolves as an AR(1)
process between piecewise-constant snapshots, so dead ends see slow eddies instead of perfect calm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.ndimage as ndi
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .._shared._memo import ContentCache, content_digest
from ..geometry._grid import GridMap

__all__ = ["WindField", "WindSequence", "potential_flow", "make_wind"]


@dataclass(frozen=True, eq=False)
class WindField:
    """A 2-D wind snapshot on a grid map.

    Parameters
    ----------
    grid : GridMap
    velocity : (H, W, 2) ndarray
        Cell-centred (u, v) in m/s along (x, y); zero in walls.
    u_faces : (H, W + 1) ndarray or None
        x-velocity on the vertical faces (face c lies between columns c - 1 and c), if known.
    v_faces : (H + 1, W) ndarray or None
        y-velocity on the horizontal faces (face r lies between rows r - 1 and r), if known.
    """

    grid: GridMap
    velocity: np.ndarray
    u_faces: np.ndarray | None = None
    v_faces: np.ndarray | None = None

    def __post_init__(self):
        h, w = self.grid.shape
        vel = np.array(self.velocity, dtype=np.float64)
        if vel.shape != (h, w, 2):
            raise ValueError(f"velocity must have shape {(h, w, 2)} for this grid, got {vel.shape}")
        if not np.all(np.isfinite(vel)):
            raise ValueError("velocity must be finite")
        vel.flags.writeable = False
        object.__setattr__(self, "velocity", vel)
        for name, shape in (("u_faces", (h, w + 1)), ("v_faces", (h + 1, w))):
            f = getattr(self, name)
            if f is not None:
                f = np.array(f, dtype=np.float64)
                if f.shape != shape:
                    raise ValueError(f"{name} must have shape {shape}, got {f.shape}")
                f.flags.writeable = False
                object.__setattr__(self, name, f)

    @classmethod
    def from_faces(cls, grid: GridMap, u_faces, v_faces) -> "WindField":
        """Build from staggered face velocities; cell velocity = mean of its two faces per axis."""
        u_faces = np.asarray(u_faces, dtype=np.float64)
        v_faces = np.asarray(v_faces, dtype=np.float64)
        vel = np.stack([(u_faces[:, :-1] + u_faces[:, 1:]) / 2, (v_faces[:-1] + v_faces[1:]) / 2], axis=-1)
        vel[grid.occupancy] = 0.0
        return cls(grid, vel, u_faces, v_faces)

    def at(self, xy) -> np.ndarray:
        """(..., 2) wind at map-frame points (nearest cell; zero outside the map)."""
        rc = self.grid.world_to_cell(xy)
        inside = self.grid.contains(rc)
        out = np.zeros(rc.shape, dtype=np.float64)
        out[inside] = self.velocity[rc[inside][:, 0], rc[inside][:, 1]]
        return out

    def divergence(self) -> np.ndarray:
        """(H, W) net outflow of each cell, Σ faces u·n / resolution, in 1/s (needs face velocities)."""
        if self.u_faces is None or self.v_faces is None:
            raise ValueError("this wind field has no face velocities (e.g. read from a CFD export)")
        res = self.grid.resolution
        return (self.u_faces[:, 1:] - self.u_faces[:, :-1] + self.v_faces[1:] - self.v_faces[:-1]) / res

    def speed(self) -> np.ndarray:
        """(H, W) ‖velocity‖ in m/s."""
        return np.hypot(self.velocity[..., 0], self.velocity[..., 1])

    def __add__(self, other: "WindField") -> "WindField":
        if not isinstance(other, WindField) or other.grid.shape != self.grid.shape:
            return NotImplemented
        faces = all(f is not None for f in (self.u_faces, self.v_faces, other.u_faces, other.v_faces))
        if faces:
            return WindField.from_faces(self.grid, self.u_faces + other.u_faces, self.v_faces + other.v_faces)
        return WindField(self.grid, self.velocity + other.velocity)

    def scaled(self, factor: float) -> "WindField":
        """The field multiplied by ``factor``."""
        f = float(factor)
        if self.u_faces is not None and self.v_faces is not None:
            return WindField(self.grid, self.velocity * f, self.u_faces * f, self.v_faces * f)
        return WindField(self.grid, self.velocity * f)


def _check_mask(mask, grid: GridMap, name: str) -> np.ndarray:
    m = np.asarray(mask)
    if m.shape != grid.shape or m.dtype != bool:
        raise ValueError(f"{name} must be an (H, W) = {grid.shape} boolean mask, got shape {m.shape}, dtype {m.dtype}")
    return m


def _neighbour_pairs(free: np.ndarray):
    """Flat indices (a, b) of horizontally / vertically adjacent free cells (b right of / above a)."""
    h, w = free.shape
    idx = np.arange(h * w).reshape(h, w)
    hor = free[:, :-1] & free[:, 1:]
    ver = free[:-1, :] & free[1:, :]
    return (idx[:, :-1][hor], idx[:, 1:][hor]), (idx[:-1, :][ver], idx[1:, :][ver])


def potential_flow(grid: GridMap, inlet, outlet, *, mean_speed: float = 0.2) -> WindField:
    """Potential flow through the free space of ``grid`` from ``inlet`` to ``outlet`` cells.

    Parameters
    ----------
    grid : GridMap
        Walls (occupied cells) are impermeable; inlet/outlet cells are treated as free.
    inlet, outlet : (H, W) ndarray of bool
        Window cells with φ = 1 and φ = 0; disjoint and non-empty.
    mean_speed : float, keyword-only
        Mean ‖velocity‖ over the free non-window cells after scaling, m/s (> 0).

    Returns
    -------
    WindField
        With face velocities; cells not connected to any window have zero wind.

    Raises
    ------
    ValueError
        Empty or overlapping windows, or no free path from an inlet to an outlet.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.sim import GridMap, potential_flow
    >>> grid = GridMap(np.zeros((4, 6), bool), 0.5)
    >>> inlet = np.zeros((4, 6), bool); inlet[:, 0] = True
    >>> outlet = np.zeros((4, 6), bool); outlet[:, -1] = True
    >>> wind = potential_flow(grid, inlet, outlet, mean_speed=0.2)
    >>> wind.velocity[1, 1:5, 0].round(3).tolist()                  # straight from the inlet to the outlet
    [0.2, 0.2, 0.2, 0.2]
    >>> bool(np.abs(wind.velocity[..., 1]).max() < 1e-12)           # and no sideways component
    True
    """
    inlet = _check_mask(inlet, grid, "inlet")
    outlet = _check_mask(outlet, grid, "outlet")
    if not inlet.any() or not outlet.any():
        raise ValueError("inlet and outlet must each contain at least one cell")
    if (inlet & outlet).any():
        raise ValueError("inlet and outlet cells must be disjoint")
    if not (np.isfinite(mean_speed) and mean_speed > 0):
        raise ValueError(f"mean_speed must be a positive number in m/s, got {mean_speed!r}")
    field, current = _UNSCALED_FLOWS.get(_map_key(grid, inlet, outlet), lambda: _unscaled_flow(grid, inlet, outlet))
    return field.scaled(mean_speed / current)


def _map_key(grid: GridMap, inlet, outlet, *extra) -> str:
    """The content key of a map and its windows (and ``extra`` plain values) for this module's caches."""
    return content_digest(grid.occupancy, np.asarray(inlet), np.asarray(outlet), float(grid.resolution),
                          tuple(np.asarray(grid.origin, dtype=np.float64).tolist()), *extra)


#: The unscaled potential flow of each house's map and windows (one sparse solve), shared by every run of the
#: process: the simulator's wind and the robot's wind basis of every seed start from it.
_UNSCALED_FLOWS = ContentCache(maxsize=8)


def _unscaled_flow(grid: GridMap, inlet: np.ndarray, outlet: np.ndarray):
    """The potential flow's field before scaling and its mean speed over the free non-window cells; checked
    windows (:func:`potential_flow`)."""
    h, w = grid.shape
    free = grid.free | inlet | outlet
    dirichlet = inlet | outlet
    comp, _ = ndi.label(free)  # 4-connectivity, as the stencil
    live = np.isin(comp, np.unique(comp[inlet])) & np.isin(comp, np.unique(comp[outlet]))
    if not live.any():
        raise ValueError("no free path connects an inlet cell to an outlet cell")
    unknown = live & ~dirichlet
    phi = np.where(inlet, 1.0, 0.0).ravel()
    num = np.full(h * w, -1, dtype=np.int64)
    num[unknown.ravel()] = np.arange(int(unknown.sum()))
    (ha, hb), (va, vb) = _neighbour_pairs(free)
    a = np.concatenate([ha, va])
    b = np.concatenate([hb, vb])
    na, nb = num[a], num[b]
    rows, cols, vals = [], [], []
    rhs = np.zeros(int(unknown.sum()))
    for p, q, np_, nq in ((a, b, na, nb), (b, a, nb, na)):  # each edge contributes to both ends
        m = np_ >= 0
        rows.append(np_[m]); cols.append(np_[m]); vals.append(np.ones(m.sum()))  # degree term
        both = m & (nq >= 0)
        rows.append(np_[both]); cols.append(nq[both]); vals.append(-np.ones(both.sum()))
        fixed = m & (nq < 0)
        np.add.at(rhs, np_[fixed], phi[q[fixed]])  # Σ φ_j over Dirichlet neighbours
    n = rhs.size
    lap = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    if n:
        phi[unknown.ravel()] = spla.splu(lap).solve(rhs)  # Σ_j (φ_j - φ_i) = 0 on every unknown cell
    phi = phi.reshape(h, w)
    res = grid.resolution
    u_faces = np.zeros((h, w + 1))
    v_faces = np.zeros((h + 1, w))
    hor = free[:, :-1] & free[:, 1:]
    ver = free[:-1, :] & free[1:, :]
    u_faces[:, 1:-1] = np.where(hor, -(phi[:, 1:] - phi[:, :-1]) / res, 0.0)  # u = -∂φ/∂x
    v_faces[1:-1, :] = np.where(ver, -(phi[1:, :] - phi[:-1, :]) / res, 0.0)  # v = -∂φ/∂y
    field = WindField.from_faces(grid.with_occupancy(~free), u_faces, v_faces)
    inner = live & ~dirichlet
    current = field.speed()[inner].mean()
    if not current > 0:
        raise ValueError("the potential flow is zero everywhere (inlet and outlet at the same potential?)")
    return field, current  # a WindField's arrays are read-only


def _stream_perturbation(free_nodes_mask: np.ndarray, taper: np.ndarray, xi: np.ndarray, res: float, grid):
    """Face velocities of the discrete curl of ψ = taper · ξ on cell corners."""
    psi = taper * xi * free_nodes_mask
    u_faces = (psi[1:, :] - psi[:-1, :]) / res  # u = ∂ψ/∂y on vertical faces
    v_faces = -(psi[:, 1:] - psi[:, :-1]) / res  # v = -∂ψ/∂x on horizontal faces
    return WindField.from_faces(grid, u_faces, v_faces)


@dataclass(frozen=True, eq=False)
class WindSequence:
    """Piecewise-constant wind snapshots: snapshot ``k`` holds for t in [k·period, (k+1)·period).

    After the last snapshot the sequence loops (as GADEN's ``allow_looping``).

    Parameters
    ----------
    snapshots : tuple of WindField
    period : float
        Seconds per snapshot.
    """

    snapshots: tuple
    period: float

    def __post_init__(self):
        snaps = tuple(self.snapshots)
        if not snaps or not all(isinstance(s, WindField) for s in snaps):
            raise TypeError("snapshots must be a non-empty sequence of WindField")
        if not (np.isfinite(self.period) and self.period > 0):
            raise ValueError(f"period must be a positive number of seconds, got {self.period!r}")
        object.__setattr__(self, "snapshots", snaps)
        object.__setattr__(self, "period", float(self.period))
        stack = np.stack([s.velocity for s in snaps])
        stack.flags.writeable = False
        object.__setattr__(self, "_stack", stack)

    @property
    def grid(self) -> GridMap:
        return self.snapshots[0].grid

    @property
    def velocities(self) -> np.ndarray:
        """(n, H, W, 2) cell velocities of all snapshots (read-only)."""
        return self._stack

    def index(self, t: float) -> int:
        """Snapshot index in force at time ``t`` (s)."""
        return int(np.floor(t / self.period)) % len(self.snapshots)

    def at_time(self, t: float) -> WindField:
        """The snapshot in force at time ``t``."""
        return self.snapshots[self.index(t)]

    def mean(self) -> WindField:
        """Time-average of the snapshots."""
        if all(s.u_faces is not None and s.v_faces is not None for s in self.snapshots):
            return WindField.from_faces(
                self.grid,
                np.mean([s.u_faces for s in self.snapshots], axis=0),
                np.mean([s.v_faces for s in self.snapshots], axis=0),
            )
        return WindField(self.grid, self._stack.mean(axis=0))


def make_wind(
    grid: GridMap,
    inlet,
    outlet,
    *,
    mean_speed: float = 0.2,
    perturbation: float = 0.3,
    correlation_length: float = 1.0,
    correlation_time: float = 60.0,
    period: float = 10.0,
    duration: float = 600.0,
    seed: int = 0,
) -> WindSequence:
    """Potential flow plus a slow random divergence-free perturbation, as piecewise-constant snapshots.

    Parameters
    ----------
    grid, inlet, outlet, mean_speed
        As :func:`potential_flow`.
    perturbation : float, keyword-only
        Mean perturbation speed as a fraction of ``mean_speed`` (0 = steady potential flow).
    correlation_length : float, keyword-only
        Spatial scale of the eddies, metres (Gaussian smoothing of the stream function).
    correlation_time : float, keyword-only
        e-folding time of the AR(1) evolution of the stream function, seconds.
    period : float, keyword-only
        Snapshot duration, seconds.
    duration : float, keyword-only
        Time covered before the sequence loops, seconds.
    seed : int, keyword-only

    Returns
    -------
    WindSequence

    Raises
    ------
    ValueError
        ``period``, ``duration``, ``correlation_length`` or ``correlation_time`` is not a positive number,
        ``perturbation`` is negative or not finite, or :func:`potential_flow` refuses the windows or ``mean_speed``.

    Examples
    --------
    A 2 m x 3 m room with an inlet window along its west column and an outlet along its east column:

    >>> import numpy as np
    >>> from psgsl_pgm.sim import GridMap, make_wind
    >>> grid = GridMap(np.zeros((4, 6), bool), 0.5)
    >>> inlet = np.zeros((4, 6), bool); inlet[:, 0] = True
    >>> outlet = np.zeros((4, 6), bool); outlet[:, -1] = True
    >>> wind = make_wind(grid, inlet, outlet, period=10.0, duration=30.0, seed=0)
    >>> len(wind.snapshots), wind.period
    (3, 10.0)
    >>> steady = make_wind(grid, inlet, outlet, perturbation=0.0, duration=30.0)
    >>> steady.snapshots[0] is steady.snapshots[2]                  # no eddies: one potential flow
    True
    """
    for name, v in (("period", period), ("duration", duration), ("correlation_length", correlation_length),
                    ("correlation_time", correlation_time)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be a positive number, got {v!r}")
    if not (np.isfinite(perturbation) and perturbation >= 0):
        raise ValueError(f"perturbation must be a non-negative fraction of mean_speed, got {perturbation!r}")
    key = _map_key(grid, inlet, outlet, float(mean_speed), float(perturbation), float(correlation_length),
                   float(correlation_time), float(period), float(duration), int(seed))
    return _WIND_SEQUENCES.get(key, lambda: _make_wind(grid, inlet, outlet, mean_speed, perturbation,
                                                      correlation_length, correlation_time, period, duration, seed))


#: The last wind sequences made (immutable): every arm and condition of an episode runs in the same seeded wind,
#: and a grid's worker takes an episode's runs one after another.
_WIND_SEQUENCES = ContentCache(maxsize=2)


def _make_wind(grid, inlet, outlet, mean_speed, perturbation, correlation_length, correlation_time, period, duration,
               seed) -> WindSequence:
    """:func:`make_wind` on checked arguments."""
    base = potential_flow(grid, inlet, outlet, mean_speed=mean_speed)
    n = max(1, int(np.ceil(duration / period)))
    if perturbation == 0:
        return WindSequence((base,) * n, period)
    h, w = grid.shape
    res = grid.resolution
    wall = base.grid.occupancy | np.asarray(inlet) | np.asarray(outlet)
    # corners (nodes) touching a wall, window or the border keep ψ = 0: no flux through them
    padded = np.pad(wall, 1, constant_values=True)
    node_blocked = padded[:-1, :-1] | padded[:-1, 1:] | padded[1:, :-1] | padded[1:, 1:]
    node_free = ~node_blocked
    taper = np.minimum(1.0, ndi.distance_transform_edt(node_free) * res / correlation_length)
    rng = np.random.default_rng(seed)
    sigma = correlation_length / res

    def smooth_noise():
        return ndi.gaussian_filter(rng.standard_normal((h + 1, w + 1)), sigma, mode="constant")

    rho = np.exp(-period / correlation_time)
    xi = smooth_noise()
    inner = ~wall
    unit = _stream_perturbation(node_free, taper, xi, res, base.grid)
    s0 = unit.speed()[inner].mean()
    scale = perturbation * mean_speed / s0 if s0 > 0 else 0.0
    snaps = []
    for k in range(n):
        if k:
            xi = rho * xi + np.sqrt(1 - rho**2) * smooth_noise()  # AR(1): stationary variance
        snaps.append(base + _stream_perturbation(node_free, taper, xi * scale, res, base.grid))
    return WindSequence(tuple(snaps), period)
