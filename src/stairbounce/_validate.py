"""The validation contract of the public API, in one place.

Contract (docs/guide/numerics.md, "Valid numeric range and accuracy"):

* A real parameter is a number: a Python ``int`` or ``float``, a numpy integer
  or floating scalar (any ``numbers.Real`` except ``bool``).  Strings, bools,
  ``None``, complex numbers and arrays are refused, not coerced.
* A count is an integer (an integral float such as ``1e6`` is accepted), never
  a bool.
* Every refusal is a :class:`ValueError` whose message starts with the
  parameter's name and states the allowed range; no ``TypeError`` or
  ``OverflowError`` escapes.
* The map is computed in float64 only where every intermediate stays far from
  overflow: ``0 <= y <= 1e300``, ``|v| <= 1e150``, ``1e-150 <= u <= 1e150``
  (so ``v^2``, ``2y``, ``T^2 = 1/u^2`` and ``v T`` are at most about 1e300).
* Whatever grows with an argument (arrays, listed objects, loops) is estimated
  before it starts and refused with its size when it cannot fit.
"""

from __future__ import annotations

import math
import numbers
import os
import warnings
from typing import Any, TypeAlias

import numpy as np

# The type of a real parameter in the public API's hints: what _is_real accepts
# (numbers.Real, which mypy does not treat as a numeric type, less bool)
Real: TypeAlias = "float | np.floating[Any] | np.integer[Any]"

Y_MAX = 1e300
V_MAX = 1e150
U_MIN = 1e-150
U_MAX = 1e150
_INT64_MAX = 2**63 - 1
# e below 2^-53 (but not 0) is lost: (1+e)/(1-e) rounds to 1, the sliding test
# is that of e = 0 and a bouncing ball "slides" (report round 2, N8; docs/design.md)
E_MIN = 2.0**-53
E_TINY_RULE = ("e (restitution coefficient) must be 0 or in [2^-53, 1) (the valid numeric range: "
               "below 2^-53 = 1.1e-16 the ratio (1+e)/(1-e) rounds to 1 and e would be lost)")


def e_too_small(a):
    """Where ``0 < e < 2^-53`` (:data:`E_MIN`): refused by name."""
    a = np.asarray(a)
    return (a > 0.0) & (a < E_MIN)


def _is_real(x):
    return isinstance(x, numbers.Real) and not isinstance(x, (bool, np.bool_))


def real(name, x):
    """``x`` as a finite float, or ValueError naming ``name``."""
    if not _is_real(x):
        raise ValueError(f"{name} must be a real number (int or float), got {_show(x)}")
    try:
        f = float(x)
    except (OverflowError, ValueError, TypeError):
        raise ValueError(f"{name} must be finite (at most 1.8e308 in size), got {_show(x)}") from None
    if not math.isfinite(f):
        raise ValueError(f"{name} must be finite, got {f}")
    return f


def count(name, n, minimum, maximum=None):
    """``n`` as an int in ``[minimum, maximum]`` (no upper bound when None)."""
    rule = f"an integer >= {minimum}" if maximum is None else f"an integer in [{minimum}, {maximum}]"
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (numbers.Integral, float, np.floating)):
        raise ValueError(f"{name} must be {rule}, got {_show(n)}")
    if not isinstance(n, numbers.Integral):
        if not (math.isfinite(n) and float(n).is_integer()):
            raise ValueError(f"{name} must be {rule}, got {_show(n)}")
    n = int(n)
    if n < minimum or (maximum is not None and n > maximum):
        raise ValueError(f"{name} must be {rule}, got {_show(n)}")
    if n > _INT64_MAX:  # nothing that counts (numpy, numba) goes further
        raise ValueError(f"{name} must be {rule} and below 2**63, got {_show(n)}")
    return n


def window(name, spec):
    """A window along ``name`` as every function taking one accepts it:
    ``(lo, hi)`` or ``(lo, hi, n)`` (image edges, and the pixel count along
    that axis) -> ``(lo, hi, n)`` with ``n`` None when not given.  Only the
    form is checked here; each caller checks the bounds and the count."""
    if isinstance(spec, (str, bytes)) or not hasattr(spec, "__len__") or len(spec) not in (2, 3):
        raise ValueError(f"{name} must be a tuple ({name}_min, {name}_max) or ({name}_min, {name}_max, "
                         f"n_{name}), got {_show(spec)}")
    lo, hi, *n = spec
    return lo, hi, (n[0] if n else None)


def size_text(text):
    """size_text(text) -> (int, int) or None

    ``"600x400"`` -> ``(600, 400)`` (width, height; ``X`` too), ``None`` where
    ``text`` is not two integers joined by an ``x``.  The bounds are the caller's.
    """
    parts = text.lower().split("x")
    try:
        w, h = (int(p) for p in parts)
    except ValueError:
        return None
    return w, h


def renamed(old, old_value, new, new_value, default, stacklevel=3):
    """The value of a keyword renamed from ``old`` to ``new`` (default
    ``default``): ``old_value`` (None when not given) is still taken, with a
    DeprecationWarning; given together with a ``new_value`` other than the
    default, it is refused (never one of them silently dropped)."""
    if old_value is None:
        return new_value
    warnings.warn(f"{old}= is deprecated: use {new}= (the step limit is max_iter everywhere, "
                  "docs/design.md)" if new == "max_iter" else f"{old}= is deprecated: use {new}=",
                  DeprecationWarning, stacklevel=stacklevel)
    if new_value != default:
        raise ValueError(f"{old} is the deprecated name of {new}: give {new} only, got both "
                         f"{new} = {_show(new_value)} and {old} = {_show(old_value)}")
    return old_value


def among(name, values, allowed):
    """Every item of ``values`` is one of ``allowed`` (a list option such as
    a plot's overlays)."""
    for x in values:
        if x not in allowed:
            raise ValueError(f"{name} must be among {', '.join(allowed)}, got {x!r}")


def flag(name, x):
    """A bool (Python or numpy)."""
    if not isinstance(x, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {_show(x)}")
    return bool(x)


def _show(x):
    """A short repr: huge integers by their number of digits."""
    if isinstance(x, numbers.Integral) and not isinstance(x, (bool, np.bool_)):
        n = int(x)
        if abs(n) > 10**30:
            return f"an integer of {len(str(abs(n)))} digits"
        return str(n)
    r = repr(x)
    return r if len(r) <= 80 else r[:77] + "..."


# --------------------------------------------------------------------------- #
# Memory                                                                      #
# --------------------------------------------------------------------------- #


def available_memory():
    """Bytes of memory available now (MemAvailable on Linux, else free pages), or None."""
    # one raw read of the file: a text-mode open and a loop over its lines took
    # twice as long (40 us with cold caches, right after a scan's kernel)
    try:
        fd = os.open("/proc/meminfo", os.O_RDONLY)
        try:
            avail = mem_available(os.read(fd, 1 << 16))
        finally:
            os.close(fd)
        if avail is not None:
            return avail
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # pragma: no cover - no way to tell
        return None


def mem_available(meminfo):
    """Bytes of the ``MemAvailable`` line of ``/proc/meminfo`` (its bytes), or None."""
    i = meminfo.find(b"\nMemAvailable:")
    if i < 0:
        return None
    end = meminfo.find(b"\n", i + 1)
    fields = meminfo[i + 14 : end if end >= 0 else len(meminfo)].split()
    if len(fields) == 2 and fields[1] == b"kB" and fields[0].isdigit():
        return int(fields[0]) * 1024
    return None


def human(n):
    """``1536`` -> ``'1.5 KiB'``."""
    n = float(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            return f"{int(n)} B" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024.0
    return f"{n} B"  # pragma: no cover


def check_memory(what, nbytes, available=None):
    """Refuse ``what`` (a phrase naming the argument, e.g. ``"steps = 10**12"``)
    when its peak of ``nbytes`` exceeds the memory available now."""
    avail = available_memory() if available is None else available
    if avail is not None and nbytes > avail:
        raise ValueError(
            f"{what} needs about {human(nbytes)} of memory, more than the "
            f"{human(avail)} available: ask for less"
        )
    return nbytes


def check_array_memory(what, values, bytes_per_element):
    """Refuse, before anything is materialised, work on ``values`` (an array
    or a tuple of arrays) that needs ``bytes_per_element`` bytes for each of
    its elements: a zero-copy view such as ``np.broadcast_to(0.5, (3e9,))``
    holds no memory until a range check or a copy materialises it (report
    N10: numpy's MemoryError before the check).  ``what`` names the argument
    (e.g. ``"e of 3000000000 points"``; ``{n}`` is replaced by the element
    count).  Returns the element count."""
    arrays = values if isinstance(values, tuple) else (values,)
    n = max((_size(a) for a in arrays), default=0)
    if n:
        check_memory(what.format(n=n), n * bytes_per_element)
    return n


def _size(a):
    """Elements of an array-like that holds them already (numpy arrays and their
    zero-copy views, xarray objects); 0 for lists and scalars (materialised)."""
    if isinstance(a, np.ndarray):
        return a.size
    size, shape = getattr(a, "size", None), getattr(a, "shape", None)
    if isinstance(size, numbers.Integral) and isinstance(shape, tuple):
        return int(size)
    return 0


def real_array(name, value):
    """``value`` (a number or a sequence/array of numbers) as a float64 array.

    Elements must be real numbers as for :func:`real` (numeric numpy arrays
    pass as they are); strings, bools, None and complex numbers are refused.
    Finiteness and ranges are left to the caller.  An array is estimated
    before its float copy is made (a zero-copy view holds no memory until
    then; report round 3, R8): the callers estimate their outputs after.
    """
    if isinstance(value, np.ndarray):
        check_array_memory(f"{name} of {{n}} values", value, 8)
        if value.dtype.kind not in "iuf":
            raise ValueError(f"{name} must hold real numbers, got an array of {value.dtype}")
        return value.astype(np.float64)
    if _is_real(value):
        return np.asarray(real(name, value))
    if isinstance(value, (list, tuple)):
        try:
            obj = np.array(value, dtype=object)
        except ValueError:  # ragged nesting
            raise ValueError(f"{name} must be a real number or a 1-D array of them, got {_show(value)}") from None
        out = np.empty(obj.shape)
        for i, x in enumerate(obj.ravel()):
            if not _is_real(x):
                raise ValueError(f"{name}[{i}] must be a real number (int or float), got {_show(x)}")
            try:
                out.flat[i] = float(x)
            except OverflowError:
                raise ValueError(f"{name}[{i}] must be finite (at most 1.8e308 in size), got {_show(x)}") from None
        return out
    raise ValueError(f"{name} must be a real number or a 1-D array of them, got {_show(value)}")

