"""Box counting of the border in a tiled store (stairbounce.atlas_boxes): equal,
count for count, to fractal.box_counts of the same border in memory."""

from __future__ import annotations

import distributed
import numpy as np
import pytest

from stairbounce import atlas_boxes
from stairbounce.atlas import scan_to_zarr
from stairbounce.atlas_boxes import store_box_counts, store_box_dimension
from stairbounce.dimension import box_counts, box_dimension, boundary, label_boundary
from stairbounce.plane import load

from ._stores import StopAfter, stop_after

pytestmark = pytest.mark.filterwarnings("ignore:Port 8787 is already in use")

# the Fig. 7 window, coarse: the sliding region's border crosses every tile;
# 150 x 130 px, so tiles of 32 and 50 do not divide the image
WINDOW = dict(e=(0.155, 0.2138, 150), u=(0.6, 0.658, 130), max_iter=300)
ODD_SIZES = [1, 2, 3, 5, 6, 10, 25, 32, 50, 64, 100, 128, 200]


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    folder = tmp_path_factory.mktemp("stores")
    return {tile: scan_to_zarr(folder / f"t{tile}.zarr", tile=tile, **WINDOW) and folder / f"t{tile}.zarr"
            for tile in (32, 50, 64)}


@pytest.fixture(scope="module")
def image(stores):
    ds = load(stores[64])
    status = ds["status"].transpose("u", "e").values
    words = ds["word_length"].transpose("u", "e").values
    return status, words


def border_in_memory(image, which, connectivity):
    status, words = image
    region = status == 0
    if which == "sliding":
        return boundary(region, connectivity=connectivity)
    return label_boundary(np.where(region, words, -1).astype(np.int64), connectivity=connectivity)


@pytest.mark.parametrize("tile", [32, 50, 64])
@pytest.mark.parametrize("which", ["sliding", "words"])
@pytest.mark.parametrize("connectivity", [4, 8])
def test_counts_equal_box_counts_of_the_whole_border(stores, image, tile, which, connectivity):
    border = border_in_memory(image, which, connectivity)
    assert 0.01 < border.mean() < 0.5  # a real border, crossing tile edges
    for sizes in (None, ODD_SIZES):
        s, c = store_box_counts(stores[tile], which=which, connectivity=connectivity, sizes=sizes, threads=2)
        s0, c0 = box_counts(border, sizes=sizes)
        np.testing.assert_array_equal(s, s0)
        np.testing.assert_array_equal(c, c0)


def test_one_thread_and_progress(stores, image):
    seen = []
    s, c = store_box_counts(stores[50], threads=1, progress=lambda d, t: seen.append((d, t)))
    assert seen[0] == (0, 9) and seen[-1] == (9, 9) and len(seen) == 10
    np.testing.assert_array_equal(c, box_counts(border_in_memory(image, "sliding", 4))[1])


def test_dask_cluster_gives_the_same_counts(stores, image):
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        s, c = store_box_counts(stores[32], which="words", sizes=ODD_SIZES, client=client)
        s2, c2 = store_box_counts(stores[32], client=cluster.scheduler_address)
    np.testing.assert_array_equal(c, box_counts(border_in_memory(image, "words", 4), sizes=ODD_SIZES)[1])
    np.testing.assert_array_equal(c2, box_counts(border_in_memory(image, "sliding", 4))[1])


def test_unreachable_scheduler_is_refused_at_once(stores):
    """Counting connects as the tiled scan does (atlas._connect): a closed port
    is a ValueError naming the address and the reason."""
    with pytest.raises(ValueError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9: connection refused"):
        store_box_counts(stores[32], client="tcp://127.0.0.1:9")


def test_dimension_is_box_dimension_of_the_border(stores, image):
    border = border_in_memory(image, "sliding", 4)
    a = store_box_dimension(stores[50], fit_range=(2, 32))
    b = box_dimension(border, fit_range=(2, 32))
    assert a.dimension == b.dimension and a.ci == b.ci and a.fit_range == b.fit_range


def test_incomplete_store_is_refused(tmp_path):
    path = tmp_path / "part.zarr"
    with pytest.raises(StopAfter):
        scan_to_zarr(path, tile=32, progress=stop_after(2), numba_threads=2, **WINDOW)
    with pytest.raises(ValueError, match=r"is not complete: \d+ of 25 tiles are missing"):
        store_box_counts(path)


def test_bad_input(stores, tmp_path, monkeypatch):
    with pytest.raises(ValueError, match="no such store"):
        store_box_counts(tmp_path / "none.zarr")
    (tmp_path / "other.zarr").mkdir()
    with pytest.raises(ValueError, match="not a tiled scan store"):
        store_box_counts(tmp_path / "other.zarr")
    with pytest.raises(ValueError, match="which must be one of"):
        store_box_counts(stores[32], which="all")
    with pytest.raises(ValueError, match="connectivity must be 4 or 8"):
        store_box_counts(stores[32], connectivity=6)
    with pytest.raises(ValueError, match=r"sizes must be an integer in \[1, "):
        store_box_counts(stores[32], sizes=[0, 2])
    with pytest.raises(ValueError, match="threads must be an integer >= 1"):
        store_box_counts(stores[32], threads=0)
    # a side sharing no large factor with the tile would need the whole border
    monkeypatch.setattr(atlas_boxes, "_MAX_REDUCED_PIXELS", 1000)
    with pytest.raises(ValueError, match="share only a factor 1 with the tile size 32"):
        store_box_counts(stores[32], sizes=[3])
