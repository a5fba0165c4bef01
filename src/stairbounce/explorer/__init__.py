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
from .preview import page_preview, with_preview

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
    "websocket_origins",
    "browse_url",
    "normalize_host",
]


_LOOPBACK = ("127.0.0.1", "localhost", "::1")
_ANY = ("0.0.0.0", "::", "")

# A query value longer than this is cut before Panel sees it: Panel parses
# digit strings with int(), which refuses more than 4300 digits (HTTP 500).
MAX_QUERY_VALUE = 1000


def _netloc(host: str, port: int) -> str:
    """``host:port`` as a browser's Origin header writes it (IPv6 in brackets)."""
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def normalize_host(host: str) -> str:
    """``"[::1]"`` -> ``"::1"``: the address to bind, without URL brackets."""
    host = host.strip()
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    return host


def _local_names() -> set[str]:
    """Names and addresses this machine answers to (for a server on all addresses)."""
    import socket

    names = {"localhost", "127.0.0.1", "::1"}
    for name in (socket.gethostname(), socket.getfqdn()):
        if name:
            names.add(name.lower())
            try:
                names |= {str(info[4][0]) for info in socket.getaddrinfo(name, None)}
            except OSError:
                pass
    try:
        import psutil

        for addrs in psutil.net_if_addrs().values():
            names |= {a.address.split("%")[0] for a in addrs if a.family in (socket.AF_INET, socket.AF_INET6)}
    except Exception:  # psutil is optional
        pass
    return names


def websocket_origins(host: str, port: int, extra=()) -> list[str]:
    """websocket_origins(host, port, extra=()) -> list of ``name:port``

    The ``Origin`` hosts whose pages may open the app's websocket: the
    address served and its loopback aliases (``localhost``, ``127.0.0.1``,
    ``[::1]``); for ``0.0.0.0`` / ``::`` every name and address of this
    machine; plus ``extra`` (``--allow-websocket-origin``: ``NAME`` or
    ``NAME:PORT``, e.g. the public name of a reverse proxy; without a port
    it matches the default ports, as browsers omit them).
    """
    host = normalize_host(host)
    if host in _LOOPBACK:
        names = set(_LOOPBACK)
    elif host in _ANY:
        names = _local_names()
    else:
        names = {host.lower()}
    out = {_netloc(n, port) for n in names}
    for item in extra:
        item = item.strip()
        if "://" in item:  # a whole URL pasted: keep its host[:port]
            from urllib.parse import urlsplit

            item = urlsplit(item).netloc
        if item.startswith("["):  # [v6] or [v6]:port
            name, _, rest = item[1:].partition("]")
            out.add(f"[{name.lower()}]:{rest.lstrip(':') or 80}")
        elif item.count(":") > 1:  # a bare IPv6 address
            out.add(f"[{item.lower()}]:80")
        elif ":" in item:
            out.add(item.lower())
        else:  # browsers omit default ports; Bokeh compares such an Origin as NAME:80
            out.add(f"{item.lower()}:80")
    return sorted(out)


def browse_url(host: str, port: int) -> str:
    """The URL to open for a server on ``host``: the machine's name for all
    addresses, brackets for IPv6."""
    import socket

    host = normalize_host(host)
    if host in _ANY:
        host = socket.gethostname() or "127.0.0.1"
    return f"http://{_netloc(host, port)}/"


def _label_ipv6_host(request) -> None:
    """Let Panel read an IPv6 ``Host`` header: Panel splits it at ':' for its
    Location (hostname, port), which fails on "[::1]:5006"; the page's
    websocket URL is taken from the browser's address, so this name is only
    a label."""
    host = request.host
    if host.startswith("["):
        request.host = "localhost:" + host.rpartition("]:")[2] if "]:" in host else "localhost"


def _guard_long_queries(tornado_app) -> None:
    """Redirect a page request with an over-long query value to the same
    query with that value cut (the page then reports it as a bad value); let
    Panel read an IPv6 ``Host`` header, in the page request and in the
    websocket request (where the page's session is built)."""
    from urllib.parse import urlencode

    from panel.io.server import DocHandler, WSHandler

    class _CutQueryDocHandler(DocHandler):
        _preview = ""

        async def get(self, *args, **kwargs):
            args_ = self.request.query_arguments
            if any(len(v) > MAX_QUERY_VALUE for vs in args_.values() for v in vs):
                cut = [(k, v if len(v) <= MAX_QUERY_VALUE else v[:20] + f"...({len(v)} characters)".encode())
                       for k, vs in args_.items() for v in vs]
                self.redirect(self.request.path + "?" + urlencode(cut, safe=":,"))
                return
            _label_ipv6_host(self.request)
            self._preview = await _page_preview(args_)
            return await super().get(*args, **kwargs)

        def write(self, chunk):
            if self._preview and isinstance(chunk, (str, bytes)):
                text = chunk.decode("utf-8") if isinstance(chunk, bytes) else chunk
                chunk, self._preview = with_preview(text, self._preview), ""
            return super().write(chunk)

    class _IPv6WSHandler(WSHandler):
        def open(self, *args, **kwargs):
            _label_ipv6_host(self.request)
            return super().open(*args, **kwargs)

    for rule in tornado_app.wildcard_router.rules:
        if rule.target is DocHandler:
            rule.target = _CutQueryDocHandler
        elif rule.target is WSHandler:
            rule.target = _IPv6WSHandler


async def _page_preview(query_arguments) -> str:
    """The view's picture for the page's HTML (:mod:`.preview`), computed on
    the app's scheduler once its kernels are loaded; ``""`` when there is
    none (a bad query, a large view, a busy server) or it failed."""
    from .app import _WARM, SCHEDULER

    try:
        return await page_preview(query_arguments, SCHEDULER, ready=_WARM)
    except Exception:  # the page works without its preview
        return ""


def _host_key(host: str) -> str:
    """A ``Host`` header as the allowed names are written: ``name:port``,
    lower case, port 80 when the header has none (as Bokeh reads an Origin)."""
    host = host.strip().lower()
    if host.startswith("["):
        name, sep, rest = host[1:].partition("]")
        if not sep or (rest and not rest.startswith(":")):
            return ""  # malformed: matches no allowed name
        return f"[{name}]:{rest[1:] or 80}"
    if host.count(":") > 1:
        return ""  # an IPv6 address without brackets: not a valid Host
    name, _, port = host.partition(":")
    return f"{name}:{port or 80}"


def _guard_host(tornado_app) -> None:
    """Refuse (403) every request, page, websocket, static file or other route,
    whose ``Host`` header is not one of the names the websocket's origins
    allow (report N4: a page whose name is rebound to this machine sends its
    own name as Host and as Origin, and Tornado then accepts the websocket
    without asking the origin check).  The allowed set is read on every
    request, so a change of it applies at once."""
    from tornado.routing import Matcher, Rule
    from tornado.web import HTTPError, RequestHandler

    class _ForeignHost(Matcher):
        def match(self, request):
            return None if _host_key(request.host or "") in tornado_app.websocket_origins else {}

    class _Refuse(RequestHandler):
        def prepare(self):
            raise HTTPError(403, reason="Host not allowed")

    tornado_app.default_router.rules.insert(0, Rule(_ForeignHost(), _Refuse))


def _page_key(request) -> str:
    """The kept session serving a page request: one per path."""
    return request.path


def _prepare_page(server, host: str) -> None:
    """Request the page once, so that the session every later page request
    is rendered from is built now, not for the first visitor (whose own
    session it would then also be)."""
    import urllib.request

    host = normalize_host(host)
    local = ("::1" if host == "::" else "127.0.0.1") if host in _ANY else host
    direct = urllib.request.build_opener(urllib.request.ProxyHandler({}))  # never through a proxy
    with direct.open(browse_url(local, server.port), timeout=60) as answer:
        answer.read()


def _page_with_local_resources():
    """The app's page (:func:`~stairbounce.explorer.app.create_app`) in the
    session's document, its stylesheets served by this server.

    Panel's components import their stylesheets from its CDN
    (``cdn.holoviz.org``); Panel rewrites them to its own static route only
    in the document it renders a page's HTML from, not in the session each
    page's websocket then builds (``reuse_sessions``).  Rewritten here, in
    every session, with Panel's own rewriting, so that a page loads nothing
    from outside the server (offline, behind a firewall).
    """
    import panel as pn
    from panel.io.resources import LOCAL_DIST, patch_model_css

    from .app import create_app

    doc = pn.state.curdoc
    if doc is None:  # outside a server: nothing to rewrite
        return create_app()
    # the designs (themes) patch the stylesheets they apply, now and later,
    # to the document's dist_url, else to the CDN
    doc._template_variables["dist_url"] = LOCAL_DIST
    layout = create_app()
    layout.server_doc(doc, title=TITLE)
    for root in doc.roots:
        patch_model_css(root, dist_url=LOCAL_DIST)
    return None


TITLE = "stairbounce explorer"


def make_server(port=5006, host="127.0.0.1", show=False, allow_websocket_origin=()):
    """make_server(port=5006, host="127.0.0.1", show=False, allow_websocket_origin=()) -> bokeh Server

    A Panel server for the app at ``http://host:port/`` (bound, not started:
    a port in use raises :class:`OSError` here; ``port=0`` picks a free port,
    read it back from ``server.port``).  ``host`` may be a name, an IPv4 or
    IPv6 address (with or without brackets), ``0.0.0.0`` or ``::`` for all
    addresses; the page's websocket is accepted from
    :func:`websocket_origins`.
    """
    import panel as pn

    # A page request answers with the page's HTML only (the same for every
    # view: the picture and widgets come over the websocket), rendered from
    # one kept session instead of building a new session's document (0.3 s of
    # the event loop, which every open page waits for); the page's own
    # session is built when its websocket connects, from the query in its
    # token.  One kept session per path, whatever the query.
    pn.config.reuse_sessions = True
    pn.config.session_key_func = _page_key
    address = normalize_host(host)
    server = pn.serve(
        _page_with_local_resources,
        port=port,
        address=address or None,
        websocket_origin=["localhost:1"],  # replaced below, once the port is known
        show=show,
        start=False,
        title=TITLE,
        verbose=False,
        # a closed page's session is freed after 15 s; look every 5 s
        check_unused_sessions_milliseconds=5000,
    )
    origins = server._tornado.websocket_origins  # Bokeh's own set, read on every connection
    origins.clear()
    origins.update(websocket_origins(address, server.port, allow_websocket_origin))
    _guard_long_queries(server._tornado)
    _guard_host(server._tornado)
    return server


def serve(port=5006, host="127.0.0.1", show=True, on_ready=None, allow_websocket_origin=(), say=None):
    """serve(port=5006, host="127.0.0.1", show=True, on_ready=None, allow_websocket_origin=(), say=None) -> None

    Start the app's server and block until interrupted: bind the port first
    (a port in use fails at once), call ``on_ready(url)``, then load the
    compiled kernels on the scheduler's thread (``say(text)`` reports it;
    pages opened meanwhile say they are queued) and serve.  ``show`` opens
    the page in a web browser.
    """
    import time

    from .app import warm_up

    server = make_server(port, host, show=False, allow_websocket_origin=allow_websocket_origin)
    url = browse_url(host, server.port)
    if on_ready is not None:
        on_ready(url)
    t0 = time.perf_counter()
    if say is not None:
        say("loading the compiled kernels (the first start after an install compiles them, up to a minute) ...")
    warm = warm_up()

    def report():
        if say is not None:
            say(f"kernels ready in {time.perf_counter() - t0:.1f} s")

    def wait_warm():
        try:
            _prepare_page(server, host)
        except OSError:  # the first visitor builds it instead
            pass
        warm.wait()
        server.io_loop.add_callback(report)

    import threading

    threading.Thread(target=wait_warm, daemon=True).start()
    server.start()
    if show:
        server.io_loop.add_callback(server.show, "/")
    try:
        server.io_loop.start()
    finally:
        server.stop()
