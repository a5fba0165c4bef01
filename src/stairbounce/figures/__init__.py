"""The paper's Figures 1-9 as named recipes, and the report that sets each
beside what the paper states.

Every recipe uses only the public API (``trajectory``, ``scan``, ``fractal``,
``orbits`` and the ``plot`` renderers) and returns a :class:`Result`: the files
it wrote, a caption (what is drawn, the colours, which parameters are the
paper's and which are ours), rows of "paper says / we measured" each with a
verdict (:class:`Row`: agrees, differs by how much, or not comparable and
why, and a basis: proven, saying by what, or numerical), its parameters and
how long it took.  :func:`make_figures` runs a
selection, keeps going when one fails, and caches the expensive datasets on
disk keyed by their inputs; :func:`write_report` writes ``report.md``,
``report.html`` and ``manifest.json``, keeping the figures of an earlier run
in the same folder that this run did not make (merged by figure).

Recipes added by other parts of the project return the same :class:`Result`
and fill :attr:`Row.verdict` and :attr:`Row.why`.

One module per figure family, each importing only the ones above it:

- :mod:`.settings`: the run's :class:`Settings`, the windows shared by several
  recipes, and a recipe's tools (the cached scan, saving a figure);
- :mod:`.rows`: :class:`Row`, :class:`Result` and the report's criteria;
- :mod:`.proven`: the certified rows (Figs. 5e, 6, 7);
- :mod:`.plane`: the plane and its zooms (Figs. 3, 4, 5a-e);
- :mod:`.dimension`: borders and dimension (Figs. 6, 7);
- :mod:`.orbits`: orbits and cascades (Figs. 1, 2, 8, 9);
- :mod:`.motion`: the non-sliding motion (motion_k, motion_lyap, motion_cut);
- :mod:`.recipes`: :data:`FIGURES` and :func:`make_figures`;
- :mod:`.report`: :func:`write_report` and the manifest.
"""

from .dimension import STUDY_FILE, load_border_dimension
from .recipes import FIGURES, make_figures, select
from .report import (basis_tally, merge_results, read_manifest, rows_with_verdict, verdict_tally,
                     write_report)
from .rows import BASES, BASIS_CRITERION, CRITERION, VERDICTS, Result, Row
from .settings import BLOWUPS, DIMENSION_WINDOWS, Settings, check_outputs, default_cache_dir, output_files

__all__ = ["FIGURES", "Settings", "Row", "Result", "VERDICTS", "make_figures", "write_report",
           "read_manifest", "load_border_dimension", "BLOWUPS",
           # used by the CLI and the tests
           "BASES", "CRITERION", "BASIS_CRITERION", "DIMENSION_WINDOWS", "STUDY_FILE", "select",
           "check_outputs", "output_files", "default_cache_dir", "merge_results", "verdict_tally",
           "basis_tally", "rows_with_verdict"]
