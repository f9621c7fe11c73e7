"""``summary.csv``: the run's checks (``results.json``'s ``summary``) as one CSV row each, with units.

The first line is a ``#`` comment naming the columns' units; then a header row; then one row per check in
the order of ``results.json``. ``unit`` is the unit of ``measured`` and ``predicted``, ``error_unit`` that of
``error``, ``sigma`` and ``tolerance_value`` (the wedge's error is relative: measured / predicted - 1).
Missing numbers are empty cells; ``pass`` and ``tolerance_inside_noise`` are ``true``, ``false`` or empty (n/a).
Numbers are written with 10 significant digits, so the file matches ``results.json`` to that precision.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

from satchain.report._save import write_text

__all__ = ["SUMMARY_COLUMNS", "UNITS", "summary_csv_text", "write_summary_csv"]

#: Columns of summary.csv, in order.
SUMMARY_COLUMNS = (
    "figure", "kind", "id", "unit", "measured", "predicted", "error_unit", "error", "sigma", "z",
    "tolerance", "tolerance_value", "tolerance_inside_noise", "pass", "reason", "sigma_null_means",
)  # fmt: skip
#: Per check kind: (unit of measured / predicted, unit of error and sigma).
UNITS = {
    "edge_mtf_at_nyquist": ("1 (MTF)", "1 (MTF)"),
    "edge_angle": ("deg", "deg"),
    "star_mtf": ("1 (MTF)", "1 (MTF)"),
    "bar_ctf": ("1 (CTF)", "1 (CTF)"),
    "wedge_resolution": ("m (ground line width)", "1 (relative: measured / predicted - 1)"),
    "niirs": ("NIIRS levels", "NIIRS levels"),
    # the focal plane as flown (satchain.focal)
    "band_edge_mtf_at_nyquist": ("1 (MTF)", "1 (MTF)"),
    "band_snr": ("1 (SNR)", "1 (relative: measured / predicted - 1)"),
    "band_registration": ("px (the band's own pixels)", "px (the band's own pixels)"),
    "cfa_plane_mtf": ("1 (MTF)", "1 (MTF)"),
    "staggered_edge_mtf_at_nyquist": ("1 (MTF)", "1 (MTF)"),
    "staggered_edge_mtf_at_single_nyquist": ("1 (MTF)", "1 (MTF)"),
    "staggered_bar_ctf": ("1 (CTF)", "1 (CTF)"),
}


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        x = float(v)
        return "" if not math.isfinite(x) else f"{x:.10g}"
    return str(v)


def summary_csv_text(results: dict[str, Any]) -> str:
    """The text of summary.csv from ``results.json``'s content."""
    buf = io.StringIO()
    buf.write(
        "# satchain checks, one row per check (results.json 'summary'); units: 'unit' for measured and predicted, "
        "'error_unit' for error, sigma and tolerance_value; z = error / sigma; empty = not available\n"
    )
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(SUMMARY_COLUMNS)
    for r in results.get("summary", []):
        unit, err_unit = UNITS.get(str(r.get("kind")), ("", ""))
        row = dict(r, unit=unit, error_unit=err_unit)
        w.writerow([_cell(row.get(c)) for c in SUMMARY_COLUMNS])
    return buf.getvalue()


def write_summary_csv(results: dict[str, Any], path: str | Path) -> None:
    """Write summary.csv atomically."""
    write_text(path, summary_csv_text(results))
