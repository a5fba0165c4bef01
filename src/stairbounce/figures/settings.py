"""What every recipe shares: the :class:`Settings` of a run, the paper's
windows that more than one family draws (:data:`BLOWUPS`, the blow-ups of
Fig. 5; :data:`DIMENSION_WINDOWS`, Figs. 6 and 7), and the tools of a recipe:
the cached scan, saving a figure atomically, the output folder's checks."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

from .._version import __version__
from .._io import atomic_path


# Figure 5 of the paper: a) .. e)
BLOWUPS = {
    "fig5a": ((0.0, 0.3), (0.3, 0.7)),
    "fig5b": ((0.0, 0.2), (0.7, 1.0)),
    "fig5c": ((0.0, 0.1), (1.0, 1.22)),
    "fig5d": ((0.0, 0.1), (0.9, 1.0)),
    "fig5e": ((0.04, 0.065), (0.92, 0.945)),
}


@dataclass
class Settings:
    """What every recipe needs: where to write, how, and how big.

    ``progress(text)``, when given, is told what a recipe is doing (its
    scans, its drawing), so that a long figure is never silent;
    ``border_dimension`` is the dimension study's JSON file (None: the one
    shipped in ``stairbounce/data``)."""

    out: Path
    fmt: str = "png"
    dpi: int = 150
    scale: float = 1.0
    max_iter: int = 1000
    cache_dir: Path | None = None  # None: no cache
    progress: object = field(default=None, repr=False, compare=False)
    border_dimension: Path | None = None
    # replace existing files that are not from an earlier run into this folder
    overwrite: bool = False
    # draw the exact borders (stairbounce.border_points) over Figs. 4 and 5a-e
    borders: bool = False

    def px(self, n):
        """A pixel count of the default set, scaled (at least 16)."""
        return max(16, int(round(n * self.scale)))

    def note(self, text):
        if self.progress is not None:
            self.progress(text)

    def record(self):
        """The settings as they go into the manifest (paths as text)."""
        out = {"fmt": self.fmt, "dpi": self.dpi, "scale": self.scale, "max_iter": self.max_iter}
        if self.borders:
            out["borders"] = True
        return out


# --------------------------------------------------------------------------- #
# helpers                                                                     #
# --------------------------------------------------------------------------- #


def _cached(settings, kind, inputs, compute):
    """``compute()`` -> xarray.Dataset, cached as netCDF under a hash of the
    request (the inputs and the kernels' source, :mod:`stairbounce._cache`);
    an entry is used only when its recorded request and data checksum agree."""
    from .. import _cache

    if settings.cache_dir is None:
        return compute()
    path = _cache.entry_path(settings.cache_dir, kind, inputs)
    ds = _cache.read_entry(path, kind, inputs)
    if ds is not None:
        return ds
    ds = compute()
    try:
        _cache.write_entry(path, ds, kind, inputs)
    except (OSError, ValueError, RuntimeError) as exc:
        # an unwritable or full cache costs time, never a figure (netCDF4
        # reports a full disk as a RuntimeError, report N6)
        _cache_warning(settings.cache_dir, exc)
    return ds


_CACHE_WARNED: set[str] = set()


def _cache_warning(cache_dir, exc):
    import warnings

    key = str(cache_dir)
    if key not in _CACHE_WARNED:
        _CACHE_WARNED.add(key)
        reason = " ".join(str(exc).split())
        warnings.warn(f"cannot write the cache {cache_dir} ({reason}): computing without it",
                      RuntimeWarning, stacklevel=3)


def _scan(settings, label, e, u, n_e, n_u):
    from ..plane import scan

    def rows(done, total):
        settings.note(f"{label}: scan {n_e} x {n_u}, row {done}/{total}")

    settings.note(f"{label}: scan {n_e} x {n_u}")
    inputs = {"e": list(e), "u": list(u), "n_e": n_e, "n_u": n_u, "max_iter": settings.max_iter}
    return _cached(
        settings, "scan", inputs,
        lambda: scan(e=(e[0], e[1], n_e), u=(u[0], u[1], n_u), max_iter=settings.max_iter,
                     progress=rows),
    )


def _replaceable(settings):
    """Whether files in the output folder may be replaced: asked for, or the
    folder holds the manifest of an earlier run (its files are ours)."""
    if settings.overwrite:
        return True
    try:
        manifest = json.loads((Path(settings.out) / "manifest.json").read_text())
    except (OSError, ValueError):
        return False
    return isinstance(manifest, dict) and "stairbounce_version" in manifest


def _mark_folder(settings):
    """Write a provisional manifest (replaced by :func:`write_report`), so that
    a run cut short (Ctrl-C, a kill) leaves a folder recognisably ours: the
    rerun replaces its figures without --force."""
    path = Path(settings.out) / "manifest.json"
    if path.exists():
        # an earlier run's manifest already marks the folder ours, and a partial
        # run's report is merged with it (write_report); one not ours makes the
        # figures' own writes refuse to replace anything
        return
    with atomic_path(path, overwrite=True) as tmp:
        tmp.write_text(json.dumps({"stairbounce_version": __version__, "complete": False, "figures": []}))


def output_files(settings, names):
    """The files :func:`make_figures` and :func:`write_report` write for ``names``."""
    out = Path(settings.out)
    return [out / f"{n}.{settings.fmt}" for n in names] + [
        out / "report.md", out / "report.html", out / "manifest.json"]


def check_outputs(settings, names):
    """Refuse, before any figure is made, a folder where an existing file
    would be replaced without ``overwrite`` (and not from an earlier run), or
    where a target is a folder stairbounce did not write."""
    from .._io import check_output

    out = Path(settings.out)
    if not out.exists():
        if not out.parent.is_dir() and str(out.parent):
            raise ValueError(f"cannot write {out}: folder {out.parent} does not exist")
        return
    replace = _replaceable(settings)
    for path in output_files(settings, names):
        check_output(path, overwrite=replace)


def _save(fig, settings, name):
    import matplotlib.pyplot as plt

    settings.note(f"{name}: writing {name}.{settings.fmt}")
    path = Path(settings.out) / f"{name}.{settings.fmt}"
    with atomic_path(path, overwrite=_replaceable(settings)) as tmp:
        fig.savefig(tmp, dpi=settings.dpi, format=settings.fmt)
    plt.close(fig)
    return path.name


def _subplots(settings, *args, **kwargs):
    """A new figure at the dpi it will be saved at, so that what a renderer
    measures in pixels (the border of Figs. 6/7) is what the file holds."""
    import matplotlib.pyplot as plt

    return plt.subplots(*args, dpi=settings.dpi, **kwargs)


# Figures 6 and 7: window, the paper's dimension
DIMENSION_WINDOWS = {
    "fig6": (((0.0, 0.333), (0.4, 0.733)), 1.324),
    "fig7": (((0.155, 0.2138), (0.6, 0.658)), 1.403),
}


def default_cache_dir() -> Path:
    """``$XDG_CACHE_HOME/stairbounce`` (``~/.cache/stairbounce``)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "stairbounce"
