"""The check registry (one entry per target kind) and :func:`compare`, which runs it."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

from satchain.comparison.bars import bar_checks
from satchain.comparison.edge import edge_checks
from satchain.comparison.niirs import niirs_check
from satchain.comparison.records import CheckRow, Comparison, result_key
from satchain.comparison.star import star_checks
from satchain.comparison.wedge import wedge_checks
from satchain.prediction.core import Predictions
from satchain.scene.targets import BarTarget, HyperbolicWedge, SiemensStar, SlantedEdge

__all__ = ["CHECKS", "TargetChecks", "compare"]


@dataclass(frozen=True)
class TargetChecks:
    """How one target kind is checked.

    ``key``: its entry in the measurement's dict, in results.json and in :attr:`Comparison.details`;
    ``build(entries, predicted, tolerances) -> (records, rows)``: its per-target records and check rows;
    ``skipped``: the row a target of this kind would have had, for an n/a row when it was not measured
    (figure label with ``{}`` for the id, row kind, tolerance attribute, tolerance text with ``{}``).
    """

    key: str
    build: Callable[[list[dict], Predictions, Any], tuple[list, list[CheckRow]]]
    skipped: tuple[str, str, str, str]


#: Truth kind -> its checks, in the order the rows are listed. A new target kind is one entry here.
CHECKS: dict[str, TargetChecks] = {
    SlantedEdge.kind: TargetChecks(
        result_key(SlantedEdge.kind),
        edge_checks,
        ("edge {} MTF@Nyquist", "edge_mtf_at_nyquist", "edge_mtf_at_nyquist", "±{}"),
    ),
    SiemensStar.kind: TargetChecks(
        result_key(SiemensStar.kind),
        star_checks,
        ("star {} MTF, largest error to Nyquist", "star_mtf", "star_mtf", "≤{}"),
    ),
    BarTarget.kind: TargetChecks(
        result_key(BarTarget.kind), bar_checks, ("bars {} max |CTF error| (Coltman)", "bar_ctf", "bar_ctf", "≤{}")
    ),
    HyperbolicWedge.kind: TargetChecks(
        result_key(HyperbolicWedge.kind),
        wedge_checks,
        ("wedge {} resolution (m)", "wedge_resolution", "wedge_resolution_rel", "±{:.0%}"),
    ),
}


def _skipped_rows(measured: dict, tol: Any) -> list[CheckRow]:
    """An n/a row for every target the measurement had to skip (real-world objects have no check)."""
    rows = []
    for sk in measured.get("skipped", []):
        if sk.get("kind") not in CHECKS:
            continue
        label, kind, attr, text = CHECKS[sk["kind"]].skipped
        t = getattr(tol, attr)
        reason = f"not measured: {sk.get('reason', 'no reason given')}"
        rows.append(
            CheckRow(label.format(sk["id"]), kind, sk["id"], None, None, None, t, text.format(t), None, reason, None,
                     "no error (the target was not measured)")
        )  # fmt: skip
    return rows


def _with_sigma_reason(row: CheckRow) -> CheckRow:
    """Every row carries a sigma or says why not: a row left without either gets a generic reason."""
    if row.sigma is not None or row.sigma_null_means:
        return row
    why = "no error (the check is n/a)" if row.error is None else f"no uncertainty model for {row.kind} checks yet"
    return replace(row, sigma_null_means=why)


def _measured_dict(measured: Any) -> dict[str, Any]:
    if isinstance(measured, Mapping):
        return dict(measured)
    if hasattr(measured, "auto"):  # satchain.api.Measurements
        out = _with_edge_cnr(measured.auto)
        if getattr(measured, "snr", None) is not None:
            out["snr"] = measured.snr.to_dict()
        return out
    return _with_edge_cnr(measured)


def _with_edge_cnr(auto: Any) -> dict[str, Any]:
    """``auto.to_dict()`` with each edge's contrast-to-noise ratio (from its EdgeResult) for the angle's sigma."""
    out = dict(auto.to_dict())
    cnr = {}
    for it in getattr(auto, "items", ()):
        r = getattr(it, "result", None)
        c, n = getattr(r, "contrast", None), getattr(r, "noise_sigma", None)
        if it.kind == SlantedEdge.kind and c is not None and n:
            cnr[it.id] = abs(float(c)) / float(n)
    edges = result_key(SlantedEdge.kind)
    out[edges] = [dict(e, cnr=e.get("cnr", cnr.get(e.get("id")))) for e in out.get(edges, [])]
    return out


def compare(measured: Any, predicted: Predictions, tolerances: Any) -> Comparison:
    """Put measurements beside predictions and check each against its tolerance (pure; no I/O).

    Parameters
    ----------
    measured : AutoResult, Measurements or dict
        ``measure_auto(...)`` or its ``to_dict()`` (``slanted_edges``, ``siemens_star``, ``bar_targets``,
        ``hyperbolic_wedge``, ``skipped``: each skipped target gets an n/a row); an optional ``"snr"``
        entry (``measure_snr(...).to_dict()``) feeds the NIIRS check.
    predicted : Predictions
        From :func:`satchain.prediction.core.predict` (or :func:`~satchain.prediction.core.predict_from_mtf`).
    tolerances : Tolerances
        Any object with ``edge_mtf_at_nyquist``, ``edge_angle_deg``, ``star_mtf``, ``bar_ctf``,
        ``wedge_resolution_rel`` and ``niirs`` (see :class:`satchain.config.run.Tolerances`).

    Returns
    -------
    Comparison
        ``rows`` (one :class:`CheckRow` per check), ``passed`` (False if any failed, None if none could be
        evaluated) and the per-target detail.
    """
    m = _measured_dict(measured)
    details, rows = {}, []
    for checks in CHECKS.values():
        recs, r = checks.build(list(m.get(checks.key, [])), predicted, tolerances)
        details[checks.key] = tuple(recs)
        rows += r
    snr = dict(m.get("snr") or {})
    rows += _skipped_rows(m, tolerances)
    niirs, row = niirs_check(details[result_key(SlantedEdge.kind)], snr, predicted, tolerances)
    rows.append(row)
    rows = [_with_sigma_reason(r) for r in rows]
    return Comparison(tuple(rows), details, niirs, snr)
