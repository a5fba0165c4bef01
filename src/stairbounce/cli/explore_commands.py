"""``stairbounce explore``: serve the browser app (the ``web`` extra)."""

from __future__ import annotations

import typer

from ._app import CLIError, app


@app.command(short_help="Serve the zoomable (e, u) plane in a browser.")
def explore(
    port: int = typer.Option(5006, "--port", help="TCP port to serve on (0: any free port)."),
    host: str = typer.Option(
        "127.0.0.1", "--host",
        help="Address to listen on; the default serves this machine only. 0.0.0.0 (or ::) "
             "serves every address of this machine; IPv6 addresses with or without brackets.",
    ),
    allow_websocket_origin: list[str] = typer.Option(
        [], "--allow-websocket-origin",
        help="Also accept pages served under this HOST[:PORT] (repeatable), e.g. the public "
             "name of a reverse proxy in front of the app.",
    ),
    no_browser: bool = typer.Option(False, "--no-browser", help="Do not open a web browser."),
):
    """Serve an interactive, zoomable map of the (e, u) plane; tap a point to see its orbit."""
    if not 0 <= port <= 65535:
        raise CLIError(f"--port must be in [0, 65535], got {port}")
    if not host.strip():
        raise CLIError("--host must not be empty")
    for origin in allow_websocket_origin:
        if not origin.strip() or any(c.isspace() or c in "/?#," for c in origin.split("://")[-1].rstrip("/")):
            raise CLIError(f"--allow-websocket-origin must be HOST or HOST:PORT, got {origin!r}")
    try:
        import bokeh  # noqa: F401
        import panel  # noqa: F401
    except ImportError:
        raise CLIError(
            "the browser app needs Panel and Bokeh: pip install 'stairbounce[web]'"
        ) from None
    from .. import explorer

    _warn_if_public(host, port)

    def ready(url):
        typer.echo(f"stairbounce explorer at {url} (Ctrl-C to stop)", err=False)

    def say(text):
        typer.echo(text)

    try:
        explorer.serve(port=port, host=host, show=not no_browser, on_ready=ready,
              allow_websocket_origin=allow_websocket_origin, say=say)
    except OSError as exc:  # port in use, address not available
        raise CLIError(f"cannot serve on {host}:{port}: {exc.strerror or exc}") from None
    typer.echo("stairbounce explorer stopped")


def _warn_if_public(host: str, port: int) -> None:
    """Say on the terminal that a server on a non-loopback address is open to
    the network without a login (report round 2, finding 10)."""
    import sys

    from ..explorer import _LOOPBACK, normalize_host

    if normalize_host(host).lower() in _LOOPBACK:
        return
    print(f"stairbounce: warning: --host {host} serves the explorer to the network: it has no login, so "
          f"anyone who can reach this machine on port {port or 'chosen'} can use it (its computing time, "
          "views and exports); serve on 127.0.0.1 (the default) unless that is meant", file=sys.stderr)
