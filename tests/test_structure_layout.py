"""The layout of the plane's exact structure (issue 36, item 9): borders,
regions, their export and the certifier are one package,
``stairbounce.structure``, one module per concept (docs/design.md,
"Architecture and data flow").

The old modules ``stairbounce.borders``, ``stairbounce.regions`` and
``stairbounce._region_export`` are re-export shims: every name they defined
(listed below, generated once from their top-level definitions before the
move, as no git history is guaranteed here) gives the very object of the module
that holds it now.  The monkeypatch points the tests use are checked to be
where the code looks the name up, so a patch changes what the code does.
"""

import ast
import importlib
import inspect
from pathlib import Path

import numpy as np
import pytest

import stairbounce as sb
from stairbounce import structure
from stairbounce.structure import borders, itinerary, regions, words

from .test_architecture import CORE, FORBIDDEN

# this file tests the deprecated shims themselves (their warning: test_architecture.py)
pytestmark = pytest.mark.filterwarnings(r"ignore:stairbounce\.(borders|regions|_region_export) is deprecated")

SRC = Path(__file__).resolve().parents[1] / "src" / "stairbounce"
NEW = ["itinerary", "words", "slices", "borders", "bifurcations", "checks", "continuation", "regions", "trace", "graph",
       "export"]
OLD_ALL = {
    "borders": ["itinerary", "border_points", "word_table", "bifurcations"],
    "regions": ["BorderArc", "Corner", "Region", "RegionComponent", "BorderGraph", "trace_border", "word_region",
                "window_regions", "border_graph", "regions_geojson", "regions_svg", "write_regions",
                "band_similarity"],
}

# old module -> {new module: [every top-level name the old module defined that is there now]}
OLD_NAMES = {
    "borders": {
        "bifurcations": "_bifurcation_kernel _long_run _long_run_kernel _MAX_ROUNDS _run_text _same_run bifurcations".split(),
        "borders": (
            "_at _bisect_pair _bisect_sliding_pair _border_kernel _CONVENTION _event_of _finish_sliding "
            "_first_difference _grid_input _OUT _pairs _ROUND_LANES_MIN _ROUND_UNIT_MIN _run_pairs "
            "_scan_input _shrink_secant _slide_period _slide_periods _SLIDING _sliding_rounds _table _trial "
            "_WORD _WORD_BISECT _word_table_rows _write_point _write_sliding_point "
            "border_point_slices border_points PAIR_TRIALS pair_work staged word_group_slices "
            "word_table word_table_slices "
        ).split(),
        "checks": "above_no_sliding_curve side_agreement tongue_distances TONGUE_WINDOW".split(),
        "itinerary": (
            "_BLOCK _check_max_iter _event_margin _follows _impact_time_at _impacts_from_rest _itinerary_args "
            "_itinerary_block _itinerary_blocks _ITINERARY_BYTES _ITINERARY_NAMES _margin _next_margin "
            "CHATTER EDGE GRAZE itinerary KINDS "
        ).split(),
        "slices": "_work_blocks grid_blocks".split(),
        "words": "_fill_impacts _hash_rows _rows_equal _word_groups _word_text _words NONE_WORD".split(),
    },
    "regions": {
        "checks": "band_similarity".split(),
        "continuation": (
            "_Arc _corner _corner_on_arc _correct _EPS _follow _into_window _locate_corner _Margins _MAX_TURN "
            "_NEWTON _noise _outgoing _ROUND_ULPS _solve2 _tangent _ulps _unit _walk "
        ).split(),
        "export": "_export_options regions_geojson regions_svg write_regions".split(),
        "graph": (
            "_corners_on_arcs _curves _GraphMargins _on_arc_curve _region_list _split_arc border_graph "
            "BorderGraph "
        ).split(),
        "itinerary": "_hash_itinerary _itinerary_of _margins _words_grid".split(),
        "regions": (
            "_arc_area _as_word _below_rounding _bisect_into _check_centres _check_run _check_steps "
            "_check_window _chord_position _chord_positions _closed _CORNER_DIRECTIONS _CORNER_MIN_AREA "
            "_CORNER_RADII _corner_rings _CORNER_ROUNDS _CORNER_SEEDS _corner_seeds _crossing _curve_area "
            "_DEFAULT_RESOLUTION _E_TOP _fill _GAUSS _grid _hermite_area _image_window _inside_polygon "
            "_label_grid _label_grid_slices _MAX_STEPS _new_curve _on_curves _point_seeds _position_rounding "
            "_seed_grid _to_arcs _trace_word _U_BOTTOM _words_points BorderArc Corner iter_window_regions "
            "itinerary_of_word Region RegionComponent traced_columns window_regions word_region "
        ).split(),
        "trace": "_event_between _outcome _prescribed_step _same _side_itinerary _word_text trace_border".split(),
    },
    "_region_export": {
        "export": (
            "_cells _crossings _deviation _Edge _EPS _find_crossings _loops _MAX_ROUNDS _meet _on_segment "
            "_orient _polygons _project _reason _S _SAME _same_curve _segments _signed_area _ticks _untangle "
            "_untraced_reason build coverage FACE_COLOUR geojson Partition svg TOLERANCE untraced write "
        ).split(),
    },
}


def _cases():
    return [(old, new, name) for old, by in OLD_NAMES.items() for new, names in by.items() for name in names]


def test_the_list_covers_every_old_name_once():
    for old, by in OLD_NAMES.items():
        names = [n for ns in by.values() for n in ns]
        assert len(names) == len(set(names)), old
        assert set(by) <= set(NEW), old
    assert len(_cases()) == 196  # the three old modules' top-level definitions


@pytest.mark.parametrize("old", sorted(OLD_NAMES))
def test_every_old_name_is_the_object_of_its_new_module(old):
    """``stairbounce.OLD.X`` (and ``from stairbounce.OLD import X``) is the very
    object of ``stairbounce.structure.NEW.X``, and X is defined in NEW (a
    top-level definition there, not an import)."""
    shim = importlib.import_module(f"stairbounce.{old}")
    for new, names in OLD_NAMES[old].items():
        module = importlib.import_module(f"stairbounce.structure.{new}")
        defined = _defined(module)
        for name in names:
            assert name in defined, f"{name} is not defined in stairbounce.structure.{new}"
            assert getattr(shim, name) is getattr(module, name), (old, new, name)
            ns = {}
            exec(f"from stairbounce.{old} import {name}", ns)
            assert ns[name] is getattr(module, name)
    assert getattr(shim, "__all__", []) == OLD_ALL.get(old, [])
    for name in getattr(shim, "__all__", []):
        assert getattr(sb, name) is getattr(shim, name)


def _defined(module):
    names = set()
    for node in ast.parse(Path(module.__file__).read_text()).body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names |= {n.id for t in node.targets for n in ast.walk(t) if isinstance(n, ast.Name)}
    return names


def test_the_shims_define_nothing():
    """The old modules only re-export: no definition of their own to drift
    (their one statement: the DeprecationWarning)."""
    for old in OLD_NAMES:
        tree = ast.parse((SRC / f"{old}.py").read_text())
        body = [n for n in tree.body if not isinstance(n, ast.ImportFrom)
                and not (isinstance(n, ast.Import) and [a.name for a in n.names] == ["warnings"])]
        assert all(isinstance(n, ast.Expr) or (isinstance(n, ast.Assign) and n.targets[0].id == "__all__")
                   for n in body), old
        assert all(n.level == 1 and n.module.startswith("structure.") for n in tree.body
                   if isinstance(n, ast.ImportFrom)), old


def test_every_structure_module_is_core_and_imports_no_plotting_cli_or_web():
    """Each module of the package is in test_architecture's CORE list (which
    runs each in a fresh interpreter and checks sys.modules), and none of
    them names a plotting, CLI or web package in any import, at any depth."""
    found = sorted(p.stem for p in (SRC / "structure").glob("*.py") if p.stem != "__init__")
    assert set(NEW) <= set(found)
    for stem in found:
        assert stem not in NEW or f"structure.{stem}" in CORE, stem
        for node in ast.walk(ast.parse((SRC / "structure" / f"{stem}.py").read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else [])
            rel = [node.module or ""] if isinstance(node, ast.ImportFrom) and node.level else []
            assert not [n for n in names if n.split(".")[0] in FORBIDDEN], (stem, names)
            assert not [m for m in rel if m.split(".")[0] in ("plot", "cli", "explorer", "figures")], (stem, rel)


def test_the_structure_modules_import_one_way():
    """itinerary <- words <- borders <- bifurcations; itinerary <- continuation
    <- regions <- trace, graph <- export; checks on top: no cycle among the
    module-level imports (a function may import upwards, late)."""
    graph = {}
    for stem in NEW:
        tree = ast.parse((SRC / "structure" / f"{stem}.py").read_text())
        graph[stem] = set()
        for node in tree.body:
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                graph[stem] |= {node.module} if node.module else {a.name for a in node.names}
    order = []
    while len(order) < len(NEW):
        ready = [m for m in NEW if m not in order and graph[m] & set(NEW) <= set(order)]
        assert ready, f"a cycle among {sorted(set(NEW) - set(order))}"
        order += ready
    assert order.index("itinerary") < order.index("borders") < order.index("bifurcations")
    assert order.index("slices") < order.index("borders") and order.index("slices") < order.index("regions")
    assert order.index("continuation") < order.index("regions") < order.index("graph") < order.index("export")


class _Counter:
    """Wrap ``module.name`` (through monkeypatch), counting its calls."""

    def __init__(self, monkeypatch, module, name):
        self.calls = 0
        orig = getattr(module, name)

        def wrapped(*a, **k):
            self.calls += 1
            return orig(*a, **k)

        monkeypatch.setattr(module, name, wrapped)


TINY = dict(e=(0.05, 0.5, 12), u=(0.3, 1.2, 12), max_iter=200)


def test_the_patch_points_of_the_tests_are_where_the_code_looks_them_up(monkeypatch):
    """The names the tests patch (tests/test_borders.py, test_faults_round3.py)
    are looked up, at their use, in the module the tests patch: patching them
    there changes what the code does (a call counted, a branch taken)."""
    it = _Counter(monkeypatch, itinerary, "_itinerary_block")
    sb.itinerary(0.02, 0.7, max_iter=100)
    assert it.calls == 1
    fill = _Counter(monkeypatch, words, "_fill_impacts")
    rows = _Counter(monkeypatch, words, "_rows_equal")
    kernel = _Counter(monkeypatch, borders, "_border_kernel")
    ds = sb.scan(**TINY)
    sb.word_table(ds)
    assert fill.calls >= 1 and rows.calls >= 1 and kernel.calls >= 1
    # _ROUND_LANES_MIN chooses the bisection rounds, looked up in structure.borders
    rounds = _Counter(monkeypatch, borders, "_sliding_rounds")
    monkeypatch.setattr(borders, "_ROUND_LANES_MIN", 10**9)
    a = sb.border_points(ds, outcome="sliding")
    assert rounds.calls == 0
    monkeypatch.setattr(borders, "_ROUND_LANES_MIN", 1)
    b = sb.border_points(ds, outcome="sliding")
    assert rounds.calls == 1 and a.sizes["point"] == b.sizes["point"] > 0
    assert np.array_equal(a.e.values, b.e.values) and np.array_equal(a.u.values, b.u.values)


def test_the_region_patch_points_take_effect(monkeypatch):
    """``regions._trace_word`` and ``regions._words_grid`` (patched by
    tests/test_faults_round3.py's work meter) are looked up in
    stairbounce.structure.regions, and the command line's ``words --regions``
    calls ``window_regions`` there (tests/test_faults_round3_b.py)."""
    trace = _Counter(monkeypatch, regions, "_trace_word")
    grid = _Counter(monkeypatch, regions, "_words_grid")
    sb.word_region((2,), e=(0.05, 0.2), u=(0.75, 0.95), resolution=8, max_iter=100)
    assert trace.calls >= 1 and grid.calls >= 1
    from stairbounce.cli import borders_commands

    assert "rg.window_regions(" in inspect.getsource(borders_commands._regions)
    assert "from ..structure import regions as rg" in inspect.getsource(borders_commands._regions)


def test_the_export_reads_the_former_regions_names_from_their_new_modules(monkeypatch):
    """structure/export.py keeps the former ``_rg.NAME`` of
    stairbounce._region_export: each resolves, at its use, to the module that
    holds the name now (a patch there is seen), and an unknown name fails."""
    from stairbounce.structure import export, graph

    for name in ("Region", "_grid", "_inside_polygon", "_label_grid", "_itinerary_of", "_GraphMargins",
                 "border_graph"):
        assert getattr(export._rg, name) is getattr(sb.regions, name)
    for module, name in ((graph, "border_graph"), (itinerary, "_itinerary_of"), (regions, "_label_grid")):
        marker = object()
        monkeypatch.setattr(module, name, marker)
        assert getattr(export._rg, name) is marker, name
    with pytest.raises(AttributeError):
        export._rg.no_such_name
    assert sb._region_export.build is export.build and sb.regions.regions_svg is export.regions_svg


def test_the_package_modules_are_reachable_after_import_stairbounce():
    for stem in NEW:
        assert getattr(structure, stem).__name__ == f"stairbounce.structure.{stem}"
