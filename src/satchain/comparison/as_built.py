"""The as-built prediction beside the design's (issue 29): a run whose camera was simulated as built
(``[as_built]``) is checked against the design, and every row and target also carries what the camera as built
predicts, so the page can show that the changed parameter explains the failures.

:func:`with_as_built` takes the run's comparison (measured vs the design's prediction) and the comparison of the
same measurements with the as-built camera's prediction, and returns the first with the second's predictions
attached: each :class:`~satchain.comparison.records.CheckRow` gets ``as_built = {"predicted", "error", "sigma",
"z", "pass"}`` (results.json: ``predicted_as_built``, ``error_as_built``, ``sigma_as_built``, ``z_as_built``,
``pass_as_built``); each per-target record gets ``as_built``: its predicted entries (every key that holds
``predicted``, the errors and the pass; for the star, per direction) for the camera as built. The verdict stays
the design's.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from satchain.comparison.records import CheckRow, Comparison

__all__ = ["with_as_built"]


def _row_part(r: CheckRow) -> dict[str, Any]:
    return {"predicted": r.predicted, "error": r.error, "sigma": r.sigma, "z": r.z, "pass": r.passed}


def _predicted_part(d: dict[str, Any]) -> dict[str, Any]:
    """The entries of a record's dict that the prediction decides: keys naming a prediction or an error, the pass,
    and, in nested tables (the star's directions), the same."""
    out: dict[str, Any] = {}
    for k, v in d.items():
        if isinstance(v, dict) and k == "directions":
            out[k] = {name: _predicted_part(sub) for name, sub in v.items() if isinstance(sub, dict)}
        elif "predicted" in k or "error" in k or k in ("pass", "worst_direction", "worst_f_cy_per_px", "worst_group"):
            out[k] = v
    return out


def with_as_built(design: Comparison, built: Comparison) -> Comparison:
    """``design`` with ``built``'s predictions attached (rows matched by kind and id, records by id).

    Parameters
    ----------
    design : Comparison
        The measurements against the design's prediction (the run's checks and verdict).
    built : Comparison
        The same measurements against the prediction for the camera as built.

    Returns
    -------
    Comparison
        ``design``, its rows and records carrying ``as_built``.
    """
    by_key = {(r.kind, r.id, r.figure): r for r in built.rows}
    rows = []
    for r in design.rows:
        b = by_key.get((r.kind, r.id, r.figure))
        rows.append(r if b is None else replace(r, as_built=_row_part(b)))
    details = {}
    for key, recs in design.details.items():
        other = {getattr(x, "id", None): x for x in built.details.get(key, ())}
        details[key] = tuple(
            x if getattr(x, "id", None) not in other else replace(x, as_built=_predicted_part(other[x.id].to_dict()))
            for x in recs
        )
    niirs = replace(design.niirs, as_built=_predicted_part(built.niirs.to_dict()))
    return replace(design, rows=tuple(rows), details=details, niirs=niirs)
