"""``stairbounce.fractal``: the old name of :mod:`stairbounce.dimension`, kept
as an alias so that ``from stairbounce.fractal import box_dimension`` and
``stairbounce.fractal.box_counts`` keep working.

Every name is looked up in the package's modules (public names and the
private ones older code and tests reach for alike), and an assignment to a
name (``monkeypatch.setattr(fractal, "_CHUNK", 700)``) is made in the module
that defines it, so the alias and the module are one and the same state;
deleting such a name through the alias restores its first value.
"""

from __future__ import annotations

import sys
import types
import warnings

from .dimension import __all__ as _public
from .dimension import borders, boxes, classifier, fit, perimeter, result, slicing, study, uncertainty

_SAVED: dict = {}
_MODULES = (boxes, borders, fit, uncertainty, slicing, perimeter, classifier, result, study)
__all__ = list(_public)


def _owner(name):
    for module in _MODULES:
        if name in vars(module):
            return module
    return None


class _Alias(types.ModuleType):
    def __getattr__(self, name):
        module = _owner(name)
        if module is None:
            raise AttributeError(f"module {self.__name__!r} has no attribute {name!r}")
        return getattr(module, name)

    def __setattr__(self, name, value):
        module = _owner(name)
        if module is None or name.startswith("__"):
            super().__setattr__(name, value)
        else:
            # the first value is kept, so that deleting the name through the
            # alias (how pytest's monkeypatch undoes a name the alias's own
            # __dict__ never held) restores it
            _SAVED.setdefault(name, getattr(module, name))
            setattr(module, name, value)

    def __delattr__(self, name):
        if name in _SAVED:
            setattr(_owner(name), name, _SAVED.pop(name))
        else:
            super().__delattr__(name)

    def __dir__(self):
        return sorted(set(__all__) | set(super().__dir__()))


sys.modules[__name__].__class__ = _Alias

warnings.warn("stairbounce.fractal is deprecated since 0.5.0 and will be removed in 0.6.0: "
              "import from stairbounce.dimension"
              ", or use the flat stairbounce API",
              DeprecationWarning, stacklevel=2)
