"""The report of a run: ``report.md``, ``report.html`` and ``manifest.json``,
merged by figure with an earlier run in the same folder."""

from __future__ import annotations

import html
import json
from dataclasses import asdict
from pathlib import Path

import numpy as np

from .._version import __version__
from .._io import atomic_path
from .recipes import FIGURES
from .rows import BASES, BASIS_CRITERION, CRITERION, VERDICTS, Result, Row
from .settings import Settings, _replaceable


def _cell(text):
    """Markdown table cell: never blank, no bar breaking the row."""
    text = str(text).replace("|", "\\|").strip()
    return text or "-"


def _md_table(rows):
    lines = ["| quantity | paper | here | verdict | basis |", "|---|---|---|---|---|"]
    for r in rows:
        v = r.verdict_text()
        v = f"**{v}**" if r.verdict != "agrees" else v
        b = r.basis_text()
        b = f"**{b}**" if r.basis == "proven" else b
        lines.append(f"| {_cell(r.quantity)} | {_cell(r.paper)} | {_cell(r.measured)} | {_cell(v)} "
                     f"| {_cell(b)} |")
    return lines


def read_manifest(out):
    """read_manifest(out) -> list[Result]

    The results recorded in ``out/manifest.json`` by an earlier run (each
    with the settings it was made with in ``params["settings"]``); [] when
    there is none or it cannot be read."""
    path = Path(out) / "manifest.json"
    try:
        data = json.loads(path.read_text())
        results = []
        for f in data["figures"]:
            rows = [Row(**x) for x in f.get("rows", [])]
            keep = {k: f[k] for k in ("name", "title", "files", "params", "seconds", "error",
                                      "caption") if k in f}
            results.append(Result(rows=rows, **keep))
        return results
    except (OSError, ValueError, KeyError, TypeError):
        return []


def merge_results(earlier, results):
    """``results`` with the figures of ``earlier`` that this run did not
    make, in the paper's order: a partial run (``--only``) into a folder that
    holds a full one keeps the other figures' rows."""
    made = {r.name for r in results}
    kept = [r for r in earlier if r.name not in made and r.name in FIGURES]
    order = {name: i for i, name in enumerate(FIGURES)}
    every = sorted(kept + list(results), key=lambda r: order.get(r.name, len(order)))
    return every, [r.name for r in kept]


def write_report(results, settings: Settings, total_seconds=None, merge=True):
    """write_report(results, settings, total_seconds=None, merge=True) -> (paths, kept)

    ``report.md`` and ``report.html`` (figures linked by relative path, so the
    folder reads offline) and ``manifest.json`` (every input, the package
    version, timings), all written atomically.  With ``merge`` the figures
    of an earlier run in the same folder that this run did not make are kept
    (merged by figure, each with the settings it was made with); ``kept``
    names them.
    """
    out = Path(settings.out)
    replace = _replaceable(settings)
    for r in results:
        r.params.setdefault("settings", settings.record())
    kept = []
    if merge:
        results, kept = merge_results(read_manifest(out), results)
    summary = [Row(f"{r.name}: {x.quantity}", x.paper, x.measured, x.agrees, x.verdict, x.why,
                   x.basis, x.proof)
               for r in results for x in r.rows]
    tally = verdict_tally(results)
    mixed = len({json.dumps(r.params.get("settings"), sort_keys=True) for r in results}) > 1
    md = [
        "# stairbounce: the paper reproduced",
        "",
        f"Campos, Romero-Valles, Torres, *A fractal structure in a bouncing ball model*. "
        f"stairbounce {__version__}; this run: format {settings.fmt}, dpi {settings.dpi}, "
        f"scale {settings.scale}, max_iter {settings.max_iter}.",
        "",
    ]
    if kept:
        md += [f"Figures {', '.join(kept)} are kept from an earlier run in this folder "
               f"(merged by figure){'; their settings differ, see each section' if mixed else ''}.",
               ""]
    md += [
        f"**Criterion.** {CRITERION}",
        "",
        f"**Basis.** {BASIS_CRITERION}",
        "",
        "## Summary",
        "",
        f"Every row states a verdict: agrees, differs (by how much), or not comparable (why), "
        f"and its basis: proven (by what) or numerical. Here: {tally}; {basis_tally(results)}.",
        "",
        *_md_table(summary),
        "",
    ]
    for r in results:
        md += [f"## {r.name}: {r.title}", ""]
        if r.error:
            md += [f"**failed**: {r.error}", ""]
        for f in r.files:
            md += [f"![{r.name}]({f})" if not f.endswith(".pdf") else f"[{f}]({f})", ""]
        if r.caption:
            md += [f"*{r.caption}*", ""]
        md += _md_table(r.rows) + [""]
        params = {k: v for k, v in r.params.items() if k != "traceback"}
        md += [f"Parameters: `{json.dumps(params, default=_jsonable)}`; time {r.seconds:.2f} s.", ""]
    if total_seconds is not None:
        md += [f"Total time of this run: {total_seconds:.1f} s.", ""]
    md += [f"Tally: {tally}.", ""]
    paths = []
    with atomic_path(out / "report.md", overwrite=replace) as tmp:
        tmp.write_text("\n".join(md))
    paths.append(out / "report.md")
    with atomic_path(out / "report.html", overwrite=replace) as tmp:
        tmp.write_text(_html(results, settings, summary, total_seconds, kept, tally))
    paths.append(out / "report.html")
    manifest = {
        "stairbounce_version": __version__,
        "settings": {k: str(v) if isinstance(v, Path) else v for k, v in asdict(settings).items()
                     if k != "progress"},
        "total_seconds": total_seconds,
        "kept_from_earlier_run": kept,
        "figures": [
            {**{k: v for k, v in asdict(r).items() if k != "rows"},
             "rows": [asdict(x) for x in r.rows]}
            for r in results
        ],
    }
    with atomic_path(out / "manifest.json", overwrite=replace) as tmp:
        tmp.write_text(json.dumps(manifest, indent=2, default=_jsonable))
    paths.append(out / "manifest.json")
    return paths, kept


def verdict_tally(results):
    """``"N agrees, M differs, K not comparable"`` over every row of ``results``."""
    counts = {v: sum(x.verdict == v for r in results for x in r.rows) for v in VERDICTS}
    return ", ".join(f"{n} {v}" for v, n in counts.items())


def basis_tally(results):
    """``"N proven, M numerical"`` over every row of ``results``."""
    counts = {b: sum(x.basis == b for r in results for x in r.rows) for b in BASES}
    return ", ".join(f"{n} {b}" for b, n in counts.items())


def rows_with_verdict(results, verdict="differs", width=160):
    """One line per row of ``results`` with that ``verdict``: ``"fig6: QUANTITY
    (paper P; here M): WHY"``, cut at ``width`` characters (the report has
    it whole), so a summary names what it counts."""
    lines = []
    for r in results:
        for x in r.rows:
            if x.verdict == verdict:
                here = x.measured.split(". ")[0]
                line = f"{r.name}: {x.quantity} (paper {x.paper}; here {here})" + (f": {x.why}" if x.why else "")
                lines.append(line if len(line) <= width else line[: width - 3] + "...")
    return lines


def _jsonable(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, (tuple, set)):
        return list(x)
    return str(x)


def _html(results, settings, summary, total_seconds, kept, tally):
    esc = html.escape

    def table(rows):
        cells = "".join(
            f"<tr><td>{esc(r.quantity)}</td><td>{esc(r.paper)}</td><td>{esc(r.measured)}</td>"
            f"<td class='{esc((r.verdict or 'none').replace(' ', '-'))}'>"
            f"{esc(r.verdict_text())}</td><td class='{esc(r.basis)}'>{esc(r.basis_text())}</td></tr>"
            for r in rows
        )
        return ("<table><tr><th>quantity</th><th>paper</th><th>here</th><th>verdict</th>"
                "<th>basis</th></tr>"
                f"{cells}</table>")

    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>stairbounce report</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}"
        "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:3px 6px;"
        "vertical-align:top}img{max-width:100%}.differs,.none{font-weight:bold;color:#a00}"
        ".not-comparable{color:#555}.proven{font-weight:bold;color:#060}figcaption{font-style:italic;margin:.3em 0 .8em}</style>"
        "</head><body>",
        "<h1>stairbounce: the paper reproduced</h1>",
        f"<p>stairbounce {esc(__version__)}; this run: scale {settings.scale}, "
        f"max_iter {settings.max_iter}, dpi {settings.dpi}.</p>",
    ]
    if kept:
        parts.append(f"<p>Figures {esc(', '.join(kept))} are kept from an earlier run in this "
                     "folder (merged by figure).</p>")
    crit = esc(CRITERION).replace("**agrees**", "<b>agrees</b>").replace(
        "**differs**", "<b>differs</b>").replace("**not comparable**", "<b>not comparable</b>")
    basis = esc(BASIS_CRITERION).replace("**proven**", "<b>proven</b>").replace(
        "**numerical**", "<b>numerical</b>")
    parts += [f"<p><b>Criterion.</b> {crit}</p>", f"<p><b>Basis.</b> {basis}</p>",
              "<h2>Summary</h2>",
              f"<p>Every row states a verdict and its basis. Here: {esc(tally)}; "
              f"{esc(basis_tally(results))}.</p>",
              table(summary)]
    for r in results:
        parts.append(f"<h2>{esc(r.name)}: {esc(r.title)}</h2>")
        if r.error:
            parts.append(f"<p><b>failed</b>: {esc(r.error)}</p>")
        parts.append("<figure>")
        for f in r.files:
            if f.endswith(".pdf"):
                parts.append(f"<p><a href='{esc(f)}'>{esc(f)}</a></p>")
            else:
                parts.append(f"<img src='{esc(f)}' alt='{esc(r.name)}'>")
        if r.caption:
            parts.append(f"<figcaption>{esc(r.caption)}</figcaption>")
        parts.append("</figure>")
        parts.append(table(r.rows))
        params = {k: v for k, v in r.params.items() if k != "traceback"}
        parts.append(f"<p>Parameters: <code>{esc(json.dumps(params, default=_jsonable))}</code>; "
                     f"time {r.seconds:.2f} s.</p>")
    if total_seconds is not None:
        parts.append(f"<p>Total time of this run: {total_seconds:.1f} s.</p>")
    parts.append(f"<p>Tally: {esc(tally)}.</p>")
    parts.append("</body></html>")
    return "\n".join(parts)
