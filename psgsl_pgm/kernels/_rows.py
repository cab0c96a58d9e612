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

__all__ = ["rows4", "VECTOR_BYTES"]

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


@intrinsic
def rows4(typingctx, q, r, rho):
    """(w_0..w_3, s_0..s_3, neg) for rows r … r+3 of the C-contiguous (n, k) ``q``, in q's dtype.

    w_j = Σ_i q[r+j, i] ρ_i, s_j = Σ_i q[r+j, i], neg = Σ_i min(q[r..r+3, i], 0) (negative iff an entry is).
    ``rho`` is a C-contiguous (k,) array of q's dtype; the caller guarantees r + 4 ≤ n.
    """
    if not (isinstance(q, types.Array) and q.ndim == 2 and q.layout == "C" and isinstance(rho, types.Array)
            and rho.ndim == 1 and rho.layout == "C" and rho.dtype == q.dtype and isinstance(r, types.Integer)
            and q.dtype in (types.float32, types.float64)):
        return None
    dtype = q.dtype
    sig = types.UniTuple(dtype, 9)(q, r, rho)

    def codegen(context, builder, signature, args):
        qa = context.make_array(signature.args[0])(context, builder, args[0])
        ra = context.make_array(signature.args[2])(context, builder, args[2])
        k = cgutils.unpack_tuple(builder, qa.shape, 2)[1]
        ft = context.get_value_type(dtype)
        size = context.get_abi_sizeof(ft)
        lanes = VECTOR_BYTES // size
        vt = ir.VectorType(ft, lanes)
        vp = vt.as_pointer()
        i64 = ir.IntType(64)
        i1 = ir.IntType(1)
        zero_v = ir.Constant(vt, [0.0] * lanes)
        row = builder.sext(args[1], i64) if args[1].type.width < 64 else args[1]
        bases = [builder.gep(qa.data, [builder.mul(builder.add(row, ir.Constant(i64, j)), k)]) for j in range(4)]
        ml_ty = ir.FunctionType(vt, [vp, ir.IntType(32), ir.VectorType(i1, lanes), vt])
        name = f"llvm.masked.load.v{lanes}f{8 * size}.p0"  # (vector, pointer) overload, e.g. llvm.masked.load.v16f32.p0
        masked_load = cgutils.get_or_insert_function(builder.module, ml_ty, name)

        def load(ptr, i, mask):
            p = builder.bitcast(builder.gep(ptr, [i]), vp)
            if mask is None:
                return builder.load(p, align=size)
            return builder.call(masked_load, [p, ir.Constant(ir.IntType(32), size), mask, zero_v])

        def step(i, acc, mask=None):
            p = load(ra.data, i, mask)
            xs = [load(b, i, mask) for b in bases]
            a = [builder.fadd(acc[j], builder.fmul(xs[j], p, flags=_FLAGS), flags=_FLAGS) for j in range(4)]
            s = [builder.fadd(acc[4 + j], xs[j], flags=_FLAGS) for j in range(4)]

            def vmin(u, v):
                return builder.select(builder.fcmp_ordered("<", u, v), u, v)

            m = vmin(vmin(vmin(xs[0], xs[1]), vmin(xs[2], xs[3])), zero_v)
            return a + s + [builder.fadd(acc[8], m, flags=_FLAGS)]

        # main loop over whole vectors: i = 0, lanes, … while i + lanes <= k
        full = builder.mul(builder.udiv(k, ir.Constant(i64, lanes)), ir.Constant(i64, lanes))
        pre = builder.block
        loop = builder.append_basic_block("rows4.loop")
        body = builder.append_basic_block("rows4.body")
        done = builder.append_basic_block("rows4.done")
        builder.branch(loop)
        builder.position_at_end(loop)
        i_phi = builder.phi(i64)
        acc_phi = [builder.phi(vt) for _ in range(9)]
        i_phi.add_incoming(ir.Constant(i64, 0), pre)
        for ph in acc_phi:
            ph.add_incoming(zero_v, pre)
        builder.cbranch(builder.icmp_signed("<", i_phi, full), body, done)
        builder.position_at_end(body)
        new = step(i_phi, acc_phi)
        nxt = builder.add(i_phi, ir.Constant(i64, lanes))
        end_body = builder.block
        i_phi.add_incoming(nxt, end_body)
        for ph, v in zip(acc_phi, new):
            ph.add_incoming(v, end_body)
        builder.branch(loop)
        builder.position_at_end(done)
        acc = list(acc_phi)
        # the rest of the row (k mod lanes classes): one masked step; masked-off lanes load 0
        rest = builder.sub(k, full)
        with builder.if_then(builder.icmp_signed(">", rest, ir.Constant(i64, 0)), likely=False):
            iota = ir.Constant(ir.VectorType(i64, lanes), list(range(lanes)))
            splat = builder.insert_element(ir.Constant(ir.VectorType(i64, lanes), ir.Undefined), rest,
                                           ir.Constant(ir.IntType(32), 0))
            splat = builder.shuffle_vector(splat, splat, ir.Constant(ir.VectorType(ir.IntType(32), lanes),
                                                                     [0] * lanes))
            mask = builder.icmp_unsigned("<", iota, splat)
            tail = step(full, acc, mask)
            then_block = builder.block
        merged = []
        for j in range(9):
            ph = builder.phi(vt)
            ph.add_incoming(acc[j], done)
            ph.add_incoming(tail[j], then_block)
            merged.append(ph)
        # transposed reduction: [w0 w1 | w2 w3 | s0 s1 | s2 s3] -> [w0..w3 | s0..s3] -> one vector, 8 groups
        c = [_halve(builder, merged[0], merged[1], 1, lanes), _halve(builder, merged[2], merged[3], 1, lanes),
             _halve(builder, merged[4], merged[5], 1, lanes), _halve(builder, merged[6], merged[7], 1, lanes)]
        c = [_halve(builder, c[0], c[1], 2, lanes), _halve(builder, c[2], c[3], 2, lanes)]
        v = _halve(builder, c[0], c[1], 4, lanes)
        width, group = lanes, lanes // 8
        i32 = ir.IntType(32)
        while group > 1:  # float32: two lanes per accumulator left
            half = group // 2
            lo = [g * group + t for g in range(8) for t in range(half)]
            hi = [g * group + half + t for g in range(8) for t in range(half)]
            width = 8 * half
            a = builder.shuffle_vector(v, v, ir.Constant(ir.VectorType(i32, width), lo))
            b = builder.shuffle_vector(v, v, ir.Constant(ir.VectorType(i32, width), hi))
            v = builder.fadd(a, b, flags=_FLAGS)
            group = half
        outs = [builder.extract_element(v, ir.Constant(i32, j)) for j in range(8)]
        outs.append(_fold(builder, merged[8], lanes))
        return context.make_tuple(builder, signature.return_type, outs)

    return sig, codegen
