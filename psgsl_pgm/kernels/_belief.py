"""Compiled single-pass kernels over the ``(n, k)`` class beliefs and over per-cell vectors.

The cost of the closed form is one read of ``class_probs``. Each kernel reads every row once and, while the
row (k values) is in L1, derives every per-cell quantity the caller needs — the semantic weight
w_c = q_c · ρ, the row sum, the number of negative entries, the mass on zero-prior classes and, for the
information gain, the central moments of ρ under q_c. The weight kernel reduces :data:`ROWS` rows at a time
(one load of ρ_i serves four dot products) in explicit 64-byte vectors with one transposed reduction tree for
the eight sums (:mod:`psgsl_pgm.kernels._rows`), and is memory-bound. The moments kernel does about five times the
arithmetic per entry and is compute-bound on a 2-core machine; it takes four rows' weights in one pass
(:func:`~psgsl_pgm.kernels._rows.rows4v`) and each row's moments in a second pass from L1
(:func:`~psgsl_pgm.kernels._rows.central`), both in explicit vectors with one reduction tree (measured on an
AMD EPYC 9004, one core, 80-class rows in L2: 48 ns per row with the ν moments, 36 without). Both prefetch the rows :data:`AHEAD` bytes on (:mod:`psgsl_pgm.kernels._prefetch`), so that memory reads
overlap the arithmetic. Fusion of two inputs takes two passes and no temporary: the normaliser, then the
output, written once.

Rows are grouped in fixed chunks of :data:`CHUNK` cells; the compiled loops release the GIL, and :func:`run`
hands contiguous ranges of chunks to one thread per core as each finishes its last (a core slowed by other
work takes fewer). Partial sums are kept per chunk and added in chunk order, so results do not depend on the
number of threads or on who ran which range.

Floating-point contract: float32 beliefs are read as float32 (no float64 copy of the array is ever made); the
weights are accumulated in float32, as a BLAS ``sgemv`` would, the moments in float64. NaN and ±inf
propagate (the fast-math flags allow re-association, which lets the compiler vectorise the sums, but not
``nnan``/``ninf``). A NaN or inf entry makes its row sum non-finite, which the row-sum statistic reports as
an infinite deviation.

Kernels are compiled by numba on first call and cached on disk (``cache=True``); there is no interpreted
twin. The ``_``-prefixed functions are the compiled loops; the public names allocate their outputs and
combine the per-chunk partials.
"""

from __future__ import annotations

import math
import os
from collections import deque
from concurrent.futures import ThreadPoolExecutor

import numba as nb
import numpy as np
from numba import types
from numba.extending import overload

from . import _cache as _numba_cache  # noqa: F401  (kernels cached in the user cache dir, not site-packages)
from ._prefetch import prefetch
from ._rows import central, rows4, rows4v

__all__ = [
    "CHUNK",
    "PARALLEL_MIN",
    "combine_stats",
    "n_chunks",
    "run",
    "ORDER",
    "belief_weights",
    "belief_moments",
    "cell_logs",
    "entropy_terms",
    "gain_from_moments",
    "fuse_sum",
    "fuse_write",
    "fuse_step",
    "fuse_finish",
    "column_sums",
]

CHUNK = 4096  # cells per parallel work item: large enough to amortise scheduling, small enough to balance
ORDER = 5  # information-gain series order J (the kernels below hold μ_2..μ_5 and ν_1..ν_4 in registers)
TINY = 2.0**-1000  # a product below this (of positive factors) may have lost bits: that cell goes to log space
HUGE = 2.0**1000  # a quotient above this (division by a tiny prior) goes to log space too

ROWS = 4  # rows reduced together by the weight kernel
AHEAD = 4096  # bytes of q ahead of the rows being reduced that the kernels prefetch (measured: 2–8 KiB alike)
LINE = 64  # bytes per cache line

PASS_WORK = 16  # the work a cell of a light per-cell pass (fusion, entropy) counts for in run(): two to four
#                arrays read per cell, with compares and products; measured, two threads pay off from about
#                half a million cells

SPLITS = 8  # ranges per thread handed out by run(): a slower core takes fewer of them
PARALLEL_MIN = 1 << 23  # elements read below which one thread is used: ~5 ms of work, more than a thread
#                        hand-off costs even on a loaded machine

_FASTMATH = {"reassoc", "contract", "nsz", "arcp"}  # never nnan / ninf: NaN and inf must propagate
_JIT = dict(nogil=True, cache=True, fastmath=_FASTMATH, error_model="numpy")
_JIT_STRICT = dict(nogil=True, cache=True, error_model="numpy")  # no re-association: a fixed summation order
_THREADS = max(1, min(8, os.cpu_count() or 1))
_POOL: ThreadPoolExecutor | None = None


def _pool() -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None:  # created on first use, never at import
        _POOL = ThreadPoolExecutor(max_workers=_THREADS, thread_name_prefix="psgsl-kernel")
    return _POOL


def run(kernel, n: int, work: int, *args) -> None:
    """Run ``kernel(*args, c0, c1)`` over the chunks [0, ⌈n / CHUNK⌉) of n cells.

    The kernels release the GIL, so when ``work`` (elements read) is at least :data:`PARALLEL_MIN` the chunks
    are split into :data:`SPLITS` contiguous ranges per core, which the calling thread and one pool thread
    per further core take in turn until none is left (a core slowed by other work takes fewer); otherwise
    they run on the calling thread. Every kernel writes per-chunk partial results into arrays the caller
    owns, so the outcome does not depend on how the chunks were split or who ran them.
    """
    nch = (n + CHUNK - 1) // CHUNK
    threads = min(_THREADS, nch) if work >= PARALLEL_MIN else 1
    if threads <= 1:
        kernel(*args, 0, nch)
        return
    parts = min(nch, SPLITS * threads)
    edges = [nch * i // parts for i in range(parts + 1)]
    ranges = deque(range(parts))  # popleft is thread-safe: each range is taken exactly once

    def drain():
        while True:
            try:
                i = ranges.popleft()
            except IndexError:
                return
            kernel(*args, edges[i], edges[i + 1])

    futures = [_pool().submit(drain) for _ in range(threads - 1)]
    drain()  # the calling thread works too
    for fut in futures:
        fut.result()


def n_chunks(n: int) -> int:
    """Number of :data:`CHUNK`-cell chunks (rows of the partial-result arrays) for n cells."""
    return (n + CHUNK - 1) // CHUNK


def combine_stats(part: np.ndarray) -> np.ndarray:
    """Belief statistics from per-chunk partials (columns: negatives, worst |Σ−1|, its row, leak, total)."""
    out = np.zeros(5)
    if part.shape[0]:
        out[0] = part[:, 0].sum()
        best = int(np.argmax(part[:, 1]))
        out[1], out[2] = part[best, 1], part[best, 2]
        out[3] = part[:, 3].max()
        out[4] = part[:, 4].sum()
    return out


@nb.njit(**_JIT)
def _belief_weights(q, rho, zero, has_zero, w, part, c0, c1):
    """Rows of chunks [c0, c1): w = q @ rho (accumulated in q's dtype, like a BLAS GEMV) and statistics.

    :data:`ROWS` rows are reduced together by :func:`psgsl_pgm.kernels._rows.rows4`, so each load of ρ serves
    four dot products and the loop over the classes runs once per four rows; the rows :data:`AHEAD` bytes on are
    prefetched meanwhile. Negative entries are found from the sum of min(entry, 0) (a sum of non-positive terms
    is negative iff one of them is), kept in a register; the zero-prior mass is kept per class and reduced once
    per chunk.
    """
    n, k = q.shape
    nought = rho[0] - rho[0]  # 0 in q's dtype (rho is finite)
    leak = np.empty(k, q.dtype)
    sums = np.empty(ROWS)  # row sums of the current block (float64: exact for float32 sums)
    ahead = AHEAD // q.itemsize
    line = LINE // q.itemsize
    size = q.size
    for c in range(c0, c1):
        lo = nought  # Σ of min(entries, 0): negative iff some entry is (a sum of non-positive terms cannot cancel)
        leak[:] = nought
        worst = 0.0
        worst_row = 0
        tot = 0.0
        r = c * CHUNK
        end = min(n, (c + 1) * CHUNK)
        while r < end:
            rows = min(ROWS, end - r)
            start = r * k + ahead
            for e in range(start, min(start + rows * k, size), line):
                prefetch(q, e)
            if rows == ROWS:  # one pass over the four rows in explicit vectors (psgsl_pgm.kernels._rows)
                a0, a1, a2, a3, s0, s1, s2, s3, neg = rows4(q, r, rho)
                lo += neg
                w[r] = a0
                w[r + 1] = a1
                w[r + 2] = a2
                w[r + 3] = a3
                tot += (np.float64(a0) + np.float64(a1)) + (np.float64(a2) + np.float64(a3))
                sums[0] = s0
                sums[1] = s1
                sums[2] = s2
                sums[3] = s3
            else:  # the last rows of the array
                for j in range(rows):
                    acc = nought
                    s = nought
                    for i in range(k):
                        x = q[r + j, i]
                        acc += x * rho[i]
                        s += x
                        lo += min(x, nought)
                    w[r + j] = acc
                    tot += acc
                    sums[j] = s
            if has_zero:
                for j in range(rows):
                    for i in range(k):
                        leak[i] = max(leak[i], q[r + j, i] * zero[i])
            for j in range(rows):
                d = abs(sums[j] - 1.0)
                if d != d:
                    d = math.inf
                if d > worst:
                    worst = d
                    worst_row = r + j
            r += rows
        part[c, 0] = -lo
        part[c, 1] = worst
        part[c, 2] = worst_row
        part[c, 3] = leak.max()
        part[c, 4] = tot


@nb.njit(**_JIT)
def _belief_moments(q, rho, rho_log_rho, zero, f, f_uniform, paper, w, mom, part, c0, c1):
    """Rows of chunks [c0, c1): w, v = q · ρ log ρ, μ_2…μ_5 (and ν_1…ν_4), Σ f w and the belief statistics.

    :data:`ROWS` rows at a time: their weights, v and row sums in one pass (:func:`psgsl_pgm.kernels._rows.rows4v`),
    then each row's central moments about its weight (:func:`psgsl_pgm.kernels._rows.central`), with the row
    still in L1. All arithmetic in float64.
    """
    n, k = q.shape
    has_f = f.shape[0] > 0
    has_zero = zero.max() > 0.0
    ahead = AHEAD // q.itemsize
    line = LINE // q.itemsize
    size = q.size
    ws = np.empty(ROWS)
    vs = np.empty(ROWS)
    ss = np.empty(ROWS)
    for c in range(c0, c1):
        neg = 0.0
        worst = 0.0
        worst_row = 0
        leak = 0.0
        tot = 0.0
        r = c * CHUNK
        end = min(n, (c + 1) * CHUNK)
        while r < end:
            rows = min(ROWS, end - r)
            start = r * k + ahead
            for e in range(start, min(start + rows * k, size), line):
                prefetch(q, e)
            if rows == ROWS:
                w0, w1, w2, w3, v0, v1, v2, v3, s0, s1, s2, s3, lo = rows4v(q, r, rho, rho_log_rho)
                ws[0], ws[1], ws[2], ws[3] = w0, w1, w2, w3
                vs[0], vs[1], vs[2], vs[3] = v0, v1, v2, v3
                ss[0], ss[1], ss[2], ss[3] = s0, s1, s2, s3
                neg += lo
            else:  # the last rows of the array
                for j in range(rows):
                    acc = 0.0
                    v = 0.0
                    s = 0.0
                    for i in range(k):
                        x = np.float64(q[r + j, i])
                        acc += x * rho[i]
                        v += x * rho_log_rho[i]
                        s += x
                        neg += min(x, 0.0)
                    ws[j] = acc
                    vs[j] = v
                    ss[j] = s
            for j in range(rows):
                row = r + j
                acc = ws[j]
                if has_zero:  # mass on zero-prior classes (an error): only looked for when there are such classes
                    z = 0.0
                    for i in range(k):
                        z += q[row, i] * zero[i]
                    if z > leak:
                        leak = z
                if paper:
                    m2, m3, m4, m5, n1, n2, n3, n4 = central(q, row, rho, rho_log_rho, acc, True)
                    mom[row, 5] = n1
                    mom[row, 6] = n2
                    mom[row, 7] = n3
                    mom[row, 8] = n4
                else:
                    m2, m3, m4, m5, _, _, _, _ = central(q, row, rho, rho_log_rho, acc, False)
                w[row] = acc
                mom[row, 0] = vs[j]  # Σ_i q_i ρ_i log ρ_i; the gain pass subtracts w log w (a log per row costs
                #                      this compute-bound pass a fifth of its time, the gain pass far less)
                mom[row, 1] = m2
                mom[row, 2] = m3
                mom[row, 3] = m4
                mom[row, 4] = m5
                tot += (f[row] if has_f else f_uniform) * acc
                d = abs(ss[j] - 1.0)
                if d != d:
                    d = math.inf
                if d > worst:
                    worst = d
                    worst_row = row
            r += rows
        part[c, 0] = -neg
        part[c, 1] = worst
        part[c, 2] = worst_row
        part[c, 3] = leak
        part[c, 4] = tot


@nb.njit(**_JIT)
def _gain_from_moments(q, w, mom, f, f_uniform, total, rho, rho_log_rho, entropy, radius, paper, log_w, log_f,
                       log_total, out, c0, c1):
    r"""I(S; O_n) for every cell from its moments (series) or, where the series converges slowly, its row.

    With a_n = f_n / U and x_ni = a_n (ρ_i − w_n): the series is used where a_n · max_i |ρ_i − w_n| ≤
    ``radius`` (truncation ≲ radius^(ORDER−1) relative to the leading term); other cells sum φ(x_ni) (exact) or the paper's terms over
    their row of ``q`` directly. Formulas: module docstring of :mod:`psgsl_pgm.core._infogain`.
    """
    n, k = q.shape
    has_f = f.shape[0] > 0
    rmax = rho.max()
    rmin = rho.min()
    log_uniform = math.log(f_uniform) if f_uniform > 0 else 0.0
    for r in range(c0 * CHUNK, min(n, c1 * CHUNK)):
        a = (f[r] if has_f else f_uniform) / total
        wn = w[r]
        wlw = wn * log_w[r] if wn > 0 else 0.0
        jensen = mom[r, 0] - wlw  # Jensen gap v − w log w ≥ 0
        spread = max(rmax - wn, wn - rmin)
        alog = a * ((log_f[r] if has_f else log_uniform) - log_total) if a > 0 else 0.0  # a log a
        if a * spread <= radius:
            # (−a)^j μ_j, j = 2..5 (μ_1 = 0 exactly)
            na = -a
            p2 = na * na
            p3 = p2 * na
            p4 = p3 * na
            p5 = p4 * na
            m2, m3, m4, m5 = mom[r, 1], mom[r, 2], mom[r, 3], mom[r, 4]
            t2, t3, t4, t5 = p2 * m2, p3 * m3, p4 * m4, p5 * m5
            if not paper:
                # Σ_i q_i φ(x_i) = Σ_{j≥2} (−a)^j μ_j / (j (j−1))
                g = a * jensen - (t2 / 2.0 + t3 / 6.0 + t4 / 12.0 + t5 / 20.0)
                out[r] = g if g > 0.0 else 0.0
            else:
                one_minus_s0 = -(t2 + t3 + t4 + t5)  # 1 − Σ q / Z
                t1 = na * m2 + p2 * m3 + p3 * m4 + p4 * m5  # Σ q (ρ − w) / Z
                n1, n2, n3, n4 = mom[r, 5], mom[r, 6], mom[r, 7], mom[r, 8]
                s2_gap = jensen + (
                    na * n1  # μ_1 = 0
                    + p2 * (n2 - wlw * m2)
                    + p3 * (n3 - wlw * m3)
                    + p4 * (n4 - wlw * m4)
                )
                s3 = -(t2 / 2.0 + t3 / 3.0 + t4 / 4.0 + t5 / 5.0)  # Σ q log Z
                out[r] = entropy * one_minus_s0 + alog * t1 + a * s2_gap - s3
        else:
            if not paper:
                acc = 0.0
                for i in range(k):
                    x = a * (rho[i] - wn)
                    zz = 1.0 + x
                    phi = (zz * math.log1p(x) if zz > 0 else 0.0) - x  # φ(x) = Z log Z − x
                    acc += q[r, i] * phi
                g = a * jensen - acc
                out[r] = g if g > 0.0 else 0.0
            else:
                s_x = 0.0
                s_d = 0.0
                s_gap = 0.0
                s_log = 0.0
                for i in range(k):
                    qi = q[r, i]
                    d = rho[i] - wn
                    x = a * d
                    zz = 1.0 + x
                    if zz > 0:  # impossible outcomes (Z = 0) contribute nothing
                        qz = qi / zz
                        s_x += qz * x
                        s_d += qz * d
                        s_gap += qz * (rho_log_rho[i] - wlw)
                        s_log += qi * math.log1p(x)
                out[r] = entropy * s_x + alog * s_d + a * s_gap - s_log


@nb.njit(**_JIT)
def _fuse_write(out, a, b, prior, extra, total, c0, c1):
    """Second pass: out = a b / prior^extra / T, rounded once to ``out``'s dtype (eq. (11))."""
    n = a.shape[0]
    has_prior = prior.shape[0] > 0
    lo, hi = c0 * CHUNK, min(n, c1 * CHUNK)
    oc, ac, bc, pc = out[lo:hi], a[lo:hi], b[lo:hi], prior[lo:hi] if has_prior else prior
    for i in range(hi - lo):
        z = np.float64(ac[i]) * np.float64(bc[i])
        if has_prior and z > 0.0:
            pr = np.float64(pc[i])
            for _ in range(extra):
                z /= pr
        oc[i] = z / total


# --- The light per-cell passes (entropy, fusion): one chunk driver, one body per pass ---------------------------


def each_chunk(body, part, n, c0, c1, args):
    """Run ``body(part[c], lo, hi, *args)`` on the cells [lo, hi) of every chunk c in [c0, c1) (compiled only).

    ``body`` is the name (a string literal) of a per-chunk body in :data:`_BODIES`; each body reads its cells,
    writes the chunk's partial results into its row ``part[c]`` and returns nothing. (A name rather than the
    function itself: numba cannot cache a function that is handed another compiled function as a value.)
    """
    raise TypeError("each_chunk is called from compiled kernels only")


@overload(each_chunk, jit_options=_JIT)
def _each_chunk_impl(body, part, n, c0, c1, args):
    if not isinstance(body, types.StringLiteral):
        return None
    cells = _BODIES[body.literal_value]

    def impl(body, part, n, c0, c1, args):
        for c in range(c0, c1):
            cells(part[c], c * CHUNK, min(n, (c + 1) * CHUNK), *args)

    return impl


@nb.njit(**_JIT)
def _entropy_cells(row, lo, hi, w, f, f_uniform, total, log_w, log_f, log_total):
    """Σ −P_n log P_n over cells [lo, hi), with P_n = f_n w_n / U (``total`` = U), log P_n = log f_n + log w_n − log U."""
    has_f = f.shape[0] > 0
    log_uniform = math.log(f_uniform) if f_uniform > 0 else 0.0
    wc, lwc = w[lo:hi], log_w[lo:hi]  # views: indices from 0 vectorise to contiguous loads, not gathers
    fc, lfc = (f[lo:hi], log_f[lo:hi]) if has_f else (f[:0], log_f[:0])
    h = 0.0
    for r in range(hi - lo):
        p = (fc[r] if has_f else f_uniform) * wc[r] / total
        if p > 0:
            h -= p * ((lfc[r] if has_f else log_uniform) + lwc[r] - log_total)
    row[0] = h


@nb.njit(**_JIT)
def _fuse_sum_cells(row, lo, hi, a, b, prior, extra):
    """First pass of fusing two inputs over cells [lo, hi): the checks of both and T = Σ_c a_c b_c / prior_c^extra.

    Nothing is stored. A cell whose product of positive factors falls below :data:`TINY`, or whose quotient
    exceeds :data:`HUGE`, is counted as unsafe and left out of T (the caller then takes the log-space route).
    ``row``: [negatives of a, Σ a, negatives of b, Σ b, unsafe cells, T, cells where the product is positive
    but the prior is zero]. The vectorised sums do not depend on where the inputs sit in memory (tested:
    tests/kernels/test_kernels_speed.py).
    """
    has_prior = prior.shape[0] > 0
    neg_a = 0
    neg_b = 0
    sa = 0.0
    sb = 0.0
    total = 0.0
    unsafe = 0
    zero_support = 0
    ac, bc, pc = a[lo:hi], b[lo:hi], prior[lo:hi] if has_prior else prior
    for i in range(hi - lo):
        x = np.float64(ac[i])
        y = np.float64(bc[i])
        neg_a += x < 0
        neg_b += y < 0
        sa += x
        sb += y
        z = x * y  # p(s_c|e_1) p(s_c|e_2)
        bad = (z < TINY) & (x > 0) & (y > 0)
        if has_prior:
            pr = np.float64(pc[i])
            if z != 0.0 and pr == 0.0:
                zero_support += 1
                z = 0.0
            elif z > 0.0:
                for _ in range(extra):
                    z /= pr  # ÷ p(s_c)^(m−1)
                bad |= z > HUGE
        unsafe += bad
        total += 0.0 if bad else z
    row[0] = neg_a
    row[1] = sa
    row[2] = neg_b
    row[3] = sb
    row[4] = unsafe
    row[5] = total
    row[6] = zero_support


@nb.njit(**_JIT)
def _fuse_step_cells(row, lo, hi, p, a, first):
    """Multiply the running product ``p`` by ``a`` in place on cells [lo, hi) (``first``: set p = a).

    A cell whose product of positive factors falls below :data:`TINY` is marked −1 (it is recomputed in log
    space by the caller) and stays marked. ``row``: [negative entries of a, Σ a, newly marked cells].
    """
    neg = 0
    s = 0.0
    unsafe = 0
    pch, ac = p[lo:hi], a[lo:hi]
    for i in range(hi - lo):
        x = np.float64(ac[i])
        neg += x < 0
        s += x
        if first:
            pch[i] = x
        else:
            pc = pch[i]
            z = pc * x
            bad = (z < TINY) & (pc > 0) & (x > 0)
            unsafe += bad
            pch[i] = -1.0 if (bad | (pc < 0)) else z
    row[0] = neg
    row[1] = s
    row[2] = unsafe


@nb.njit(**_JIT)
def _fuse_finish_cells(row, lo, hi, p, prior, extra):
    """Divide the product by prior^extra (when ``prior`` is non-empty) and sum the cells of [lo, hi) not marked.

    A quotient above :data:`HUGE` is marked −1 too. ``row``: [Σ unmarked p, marked cells, cells where the
    product is positive (or marked) but the prior is zero].
    """
    has_prior = prior.shape[0] > 0
    s = 0.0
    marked = 0
    zero_support = 0
    pch, prc = p[lo:hi], prior[lo:hi] if has_prior else prior
    for i in range(hi - lo):
        y = pch[i]
        if has_prior:
            pr = prc[i]
            if y != 0.0 and pr == 0.0:
                zero_support += 1
            elif y > 0.0:
                for _ in range(extra):
                    y /= pr
                if y > HUGE:
                    y = -1.0
                pch[i] = y
        if y < 0.0:
            marked += 1
        else:
            s += y
    row[0] = s
    row[1] = marked
    row[2] = zero_support


_BODIES = {"entropy": _entropy_cells, "fuse_sum": _fuse_sum_cells, "fuse_step": _fuse_step_cells,
           "fuse_finish": _fuse_finish_cells}


@nb.njit(**_JIT)
def _entropy_terms(w, f, f_uniform, total, log_w, log_f, log_total, part, c0, c1):
    """H(S) = −Σ_n P_n log P_n with P_n = f_n w_n / U, one partial per chunk (:func:`_entropy_cells`)."""
    each_chunk("entropy", part, w.shape[0], c0, c1, (w, f, f_uniform, total, log_w, log_f, log_total))


@nb.njit(**_JIT)
def _fuse_sum(a, b, prior, extra, part, c0, c1):
    """First pass of fusing two inputs, one row of partials per chunk (:func:`_fuse_sum_cells`)."""
    each_chunk("fuse_sum", part, a.shape[0], c0, c1, (a, b, prior, extra))


@nb.njit(**_JIT)
def _fuse_step(p, a, first, part, c0, c1):
    """Multiply the running product ``p`` by ``a`` in place, one row of partials per chunk (:func:`_fuse_step_cells`)."""
    each_chunk("fuse_step", part, p.shape[0], c0, c1, (p, a, first))


@nb.njit(**_JIT)
def _fuse_finish(p, prior, extra, part, c0, c1):
    """Divide by prior^extra and sum the unmarked cells, one row of partials per chunk (:func:`_fuse_finish_cells`)."""
    each_chunk("fuse_finish", part, p.shape[0], c0, c1, (p, prior, extra))


@nb.njit(**_JIT_STRICT)
def _column_sums(w3, out, c0, c1):
    """out[a, b] = Σ_j w3[a, j, b], j = 0, 1, … in turn, for the output cells of chunks [c0, c1) (flat a·B + b).

    Compiled without re-association, so every column is summed in the same order (the voxels from the first
    along the column axis), whatever the CPU or where the column lies; the columns are independent chains the
    CPU overlaps.
    """
    size_a, m, size_b = w3.shape
    flat = out.reshape(-1)
    for cell in range(c0 * CHUNK, min(size_a * size_b, c1 * CHUNK)):
        a = cell // size_b
        b = cell - a * size_b
        s = 0.0
        for j in range(m):
            s += w3[a, j, b]
        flat[cell] = s


# --- Python entry points: allocate outputs, run the chunks, combine the partials in chunk order -------------


def belief_weights(q, rho, zero):
    """w = q @ rho and the validation statistics of ``q``, in one pass over ``q``.

    Parameters
    ----------
    q : (n, k) float32 or float64 ndarray, C-contiguous
    rho : (k,) float64 ndarray
    zero : (k,) float64 ndarray
        1.0 for classes with zero prior, else 0.0.

    Returns
    -------
    w : (n,) float64 ndarray
        Accumulated in the dtype of ``q`` (float32 sums for float32 beliefs, as a BLAS GEMV would).
    stats : (5,) float64 ndarray
        [minus the sum of the negative entries (> 0 iff there is one), largest |row sum − 1| (inf for a
        non-finite row sum), the row where it occurs, largest mass on zero-prior classes, Σ_c w_c].
    """
    n = q.shape[0]
    w = np.empty(n)
    part = np.zeros((n_chunks(n), 5))
    run(_belief_weights, n, q.size, q, rho.astype(q.dtype), zero.astype(q.dtype), bool(zero.any()), w, part)
    return w, combine_stats(part)


def belief_moments(q, rho, rho_log_rho, zero, f, f_uniform, paper):
    r"""Per-cell weight, v and central moments for the information gain, in one pass over ``q``.

    For each cell n with w_n = q_n · ρ: v_n = q_n · ρ log ρ (the gain pass forms the Jensen gap
    v_n − w_n log w_n), the central
    moments μ_j = Σ_i q_ni (ρ_i − w_n)^j for j = 2 … 5 and, when ``paper``, ν_j = Σ_i q_ni ρ_i log ρ_i
    (ρ_i − w_n)^j for j = 1 … 4. Each row is read from memory once; the second loop over it runs from L1.

    Parameters
    ----------
    q : (n, k) float32 or float64 ndarray, C-contiguous
    rho, rho_log_rho, zero : (k,) float64 ndarray
    f : (n,) float64 ndarray, or empty
        Olfactory posterior; when empty every cell has weight ``f_uniform``.
    f_uniform : float
    paper : bool
        Also compute the ν moments.

    Returns
    -------
    w : (n,) float64 ndarray
    mom : (n, 5) or (n, 9) float64 ndarray
        Columns [v, μ_2 … μ_5] (+ [ν_1 … ν_4] when ``paper``).
    stats : (5,) float64 ndarray
        As :func:`belief_weights`, with the last entry U = Σ_c f_c w_c instead of Σ_c w_c.
    """
    n = q.shape[0]
    w = np.empty(n)
    mom = np.empty((n, 9 if paper else 5))
    part = np.zeros((n_chunks(n), 5))
    run(_belief_moments, n, q.size * (3 if paper else 2), q, rho, rho_log_rho, zero, f, f_uniform, paper, w, mom, part)
    return w, mom, combine_stats(part)


def _cell_logs(w, f, log_w, log_f, c0, c1):
    """log w and log f on the cells of chunks [c0, c1) (NumPy's ufunc loop releases the GIL)."""
    cells = slice(c0 * CHUNK, c1 * CHUNK)
    with np.errstate(divide="ignore", invalid="ignore"):  # 0 -> -inf; the kernels use a log only where x > 0
        np.log(w[cells], out=log_w[cells])
        np.log(f[cells], out=log_f[cells])


def cell_logs(w, f):
    """(log w, log f) per cell, by NumPy's vectorised logarithm (−inf where a value is 0; f may be empty).

    The entropy and gain passes need log w_n, log f_n and log U for every cell: a scalar ``math.log`` in
    the compiled loops costs about 7 ns per call here, NumPy's SIMD log about 1.3 ns. Large maps are split
    over the kernel threads like the compiled passes.
    """
    log_w = np.empty_like(w)
    log_f = np.empty_like(f)
    run(_cell_logs, w.shape[0], PASS_WORK * w.shape[0], w, f, log_w, log_f)
    return log_w, log_f


def entropy_terms(w, f, f_uniform, total, logs=None) -> float:
    """H(S) = −Σ_n P_n log P_n with P_n = f_n w_n / U (``total`` = U); ``logs`` from :func:`cell_logs`."""
    n = w.shape[0]
    log_w, log_f = cell_logs(w, f) if logs is None else logs
    part = np.zeros((n_chunks(n), 1))
    run(_entropy_terms, n, PASS_WORK * n, w, f, f_uniform, total, log_w, log_f, math.log(total), part)
    return float(part.sum())


def gain_from_moments(q, w, mom, f, f_uniform, total, rho, rho_log_rho, entropy, radius, paper, logs=None):
    r"""I(S; O_n) for every cell from its moments (series) or, where the series converges slowly, its row.

    With a_n = f_n / U and x_ni = a_n (ρ_i − w_n): the series is used where a_n · max_i |ρ_i − w_n| ≤
    ``radius`` (truncation ≲ radius^(ORDER−1) relative to the leading term); other cells sum φ(x_ni) (exact)
    or the paper's terms over their row of ``q`` directly. Formulas: module docstring of
    :mod:`psgsl_pgm.core._infogain`. ``logs``: (log w, log f) from :func:`cell_logs` (computed when omitted).
    """
    n = q.shape[0]
    log_w, log_f = cell_logs(w, f) if logs is None else logs
    out = np.empty(n)
    run(_gain_from_moments, n, 4 * mom.size, q, w, mom, f, f_uniform, total, rho, rho_log_rho, entropy, radius,
        paper, log_w, log_f, math.log(total), out)
    return out


def fuse_sum(a, b, prior, extra: int):
    """Checks of a and b and the normaliser T of their fusion, without storing the product (see :func:`_fuse_sum`).

    Returns ([neg a, Σ a], [neg b, Σ b], unsafe cells, T, cells with a positive product and a zero prior).
    """
    n = a.shape[0]
    part = np.zeros((n_chunks(n), 7))
    run(_fuse_sum, n, PASS_WORK * n, a, b, prior, extra, part)
    t = part.sum(axis=0)
    return t[[0, 1]], t[[2, 3]], int(t[4]), float(t[5]), int(t[6])


def fuse_write(out, a, b, prior, extra: int, total: float) -> None:
    """out = a b / prior^extra / ``total`` in one pass (cells known to be safe: :func:`fuse_sum` found none unsafe)."""
    n = a.shape[0]
    run(_fuse_write, n, PASS_WORK * n, out, a, b, prior, extra, total)


def fuse_step(p, a, first: bool):
    """Multiply the running product ``p`` by ``a`` in place (``first``: set p = a); marks as :func:`_fuse_step`.

    Returns [negative entries of a, Σ a, newly marked cells].
    """
    n = p.shape[0]
    part = np.zeros((n_chunks(n), 3))
    run(_fuse_step, n, 3 * n, p, a, first, part)
    return part.sum(axis=0)


def fuse_finish(p, prior, extra: int):
    """Divide the product by prior^extra (``prior`` non-empty) and sum the unmarked cells, in place.

    A quotient above :data:`HUGE` is marked −1 too. Returns (Σ unmarked p, marked cells, cells where the
    product is positive or marked but the prior is zero).
    """
    n = p.shape[0]
    part = np.zeros((n_chunks(n), 3))
    run(_fuse_finish, n, 3 * n, p, prior, extra, part)
    t = part.sum(axis=0)
    return float(t[0]), int(t[1]), int(t[2])


def column_sums(values, axis: int):
    """Σ over one axis of a C-contiguous float64 array, each sum taken in order along the axis (one pass).

    Sec. "Voxelized Scene Representations": p(s_c | z) = Σ_{v ∈ c} p(s_v | z). NumPy's ``sum`` over a short
    last axis (a column of tens of voxels) spends most of its time starting each small reduction; this pass
    reads the weights once and sums every column as one chain of additions.

    Parameters
    ----------
    values : (...) float64 ndarray, C-contiguous
    axis : int
        A non-negative axis of ``values``.

    Returns
    -------
    sums : float64 ndarray
        ``values``'s shape without ``axis``.
    """
    shape = values.shape
    size_a = int(np.prod(shape[:axis], dtype=np.int64))
    size_b = int(np.prod(shape[axis + 1:], dtype=np.int64))
    out = np.empty(shape[:axis] + shape[axis + 1:])
    w3 = values.reshape(size_a, shape[axis], size_b)
    run(_column_sums, size_a * size_b, values.size, w3, out.reshape(size_a, size_b))
    return out
