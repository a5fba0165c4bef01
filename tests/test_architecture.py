"""docs/design.md's one-way data flow: the core imports no plotting, CLI or web code."""

import ast
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

CORE = ["_validate", "model", "symbolic", "trajectory", "units", "plane", "orbits", "fractal", "dimension", "atlas",
        "atlas_boxes", "nonsliding", "borders", "regions", "_region_export", "_colours", "_io", "_interrupt",
        "_cache", "structure", "structure.certify", "structure.certify_store", "structure._store_read", "structure.verify", "structure.verdict", "structure.tiling",
        "structure.labels", "structure.tubes",
        "structure.itinerary", "structure.words", "structure.slices", "structure.borders", "structure.bifurcations",
        "structure.checks", "structure.continuation", "structure.regions", "structure.trace", "structure.graph",
        "structure.export", "cascades", "cascades.patterns", "cascades.search", "cascades.laws",
        "cascades.members", "cascades.families", "cascades.farey"]
FORBIDDEN = ["matplotlib", "typer", "rich", "bokeh", "panel", "dask", "distributed"]


def _forbidden_after_importing(modules):
    """The FORBIDDEN packages in sys.modules of a fresh interpreter after it
    imported every one of ``modules`` (stairbounce.MODULE)."""
    code = (
        "import sys, importlib\n"
        f"for m in {list(modules)!r}:\n"
        "    importlib.import_module('stairbounce.' + m)\n"
        f"print([m for m in {FORBIDDEN!r} if m in sys.modules])"
    )
    r = subprocess.run([sys.executable, "-W", "ignore::DeprecationWarning", "-c", code],
                       capture_output=True, text=True, check=True)
    return r.stdout.strip()


@pytest.fixture(scope="module")
def core_imports():
    """What each core module pulls in, from one interpreter for all of them: when
    none of FORBIDDEN is loaded after importing them all, none of them imports
    any (the union holds each); only then is an interpreter per module spared,
    which names the culprit when the union is not clean."""
    together = _forbidden_after_importing(CORE)
    if together == "[]":
        return dict.fromkeys(CORE, "[]")
    return {module: _forbidden_after_importing([module]) for module in CORE}


@pytest.mark.parametrize("module", CORE)
def test_core_module_imports_no_plotting_cli_or_web(module, core_imports):
    assert core_imports[module] == "[]", f"stairbounce.{module} imports {core_imports[module]}"


def test_the_batched_import_check_sees_a_forbidden_import():
    # the check can fail: the command line (not core) imports Typer
    assert "typer" in _forbidden_after_importing(["model", "cli"])


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


SHIMS = {"fractal": "stairbounce.dimension", "borders": "stairbounce.structure.borders",
         "regions": "stairbounce.structure.regions", "_region_export": "stairbounce.structure.export"}


def test_the_shims_warn_naming_the_new_path_and_the_version_that_removes_them():
    """Issue 46, item 5: ``import stairbounce`` warns of nothing; each old path
    warns once, when imported, naming its new module and the version that
    removes it (a fresh interpreter: a module warns at its first import only)."""
    code = (
        "import warnings, importlib\n"
        "warnings.simplefilter('error')\n"
        "import stairbounce, stairbounce.figures\n"
        f"for old in {sorted(SHIMS)!r}:\n"
        "    with warnings.catch_warnings(record=True) as w:\n"
        "        warnings.simplefilter('always')\n"
        "        importlib.import_module('stairbounce.' + old)\n"
        "    print(old, '|', ' / '.join(f'{x.category.__name__}: {x.message}' for x in w))\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    said = dict(line.split(" | ", 1) for line in r.stdout.splitlines())
    assert set(said) == set(SHIMS)
    for old, new in SHIMS.items():
        assert said[old].count("DeprecationWarning") == 1, said[old]
        assert f"stairbounce.{old} is deprecated" in said[old] and new in said[old], said[old]
        assert "removed in 0.6.0" in said[old], said[old]


def _shim_imports(path):
    """The imports of a deprecated shim in ``path`` (ast), as text."""
    found = []
    inside = path.resolve().is_relative_to(SRC)
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found += [a.name for a in node.names if a.name.split(".")[:2] in [["stairbounce", s] for s in SHIMS]]
        elif isinstance(node, ast.ImportFrom):
            mod = node.module or ""
            if not node.level and mod.startswith("stairbounce"):
                parts = mod.split(".")
                names = [a.name for a in node.names] if len(parts) == 1 else [parts[1]]
                found += [f"stairbounce.{n}" for n in names if n in SHIMS]
            elif node.level and inside:
                package = path.relative_to(SRC).parent.parts
                if node.level - 1 == len(package):  # relative to stairbounce itself
                    names = [mod.split(".")[0]] if mod else [a.name for a in node.names]
                    found += [f"stairbounce.{n}" for n in names if n in SHIMS]
    return found


def test_our_code_and_tests_import_no_deprecated_shim(tmp_path):
    """Issue 46, item 5: the package, its tests, benchmarks, scripts and the
    docs' extension import the new paths; only the shims' own tests
    (tests/test_structure_layout.py, the warning test above) reach the old ones."""
    root = SRC.parents[1]
    own = {SRC / f"{s}.py" for s in SHIMS} | {SRC / "__init__.py", root / "tests" / "test_structure_layout.py"}
    files = [p for d in ("src/stairbounce", "tests", "benchmarks", "scripts", "docs/_ext")
             for p in sorted((root / d).rglob("*.py")) if p not in own]
    bad = {str(p.relative_to(root)): found for p in files if (found := _shim_imports(p))}
    attr = re.compile(r"\bsb\.(fractal|borders|regions|_region_export)\.")
    bad.update({str(p.relative_to(root)): ["sb." + m for m in attr.findall(p.read_text())]
                for p in files if p != Path(__file__).resolve() and attr.search(p.read_text())})
    assert not bad, bad
    # the check sees each form of an import of a shim, and structure/borders.py is not the shim
    probe = tmp_path / "probe.py"
    probe.write_text("import stairbounce.regions\nfrom stairbounce.fractal import box_counts\n"
                     "from stairbounce import _region_export, plane\nfrom stairbounce.structure import borders\n")
    assert _shim_imports(probe) == ["stairbounce.regions", "stairbounce.fractal", "stairbounce._region_export"]
    assert not _shim_imports(SRC / "structure" / "borders.py")


@pytest.mark.slow  # two interpreters compiling and loading a kernel: 5 s
def test_the_kernels_are_cached_on_disk_and_the_cache_serves_another_process(tmp_path):
    """Issue 46, item 7: every numba kernel is compiled with ``cache=True``, and
    the on-disk cache is valid across processes: a second interpreter loads the
    sliding-word kernel from it (a cache hit, no miss) instead of compiling it
    again (1.5 s; a scan, border points and an orbit diagram: 17.9 s cold, 1.7 s
    warm).  The scan kernel's own cache, in a user-wide folder beside a read-only
    install, is tested by tests/test_wheel.py."""
    uncached = []
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef):
                for d in node.decorator_list:
                    call = d if isinstance(d, ast.Call) else None
                    name = (call.func if call else d)
                    name = getattr(name, "id", getattr(name, "attr", ""))
                    if name in ("njit", "jit", "vectorize", "guvectorize"):
                        kw = {k.arg: k.value for k in call.keywords} if call else {}
                        if not (isinstance(kw.get("cache"), ast.Constant) and kw["cache"].value is True):
                            uncached.append(f"{path.relative_to(SRC)}:{node.lineno} {node.name}")
    assert not uncached, uncached
    code = (
        "import stairbounce as sb, stairbounce.symbolic as S\n"
        "assert sb.sliding_word(0.05, 0.93).letters == (2, 2, 2)\n"
        "s = S._impacts_until_slide.stats\n"
        "print(sum(s.cache_hits.values()), sum(s.cache_misses.values()))\n"
    )
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    first, second = (subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                                    env=env).stdout.split() for _ in range(2))
    assert first == ["0", "1"]  # an empty cache: compiled and written
    assert second == ["1", "0"]  # the next process: read back, not compiled


@pytest.mark.parametrize("module", ["structure.certify", "structure.certificate", "structure.trapping",
                                    "structure.verify", "structure.verify_trapping", "structure.verdict"])
def test_the_certifier_and_the_checker_import_in_layers(module):
    # certify -> trapping -> certificate and verdict -> verify_trapping -> verify: what two
    # modules share lives in the lower one (issue 46 item 4)
    graph = _import_graph()
    name = f"stairbounce.{module}"
    assert name in graph
    assert not [c for c in _circles(graph) if name in c]
    layers = {"structure.trapping": "structure.certificate", "structure.certify": "structure.trapping",
              "structure.verify_trapping": "structure.verify", "structure.verdict": "structure.verify_trapping"}
    if module in layers:  # the arrow goes down, and not back
        assert f"stairbounce.{layers[module]}" in graph[name]
