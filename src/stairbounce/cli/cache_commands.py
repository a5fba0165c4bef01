"""``stairbounce cache info|clear``: the figures' cache of computed scans."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app, plural

cache_app = typer.Typer(
    help="See or empty the cache of computed scans that 'figures' keeps (default ~/.cache/stairbounce).",
    no_args_is_help=True,
)
app.add_typer(cache_app, name="cache", short_help="See or empty the figures' cache of scans.")

CACHE_DIR_HELP = "The cache folder (default $XDG_CACHE_HOME/stairbounce, ~/.cache/stairbounce)."


def _folder(cache_dir):
    from ..figures import default_cache_dir

    return Path(cache_dir) if cache_dir is not None else default_cache_dir()


@cache_app.command("info")
def info(cache_dir: Path = typer.Option(None, "--cache-dir", help=CACHE_DIR_HELP)):
    """Where the cache is, how many entries it holds, their size and the size bound."""
    from .. import _cache
    from .._validate import human

    folder = _folder(cache_dir)
    found = _cache.entries(folder)
    total = sum(n for _, n in found)
    kinds: dict[str, int] = {}
    for p, _ in found:
        kind = p.name.split("-")[0]
        kinds[kind] = kinds.get(kind, 0) + 1
    detail = f" ({', '.join(f'{k} {n}' for k, n in sorted(kinds.items()))})" if kinds else ""
    typer.echo(f"cache {folder}: {plural(len(found), 'entry', 'entries')}{detail}, {human(total)}; "
               f"bound {human(_cache.max_bytes())} ($STAIRBOUNCE_CACHE_MAX_BYTES), least recently "
               f"used entries removed beyond it; kernels {_cache.kernel_hash()}")


@cache_app.command("clear")
def clear(cache_dir: Path = typer.Option(None, "--cache-dir", help=CACHE_DIR_HELP)):
    """Remove every cache entry (nothing else in the folder)."""
    from .. import _cache
    from .._validate import human

    folder = _folder(cache_dir)
    n, freed = _cache.clear(folder)
    typer.echo(f"removed {plural(n, 'entry', 'entries')} ({human(freed)}) from {folder}")
