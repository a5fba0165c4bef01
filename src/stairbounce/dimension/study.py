"""The dimension study's shipped result (``data/border_dimension.json``)."""

from __future__ import annotations

__all__ = ["border_dimension_estimates"]


def border_dimension_estimates(path=None):
    """border_dimension_estimates(path=None) -> dict

    The measured dimension of the border of the sliding region in the
    paper's Fig. 6 and Fig. 7 windows, as written by
    ``benchmarks/dimension_study.py --json`` into the package's
    ``data/border_dimension.json`` (or into ``path``): per window
    (``"fig6"``, ``"fig7"``) the best estimate (``dimension``, ``ci95``,
    ``method``, ``details``), the paper's value, the uncertainty-exponent
    results per ``max_iter`` and the tiled box count; plus ``generated_by``
    and ``date``.
    """
    import json
    from pathlib import Path

    if path is not None:
        return json.loads(Path(path).read_text())
    from importlib.resources import files

    return json.loads(files("stairbounce").joinpath("data", "border_dimension.json").read_text())
