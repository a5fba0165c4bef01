"""Settings every test shares."""

import os

# Off a terminal, long commands write a progress line every 10 s to stderr
# (stairbounce._progress).  On a loaded machine a test's command can run that
# long, and the tests that read stderr line by line (one-line errors, empty
# stderr) would see those lines at random; the tests of the lines themselves
# set a short interval (tests/test_conventions.py).  Subprocesses inherit it.
os.environ.setdefault("STAIRBOUNCE_PROGRESS_INTERVAL", "1e9")
