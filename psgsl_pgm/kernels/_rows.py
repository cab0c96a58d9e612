"""``rows4(q, r, rho)``: the weights, sums and negative mass of four rows of ``q``, in explicit 64-byte vectors.

numba's loop vectoriser reduces each accumulator of a row loop on its own after the loop (five shuffles and adds
per accumulator for 16 float32 lanes) and, when the row length is not a multiple of its unrolled width (80
float32 classes are two 32-wide steps and a rest), runs a second vector loop with a second set of reductions.
For four rows of 80 float32 classes that was about half of the work. This intrinsic emits the loop itself:
vectors of 64 bytes (16 float32 or 8 float64 lanes; LLVM splits them on a CPU with narrower registers), a
masked last step for the rest of the row, and one transposed reduction tree that folds the eight accumulators
(4 weights, 4 row sums) into one vector in three shuffle-and-add levels. Nothing in it depends on the CPU
model: it is target-independent LLVM IR (vector loads, ``llvm.masked.load``, ``shufflevector``).

Summation order (fixed, the same on every call and thread): lane l of the accumulator takes the classes
i ≡ l (mod lanes) in increasing i; the lanes are then added pairwise by the tree.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

__all__ = ["rows4", "rows4v", "central", "VECTOR_BYTES"]

VECTOR_BYTES = 64  # bytes per vector: one AVX-512 register, two AVX2 registers
_FLAGS = ("contract", "reassoc", "nsz", "arcp")  # the kernels' fast-math flags; never nnan / ninf


def _halve(builder, u, v, groups, width):
    """Pair two vectors holding ``groups`` accumulators each (contiguous lane groups): 2·groups accumulators."""
    size = width // groups
    lo, hi = [], []
    for off in (0, width):  # u's groups, then v's
        for g in range(groups):
            start = off + g * size
            lo.extend(range(start, start + size // 2))
            hi.extend(range(start + size // 2, start + size))
    i32 = ir.IntType(32)
    a = builder.shuffle_vector(u, v, ir.Constant(ir.VectorType(i32, width), lo))
    b = builder.shuffle_vector(u, v, ir.Constant(ir.VectorType(i32, width), hi))
    return builder.fadd(a, b, flags=_FLAGS)


def _fold(builder, x, width):
    """Sum of all lanes of x by halving (log2 width shuffles and adds)."""
    i32 = ir.IntType(32)
    while width > 1:
        half = width // 2
        a = builder.shuffle_vector(x, x, ir.Constant(ir.VectorType(i32, half), list(range(half))))
        b = builder.shuffle_vector(x, x, ir.Constant(ir.VectorType(i32, half), list(range(half, width))))
        x = builder.fadd(a, b, flags=_FLAGS)
        width = half
    return builder.extract_element(x, ir.Constant(i32, 0))


class _Rows:
    """IR helpers shared by the intrinsics: the vector type of q's dtype, (masked) loads, the loop over a row."""

    def __init__(self, context, builder, dtype):
        self.b = builder
        self.ft = context.get_value_type(dtype)
        self.size = context.get_abi_sizeof(self.ft)
        self.lanes = VECTOR_BYTES // self.size
        self.vt = ir.VectorType(self.ft, self.lanes)
        self.vp = self.vt.as_pointer()
        self.zero = ir.Constant(self.vt, [0.0] * self.lanes)
        ml_ty = ir.FunctionType(self.vt, [self.vp, ir.IntType(32), ir.VectorType(ir.IntType(1), self.lanes), self.vt])
        name = f"llvm.masked.load.v{self.lanes}f{8 * self.size}.p0"  # (vector, pointer) overload, e.g. v16f32.p0
        self.masked_load = cgutils.get_or_insert_function(builder.module, ml_ty, name)

    def load(self, ptr, i, mask):
        p = self.b.bitcast(self.b.gep(ptr, [i]), self.vp)
        if mask is None:
            return self.b.load(p, align=self.size)
        return self.b.call(self.masked_load, [p, ir.Constant(ir.IntType(32), self.size), mask, self.zero])

    def load_widened(self, ptr, dtype_ft, i, mask):
        """``lanes`` values of a narrower float type (float32 q in float64 arithmetic), widened."""
        if dtype_ft == self.ft:
            return self.load(ptr, i, mask)
        half = ir.VectorType(dtype_ft, self.lanes)
        size = 4
        p = self.b.bitcast(self.b.gep(ptr, [i]), half.as_pointer())
        if mask is None:
            x = self.b.load(p, align=size)
        else:
            ml_ty = ir.FunctionType(half, [half.as_pointer(), ir.IntType(32), mask.type, half])
            fn = cgutils.get_or_insert_function(self.b.module, ml_ty, f"llvm.masked.load.v{self.lanes}f32.p0")
            x = self.b.call(fn, [p, ir.Constant(ir.IntType(32), size), mask, ir.Constant(half, [0.0] * self.lanes)])
        return self.b.fpext(x, self.vt)

    def splat(self, x):
        v = self.b.insert_element(ir.Constant(self.vt, ir.Undefined), x, ir.Constant(ir.IntType(32), 0))
        return self.b.shuffle_vector(v, v, ir.Constant(ir.VectorType(ir.IntType(32), self.lanes), [0] * self.lanes))

    def loop(self, k, count, step):
        """Accumulators after ``step(i, acc, mask)`` over i = 0, lanes, … < k (the last step masked if k mod lanes)."""
        b, lanes, i64 = self.b, self.lanes, ir.IntType(64)
        full = b.mul(b.udiv(k, ir.Constant(i64, lanes)), ir.Constant(i64, lanes))
        pre = b.block
        head = b.append_basic_block("rows.loop")
        body = b.append_basic_block("rows.body")
        done = b.append_basic_block("rows.done")
        b.branch(head)
        b.position_at_end(head)
        i_phi = b.phi(i64)
        acc = [b.phi(self.vt) for _ in range(count)]
        i_phi.add_incoming(ir.Constant(i64, 0), pre)
        for ph in acc:
            ph.add_incoming(self.zero, pre)
        b.cbranch(b.icmp_signed("<", i_phi, full), body, done)
        b.position_at_end(body)
        new = step(i_phi, acc, None)
        end_body = b.block
        i_phi.add_incoming(b.add(i_phi, ir.Constant(i64, lanes)), end_body)
        for ph, v in zip(acc, new):
            ph.add_incoming(v, end_body)
        b.branch(head)
        b.position_at_end(done)
        rest = b.sub(k, full)
        with b.if_then(b.icmp_signed(">", rest, ir.Constant(i64, 0)), likely=False):
            iota = ir.Constant(ir.VectorType(i64, lanes), list(range(lanes)))
            spl = b.insert_element(ir.Constant(ir.VectorType(i64, lanes), ir.Undefined), rest,
                                   ir.Constant(ir.IntType(32), 0))
            spl = b.shuffle_vector(spl, spl, ir.Constant(ir.VectorType(ir.IntType(32), lanes), [0] * lanes))
            tail = step(full, acc, b.icmp_unsigned("<", iota, spl))
            then_block = b.block
        merged = []
        for j in range(count):
            ph = b.phi(self.vt)
            ph.add_incoming(acc[j], done)
            ph.add_incoming(tail[j], then_block)
            merged.append(ph)
        return merged

    def fma(self, acc, x, y):
        return self.b.fadd(acc, self.b.fmul(x, y, flags=_FLAGS), flags=_FLAGS)

    def mul(self, x, y):
        return self.b.fmul(x, y, flags=_FLAGS)

    def add(self, x, y):
        return self.b.fadd(x, y, flags=_FLAGS)


def _row_pointer(context, builder, qa, row, j=0):
    """Pointer to q[row + j, 0] of the C-contiguous (n, k) array ``qa``; also returns k."""
    i64 = ir.IntType(64)
    k = cgutils.unpack_tuple(builder, qa.shape, 2)[1]
    row = builder.sext(row, i64) if row.type.width < 64 else row
    return builder.gep(qa.data, [builder.mul(builder.add(row, ir.Constant(i64, j)), k)]), k


def _is_rows(q, rho):
    return (isinstance(q, types.Array) and q.ndim == 2 and q.layout == "C" and q.dtype in (types.float32, types.float64)
            and isinstance(rho, types.Array) and rho.ndim == 1 and rho.layout == "C")


def _block_codegen(dtype, with_v):
    """Codegen of rows4 (``dtype`` = q's) and rows4v (``dtype`` = float64, q's entries widened)."""

    def codegen(context, builder, signature, args):
        qa = context.make_array(signature.args[0])(context, builder, args[0])
        ra = context.make_array(signature.args[2])(context, builder, args[2])
        ga = context.make_array(signature.args[3])(context, builder, args[3]) if with_v else None
        v = _Rows(context, builder, dtype)
        q_ft = context.get_value_type(signature.args[0].dtype)
        bases = [_row_pointer(context, builder, qa, args[1], j)[0] for j in range(4)]
        k = _row_pointer(context, builder, qa, args[1])[1]

        def vmin(x, y):
            return builder.select(builder.fcmp_ordered("<", x, y), x, y)

        def step(i, acc, mask):
            p = v.load(ra.data, i, mask)
            xs = [v.load_widened(base, q_ft, i, mask) for base in bases]
            m = vmin(vmin(vmin(xs[0], xs[1]), vmin(xs[2], xs[3])), v.zero)
            out = [v.fma(acc[j], xs[j], p) for j in range(4)]  # w_j
            if with_v:
                gg = v.load(ga.data, i, mask)
                out += [v.fma(acc[4 + j], xs[j], gg) for j in range(4)]  # v_j
            n = len(out)
            return out + [v.add(acc[n + j], xs[j]) for j in range(4)] + [v.add(acc[n + 4], m)]  # s_j, neg

        count = 13 if with_v else 9
        acc = v.loop(k, count, step)
        # transposed reduction: [w0 w1 | w2 w3 | s0 s1 | s2 s3] -> [w0..w3 | s0..s3] -> one vector, 8 groups
        if with_v:
            outs = _tree(builder, acc[:8], v.lanes) + _tree(builder, acc[8:12], v.lanes) + _tree(builder, acc[12:], v.lanes)
        else:
            outs = _tree(builder, acc[:8], v.lanes) + _tree(builder, acc[8:], v.lanes)
        return context.make_tuple(builder, signature.return_type, outs)

    return codegen


@intrinsic
def rows4(typingctx, q, r, rho):
    """(w_0..w_3, s_0..s_3, neg) for rows r … r+3 of the C-contiguous (n, k) ``q``, in q's dtype.

    w_j = Σ_i q[r+j, i] ρ_i, s_j = Σ_i q[r+j, i], neg = Σ_i min(q[r..r+3, i], 0) (negative iff an entry is).
    ``rho`` is a C-contiguous (k,) array of q's dtype; the caller guarantees r + 4 ≤ n.
    """
    if not (_is_rows(q, rho) and rho.dtype == q.dtype and isinstance(r, types.Integer)):
        return None
    return types.UniTuple(q.dtype, 9)(q, r, rho), _block_codegen(q.dtype, False)


@intrinsic
def rows4v(typingctx, q, r, rho, g):
    """(w_0..w_3, v_0..v_3, s_0..s_3, neg) in float64 for rows r … r+3: as :func:`rows4`, and v_j = Σ_i q g_i.

    ``rho`` and ``g`` are float64; float32 entries of ``q`` are widened to float64 as they are loaded.
    """
    if not (_is_rows(q, rho) and rho.dtype == types.float64 and isinstance(g, types.Array)
            and g.dtype == types.float64 and isinstance(r, types.Integer)):
        return None
    return types.UniTuple(types.float64, 13)(q, r, rho, g), _block_codegen(types.float64, True)


@intrinsic
def central(typingctx, q, r, rho, g, w, paper):
    """Central moments of row r of ``q`` about ``w`` (float64 arithmetic; q float32 is widened per element).

    With d_i = ρ_i − w and x_i = q[r, i]: μ_j = Σ_i x_i d_i^j for j = 2…5 and, when the literal ``paper`` is
    True, ν_j = Σ_i x_i g_i d_i^j for j = 1…4. Returns (μ_2, μ_3, μ_4, μ_5, ν_1, ν_2, ν_3, ν_4) (ν = 0 when not
    ``paper``). ``rho`` and ``g`` are C-contiguous float64 (k,) arrays.
    """
    if not (_is_rows(q, rho) and rho.dtype == types.float64 and isinstance(g, types.Array)
            and g.dtype == types.float64 and isinstance(r, types.Integer)
            and isinstance(paper, types.BooleanLiteral)):
        return None
    with_nu = paper.literal_value
    sig = types.UniTuple(types.float64, 8)(q, r, rho, g, w, paper)

    def codegen(context, builder, signature, args):
        qa = context.make_array(signature.args[0])(context, builder, args[0])
        ra = context.make_array(signature.args[2])(context, builder, args[2])
        ga = context.make_array(signature.args[3])(context, builder, args[3])
        base, k = _row_pointer(context, builder, qa, args[1])
        v = _Rows(context, builder, types.float64)
        q_ft = context.get_value_type(q.dtype)
        wv = v.splat(args[4])

        def step(i, acc, mask):
            x = v.load_widened(base, q_ft, i, mask)
            d = builder.fsub(v.load(ra.data, i, mask), wv, flags=_FLAGS)
            t = v.mul(x, d)
            out = list(acc)
            if with_nu:
                gg = v.load(ga.data, i, mask)
                out[4] = v.fma(acc[4], t, gg)  # ν_1
            t = v.mul(t, d)
            out[0] = v.add(acc[0], t)  # μ_2
            if with_nu:
                out[5] = v.fma(acc[5], t, gg)  # ν_2
            t = v.mul(t, d)
            out[1] = v.add(acc[1], t)  # μ_3
            if with_nu:
                out[6] = v.fma(acc[6], t, gg)  # ν_3
            t = v.mul(t, d)
            out[2] = v.add(acc[2], t)  # μ_4
            if with_nu:
                out[7] = v.fma(acc[7], t, gg)  # ν_4
            out[3] = v.fma(acc[3], t, d)  # μ_5
            return out

        count = 8 if with_nu else 4
        acc = v.loop(k, count, lambda i, a, m: step(i, a + [v.zero] * (8 - count), m)[:count])
        outs = _tree(builder, acc, v.lanes) + [ir.Constant(v.ft, 0.0)] * (8 - count)
        return context.make_tuple(builder, signature.return_type, outs)

    return sig, codegen

def _tree(builder, vecs, lanes):
    """Lane sums of up to ``lanes`` vectors, by one transposed tree (pairs of vectors, then halves within one)."""
    count = len(vecs)
    width = 1
    while width < count:
        width *= 2
    zero = ir.Constant(vecs[0].type, [0.0] * lanes)
    vecs = list(vecs) + [zero] * (width - count)
    groups = 1
    while len(vecs) > 1:
        vecs = [_halve(builder, vecs[i], vecs[i + 1], groups, lanes) for i in range(0, len(vecs), 2)]
        groups *= 2
    v, group, i32 = vecs[0], lanes // width, ir.IntType(32)
    while group > 1:
        half = group // 2
        lo = [g * group + t for g in range(width) for t in range(half)]
        hi = [g * group + half + t for g in range(width) for t in range(half)]
        a = builder.shuffle_vector(v, v, ir.Constant(ir.VectorType(i32, width * half), lo))
        b = builder.shuffle_vector(v, v, ir.Constant(ir.VectorType(i32, width * half), hi))
        v = builder.fadd(a, b, flags=_FLAGS)
        group = half
    return [builder.extract_element(v, ir.Constant(i32, j)) for j in range(count)]
