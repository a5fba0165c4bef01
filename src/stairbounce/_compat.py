"""Old import paths kept alive, with a DeprecationWarning.

The parameter-plane module was ``stairbounce.scan`` until the function
:func:`stairbounce.scan` needed the name; it is now :mod:`stairbounce.plane`.
Python's import system sets a submodule as an attribute of its package, so a
plain alias module would overwrite the function the moment anyone ran
``import stairbounce.scan``.  Instead one object plays both parts: a module
subclass that is callable.  It is registered in ``sys.modules`` under the old
module name *and* bound as the package's ``scan``, so importing the old path
finds it already loaded and sets the very same object again: nothing is
clobbered.

- Calling it (``sb.scan(...)``) calls the function, silently.
- Reading a module attribute through it (``from stairbounce.scan import
  scan_coords``, ``from stairbounce import scan; scan.scan(...)``) warns and
  forwards to the new module.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import sys
import types
import warnings


class DeprecatedModuleAlias(types.ModuleType):
    """A module name that moved, optionally also callable as a function.

    ``DeprecatedModuleAlias(old, new, function=None, package_attr=None)``:
    attributes are read from the module ``new`` with a DeprecationWarning;
    calling the object calls ``function`` (no warning).  Pickles by
    reference, as ``package_attr`` of its package when given.
    """

    def __init__(self, old, new, function=None, package_attr=None):
        super().__init__(old)
        # object.__setattr__ keeps these out of the warning path of __getattr__
        d = self.__dict__
        d["_alias_new"] = new
        d["_alias_function"] = function
        d["_alias_package_attr"] = package_attr
        if function is not None:
            functools.update_wrapper(self, function, updated=())
            d["__name__"] = old  # update_wrapper copied the function's name
            d["__module__"] = old.rpartition(".")[0]
            d["__signature__"] = inspect.signature(function)
        else:
            d["__doc__"] = f"Deprecated alias of :mod:`{new}`."

    def __call__(self, *args, **kwargs):
        function = self.__dict__["_alias_function"]
        if function is None:
            raise TypeError(f"module {self.__name__!r} is not callable")
        return function(*args, **kwargs)

    def __getattr__(self, name):
        if name.startswith("_"):  # dunders probed by tools; private names were never API
            raise AttributeError(f"module {self.__name__!r} has no attribute {name!r}")
        new = self.__dict__["_alias_new"]
        warnings.warn(
            f"the module {self.__name__} is deprecated: use {new} "
            f"(e.g. stairbounce.{name} or {new}.{name})",
            DeprecationWarning,
            stacklevel=2,
        )
        return getattr(importlib.import_module(new), name)

    def __repr__(self):
        function = self.__dict__["_alias_function"]
        if function is not None:
            return f"<function {self.__module__}.{function.__name__} (also the deprecated module {self.__name__})>"
        return f"<deprecated module {self.__name__!r}, now {self.__dict__['_alias_new']!r}>"

    def __reduce__(self):
        # pickle.save_global looks the name up in __module__ and checks identity
        attr = self.__dict__["_alias_package_attr"]
        if attr is not None:
            return attr
        return (importlib.import_module, (self.__name__,))


def register_alias(old, new, function=None, package_attr=None):
    """Create the alias ``old`` -> ``new`` and register it in ``sys.modules``."""
    alias = DeprecatedModuleAlias(old, new, function=function, package_attr=package_attr)
    sys.modules[old] = alias
    return alias
