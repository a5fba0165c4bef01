"""Wide vectors for the lane kernels (issue 26).

The lane kernels (:func:`stairbounce.plane._run_unit`, the non-sliding
motion's ``_motion_lanes``) run the same operations on LANES pixels side by side
so that LLVM vectorises their loops.  On the x86 processors with AVX-512 of
the Skylake-server line and later (our development machine is an Emerald
Rapids Xeon), LLVM's tuning for the host prefers 256-bit vectors, four
float64, though the registers hold eight.  :func:`prefer_wide_vectors`, called
at the top of a kernel, gives the LLVM function it is lowered into the
attribute ``"prefer-vector-width"="512"`` (what clang's
``-mprefer-vector-width=512`` sets), so its loops use eight-wide vectors
where the machine has them.  Where it has not (AVX2 or older, other
architectures) LLVM caps the width at the widest legal vector and nothing
changes.

The answers do not depend on it: the lane loops are compiled without
fastmath, so each lane gets the same IEEE operations, rounded the same way,
whatever the vector width; the bit-for-bit tests against ``model._step``
hold either way.  Only the speed does (``benchmarks/README.md``, A/B on the
Xeon: the paper's grid 23 % less CPU time on one thread and 29 % less wall
time on two, the Fig. 5e window 14 % and 21 %; the motion scan 12 %).

llvmlite's Python IR builder accepts only LLVM's keyword attributes on a
function, and this one is a string attribute; it is added to the builder's
attribute set directly, as text that the IR printer writes out.  If a later
llvmlite refuses that, the kernel is compiled without the attribute (as
before issue 26's fifth round) rather than failing: ``WIDE_ATTRIBUTE`` is the
text, and ``tests/test_kernel_paths.py`` checks that it reaches the IR.
Nothing here imports more than numba.
"""

from __future__ import annotations

from numba.core import types
from numba.extending import intrinsic

__all__ = ["prefer_wide_vectors", "WIDE_ATTRIBUTE"]

WIDE_ATTRIBUTE = '"prefer-vector-width"="512"'


@intrinsic
def prefer_wide_vectors(typingctx):
    """prefer_wide_vectors() in a numba function: vectorise its loops 512 bits wide where possible."""

    def codegen(context, builder, signature, args):
        try:  # past llvmlite's check of keyword attributes (see above)
            set.add(builder.function.attributes, WIDE_ATTRIBUTE)
        except Exception:  # a later llvmlite: compile without it (speed only)
            pass
        return context.get_dummy_value()

    return types.none(), codegen
