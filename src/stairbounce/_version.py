"""The package's version, in one place.

Read by the package (``stairbounce.__version__``), by the modules that stamp
it on what they write (``plane``, ``orbits``, ``nonsliding``, ``figures``:
they import this leaf module, never the package's ``__init__``), and by the
build (``[tool.hatch.version]`` in pyproject.toml).  Each release says what
changed in CHANGELOG.md.
"""

__version__ = "0.4.0"
