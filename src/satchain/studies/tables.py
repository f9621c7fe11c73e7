"""The study table: ``DIR/study.csv`` and ``DIR/study.parquet``, one row per case x figure of merit.

Columns: the axes' keys (their values), then :data:`COLUMNS`: ``case``, ``repeat`` and ``seed`` (the noise
realisation), ``case_status`` (``ok``; ``failed``: a check of the case failed; ``error``: the case raised, its
one-line ``message`` beside it and no figure), ``figure`` (at budget depth the budget quantity, e.g. ``niirs``; at
run depth the check, e.g. ``edge edge_act MTF@Nyquist (ACT)``), ``kind``, ``check_id``, ``unit``, ``measured``,
``predicted``, ``error``, ``sigma``, ``z``, ``pass``, ``message``, the budget's derived quantities of the case
(:data:`DERIVED`: GSD, Q = lambda N / p, MTF at Nyquist ACT/ALT, SNR, NIIRS) and ``folder`` / ``report`` (the case's
folder and its kept report, relative to DIR). Both files are written atomically; the Parquet file holds the same
table typed (text, int64, nullable bool, float64; empty cells are nulls).
"""

from __future__ import annotations

import csv
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = ["BUDGET_UNITS", "COLUMNS", "DERIVED", "FIGURES", "budget_rows", "derived", "write_tables"]

#: the figures of a budget-depth study (one row each per case) and the SystemBudget attribute each reads
FIGURES: dict[str, str] = {
    "niirs": "niirs",
    "rer": "rer",
    "rer_act": "rer_act",
    "rer_alt": "rer_alt",
    "snr": "snr",
    "mtf_nyquist_act": "mtf_at_nyquist_act",
    "mtf_nyquist_alt": "mtf_at_nyquist_alt",
    "gsd_m": "gsd_m",
    "q": "q",
}
#: the unit of each budget-depth figure
BUDGET_UNITS: dict[str, str] = {
    "niirs": "NIIRS levels",
    "rer": "1 (edge response slope, per pixel)",
    "rer_act": "1 (edge response slope, per pixel)",
    "rer_alt": "1 (edge response slope, per pixel)",
    "snr": "1",
    "mtf_nyquist_act": "1 (MTF)",
    "mtf_nyquist_alt": "1 (MTF)",
    "gsd_m": "m",
    "q": "1 (lambda N / p)",
}
#: the budget's derived quantities written on every row of a case
DERIVED = ("gsd_m", "q", "mtf_at_nyquist_act", "mtf_at_nyquist_alt", "snr", "niirs")
#: the columns after the axes' keys
COLUMNS = (
    "case", "repeat", "seed", "case_status", "figure", "kind", "check_id", "unit", "measured", "predicted", "error",
    "sigma", "z", "pass", "message", *DERIVED, "folder", "report",
)  # fmt: skip

#: the columns that are not float64 in study.parquet
_TEXT = ("case", "case_status", "figure", "kind", "check_id", "unit", "message", "folder", "report")
_INTEGER = ("repeat", "seed")
_BOOLEAN = ("pass",)


def derived(system: Any) -> dict[str, float]:
    """The budget's derived quantities of ``system`` (:data:`DERIVED`), and its budget."""
    from satchain.prediction.budget import budget

    b = budget(system)
    return {k: float(getattr(b, k)) for k in DERIVED}


def budget_rows(cases: Sequence[Any]) -> list[dict[str, Any]]:
    """The rows of a budget-depth study: one per case x figure (measured, error, sigma, z and pass empty)."""
    from satchain.prediction.budget import budget

    rows = []
    for case in cases:
        b = budget(case.system)
        d = {k: float(getattr(b, k)) for k in DERIVED}
        for fig, attr in FIGURES.items():
            rows.append(
                {
                    **case.values,
                    "case": case.case_id,
                    "repeat": 1,
                    "seed": case.seeds[0],
                    "case_status": "ok",
                    "figure": fig,
                    "kind": "budget",
                    "check_id": None,
                    "unit": BUDGET_UNITS[fig],
                    "measured": None,
                    "predicted": float(getattr(b, attr)),
                    "error": None,
                    "sigma": None,
                    "z": None,
                    "pass": None,
                    "message": None,
                    **d,
                    "folder": None,
                    "report": None,
                }
            )
    return rows


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    return str(v)


def write_tables(out: Path, keys: Sequence[str], rows: Sequence[Mapping[str, Any]]) -> Path:
    """Write ``out/study.parquet`` and ``out/study.csv`` (each atomically); return the CSV's path."""
    from satchain.io.images import atomic_path

    header = [*keys, *COLUMNS]
    with atomic_path(out / "study.parquet") as tmp:
        _write_parquet(tmp, header, rows)
    path = out / "study.csv"
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for r in rows:
            w.writerow([_cell(r.get(h)) for h in header])
    return path


def _write_parquet(path: Path, header: Sequence[str], rows: Sequence[Mapping[str, Any]]) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    def kind(name: str) -> pa.DataType:
        if name in _TEXT:
            return pa.string()
        if name in _INTEGER:
            return pa.int64()
        return pa.bool_() if name in _BOOLEAN else pa.float64()

    schema = pa.schema([(h, kind(h)) for h in header])
    table = pa.Table.from_pylist([{h: r.get(h) for h in header} for r in rows], schema=schema)
    pq.write_table(table, path)
