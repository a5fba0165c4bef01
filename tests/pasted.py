"""Run the Python examples of one Markdown page as a reader would paste them.

``python tests/pasted.py PAGE.md`` runs, in this fresh interpreter, every
Python example of the page from top to bottom in one namespace that starts
empty (no set-up code is added: each name an example uses is imported or
defined on the page above it):

* ```` ```python ```` and ```` ```{code-cell} ```` blocks are executed;
* ```` ```pycon ```` and ```` ```{doctest} ```` blocks are run by :mod:`doctest`,
  and their printed output must match (``ELLIPSIS``, ``NORMALIZE_WHITESPACE``).

A block may be left out only with a stated reason, on the line right above its
fence: ``<!-- not run: REASON -->``.

``python tests/pasted.py PAGE.md --without-cells`` leaves the ```` ```{code-cell} ````
blocks to the site build, which executes them (MyST-NB: the page's cells in a fresh
kernel, top to bottom, an error failing the build) and shows their output on the page;
tests/test_docs.py runs both, so each block is executed once.  The other blocks then
run without the cells' names: a block that needs one fails here, as it would for a
reader who skipped the cell.  The last line printed is a JSON summary
(blocks run, examples checked, blocks not run with their reasons, failures).
"""

from __future__ import annotations

import doctest
import json
import re
import sys
from pathlib import Path

FENCE = re.compile(r"^(?P<indent> {0,3})(?P<fence>`{3,}|~{3,})(?P<info>[^\n`]*)$")
NOT_RUN = re.compile(r"^\s*<!--\s*not run:\s*(?P<reason>.*?)\s*-->\s*$")
EXEC_KINDS = {"python", "py", "{code-cell}"}
DOCTEST_KINDS = {"pycon", "{doctest}"}


def blocks(text):
    """(kind, source, first line number, reason-not-run or None) of each fenced block, in order."""
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, info = m.group("fence"), m.group("info").strip()
        kind = info.split()[0] if info else ""
        reason = None
        if i > 0 and (n := NOT_RUN.match(lines[i - 1])):
            reason = n.group("reason")
        body, j = [], i + 1
        while j < len(lines) and not lines[j].strip().startswith(fence):
            body.append(lines[j])
            j += 1
        if kind in EXEC_KINDS | DOCTEST_KINDS:
            # a directive's options (":tags: ...", or a "---" block of them) are not code
            while body and kind.startswith("{") and body[0].startswith(":"):
                body.pop(0)
            yield kind, "\n".join(body) + "\n", i + 2, reason
        i = j + 1


def run(path, cells=True):
    path = Path(path)
    text = path.read_text()
    namespace = {"__name__": "__main__"}
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    parser = doctest.DocTestParser()
    summary = {"page": str(path), "blocks": 0, "examples": 0, "not_run": [], "failures": [], "cells_left": 0}
    for kind, source, line, reason in blocks(text):
        if kind == "{code-cell}" and not cells and reason is None:
            summary["cells_left"] += 1  # the site build's (see the module's docstring)
            continue
        if reason is not None:
            if not reason:
                summary["failures"].append(f"{path}:{line}: '<!-- not run: -->' without a reason")
            summary["not_run"].append(f"{path}:{line}: {reason}")
            continue
        summary["blocks"] += 1
        if kind in DOCTEST_KINDS:
            test = parser.get_doctest(source, namespace, f"{path.name}:{line}", str(path), line - 1)
            runner = doctest.DocTestRunner(optionflags=flags)
            out = []
            runner.run(test, out=out.append, clear_globs=False)
            summary["examples"] += len(test.examples)
            if runner.failures:
                summary["failures"].append("".join(out))
            # the namespace goes on to the next block, as in a session
            namespace = test.globs
        else:
            summary["examples"] += 1
            try:
                exec(compile(source, f"{path}:{line}", "exec"), namespace)
            except BaseException as exc:  # noqa: BLE001 - reported, the test fails
                import traceback

                summary["failures"].append(f"{path}:{line}: the block raised\n"
                                           + "".join(traceback.format_exception(exc)))
        if "matplotlib.pyplot" in sys.modules:  # figures never pile up over the page
            sys.modules["matplotlib.pyplot"].close("all")
    return summary


if __name__ == "__main__":
    print(json.dumps(run(sys.argv[1], cells="--without-cells" not in sys.argv[2:])))
