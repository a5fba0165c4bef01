"""The fourth fault campaign and the fifth newcomer's run (issue 45, reports
``reliability-round4.md`` and ``newcomer-round5.md``): the regions export at
tiny windows (R6), read failures and malformed inputs named (R9, R10), checks
made before the work (R11), Ctrl-C in the long commands (R8), one vocabulary
(F12).

Each test of a finding fails on the code the reports tested (1560fca) with
the report's symptom.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import stairbounce as sb
from stairbounce.structure import export

from .test_faults import run as _run_cli  # the CLI in process: (exit status, out, err)
from .test_faults_round2 import one_line_error

shapely = pytest.importorskip("shapely")
from shapely.geometry import shape  # noqa: E402


def _strict(text):
    """The JSON document ``text``, refusing Infinity and NaN (RFC 8259)."""
    def bad(token):
        raise ValueError(f"not JSON: {token}")
    return json.loads(text, parse_constant=bad)


# --------------------------------------------------------------------------- #
# R6: the regions export at tiny windows                                      #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize("width,where", [(1e-14, (0.05, 0.93)), (1e-13, (0.05, 0.93)),
                                         (3e-15, (0.05, 0.93)), (1e-14, (0.33, 0.35))])
def test_r6_tiny_windows_export_valid_polygons_with_finite_coordinates(width, where):
    # the report: 1e-14 and 3e-15 squares wrote a "clipped" feature with Infinity
    # coordinates (2538 crossings); the 1e-13 square 5 polygons, 4 invalid
    e, u = (where[0], where[0] + width), (where[1], where[1] + width)
    regs = sb.window_regions(e, u, resolution=24)
    gj = sb.regions_geojson(regs, resolution=24)
    _strict(json.dumps(gj, allow_nan=False))
    meta = gj["metadata"]
    assert meta["crossings"] == 0 and meta["clipped"] == []
    geoms = [shape(f["geometry"]) for f in gj["features"] if f["geometry"] is not None]
    assert len(geoms) == sum(len(r.components) for r in regs) >= 1
    assert all(g.is_valid for g in geoms)
    # the polygons fill the window (one word in it), to rounding of the window's area
    W = (e[1] - e[0]) * (u[1] - u[0])
    assert abs(sum(g.area for g in geoms) - W) <= 1e-6 * W
    # the tolerance is floored at a few ulps of the coordinates
    assert meta["tolerance"] >= 4 * np.spacing(max(e[1], u[1])) * 0.99


def test_r6_words_regions_at_a_1e_14_window_writes_strict_json(tmp_path, capsys):
    out = tmp_path / "t14.geojson"
    code, _, err = _run_cli(["words", "--regions", "--e", "0.05:0.05000000000001", "--u",
                             "0.93:0.93000000000001", "--size", "24x24", "--out", out], capsys)
    assert code == 0, err
    assert "invalid value" not in err
    doc = _strict(out.read_text())
    assert all(f["properties"]["word"] is not None for f in doc["features"])


def test_r6_a_user_tolerance_below_rounding_is_raised_to_the_floor():
    regs = sb.window_regions((0.05, 0.05 + 1e-12), (0.93, 0.93 + 1e-12), resolution=8)
    meta = sb.regions_geojson(regs, tolerance=1e-30)["metadata"]
    assert meta["tolerance"] == export.tolerance_floor((0.05, 0.05 + 1e-12, 0.93, 0.93 + 1e-12)) > 1e-30


def test_r6_a_non_finite_coordinate_is_refused_by_name():
    feats = [{"type": "Feature", "properties": {"word": "(2, 0^inf)"},
              "geometry": {"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [math.inf, 1], [0, 0]]]}}]
    with pytest.raises(ValueError, match="too narrow to export.*non-finite"):
        export._check_finite(feats, (0.05, 0.05 + 1e-14, 0.93, 0.93 + 1e-14))


def test_r6_the_whole_plane_export_states_and_holds_its_overlap_bound():
    # the report: at resolution 24 the pair (1, 0^inf), (1, 0, 1, 0^inf) overlaps by
    # 1.9e-15 of the window, above the tests' 1e-15: the export now states its bound
    e, u = (0.0, 1.0), (0.0, 1.5)
    regs = sb.window_regions(e, u, resolution=24)
    gj = sb.regions_geojson(regs, resolution=24)
    meta = gj["metadata"]
    assert "max_deviation times the sum of their perimeters" in meta["overlap_bound"]
    feats = [f for f in gj["features"] if f["geometry"] is not None]
    geoms = [shape(f["geometry"]) for f in feats]
    tree = shapely.STRtree(geoms)
    a, b = tree.query(geoms, predicate="intersects")
    worst = 0.0
    for i, j in zip(a, b):
        if i < j:
            over = geoms[i].intersection(geoms[j]).area
            assert over <= meta["max_deviation"] * (geoms[i].length + geoms[j].length)
            worst = max(worst, over)
    assert worst > 0.0     # the pair at the tongue tip is still there: the bound is what holds


# --------------------------------------------------------------------------- #
# R9, R10: read failures named as reads; malformed inputs as ValueErrors       #
# --------------------------------------------------------------------------- #

import dataclasses  # noqa: E402
import os  # noqa: E402


@pytest.fixture(scope="module")
def small_atlas():
    return sb.certify(e=(0.04, 0.065), u=(0.92, 0.945), depth=3)


@pytest.fixture(scope="module")
def saved(small_atlas, tmp_path_factory):
    folder = tmp_path_factory.mktemp("atlas")
    small_atlas.save(folder / "a.nc")
    small_atlas.save(folder / "a.zarr")
    return folder


def _verify_cli(path, capsys):
    return _run_cli(["certify", "--verify", path], capsys)


def test_r10_verify_of_a_missing_file_says_it_cannot_read_it(tmp_path, capsys):
    code, _, err = _verify_cli(tmp_path / "missing.nc", capsys)
    assert code == 2 and one_line_error(err)
    assert "cannot read" in err and "cannot write" not in err and "no such file" in err


@pytest.mark.parametrize("damage", ["truncated", "flipped", "folder", "zarr as nc", "empty"])
def test_r10_verify_of_an_unreadable_nc_is_one_line_naming_a_read(damage, saved, tmp_path, capsys):
    bad = tmp_path / "bad.nc"
    data = (saved / "a.nc").read_bytes()
    if damage == "truncated":
        bad.write_bytes(data[: len(data) // 3])
    elif damage == "flipped":
        b = bytearray(data)
        for k in range(200, len(b), 97):
            b[k] ^= 0xFF
        bad.write_bytes(bytes(b))
    elif damage == "folder":
        bad.mkdir()
    elif damage == "zarr as nc":
        import shutil

        shutil.copytree(saved / "a.zarr", bad)
    else:
        bad.write_bytes(b"")
    code, _, err = _verify_cli(bad, capsys)
    if code == 1:   # a flipped byte in the data itself: read, and the boxes rejected
        assert damage == "flipped" and "rejected" in _
        return
    assert code == 2 and one_line_error(err), err
    assert "cannot read" in err and "cannot write" not in err


def test_r10_verify_refuses_a_fifo_at_once(tmp_path, capsys):
    fifo = tmp_path / "f.nc"
    os.mkfifo(fifo)
    import time

    t = time.perf_counter()
    code, _, err = _verify_cli(fifo, capsys)      # read, it would wait for a writer forever
    assert time.perf_counter() - t < 30
    assert code == 2 and one_line_error(err) and "not a regular file or a folder" in err


def test_r9_a_garbled_zarr_chunk_is_one_line(saved, tmp_path, capsys):
    import shutil

    store = tmp_path / "g.zarr"
    shutil.copytree(saved / "a.zarr", store)
    chunk = store / "e0" / "c" / "0"
    b = bytearray(chunk.read_bytes())
    b[5:20] = b"x" * 15
    chunk.write_bytes(bytes(b))
    code, _, err = _verify_cli(store, capsys)
    assert code == 2 and one_line_error(err), err
    assert "cannot read" in err and str(store) in err
    with pytest.raises(ValueError, match="cannot read .* as a certified atlas"):
        sb.CertifiedAtlas.load(store)
    with pytest.raises(ValueError, match="cannot read"):
        sb.verify(store)


def test_r9_load_of_an_atlas_without_a_variable_is_a_value_error(saved, tmp_path):
    import xarray as xr

    with xr.open_dataset(saved / "a.nc") as f:
        ds = f.load()
    ds.drop_vars("word").to_netcdf(tmp_path / "noword.nc")
    with pytest.raises(ValueError, match="word"):
        sb.CertifiedAtlas.load(tmp_path / "noword.nc")


def test_r9_certificate_from_an_empty_dict_names_what_is_missing():
    with pytest.raises(ValueError, match="lacks e, u, max_iter, status"):
        sb.Certificate.from_dict({})
    good = sb.certify_box(e=(0.05, 0.0501), u=(0.93, 0.9301)).to_dict()
    assert sb.verify(sb.Certificate.from_dict(good))
    for key, value in [("e", [0.05]), ("u", "0.93:0.94"), ("max_iter", 1.5), ("itinerary", ["a"]),
                       ("word", ["x"]), ("margins", [[1, 2, 3]])]:
        with pytest.raises(ValueError, match=key):
            sb.Certificate.from_dict({**good, key: value})


@pytest.mark.parametrize("field,value", [("e", (0.05,)), ("u", None), ("e", "0.05:0.06"),
                                         ("max_iter", 2.5), ("status", 3)])
def test_r9_verify_of_a_certificate_of_the_wrong_form_is_a_value_error(field, value):
    cert = sb.certify_box(e=(0.05, 0.0501), u=(0.93, 0.9301))
    # refused when the certificate is made (Certificate's own checks) or by verify: either names the field
    with pytest.raises(ValueError, match=rf"^(certificate )?{field} "):
        sb.verify(dataclasses.replace(cert, **{field: value}))


def test_r9_trapping_region_with_max_iter_1e12_is_refused_by_name():
    with pytest.raises(ValueError, match="max_iter"):
        sb.trapping_region(e=(0.299, 0.30), u=(0.413, 0.414), max_iter=10**12)


@pytest.mark.parametrize("n", [3 * 10**8, 10**9])
def test_r9_a_trapping_certificate_with_a_huge_grid_is_refused_by_name(n):
    from stairbounce.structure.trapping import certificate_of

    r = sb.trapping_region(e=(0.299, 0.30), u=(0.413, 0.414))
    assert r is not None
    cert = certificate_of(dataclasses.replace(r, grid=r.grid[:2] + (n,) + r.grid[3:5] + (n,)), 1000)
    # the report: MemoryError; now refused by name before anything is allocated: the
    # checker's work estimate (boxes + steps + cells + the grid's edges: it reads a region
    # by its own cells, never the whole grid) names them and the limit
    with pytest.raises(ValueError, match=rf"the trapping region: .* {2 * n + r.cells.size:,} trapping cells and "
                                         "grid edges .* limit"):
        sb.verify(cert)


def test_r9_a_region_of_a_large_grid_is_checked_by_its_cells():
    """A grid of 10^6 cells a side (10^12 cells) is within the work limit now that the
    checker reads a region by its cells: the region moved onto it is checked, in bounded
    memory, and fails (its cells' indices now name other places), and the true one passes."""
    from stairbounce.structure.trapping import certificate_of

    r = sb.trapping_region(e=(0.299, 0.30), u=(0.413, 0.414))
    assert sb.verify(certificate_of(r, 1000)).ok
    n = 10**6
    moved = certificate_of(dataclasses.replace(r, grid=r.grid[:2] + (n,) + r.grid[3:5] + (n,)), 1000)
    verdict = sb.verify(moved)
    assert not verdict.ok and verdict.check == "trapping" and "failed" in verdict.message


# --------------------------------------------------------------------------- #
# R11: checked before the work                                                #
# --------------------------------------------------------------------------- #


def test_r11_one_suffix_rule_for_the_cli_and_save(small_atlas, tmp_path, capsys):
    # the report: the CLI accepted X.GEOJSON, computed the atlas, then save refused it
    small_atlas.save(tmp_path / "A.GEOJSON")
    assert _strict((tmp_path / "A.GEOJSON").read_text())["type"] == "FeatureCollection"
    small_atlas.save(tmp_path / "A.ZARR")
    assert sb.verify(tmp_path / "A.ZARR")
    with pytest.raises(ValueError, match="path must end in .nc, .zarr or .geojson"):
        small_atlas.save(tmp_path / "A.txt")
    code, out, err = _run_cli(["certify", "--e", "0.04:0.065", "--u", "0.92:0.945", "--depth", "2",
                               "--out", tmp_path / "B.GEOJSON"], capsys)
    assert code == 0, err
    assert (tmp_path / "B.GEOJSON").exists()


def test_r11_the_suffix_is_refused_before_the_work(tmp_path, capsys, monkeypatch):
    import importlib
    import re

    C = importlib.import_module("stairbounce.structure.certify")

    def no_work(*a, **k):
        raise AssertionError("computed before the suffix was checked")

    monkeypatch.setattr(C, "certify", no_work)
    code, _, err = _run_cli(["certify", "--depth", "2", "--out", tmp_path / "X.txt"], capsys)
    assert code == 2 and one_line_error(err) and "--out must end in" in err


def test_r11_force_never_replaces_a_symlink_to_a_folder_we_did_not_write(small_atlas, tmp_path, capsys):
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "keep.txt").write_text("important")
    link = tmp_path / "link.zarr"
    link.symlink_to(theirs, target_is_directory=True)
    code, _, err = _run_cli(["certify", "--e", "0.04:0.065", "--u", "0.92:0.945", "--depth", "2",
                             "--out", link, "--force"], capsys)
    assert code == 2 and one_line_error(err) and "did not write" in err
    assert link.is_symlink() and (theirs / "keep.txt").read_text() == "important"
    with pytest.raises(ValueError, match="did not write"):
        small_atlas.save(link, overwrite=True)
    assert link.is_symlink()
    # a symlink to one of our stores is replaced with --force (the link, not the target)
    ours = tmp_path / "ours.zarr"
    small_atlas.save(ours)
    link2 = tmp_path / "link2.zarr"
    link2.symlink_to(ours, target_is_directory=True)
    small_atlas.save(link2, overwrite=True)
    assert not link2.is_symlink() and sb.verify(link2) and sb.verify(ours)


# --------------------------------------------------------------------------- #
# F12: one vocabulary                                                         #
# --------------------------------------------------------------------------- #


def test_f12_word_prints_0_inf_as_every_command_does(capsys, monkeypatch):
    # the report: `word` printed 0^∞ where certify and cascade print 0^inf
    from stairbounce.cli import model_commands

    monkeypatch.setattr(model_commands, "terminal_can_print_infinity", lambda *a: True)
    code, out, _ = _run_cli(["word", "--e", "0.05", "--u", "0.93"], capsys)
    assert code == 0 and "word:    (2, 2, 2, 0^inf)" in out and "∞" not in out
    code, out, _ = _run_cli(["word", "--e", "0.05", "--u", "0.93", "--unicode"], capsys)
    assert code == 0 and "0^∞" in out
    monkeypatch.setattr(model_commands, "terminal_can_print_infinity", lambda *a: False)
    code, out, _ = _run_cli(["word", "--e", "0.05", "--u", "0.93", "--unicode"], capsys)
    assert code == 0 and "0^inf" in out


def test_f12_every_default_window_is_named_by_its_figure(capsys):
    # one documented rule: the window of the figure the command reproduces, in its --help
    import re
    from pathlib import Path

    for cmd, fig in [("scan", "Fig. 4"), ("words", "Fig. 4"), ("borders", "Fig. 4"), ("certify", "Fig. 7"),
                     ("dimension", "Fig. 6")]:
        code, out, _ = _run_cli([cmd, "--help"], capsys)
        assert code == 0 and fig in " ".join(out.split()), cmd
    rule = (Path(__file__).resolve().parents[1] / "docs" / "guide" / "cli.md").read_text()
    assert re.search(r"\*\*Default windows\*\*", rule) and "Fig. 7" in rule and "`word --unicode`" in rule


# --------------------------------------------------------------------------- #
# Issue 43 item 5: what a researcher needs to cite a proof                     #
# --------------------------------------------------------------------------- #


@pytest.fixture(scope="module")
def trapped_atlas():
    return sb.certify(e=(0.29, 0.31), u=(0.40, 0.42), depth=4, trap=True)


def test_certified_geojson_is_rfc7946_with_metadata_and_trapping_apart(trapped_atlas, tmp_path):
    # the newcomer (F11): 2849 of 2853 outer rings clockwise, no metadata, trapping merged
    # with Corollary 2.1, the undecided area absent without a note
    atlas = trapped_atlas
    gj = _strict(json.dumps(atlas.geojson(), allow_nan=False))
    meta = gj["metadata"]
    assert meta["generator"].startswith("stairbounce ") and meta["version"] == sb.__version__
    assert "a view, not a certificate" in meta["verify"] and meta["source"] is None
    for f in gj["features"]:
        g = shape(f["geometry"])
        assert g.is_valid
        for p in getattr(g, "geoms", [g]):
            assert p.exterior.is_ccw
            assert all(not r.is_ccw for r in p.interiors)
    kinds = {(f["properties"]["status"], f["properties"]["reason"]) for f in gj["features"]}
    st, rs = atlas.boxes["status"].values, atlas.boxes["reason"].values
    assert (("no_sliding", "trapping") in kinds) == bool(((st == 1) & (rs == "trapping")).any())
    assert ("no_sliding", "trapping") in kinds     # this window has trapping regions
    W = meta["window_area"]
    drawn = sum(f["properties"]["area"] for f in gj["features"])
    assert math.isclose(drawn + meta["undecided_area"], W, rel_tol=1e-9)
    assert math.isclose(sum(meta["undecided_by_reason"].values()), meta["undecided_area"], rel_tol=1e-12)
    assert meta["undecided_area"] > 0


def test_a_loaded_atlas_s_geojson_names_its_source_and_checksum(small_atlas, tmp_path):
    import hashlib

    small_atlas.save(tmp_path / "a.nc")
    meta = sb.CertifiedAtlas.load(tmp_path / "a.nc").geojson()["metadata"]
    assert meta["source"] == str(tmp_path / "a.nc")
    assert meta["source_sha256"] == hashlib.sha256((tmp_path / "a.nc").read_bytes()).hexdigest()
    assert f"stairbounce certify --verify {tmp_path / 'a.nc'}" in meta["verify"]


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_atlas_files_carry_cf_attributes(small_atlas, tmp_path, suffix):
    import xarray as xr

    path = tmp_path / f"a{suffix}"
    small_atlas.save(path)
    ds = xr.open_zarr(path, consolidated=False) if suffix == ".zarr" else xr.open_dataset(path)
    with ds:
        from stairbounce.structure.certificate import STATUSES

        assert list(ds["status"].attrs["flag_values"]) == list(range(len(STATUSES)))
        assert ds["status"].attrs["flag_meanings"].split() == list(STATUSES)
        assert STATUSES[:4] == ("word", "no_sliding", "no_slide_within", "undecided")
        for v in ("e0", "e1", "u0", "u1", "level", "itinerary"):
            assert ds[v].attrs["long_name"] and ds[v].attrs["units"] == "1"
    assert sb.verify(path)
    assert sb.CertifiedAtlas.load(path).fraction() == small_atlas.fraction()


def test_every_reason_is_explained_where_users_look(capsys):
    # the newcomer (F10): `range` and `impacts` were explained only in design.md
    from pathlib import Path

    from stairbounce.structure.certify import UNDECIDED_REASONS

    root = Path(__file__).resolve().parents[1]
    guide = (root / "docs" / "guide" / "proven.md").read_text()
    code, out, _ = _run_cli(["certify", "--help"], capsys)
    helptext = " ".join(out.split())
    for reason in (*UNDECIDED_REASONS, "trapping"):
        assert f"| `{reason}` |" in guide, reason
        if reason != "trapping":
            assert f"{reason} (" in helptext, reason
    assert "binary floats of the typed decimals" in helptext
    citing = (root / "docs" / "citing.md").read_text()
    for needed in ("stairbounce --version", "float.hex", "stairbounce certify --verify", "view, not a certificate"):
        assert needed in citing


def test_certify_png_names_its_window_and_share_colours_word_length_and_marks_trapping(tmp_path, capsys,
                                                                                       monkeypatch):
    # the newcomer (F9): title "certified atlas, depth 10" only, no colour bar, words by period,
    # trapping drawn in Corollary 2.1's grey
    import matplotlib.figure

    seen = {}
    real = matplotlib.figure.Figure.savefig

    def spy(fig, *a, **k):
        ax, bar = fig.axes[0], fig.axes[1]
        seen.update(title=ax.get_title(), bar=bar.get_ylabel(),
                    legend=[t.get_text() for t in ax.get_legend().get_texts()])
        return real(fig, *a, **k)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", spy)
    code, _, err = _run_cli(["certify", "--e", "0.29:0.31", "--u", "0.40:0.42", "--depth", "4", "--trap",
                             "--png", tmp_path / "t.png"], capsys)
    assert code == 0, err
    assert "e 0.29..0.31 x u 0.4..0.42" in seen["title"] and "proven" in seen["title"] and "%" in seen["title"]
    assert "word's length" in seen["bar"]
    assert any("trapping" in t for t in seen["legend"])
    assert not any(t == "no sliding (Cor. 2.1)" and "trapping" in t for t in seen["legend"])


# --------------------------------------------------------------------------- #
# F13: a long run says which pass it is counting                              #
# --------------------------------------------------------------------------- #


def test_f13_certify_names_each_pass_and_counts_it():
    # the report: "certify levels: 12/12 (100%)" for 4 minutes of trapping at depth 14 (12
    # levels counted for depth 14, the trapping pass not at all): now each pass is named as
    # it begins, the levels by their numbers, and the trapping pass counts its own boxes
    names, counts = [], []
    atlas = sb.certify(e=(0.29, 0.31), u=(0.40, 0.42), depth=5, trap=True, phase=names.append,
                       progress=lambda done, total: counts.append((len(names), done, total)))
    assert names == ["levels 3-5", "trapping regions", "re-checking trapping regions"]
    levels = [c for c in counts if c[0] == 1]
    assert levels[-1][1:] == (3, 3)            # levels 3, 4 and 5 of one tile
    tried = int(atlas.boxes.attrs["trap_tried"])
    trapping = [c for c in counts if c[0] == 2]
    assert tried < 256 or trapping and trapping[-1][2] >= tried
    with pytest.raises(ValueError, match="phase must be None or a callable"):
        sb.certify(e=(0.29, 0.31), u=(0.40, 0.42), depth=3, phase="levels")


def test_f13_the_cli_bar_names_the_pass(monkeypatch, capsys):
    import contextlib

    from stairbounce.cli import certify_commands

    seen = []

    class Bar:  # records what the command shows on its bar
        def update(self, task, description=None, **_):
            if description is not None:
                seen.append(description)

    @contextlib.contextmanager
    def recording_bar(console, description, total, unit=""):
        seen.append(description)
        yield Bar(), 0

    monkeypatch.setattr(certify_commands, "progress_bar", recording_bar)
    code, out, err = _run_cli(["certify", "--e", "0.29:0.31", "--u", "0.40:0.42", "--depth", "5", "--trap"],
                              capsys)
    assert code == 0, err
    assert seen == ["certify", "certify levels 3-5", "certify trapping regions",
                    "certify re-checking trapping regions"]


def test_f13_a_level_that_needs_gigabytes_is_announced_with_its_estimate(monkeypatch, capsys):
    import warnings

    import importlib
    import re

    C = importlib.import_module("stairbounce.structure.certify")

    with warnings.catch_warnings():
        warnings.simplefilter("error", C.CertifyMemoryWarning)
        sb.certify(e=(0.29, 0.31), u=(0.40, 0.42), depth=6)      # a few kB: nothing said
    # the threshold lowered to a few kB, as a depth-16 run meets it at its gigabyte
    monkeypatch.setattr(C, "_WARN_BYTES", 20_000)
    with pytest.warns(C.CertifyMemoryWarning, match=r"certify: level \d+ of 6 holds [\d,]+ boxes, about 0\.0 GiB"):
        sb.certify(e=(0.29, 0.31), u=(0.40, 0.42), depth=6)
    code, out, err = _run_cli(["certify", "--e", "0.29:0.31", "--u", "0.40:0.42", "--depth", "6"], capsys)
    assert code == 0
    said = [line for line in err.splitlines() if "GiB" in line]
    assert len(said) == 1 and re.match(r"stairbounce: warning: certify: level \d of 6 holds [\d,]+ boxes", said[0])


# --------------------------------------------------------------------------- #
# R8 / item 5: Ctrl-C while a file is written, and the process's end          #
# --------------------------------------------------------------------------- #

import signal  # noqa: E402
import threading  # noqa: E402

import xarray as xr  # noqa: E402


@pytest.fixture
def ctrl_c_raises():
    """Python's Ctrl-C handler, for the tests that send SIGINT to this process.
    A job started in the background by a non-interactive shell (as CI runs the
    suite) inherits SIGINT ignored, and Python then installs no handler: the
    signal would be dropped and these tests could not see what they test."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


@pytest.mark.usefixtures("ctrl_c_raises")
@pytest.mark.parametrize("suffix,method", [(".nc", "to_netcdf"), (".zarr", "to_zarr")])
def test_r8_ctrl_c_while_saving_never_lands_inside_the_writer(small_atlas, tmp_path, monkeypatch, suffix, method):
    """A KeyboardInterrupt raised inside xarray's netCDF writer left its HDF5 lock
    taken and the writer's clean-up waited for it for ever (`certify --out X.nc`
    interrupted while saving hung; found while measuring item 5).  The writer now
    runs off the main thread: the interrupt reaches the caller, not the writer, no
    file is left, and the next save works (no lock left taken)."""
    original = getattr(xr.Dataset, method)
    started, release = threading.Event(), threading.Event()
    seen = {}

    def slow_writer(self, *args, **kwargs):
        seen["main"] = threading.current_thread() is threading.main_thread()
        started.set()
        release.wait(10)
        seen["result"] = original(self, *args, **kwargs)
        return seen["result"]

    monkeypatch.setattr(xr.Dataset, method, slow_writer)

    def interrupt():
        started.wait(10)
        os.kill(os.getpid(), signal.SIGINT)
        if suffix == ".zarr":  # the folder's writer is waited for: let it finish
            release.set()

    target = tmp_path / f"a{suffix}"
    timer = threading.Thread(target=interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        small_atlas.save(target)
    timer.join()
    assert seen["main"] is False
    if suffix == ".nc":  # the caller was interrupted while the writer still waited
        assert "result" not in seen
        release.set()
    monkeypatch.setattr(xr.Dataset, method, original)
    small_atlas.save(target)   # waits for the writer left behind (two at once crashed HDF5)
    assert "result" in seen   # which had ended, and removed its temporary:
    assert [p.name for p in tmp_path.iterdir()] == [target.name]
    assert sb.CertifiedAtlas.load(target).boxes.sizes["box"] == small_atlas.boxes.sizes["box"]


def test_r8_the_console_script_ends_with_main_s_status_at_once(tmp_path):
    """The console script flushes the streams and ends with os._exit (Python's own
    shutdown of numba and xarray took 0.45 s of a Ctrl-C's 0.5): what main prints
    arrives whole, and its status is the process's."""
    import subprocess
    import sys

    code = "import sys; from stairbounce.cli import console; sys.argv = ['stairbounce'] + sys.argv[1:]; console()"
    ok = subprocess.run([sys.executable, "-c", code, "word", "--e", "0.1", "--u", "0.7"],
                        capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0 and "word" in ok.stdout.lower() and ok.stdout.endswith("\n")
    bad = subprocess.run([sys.executable, "-c", code, "word", "--e", "2", "--u", "0.7"],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "e" in bad.stderr


@pytest.mark.usefixtures("ctrl_c_raises")
def test_r8_ctrl_c_stops_a_certify_job_at_its_next_kernel(monkeypatch):
    """certify runs off the main thread (run_interruptible): the main thread raises
    at once on Ctrl-C and the job, told by its halt flag, stops at its next kernel
    instead of computing the rest of its levels in the background."""
    calls = []

    def progress(done, total):
        calls.append((done, total))
        if len(calls) == 2:  # the first level is done: Ctrl-C now
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        sb.certify(depth=12, progress=progress)
    for t in [t for t in threading.enumerate() if t.name == "stairbounce-job"]:
        t.join(60)
        assert not t.is_alive()
    total = calls[0][1]
    assert calls[-1][0] < total  # the job stopped: the last levels never ran


def test_r8_unique_inverse_is_numpy_s_unique_by_hashing():
    from stairbounce.structure.tiling import unique_inverse

    rng = np.random.default_rng(3)
    words = np.array(["(1, 2, 0^inf)", "", "(1, 1, 2, 0^inf)", "(2, 0^inf)"], dtype=object)[rng.integers(0, 4, 5000)]
    for values in (words, rng.integers(-3, 9, 5000)):
        names, inverse = unique_inverse(values)
        want_names, want_inverse = np.unique(values, return_inverse=True)
        assert list(names) == list(want_names) and np.array_equal(inverse, want_inverse.ravel())
    names, inverse = unique_inverse(np.array([], dtype=object))
    assert names.size == 0 and inverse.size == 0


def test_r8_an_nc_atlas_written_in_slices_is_the_file_to_netcdf_writes(small_atlas, tmp_path, monkeypatch):
    """The text columns are written in slices (the netCDF library converts text
    holding Python's lock); the file reads back identical to xarray's own."""
    import importlib

    C = importlib.import_module("stairbounce.structure.certify")
    monkeypatch.setattr(C, "_TEXT_SLICE", 7)   # several slices and a partial last one
    small_atlas.save(tmp_path / "sliced.nc")
    plain = C._with_cf_attributes(small_atlas.boxes)
    plain.attrs = {k: (list(v) if isinstance(v, tuple) else v) for k, v in plain.attrs.items()}
    plain.to_netcdf(tmp_path / "plain.nc", engine="netcdf4", format="NETCDF4")
    with xr.open_dataset(tmp_path / "sliced.nc") as a, xr.open_dataset(tmp_path / "plain.nc") as b:
        assert a.identical(b)
        assert a["word"].values.tolist() == small_atlas.boxes["word"].values.tolist()
    assert sb.verify(tmp_path / "sliced.nc").rejected == 0
