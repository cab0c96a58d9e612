"""A software prefetch for the compiled kernels: ``prefetch(a, i)`` asks the CPU to bring ``a.flat[i]`` into cache.

The hardware prefetcher follows one linear stream well but is slow to ramp up at every 4 KiB page; a kernel that
reads a large array once and does real work per cache line (so that few loads are in flight) runs at the
memory's bandwidth only if it requests the lines it will need a few pages ahead. The hint never faults, changes
no value and compiles to one ``prefetcht0`` instruction (LLVM's ``llvm.prefetch``: read, high locality, data).
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.extending import intrinsic

__all__ = ["prefetch"]


@intrinsic
def prefetch(typingctx, array, index):
    """Prefetch element ``index`` of the C-contiguous ``array`` (counted in its flat order) for reading."""
    if not isinstance(array, types.Array) or not isinstance(index, types.Integer):
        return None
    sig = types.void(array, index)

    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        i8p = ir.IntType(8).as_pointer()
        i32 = ir.IntType(32)
        fnty = ir.FunctionType(ir.VoidType(), [i8p, i32, i32, i32])
        fn = builder.module.declare_intrinsic("llvm.prefetch", [i8p], fnty)  # name mangled by llvmlite
        address = builder.bitcast(builder.gep(data, [args[1]]), i8p)
        # (address, rw = 0 read, locality = 3 keep in all levels, cache type = 1 data)
        builder.call(fn, [address, ir.Constant(i32, 0), ir.Constant(i32, 3), ir.Constant(i32, 1)])
        return context.get_dummy_value()

    return sig, codegen
