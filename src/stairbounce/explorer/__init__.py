"""``stairbounce explore``: a browser app to zoom into the fractal and watch any orbit.

The only part of the package that imports the web stack (Panel with Bokeh,
the ``web`` extra).  :mod:`.view` holds everything the page computes or
validates as plain functions (tested without a browser); :mod:`.app` is the
Panel page; :func:`serve` starts a Panel server for it; :func:`inline` returns
the page as a Panel object for a Jupyter notebook.
"""

from __future__ import annotations

from .view import (
    DEFAULT_VIEW,
    PIXEL_BUDGET,
    WORK_BUDGET,
    View,
    check_view,
    compute_view,
    parse_query,
    view_query,
)
from ._inline import inline

__all__ = [
    "DEFAULT_VIEW",
    "PIXEL_BUDGET",
    "WORK_BUDGET",
    "View",
    "inline",
    "check_view",
    "compute_view",
    "parse_query",
    "view_query",
    "make_server",
    "serve",
]


def make_server(port=5006, host="127.0.0.1", show=False):
    """make_server(port=5006, host="127.0.0.1", show=False) -> bokeh Server

    A Panel server for the app at ``http://host:port/`` (not started;
    ``port=0`` picks a free port, read it back from ``server.port``).
    """
    import panel as pn

    from .app import create_app, warm_up

    warm_up()

    # the page's websocket is accepted only from pages served by this server
    hosts = {host}
    if host in ("127.0.0.1", "localhost"):
        hosts |= {"127.0.0.1", "localhost"}
    origins = sorted(f"{h}:{port or '*'}" for h in hosts)
    return pn.serve(
        create_app,
        port=port,
        address=host,
        websocket_origin=origins,
        show=show,
        start=False,
        title="stairbounce explorer",
        verbose=False,
    )


def serve(port=5006, host="127.0.0.1", show=True, on_ready=None):
    """serve(port=5006, host="127.0.0.1", show=True) -> None

    Start the app's server and block until interrupted; ``show`` opens the
    page in a web browser, ``on_ready(url)`` is called once it listens.
    """
    server = make_server(port, host, show=False)
    server.start()
    url = f"http://{'[' + host + ']' if ':' in host else host}:{server.port}/"
    if on_ready is not None:
        on_ready(url)
    if show:
        server.io_loop.add_callback(server.show, "/")
    try:
        server.io_loop.start()
    finally:
        server.stop()
