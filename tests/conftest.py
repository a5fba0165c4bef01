"""Settings every test shares."""

import os
import time

_STARTED = time.monotonic()  # this file is read as pytest starts, before any hook below

# Off a terminal, long commands write a progress line every 10 s to stderr
# (stairbounce._progress).  On a loaded machine a test's command can run that
# long, and the tests that read stderr line by line (one-line errors, empty
# stderr) would see those lines at random; the tests of the lines themselves
# set a short interval (tests/test_conventions.py).  Subprocesses inherit it.
os.environ.setdefault("STAIRBOUNCE_PROGRESS_INTERVAL", "1e9")

# The suite in two processes (README: pytest -n 2 --dist loadfile) ends when its
# slower process ends.  pytest-xdist hands out whole files, by default the files
# with the most tests first; a few files with few but long tests (the site build,
# Chromium, the wheel) then start late and run alone at the end.  The files are
# handed out longest first instead (longest-processing-time scheduling), by the
# seconds each took in a fresh clone's suite on the 2-core machine (2026-11-29,
# summed --durations); any file not named here comes after them, in its order.
# Only the order changes: every test still runs, each file in one process.
_SECONDS = {
    "test_docs.py": 265, "test_explorer_browser.py": 153, "test_wheel.py": 45, "test_certify_store.py": 63,
    "test_figures.py": 58, "test_atlas.py": 50, "test_regions.py": 41, "test_faults.py": 38,
    "test_architecture.py": 34, "test_cli_fractal.py": 33, "test_faults_round2.py": 26,
    "test_dimension_protocol.py": 22, "test_explorer.py": 22, "test_docs_commands.py": 22,
    "test_kernel_paths.py": 20, "test_faults_round3.py": 17, "test_api.py": 17,
}


def pytest_configure(config):
    if getattr(config.option, "loadscopereorder", None) is not None:
        config.option.loadscopereorder = False  # keep the order made below
    if _is_xdist_controller(config):
        _warm_kernels()


def _is_xdist_controller(config):
    n = getattr(config.option, "numprocesses", None)
    return bool(n) and not hasattr(config, "workerinput") and not config.option.collectonly


def _warm_kernels():
    """The numba kernels compiled into their on-disk cache once, in two processes at
    once, before pytest-xdist starts its processes (tests/_warm_kernels.py says why);
    about 60 s in a fresh clone, 3 s once cached.  A part that fails is reported here
    and the suite goes on: its kernels are then compiled where a test meets them."""
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).with_name("_warm_kernels.py")
    t0 = time.perf_counter()
    procs = {part: subprocess.Popen([sys.executable, str(script), part], stdout=subprocess.PIPE,
                                    stderr=subprocess.STDOUT, text=True)
             for part in ("proofs", "scans")}
    lines = []
    for part, proc in procs.items():
        out, _ = proc.communicate()
        lines.append(out.strip().splitlines()[-1] if proc.returncode == 0 and out.strip()
                     else f"{part}: failed ({proc.returncode}): {out.strip()[-500:]}")
    print(f"numba kernels compiled or loaded in {time.perf_counter() - t0:.0f} s ({'; '.join(lines)})",
          file=sys.stderr)


def pytest_collection_modifyitems(config, items):
    items.sort(key=lambda item: -_SECONDS.get(item.path.name, 0))  # stable: a file's own order is kept


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    # pytest's own "in N s" starts at the session, after the kernels' warm-up above: the
    # whole run's wall time is printed too (what the README and CI state)
    if not hasattr(config, "workerinput"):
        terminalreporter.write_line(f"wall time of this pytest run, the kernels' warm-up included: "
                                    f"{time.monotonic() - _STARTED:.0f} s")
