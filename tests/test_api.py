"""The flat API: ``sb.NAME`` for every public function, exactly the documented
list, a light import, and the old ``stairbounce.scan`` module paths still
working (with a DeprecationWarning)."""

import inspect
import pickle
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import stairbounce as sb
from stairbounce import plane

API_PAGES = sorted((Path(__file__).resolve().parents[1] / "docs" / "api").glob("*.md"))
_DIRECTIVE = re.compile(r"^\.\. auto(?:function|class|data):: (stairbounce(?:\.plot)?)\.(\w+)\s*$", re.M)


def _documented(module):
    """The names that have an entry on the API pages (docs/api/*.md), page by page."""
    return [name for page in API_PAGES for mod, name in _DIRECTIVE.findall(page.read_text()) if mod == module]


def _run(code):
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r.stdout.strip()


def test_all_is_exactly_the_documented_api():
    documented = _documented("stairbounce")
    assert len(documented) == len(set(documented)), "a name is documented twice"
    assert len(sb.__all__) == len(set(sb.__all__)), "a name is listed twice in __all__"
    assert sorted(sb.__all__) == sorted(documented)


def test_plot_all_is_exactly_the_documented_plot_api():
    assert sorted(sb.plot.__all__) == sorted(_documented("stairbounce.plot"))


_TABLE = re.compile(r"^\.\. autosummary::\n((?:   .*\n|\n)*)", re.M)


@pytest.mark.parametrize("page", API_PAGES, ids=lambda p: p.name)
def test_each_api_page_opens_with_a_table_of_its_entries(page):
    text = page.read_text()
    entries = [name for _, name in _DIRECTIVE.findall(text)]
    tables = _TABLE.findall(text)
    listed = [line.strip() for table in tables for line in table.splitlines()
              if line.strip() and not line.strip().startswith(":")]
    if page.name == "index.md":  # the topics' list, and the version
        assert entries == ["__version__"] and not listed
        return
    assert tables and text.index(".. autosummary::") < text.index(".. auto", text.index(".. autosummary::") + 1)
    assert listed == entries, page.name


@pytest.mark.parametrize("name", sb.__all__)
def test_every_name_resolves_and_has_a_docstring(name):
    obj = getattr(sb, name)
    if callable(obj):
        assert inspect.getdoc(obj), f"sb.{name} has no docstring"


def test_the_flat_names_are_the_module_functions():
    # the flat API re-exports, it does not wrap (one source of truth)
    assert sb.box_dimension is sb.dimension.box_dimension
    assert sb.scan_coords is plane.scan_coords
    assert sb.scan_to_zarr is sb.atlas.scan_to_zarr
    assert sb.poincare_map is sb.model.poincare_map
    # sb.scan is the one exception: a callable that forwards to plane.scan
    assert sb.scan.__wrapped__ is plane.scan
    assert inspect.signature(sb.scan) == inspect.signature(plane.scan)


def test_import_loads_no_plotting_web_or_dask_code():
    heavy = ["matplotlib", "typer", "rich", "bokeh", "panel", "dask", "distributed", "zarr",
             "IPython", "stairbounce.plot", "stairbounce.explorer", "stairbounce.cli",
             "stairbounce.figures"]
    loaded = _run(f"import sys, stairbounce; print([m for m in {heavy!r} if m in sys.modules])")
    assert loaded == "[]"


def test_lazy_submodules_load_on_first_use():
    out = _run(
        "import sys, stairbounce as sb; a = 'stairbounce.plot' in sys.modules; "
        "f = sb.plot.plot_scan; print(a, 'stairbounce.plot' in sys.modules, "
        "'plot' in dir(sb), 'matplotlib.pyplot' in sys.modules)"
    )
    # loading sb.plot does not even start pyplot: renderers import it when drawing
    assert out == "False True True False"
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        sb.nope


def test_scan_is_callable_and_equals_the_plane_function():
    a = sb.scan((0.0, 1.0, 12), (0.0, 1.5, 9), max_iter=60)
    b = plane.scan((0.0, 1.0, 12), (0.0, 1.5, 9), max_iter=60)
    assert a.identical(b)


def test_calling_scan_does_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sb.scan((0.0, 1.0, 4), (0.0, 1.5, 3), max_iter=10)


def test_help_on_scan_shows_the_function_and_warns_nothing():
    import pydoc

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        text = pydoc.render_doc(sb.scan, renderer=pydoc.plaintext)
    assert "Periodic sliding solutions" in text and "max_iter=1000" in text


def test_old_path_from_module_import_warns_and_forwards():
    with pytest.warns(DeprecationWarning, match="stairbounce.plane"):
        from stairbounce.scan import scan_coords
    assert scan_coords is plane.scan_coords


def test_old_path_module_dot_function_warns_and_forwards():
    from stairbounce import scan

    with pytest.warns(DeprecationWarning, match="stairbounce.plane"):
        f = scan.scan
    assert f is plane.scan
    with pytest.warns(DeprecationWarning):
        assert scan.no_sliding_curve is plane.no_sliding_curve
    with pytest.raises(AttributeError), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scan.not_a_function


@pytest.mark.parametrize(
    "first",
    [
        "import stairbounce.scan",
        "import stairbounce.scan as m",
        "from stairbounce.scan import scan_coords",
        "from stairbounce import scan",
        "import stairbounce.plot.scan",
    ],
)
def test_old_import_paths_in_a_fresh_interpreter_never_clobber_the_function(first):
    # the import system sets an imported submodule as an attribute of its
    # package: importing the old module path first must leave sb.scan callable
    code = (
        "import warnings; warnings.simplefilter('ignore')\n"
        f"{first}\n"
        "import sys, stairbounce as sb, stairbounce.plane as p\n"
        "ds = sb.scan((0.0, 1.0, 4), (0.0, 1.5, 3), max_iter=10)\n"
        "ok = ds.identical(p.scan((0.0, 1.0, 4), (0.0, 1.5, 3), max_iter=10))\n"
        "print(ok, sys.modules['stairbounce.scan'] is sb.scan, callable(sb.plot.scan))"
    )
    assert _run(code) == "True True True"


def test_scan_pickles_by_reference():
    assert pickle.loads(pickle.dumps(sb.scan)) is sb.scan
    assert pickle.loads(pickle.dumps(sb.plot.scan)) is sb.plot.scan


def test_old_plot_module_path_warns_and_its_name_draws():
    with pytest.warns(DeprecationWarning, match="stairbounce.plot.plane"):
        from stairbounce.plot.scan import plot_scan
    assert plot_scan is sb.plot.plot_scan
    assert sb.plot.scan.__wrapped__ is sb.plot.plot_scan


# --------------------------------------------------------------------------- #
# plot_* need nothing but the computed object                                  #
# --------------------------------------------------------------------------- #


@pytest.fixture
def plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    yield plt
    plt.close("all")


def _labels(ax):
    return ax.get_xlabel(), ax.get_ylabel()


def test_plot_scan_needs_only_the_dataset(plt):
    ds = sb.scan((0.0, 1.0, 16), (0.0, 1.5, 12), max_iter=50)
    ax = sb.plot.plot_scan(ds)
    xlabel, ylabel = _labels(ax)
    assert "e" in xlabel and "u" in ylabel
    # the image spans the window recorded in the dataset's attributes
    assert ax.get_xlim() == pytest.approx((0.0, 1.0)) and ax.get_ylim() == pytest.approx((0.0, 1.5))
    assert sb.plot.scan(ds).get_xlim() == pytest.approx((0.0, 1.0))


def test_plot_orbit_diagram_needs_only_the_dataset(plt):
    ds = sb.orbit_diagram(0.1, np.linspace(0.4, 1.2, 40), transient=50, keep=20)
    ax = sb.plot.plot_orbit_diagram(ds)
    assert ax.get_xlabel().endswith("u") and "e = 0.1" in ax.get_title()
    assert ax.get_xlim() == pytest.approx((0.4, 1.2), abs=0.05)


def test_plot_box_dimension_needs_only_the_result(plt):
    r = sb.perimeter_dimension(method="boxes", resolution=64, max_iter=100)
    fig = sb.plot.plot_box_dimension(r)
    image_ax, counts_ax = fig.axes[:2]
    assert image_ax.get_xlim() == pytest.approx(r.e)
    assert f"{r.dimension:.3f}" in counts_ax.get_title()


def test_plot_trajectory_needs_only_the_trajectory(plt):
    ax = sb.plot.plot_trajectory(sb.trajectory(0.5, 0.9, steps=3))
    assert ax.get_lines()


# --------------------------------------------------------------------------- #
# the explorer inside Jupyter                                                  #
# --------------------------------------------------------------------------- #


def test_explorer_inline_builds_renders_and_agrees_with_the_scan():
    pytest.importorskip("panel")
    import panel as pn
    from bokeh.models import Model

    from stairbounce.explorer.view import shade

    layout = sb.explorer.inline(e=(0.0, 0.4), u=(0.3, 1.1), width=60, height=50, max_iter=200,
                             point=(0.1, 0.5))
    assert isinstance(layout, pn.viewable.Viewable)
    ex = layout.explorer
    # the first view was computed before app() returned, and is the scan of that window
    ds = sb.scan((0.0, 0.4, 60), (0.3, 1.1, 50), max_iter=200)
    np.testing.assert_array_equal(ex.ds.word_length.values, ds.word_length.values)
    np.testing.assert_array_equal(ex.img_src.data["image"][0], shade(ds, "word_length"))
    # (0.1, 0.5) lies in the first tongue of Thm 3.1 (u^2 <= (1/2)(0.9/1.1)^2): word (1, 0^inf)
    assert "(1, 0^" in ex.point_pane.object
    # it renders to a Bokeh document without a browser or a server
    root = layout.get_root()
    assert isinstance(root, Model)


@pytest.mark.parametrize(
    "kwargs, words",
    [({"e": (0.5, 0.2)}, "e window must satisfy"), ({"width": 10**5}, "pixel budget"), ({"color": "hue"}, "color must be one of"),
     ({"u": 3}, r"u must be a tuple \(u_min, u_max\) or \(u_min, u_max, n_u\)")],
)
def test_explorer_inline_refuses_bad_views(kwargs, words):
    pytest.importorskip("panel")
    with pytest.raises(ValueError, match=words):
        sb.explorer.inline(**kwargs)
