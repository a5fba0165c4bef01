"""docs/design.md's one-way data flow: the core imports no plotting, CLI or web code."""

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

CORE = ["_validate", "model", "symbolic", "trajectory", "units", "plane", "orbits", "fractal", "dimension", "atlas",
        "atlas_boxes", "nonsliding", "borders", "regions", "_region_export", "_colours", "_io", "_interrupt",
        "_cache", "structure", "structure.certify", "structure.verify", "structure.labels", "structure.tubes",
        "structure.itinerary", "structure.words", "structure.slices", "structure.borders", "structure.bifurcations",
        "structure.checks", "structure.continuation", "structure.regions", "structure.trace", "structure.graph",
        "structure.export", "cascades", "cascades.patterns", "cascades.search", "cascades.laws",
        "cascades.members", "cascades.families", "cascades.farey"]
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


def _module_name(path):
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _import_graph():
    """The package's import graph read from the code (ast): ``{module: {imported
    module: [line, ...]}}`` over every stairbounce module, counting imports at
    module level and inside functions alike (a function's late import is an
    arrow all the same: it only hides the circle from the import system).
    ``from .x import name`` points at the submodule ``x.name`` when there is
    one, else at ``x``."""
    modules = {_module_name(p): p for p in SRC.rglob("*.py")}
    graph = {}
    for name, path in modules.items():
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        out = graph.setdefault(name, {})
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names if a.name.split(".")[0] == "stairbounce"]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = ".".join(package[: len(package) - (node.level - 1)] + ([node.module] if node.module else []))
                elif (node.module or "").split(".")[0] == "stairbounce":
                    base = node.module
                else:
                    continue
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
            else:
                continue
            for target in targets:
                while target not in modules and "." in target:
                    target = target.rsplit(".", 1)[0]
                if target in modules and target != name:
                    out.setdefault(target, []).append(node.lineno)
    return graph


def _circles(graph):
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_circle_finder_finds_a_circle_and_only_circles():
    graph = {"a": {"b": [1]}, "b": {"c": [2]}, "c": {"a": [3]}, "d": {"a": [4]}, "e": {}}
    assert _circles(graph) == [["a", "b", "c"]]
    del graph["c"]["a"]
    assert _circles(graph) == []
    real = _import_graph()
    # the graph is read from the code: the figures' registry imports the recipes
    assert "stairbounce.figures.plane" in real["stairbounce.figures.recipes"]
    assert "stairbounce.structure.slices" in real["stairbounce.structure.regions"]


def test_no_import_circles():
    """Issue 46, item 4: the modules' imports form layers, at module level and
    inside functions: no two modules import each other, directly or round a
    longer circle.  Each circle found is printed with the imports that make it
    (file:line)."""
    graph = _import_graph()
    circles = _circles(graph)
    lines = []
    for comp in circles:
        lines.append(" <-> ".join(comp) + ":")
        for a in comp:
            for b in comp:
                if b in graph[a]:
                    where = a.replace(".", "/").removeprefix("stairbounce/")
                    lines.append(f"    {where}.py line {', '.join(map(str, sorted(set(graph[a][b]))))} imports {b}")
    assert not circles, f"{len(circles)} import circles:\n" + "\n".join(lines)
