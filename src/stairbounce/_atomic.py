"""A counter that the threads of a numba kernel share (issue 26).

The scan kernel's units of parallel work (one per thread,
:func:`stairbounce.plane._scan_fast`) take the plane's segments one at a
time from a shared counter, so that a thread that drew cheap segments takes
more of them instead of idling while another finishes.  Each segment must go
to exactly one unit: :func:`take_next` is an atomic read-and-increment
(LLVM's ``atomicrmw add``, the ``lock xadd`` of x86), so two threads never
read the same value.  Nothing but the count itself is passed through it (each
segment's outputs are written by the one unit that took it), so the relaxed
ordering ("monotonic") is enough.  Nothing here imports more than numba.
"""

from __future__ import annotations

from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

__all__ = ["take_next"]


@intrinsic
def take_next(typingctx, counter):
    """take_next(counter) -> int, in a numba kernel: ``counter[0]`` before it is
    increased by one, atomically (``counter``: a C-contiguous int64 array)."""
    if not (isinstance(counter, types.Array) and counter.dtype == types.int64):
        return None

    def codegen(context, builder, signature, args):
        ary = context.make_array(signature.args[0])(context, builder, args[0])
        return builder.atomic_rmw("add", ary.data, ir.Constant(ir.IntType(64), 1), "monotonic")

    return types.int64(counter), codegen
