"""The filament gas model's per-filament loops, compiled: the time steps, and the filaments that reach a point.

:func:`steps` advances the filaments by whole time steps (release at the source, wind plus Gaussian noise, a
move into a wall skipped, outlets and the map's border removing); :func:`near` lists the filaments within the
cut-off of one query point whose cell the query cell sees (:func:`psgsl_pgm.kernels._sight.segment_clear`, the
package's one line-of-sight rule); :func:`sample` does both for a gas sensor's window, one call per reading. The rules are those of
:class:`psgsl_pgm.sim.FilamentModel` (its docstrings state them); every floating-point operation is the IEEE
operation of its formula there, in the same order, so the compiled loop gives the values of the formulas bit
for bit (no fused multiply-add: numba compiles without fast-math). The noise is drawn from the model's own
``numpy.random.Generator`` inside the loop (numba's ``Generator.normal`` is numpy's algorithm on the same bit
generator: the same numbers, in the same order, and the same generator state afterwards). What the compiled
code must not compute — ``exp`` and ``pow``, whose numpy implementations (SIMD on some CPUs) may round
differently from the C library's — stays in numpy, in the model.

Compiled by numba on first call and cached on disk (``cache=True``); imported lazily.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from . import _cache as _numba_cache  # noqa: F401  (kernels cached in the user cache dir, not site-packages)
from ._sight import segment_clear

__all__ = ["near", "sample", "steps"]

_JIT = dict(nogil=True, cache=True, error_model="numpy")


@nb.njit(inline="always", **_JIT)
def _row_col(x, y, ox, oy, res):
    """(row, col) of the point (x, y): floor((p − origin) / resolution), as FilamentModel._cells_of."""
    return np.int64(math.floor((y - oy) / res)), np.int64(math.floor((x - ox) / res))


@nb.njit(inline="always", **_JIT)
def _wall(walls, h, w, r, q):
    """Whether cell (r, q) is a wall; indices outside the map clipped to its border."""
    return walls[min(max(r, 0), h - 1) * w + min(max(q, 0), w - 1)]


@nb.njit(inline="always", **_JIT)
def _blocked_short(walls, h, w, ox, oy, res, ax, ay, bx, by, r0, q0, r1, q1):
    """A move a -> b of less than one cell per axis, from cell (r0, q0) to (r1, q1): is a cell on its path
    (after the first) a wall? The end cell, and for a diagonal move the cell of the boundary crossed first."""
    blocked = _wall(walls, h, w, r1, q1)
    if r1 != r0 and q1 != q0:
        cx = ox + float(max(q0, q1)) * res  # the corner between the cells
        cy = oy + float(max(r0, r1)) * res
        tx = (cx - ax) / (bx - ax)
        ty = (cy - ay) / (by - ay)
        blocked = blocked | (((tx <= ty) and _wall(walls, h, w, r0, q1)) or ((ty <= tx) and _wall(walls, h, w, r1, q0)))
    return blocked


@nb.njit(inline="always", **_JIT)
def _step(rng, s, t, n_released, pos, births, cells, n_live, vel, dt, release_rate, noise_std, source_x, source_y,
          source_r, source_q, walls, stays, h, w, ox, oy, res):
    """One time step, step number ``s`` starting at time ``t`` (the rules of :func:`steps`).

    Returns
    -------
    n_live, n_released, n_removed : int
    """
    count = np.int64(math.floor((s + 1) * dt * release_rate + 1e-9)) - n_released
    if count > 0:
        if n_live + count > pos.shape[0]:
            raise ValueError("the filament arrays cannot hold the released filaments")
        for i in range(n_live, n_live + count):
            pos[i, 0] = source_x
            pos[i, 1] = source_y
            births[i] = t
            cells[i, 0] = source_r
            cells[i, 1] = source_q
        n_live += count
        n_released += count
    noise = np.empty((n_live, 2))
    for i in range(n_live):
        noise[i, 0] = rng.normal(0.0, noise_std)
        noise[i, 1] = rng.normal(0.0, noise_std)
    step_len = 0.999 * res
    kept = 0
    for i in range(n_live):
        r0 = cells[i, 0]
        q0 = cells[i, 1]
        k = r0 * w + q0
        ax = pos[i, 0]
        ay = pos[i, 1]
        bx = ax + (vel[k, 0] * dt + noise[i, 0])
        by = ay + (vel[k, 1] * dt + noise[i, 1])
        r1, q1 = _row_col(bx, by, ox, oy, res)
        n = math.ceil(max(abs(bx - ax), abs(by - ay)) / step_len)
        if n > 1:  # sub-move j ends at a + (b − a) min(j / n, 1); the first event decides
            blocked = False
            sx, sy, sr, sq = ax, ay, r0, q0
            for j in range(1, np.int64(n) + 1):
                f = min(float(j) / n, 1.0)
                ex = ax + (bx - ax) * f
                ey = ay + (by - ay) * f
                er, eq = _row_col(ex, ey, ox, oy, res)
                wall = _blocked_short(walls, h, w, ox, oy, res, sx, sy, ex, ey, sr, sq, er, eq)
                if wall or not (er >= 0 and er < h and eq >= 0 and eq < w):
                    blocked = wall
                    break
                sx, sy, sr, sq = ex, ey, er, eq
        else:
            blocked = _blocked_short(walls, h, w, ox, oy, res, ax, ay, bx, by, r0, q0, r1, q1)
        if blocked:  # the move is skipped
            bx, by, r1, q1 = ax, ay, r0, q0
        if stays[min(max(r1 + 1, 0), h + 1) * (w + 2) + min(max(q1 + 1, 0), w + 1)]:
            pos[kept, 0] = bx
            pos[kept, 1] = by
            births[kept] = births[i]
            cells[kept, 0] = r1
            cells[kept, 1] = q1
            kept += 1
    return kept, n_released, n_live - kept


@nb.njit(inline="always", **_JIT)
def _gather(pos, births, cells, n_live, x, y, qr, qc, time, sigma0_sq, gamma, cutoff_sq, occ, seen, neg_arg, var,
            start):
    """Append, in filament order from ``start``, −|x − x_f|² / (2 σ_f²) to ``neg_arg`` and σ_f² to ``var`` for every
    filament that reaches the point (x, y) in cell (qr, qc) at ``time``: |x − x_f|² < cutoff² σ_f² with
    σ_f² = σ0² + γ (t − t_f), and the line of sight from the point's cell to the filament's cell clear (the table
    ``seen`` of the point's cell: 1 clear, 0 blocked, −1 not traversed yet — then traversed and stored).
    Returns the new end."""
    n = start
    for i in range(n_live):
        dx = pos[i, 0] - x
        dy = pos[i, 1] - y
        d2 = dx * dx + dy * dy
        s2 = sigma0_sq + gamma * (time - births[i])
        if d2 < cutoff_sq * s2:
            fr = cells[i, 0]
            fc = cells[i, 1]
            v = seen[fr, fc]
            if v < 0:
                v = np.int8(1) if segment_clear(occ, qr, qc, fr, fc) else np.int8(0)
                seen[fr, fc] = v
            if v > 0:
                neg_arg[n] = -d2 / (2 * s2)
                var[n] = s2
                n += 1
    return n


@nb.njit(**_JIT)
def steps(rng, n_steps, step0, time0, n_released, pos, births, cells, n_live, velocities, snapshot_period, dt,
          release_rate, noise_std, source_x, source_y, source_r, source_q, walls, stays, h, w, ox, oy, res):
    """Advance ``n_steps`` time steps from step ``step0`` at time ``time0`` (later steps start at step · dt); the
    filaments live in ``pos[:n_live]``, ``births[:n_live]``, ``cells[:n_live]`` (the arrays' capacity must hold
    every filament released meanwhile).

    Per step: release ⌊(step + 1) dt · rate + 1e-9⌋ − released filaments at the source (born at the step's
    start); draw the noise of every filament ((F, 2), row-major, ``rng.normal(0, noise_std)``); move each by its
    cell's wind of the snapshot in force times dt plus the noise; skip a move that meets a wall (a move of more
    than a cell per axis in sub-moves of less than one: the first sub-move that meets a wall or leaves the map
    decides); remove the filaments that end in an outlet or outside the map (the table ``stays`` over the map
    padded by one cell). The survivors keep their order.

    Returns
    -------
    n_live, n_released, n_removed : int
    """
    n_snap = velocities.shape[0]
    removed = 0
    for s in range(step0, step0 + n_steps):
        t = time0 if s == step0 else s * dt
        vel = velocities[np.int64(math.floor(t / snapshot_period)) % n_snap]
        n_live, n_released, gone = _step(rng, s, t, n_released, pos, births, cells, n_live, vel, dt, release_rate,
                                         noise_std, source_x, source_y, source_r, source_q, walls, stays, h, w, ox,
                                         oy, res)
        removed += gone
    return n_live, n_released, removed


@nb.njit(**_JIT)
def sample(rng, n_steps, step0, time0, n_released, pos, births, cells, n_live, velocities, snapshot_period, dt,
           release_rate, noise_std, source_x, source_y, source_r, source_q, walls, stays, h, w, ox, oy, res,
           x, y, qr, qc, sigma0_sq, gamma, cutoff_sq, occ, seen, neg_arg, var, ends):
    """:func:`steps`, and after each step the filaments that reach the point (x, y) in cell (qr, qc) (see
    :func:`_gather`): those of step k end at ``ends[k]`` in ``neg_arg`` and ``var`` (k = 0 … n_steps − 1).

    Returns
    -------
    n_live, n_released, n_removed : int
    """
    n_snap = velocities.shape[0]
    removed = 0
    end = 0
    for k in range(n_steps):
        s = step0 + k
        t = time0 if k == 0 else s * dt
        vel = velocities[np.int64(math.floor(t / snapshot_period)) % n_snap]
        n_live, n_released, gone = _step(rng, s, t, n_released, pos, births, cells, n_live, vel, dt, release_rate,
                                         noise_std, source_x, source_y, source_r, source_q, walls, stays, h, w, ox,
                                         oy, res)
        removed += gone
        end = _gather(pos, births, cells, n_live, x, y, qr, qc, (s + 1) * dt, sigma0_sq, gamma, cutoff_sq, occ, seen,
                      neg_arg, var, end)
        ends[k] = end
    return n_live, n_released, removed


@nb.njit(**_JIT)
def near(pos, births, cells, n_live, x, y, qr, qc, time, sigma0_sq, gamma, cutoff_sq, occ, seen, neg_arg, var):
    """The filaments that reach the point (x, y) in cell (qr, qc) at ``time`` (:func:`_gather`); returns their
    number."""
    return _gather(pos, births, cells, n_live, x, y, qr, qc, time, sigma0_sq, gamma, cutoff_sq, occ, seen, neg_arg,
                   var, 0)
