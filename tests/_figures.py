"""The tests' hook into the figures' shared tools (stairbounce/figures/settings.py)."""

import importlib
import pkgutil

from stairbounce import figures


def patch_figures(mp, name, value):
    """Replace the figures' tool ``name`` (``_save``, ``_cached``) by ``value``
    with ``mp`` (a pytest MonkeyPatch) in every module of stairbounce.figures
    that binds it: the recipe modules import the tools of figures/settings.py
    by name, so patching that module alone would miss them.  Returns how many
    modules were patched (at least settings.py itself)."""
    patched = 0
    for info in pkgutil.iter_modules(figures.__path__):
        module = importlib.import_module(f"{figures.__name__}.{info.name}")
        if hasattr(module, name):
            mp.setattr(module, name, value)
            patched += 1
    assert patched, f"no module of stairbounce.figures binds {name}"
    return patched
