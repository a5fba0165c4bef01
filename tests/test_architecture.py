"""docs/design.md's one-way data flow: the core imports no plotting, CLI or web code."""

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

CORE = ["_validate", "model", "symbolic", "trajectory", "units", "plane", "orbits", "fractal", "dimension", "atlas",
        "atlas_boxes", "nonsliding", "borders", "regions", "_region_export", "_colours", "_io", "_interrupt",
        "_cache", "structure", "structure.certify", "structure.verify", "structure.verdict", "structure.tiling", "structure.labels", "structure.tubes",
        "structure.itinerary", "structure.words", "structure.borders", "structure.bifurcations",
        "structure.checks", "structure.continuation", "structure.regions", "structure.trace", "structure.graph",
        "structure.export", "cascades", "cascade_families"]
FORBIDDEN = ["matplotlib", "typer", "rich", "bokeh", "panel", "dask", "distributed"]


@pytest.mark.parametrize("module", CORE)
def test_core_module_imports_no_plotting_cli_or_web(module):
    code = (
        f"import sys, stairbounce.{module}; "
        f"print([m for m in {FORBIDDEN!r} if m in sys.modules])"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.strip() == "[]", f"stairbounce.{module} imports {r.stdout.strip()}"


SRC = Path(__file__).resolve().parents[1] / "src" / "stairbounce"


def _relative_imports(path):
    """(level, module, names) of every relative import in ``path``, at any depth (inside functions too)."""
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level:
            yield node.level, node.module, [a.name for a in node.names]


def test_version_lives_in_one_leaf_module_that_no_module_reaches_through_the_package():
    # the lower modules stamp the version on what they write: they read the leaf
    # stairbounce._version, not the package's __init__ (an arrow back up the layers)
    upward = []
    for path in sorted(SRC.rglob("*.py")):
        if path.name == "__init__.py" and path.parent == SRC:
            continue
        for level, module, names in _relative_imports(path):
            if "__version__" in names and module != "_version":
                upward.append(f"{path.relative_to(SRC)}: from {'.' * level}{module or ''} import __version__")
    assert not upward, upward
    import stairbounce
    from stairbounce import _version

    assert stairbounce.__version__ == _version.__version__
    assert re.fullmatch(r"\d+\.\d+\.\d+", _version.__version__)
    # the build reads the same file (hatch's dynamic version), and no second literal
    pyproject = (SRC.parents[1] / "pyproject.toml").read_text()
    assert 'dynamic = ["version"]' in pyproject
    assert 'path = "src/stairbounce/_version.py"' in pyproject
    assert not re.search(r"^version\s*=", pyproject, re.M)


def test_cli_modules_import_each_other_one_way():
    # a cycle between command modules (scan <-> atlas, say) means a shared helper
    # belongs in cli/_app
    cli = SRC / "cli"
    graph = {}
    for path in cli.glob("*.py"):
        graph[path.stem] = {(m or "").split(".")[0] or n
                            for level, m, names in _relative_imports(path) if level == 1
                            for n in ([m] if m else names)} & {p.stem for p in cli.glob("*.py")}
    for start in graph:
        seen, todo = set(), list(graph[start])
        while todo:
            node = todo.pop()
            assert node != start, f"cli/{start}.py imports itself back through {sorted(seen)}"
            if node not in seen:
                seen.add(node)
                todo.extend(graph.get(node, ()))


def _module_graph():
    """Which modules of the package import which (relative imports, lazy ones inside
    functions included), by dotted name below ``stairbounce``."""
    names = {".".join(p.relative_to(SRC).with_suffix("").parts[:-1] if p.name == "__init__.py"
                      else p.relative_to(SRC).with_suffix("").parts): p for p in SRC.rglob("*.py")}
    graph = {}
    for name, path in names.items():
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        out = set()
        for level, module, imported in _relative_imports(path):
            base = package[:len(package) - (level - 1)] if level > 1 else list(package)
            stem = base + (module.split(".") if module else [])
            for n in imported:  # `from . import x` names a module; `from .m import f` the module m
                full = ".".join(stem + [n])
                out.add(full if full in names else ".".join(stem))
        graph[name] = {m for m in out if m in names and m != name and m != ""}
    return graph


def _cycle_through(graph, start):
    """A list of modules leading from ``start`` back to it, or None."""
    parent, todo = {}, [start]
    while todo:
        node = todo.pop()
        for nxt in graph.get(node, ()):
            if nxt == start:
                path = [node]
                while path[-1] != start:
                    path.append(parent[path[-1]])
                return [start] + path[::-1][1:] + [start] if node != start else [start, start]
            if nxt not in parent:
                parent[nxt] = node
                todo.append(nxt)
    return None


# circles issue 46 item 4 still has to break (each listed by one of its modules)
_KNOWN_CIRCLES = {"structure.borders", "structure.regions", "cascades", "cascade_families"}


@pytest.mark.parametrize("module", ["structure.certify", "structure.certificate", "structure.trapping",
                                    "structure.verify", "structure.verify_trapping", "structure.verdict"])
def test_the_certifier_and_the_checker_import_in_layers(module):
    # certify -> trapping -> certificate and verdict -> verify_trapping -> verify: what two
    # modules share lives in the lower one (issue 46 item 4)
    graph = _module_graph()
    assert module in graph
    assert _cycle_through(graph, module) is None, _cycle_through(graph, module)


def test_no_new_import_circle():
    graph = _module_graph()
    circles = {m: _cycle_through(graph, m) for m in graph}
    new = {m: c for m, c in circles.items() if c and m not in _KNOWN_CIRCLES}
    assert not new, new
