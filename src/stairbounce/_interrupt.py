"""Ctrl-C during a long numba kernel.

Python handles a signal only between bytecodes of the main thread, so a kernel
that runs for minutes in the main thread holds Ctrl-C back for minutes.  The
long kernels (the parameter-plane scan, the orbit diagram) therefore take a
``halt`` flag, a one-element int64 array that they read between slices of
their work (a lockstep step of the scan, 2**16 map steps of an orbit) and
return early when it is set; they are compiled ``nogil``.  :func:`run_kernel`
runs such a kernel in a helper thread while the main thread waits, so Ctrl-C
is seen at once: the flag is set, the kernel stops within a slice, and the
KeyboardInterrupt goes on (the partial outputs are never returned).

Reading the flag changes no arithmetic: the answers are the same, bit for bit,
as without it (tests/test_faults.py).  Nothing here imports more than numpy and numba.
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor
from concurrent.futures import TimeoutError as FutureTimeout

import numpy as np
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

__all__ = ["run_kernel", "new_halt", "halted"]


@intrinsic
def halted(typingctx, halt):
    """halted(halt) -> bool, in a numba kernel: whether ``halt[0]`` is set.

    An atomic load: a plain one may be hoisted out of a loop that stores
    nothing the compiler thinks can alias the flag (the orbit transient), and
    the kernel would never see the flag change.
    """
    if not (isinstance(halt, types.Array) and halt.dtype == types.int64):
        return None

    def codegen(context, builder, signature, args):
        ary = context.make_array(signature.args[0])(context, builder, args[0])
        value = builder.load_atomic(ary.data, "monotonic", 8)
        return builder.icmp_signed("!=", value, ir.Constant(value.type, 0))

    return types.boolean(halt), codegen

_POOL = None
_POOL_LOCK = threading.Lock()


def new_halt():
    """A cleared halt flag for a kernel."""
    return np.zeros(1, np.int64)


def _name_thread():
    """Name the helper thread for the system too (``top -H``, /proc/PID/task/*/comm)."""
    try:
        import ctypes

        libc = ctypes.CDLL(None)
        libc.prctl(15, b"stairbounce-ker", 0, 0, 0)  # PR_SET_NAME, at most 15 bytes
    except (OSError, AttributeError, TypeError):  # not Linux: the name is cosmetic
        pass


def _pool():
    global _POOL
    with _POOL_LOCK:
        if _POOL is None:
            # one long-lived thread: numba's thread pool (OpenMP's team) is
            # kept per launching thread, so it is made once, not per call
            _POOL = ThreadPoolExecutor(1, thread_name_prefix="stairbounce-kernel", initializer=_name_thread)
        return _POOL


def _with_threads(threads, kernel, args, halt):
    import numba

    numba.set_num_threads(threads)
    return kernel(*args, halt)


def run_kernel(kernel, *args):
    """run_kernel(kernel, *args) -> what ``kernel(*args, halt)`` returns

    Call a ``nogil`` kernel that takes a halt flag as its last argument, so
    that Ctrl-C stops it within one slice of its work.

    In the main thread the kernel runs in a helper thread and the main thread
    waits; on KeyboardInterrupt (or any exception while waiting) the flag is
    set, the kernel returns early, and the exception is raised again.  In any
    other thread (a Dask worker, a tile of a local tiled scan, a web server)
    the kernel runs in place: signals are not delivered there anyway.
    """
    halt = new_halt()
    if threading.current_thread() is not threading.main_thread():
        return kernel(*args, halt)
    import numba

    # numba's thread count is per calling thread: the helper uses the caller's
    threads = numba.get_num_threads()
    future = _pool().submit(_with_threads, threads, kernel, args, halt)
    try:
        while True:
            try:
                return future.result(timeout=0.1)
            except FutureTimeout:
                continue
    except BaseException:
        halt[0] = 1
        try:
            future.result()  # the kernel returns within a slice
        except BaseException:  # noqa: BLE001 - the interrupt is what goes on
            pass
        raise
