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

__all__ = ["run_kernel", "new_halt", "halted", "run_shielded", "run_interruptible", "check_halt"]


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
# the halt flag of the job (run_interruptible) that the current thread runs, if any
_JOB = threading.local()


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
    if threading.current_thread() is not threading.main_thread():
        halt = getattr(_JOB, "halt", None)
        if halt is None:
            return kernel(*args, new_halt())
        check_halt()
        out = kernel(*args, halt)
        check_halt()  # the kernel may have returned early: its outputs are partial
        return out
    halt = new_halt()
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


def _call_into(result, fn, *args, **kwargs):
    """``result["value"] = fn(...)``, or ``result["error"]`` what it raised (a helper
    thread's outcome, handed to the main thread by :func:`_outcome`)."""
    try:
        result["value"] = fn(*args, **kwargs)
    except BaseException as exc:  # noqa: BLE001 - handed to the main thread
        result["error"] = exc


def _outcome(result):
    if "error" in result:
        raise result["error"]
    return result.get("value")


def _start_and_wait(thread):
    """Start ``thread`` and wait for it in slices of 0.05 s, so that the main
    thread runs Python's signal handler (Ctrl-C) within one."""
    thread.start()
    while thread.is_alive():
        thread.join(0.05)


# one file writer at a time: run_shielded
_WRITING = threading.Lock()


def run_shielded(write, wait=False, cleanup=None):
    """run_shielded(write, wait=False, cleanup=None) -> what ``write()`` returns

    Run a file writer (``xarray``'s ``to_netcdf`` or ``to_zarr``) where Ctrl-C
    cannot land inside it.  A KeyboardInterrupt raised in the middle of
    xarray's netCDF writer, between taking its HDF5 lock and the ``try`` that
    releases it, left the lock taken, and the writer's own clean-up then waited
    for it forever (a ``certify --out X.nc`` interrupted while saving hung).  In
    the main thread the writer therefore runs in a helper thread (signals are
    delivered to the main thread only) while the main thread waits.  On Ctrl-C
    the main thread raises at once (``wait=False``) or once the writer has
    ended (``wait=True``: a Zarr folder, whose chunk writes would otherwise
    recreate the folder that :func:`stairbounce._io.atomic_path` removes); a
    writer left behind calls ``cleanup()`` when it ends (it removes the
    temporary file, so nothing is left in a process that goes on).  The helper
    thread is a daemon: a process ending on Ctrl-C does not wait for it (a
    temporary it leaves is a dead process's, removed by the next write in that
    folder).  In any other thread ``write()`` is called in place.

    One writer at a time (:data:`_WRITING`, taken by the helper thread): a
    writer left behind by a Ctrl-C is waited for by the next (two netCDF
    writers at once crashed HDF5: a segmentation fault); the main thread's
    wait stays interruptible.
    """
    if threading.current_thread() is not threading.main_thread():
        with _WRITING:
            return write()
    result = {}
    abandoned = threading.Event()

    def target():
        with _WRITING:  # after a writer left behind, if any
            try:
                _call_into(result, write)
            finally:
                if abandoned.is_set() and cleanup is not None:
                    cleanup()

    thread = threading.Thread(target=target, name="stairbounce-writer", daemon=True)
    try:
        _start_and_wait(thread)
    except BaseException:
        abandoned.set()
        if wait:
            while thread.is_alive():
                try:
                    thread.join(0.05)
                except KeyboardInterrupt:  # a second Ctrl-C: stop waiting
                    break
        raise
    return _outcome(result)


def check_halt():
    """In a job of :func:`run_interruptible`: raise KeyboardInterrupt once its
    caller has been interrupted (for Python loops between kernels, such as the
    trapping pass's box by box); elsewhere nothing."""
    halt = getattr(_JOB, "halt", None)
    if halt is not None and halt[0]:
        raise KeyboardInterrupt


def run_interruptible(fn, *args, **kwargs):
    """run_interruptible(fn, *args, **kwargs) -> what ``fn(*args, **kwargs)`` returns

    Run a whole job, kernels and the numpy work between them, so that Ctrl-C is
    seen within 0.05 s.  A single numpy call over millions of boxes (a sort, a
    concatenation: the certified atlas's levels) holds Python's signal handler
    back for its whole length, up to a second at depth 14.  In the main thread
    the job runs in a helper thread while the main thread waits; on Ctrl-C the
    job's halt flag is set and the main thread raises at once.  The job stops
    at its next kernel (:func:`run_kernel` passes the job's flag to the kernel,
    which returns within a slice, and raises KeyboardInterrupt before its
    partial outputs are used) or :func:`check_halt`; the helper thread is a
    daemon, so a process ending on Ctrl-C does not wait for it.  numba's thread
    count is the caller's.  In any other thread the job runs in place.
    """
    if threading.current_thread() is not threading.main_thread():
        return fn(*args, **kwargs)
    import numba

    threads = numba.get_num_threads()
    halt = new_halt()
    result = {}

    def target():
        _JOB.halt = halt
        numba.set_num_threads(threads)
        try:
            _call_into(result, fn, *args, **kwargs)
        finally:
            _JOB.halt = None

    thread = threading.Thread(target=target, name="stairbounce-job", daemon=True)
    try:
        _start_and_wait(thread)
    except BaseException:
        halt[0] = 1
        raise
    return _outcome(result)
