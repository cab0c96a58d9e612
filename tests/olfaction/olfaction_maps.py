"""Hand-made maps and flows for the olfaction tests (independent of psgsl_pgm.sim)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

RES = 0.2  # metres per cell of the test house


def potential_flow(occupancy, inlet, outlet, *, resolution, mean_speed):
    """Cell-centred potential flow u = −∇φ, ∇²φ = 0 on free cells, φ = 1 on ``inlet``, 0 on ``outlet``.

    Walls and the map border are no-flux (Neumann). Face velocities −(φ_j − φ_i)/h are averaged onto cells
    and the field is scaled so that the mean speed over free cells is ``mean_speed``.
    """
    free = ~occupancy
    if (occupancy & (inlet | outlet)).any():
        raise ValueError("inlet and outlet cells must be free")
    h, w = occupancy.shape
    n = h * w
    idx = np.arange(n).reshape(h, w)
    rows, cols = [], []
    for a, b in (
        ((slice(None), slice(None, -1)), (slice(None), slice(1, None))),
        ((slice(None, -1), slice(None)), (slice(1, None), slice(None))),
    ):
        ok = free[a] & free[b]
        rows += [idx[a][ok], idx[b][ok]]
        cols += [idx[b][ok], idx[a][ok]]
    r, c = np.concatenate(rows), np.concatenate(cols)
    adj = sp.csr_matrix((np.ones(r.size), (r, c)), shape=(n, n))
    lap = sp.diags(np.asarray(adj.sum(axis=1)).ravel()) - adj  # graph Laplacian on free cells
    fixed = (inlet | outlet).ravel()
    unknown = free.ravel() & ~fixed
    phi = np.zeros(n)
    phi[inlet.ravel()] = 1.0
    rhs = -(lap[unknown][:, fixed] @ phi[fixed])
    phi[unknown] = spla.spsolve(lap[unknown][:, unknown].tocsc(), rhs)
    phi = phi.reshape(h, w)
    wind = np.zeros((h, w, 2))
    for axis, comp in ((1, 0), (0, 1)):
        a = (slice(None), slice(None, -1)) if axis == 1 else (slice(None, -1), slice(None))
        b = (slice(None), slice(1, None)) if axis == 1 else (slice(1, None), slice(None))
        ok = free[a] & free[b]
        face = np.where(ok, -(phi[b] - phi[a]) / resolution, 0.0)
        acc = np.zeros((h, w))
        cnt = np.zeros((h, w))
        acc[a] += face
        acc[b] += face
        cnt[a] += ok
        cnt[b] += ok
        wind[..., comp] = np.divide(acc, np.maximum(cnt, 1))
    wind[occupancy] = 0.0
    speed = np.hypot(wind[..., 0], wind[..., 1])[free].mean()
    return wind * (mean_speed / speed)


def two_rooms(*, door: bool, height=14, width=25, wall_col=12, door_rows=(10, 13)):
    """Two rooms side by side, separated by a wall at column ``wall_col`` (with or without a door)."""
    occ = np.zeros((height, width), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    occ[:, wall_col] = True
    if door:
        occ[door_rows[0] : door_rows[1], wall_col] = False
    return occ


def small_house():
    """A 10 m x 8 m flat at 0.2 m: kitchen, bathroom, living room, bedroom, one window in, one out.

    Returns
    -------
    occupancy : (40, 50) bool
    rooms : dict name -> (40, 50) bool mask
    inlet, outlet : (40, 50) bool
    """
    h, w = 40, 50
    occ = np.zeros((h, w), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    occ[20, :] = True
    occ[20, 8:12] = False  # kitchen <-> living door
    occ[20, 36:40] = False  # bathroom <-> bedroom door
    occ[:20, 25] = True
    occ[8:12, 25] = False  # kitchen <-> bathroom door
    occ[20:, 30] = True
    occ[28:32, 30] = False  # living <-> bedroom door
    occ[5:8, 5:10] = True  # kitchen table
    occ[30:34, 12:20] = True  # sofa
    inlet = np.zeros((h, w), bool)
    inlet[30:34, 0] = True  # living-room window (air in)
    outlet = np.zeros((h, w), bool)
    outlet[4:8, 49] = True  # bathroom window (air out)
    occ[inlet | outlet] = False
    rr, cc = np.mgrid[0:h, 0:w]
    rooms = {
        "kitchen": (rr < 20) & (cc < 25),
        "bathroom": (rr < 20) & (cc > 25),
        "living": (rr > 20) & (cc < 30),
        "bedroom": (rr > 20) & (cc > 30),
    }
    rooms = {k: v & ~occ for k, v in rooms.items()}
    return occ, rooms, inlet, outlet


def lattice_stops(occupancy, *, step, resolution, margin=1, origin=(0.0, 0.0)):
    """Robot stops (x, y) on a regular lattice of free cells at least ``margin`` cells from any wall."""
    h, w = occupancy.shape
    pad = np.pad(occupancy, margin, constant_values=True)
    near = np.zeros_like(occupancy)
    for dr in range(-margin, margin + 1):
        for dc in range(-margin, margin + 1):
            near |= pad[margin + dr : margin + dr + h, margin + dc : margin + dc + w]
    rr, cc = np.mgrid[step // 2 : h : step, step // 2 : w : step]
    keep = ~near[rr, cc]
    x = origin[0] + (cc[keep] + 0.5) * resolution
    y = origin[1] + (rr[keep] + 0.5) * resolution
    return np.stack([x, y], axis=1)
