"""What the campaign scripts share with the tests: a raw HTTP request's status
line and stopping a child process (``tests/test_faults_round2.py`` imports them
through ``tests/_benchmarks.import_script``)."""

from __future__ import annotations

import signal
import subprocess


def raw_http(port, request, timeout=60):
    """The status line the server on ``127.0.0.1:port`` answers ``request`` (the
    request's text as it is sent, headers of any kind included) with."""
    import socket

    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(request.encode("latin-1"))
        data = b""
        while b"\r\n\r\n" not in data:
            chunk = s.recv(65536)
            if not chunk:
                break
            data += chunk
    return data.split(b"\r\n", 1)[0].decode("latin-1")


def stop(p, timeout=15):
    """The process ``p`` (None: nothing) stopped: SIGTERM, and SIGKILL after
    ``timeout`` seconds."""
    if p is not None and p.poll() is None:
        p.send_signal(signal.SIGTERM)
        try:
            p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
