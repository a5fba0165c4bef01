"""The ``[docs]`` extra is enough to build the documentation (issue 45, item 6;
newcomer round 5, F1: ``pip install -e ".[docs]"`` then ``sphinx-build``
stopped on ``No module named 'dask'``, then ``'panel'``).

Without building the site in a fresh virtual environment (minutes of CI): every
module that the build imports — the code the site executes (the ``{code-cell}``
blocks of the pages, the tutorial notebook's cells), ``docs/conf.py`` and the
site's own extensions (``docs/_ext``) — must come from a distribution that
``pip install ".[docs]"`` installs: the package's dependencies, the extra's,
and theirs (read from the installed distributions' metadata), or the standard
library.
"""

from __future__ import annotations

import ast
import importlib.metadata as md
import json
import re
import sys
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
# package modules that import an optional dependency when imported themselves
NEEDS = {"stairbounce.explorer": "panel"}


def _name(req):
    return re.sub(r"[-_.]+", "-", req.name).lower()


def _closure(extra):
    """The distributions ``pip install ".[extra]"`` installs (names normalised)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    seen = set()
    todo = [Requirement(r) for r in project["dependencies"] + project["optional-dependencies"][extra]]
    while todo:
        req = todo.pop()
        name = _name(req)
        if name == "stairbounce":   # a self-reference: its extras' requirements
            for ex in req.extras:
                todo += [Requirement(r) for r in project["optional-dependencies"][ex]]
            continue
        if req.marker is not None and not req.marker.evaluate({"extra": ""}):
            continue
        if name in seen:
            continue
        seen.add(name)
        try:
            requires = md.requires(req.name) or []
        except md.PackageNotFoundError:
            continue
        for r in map(Requirement, requires):
            env = {"extra": x for x in req.extras} if req.extras else {"extra": ""}
            if r.marker is None or any(r.marker.evaluate({"extra": x}) for x in (req.extras or {""})) \
                    or r.marker.evaluate(env):
                todo.append(r)
    return seen


def _executed_code():
    """(where, source) of every piece of code the build runs or imports."""
    for page in sorted(DOCS.rglob("*.md")):
        if "_build" in page.parts:
            continue
        blocks = re.findall(r"```\{code-cell\}[^\n]*\n(.*?)```", page.read_text(), flags=re.S)
        for k, b in enumerate(blocks):
            yield f"{page.relative_to(ROOT)} cell {k}", b
    nb = json.loads((DOCS / "tutorial.ipynb").read_text())
    for k, c in enumerate(nb["cells"]):
        if c["cell_type"] == "code":
            src = c["source"] if isinstance(c["source"], str) else "".join(c["source"])
            yield f"docs/tutorial.ipynb cell {k}", src
    for f in [DOCS / "conf.py", *sorted((DOCS / "_ext").glob("*.py"))]:
        yield str(f.relative_to(ROOT)), f.read_text()


def _imports(source):
    # cell options (":tags:", "---" front matter) and IPython magics are not Python
    lines = [ln for ln in source.splitlines() if not ln.lstrip().startswith(("%", "!", ":", "---"))]
    for node in ast.walk(ast.parse("\n".join(lines))):
        if isinstance(node, ast.Import):
            yield from (a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            yield node.module


def test_the_docs_extra_brings_every_module_the_build_imports():
    provided = _closure("docs")
    dists = md.packages_distributions()
    missing = {}
    for where, src in _executed_code():
        for module in _imports(src):
            top = module.split(".")[0]
            for prefix, dep in NEEDS.items():
                if module == prefix or module.startswith(prefix + "."):
                    top = dep
            if top in sys.stdlib_module_names or top in ("stairbounce", "sb_gallery", "sb_mathjax",
                                                         "sb_offline_panel"):
                continue
            names = {re.sub(r"[-_.]+", "-", d).lower() for d in dists.get(top, [])}
            if not names:
                pytest.fail(f"{where} imports {module}, which no installed distribution provides")
            if not names & provided:
                missing.setdefault(top, where)
    assert missing == {}, f"modules the docs build imports that .[docs] does not install: {missing}"
