"""The feasibility map of ``satchain design`` with two keys (:class:`satchain.studies.design_map.FeasibilityMap`):
``feasibility.csv`` (one row per grid cell) and ``feasibility.png`` (each target's unmet side shaded, its
margin = 0 line drawn and labelled: the white region meets every target). Draws, never computes physics."""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import TYPE_CHECKING

from satchain.report._save import save_figure, write_text

if TYPE_CHECKING:
    from satchain.studies.design_map import FeasibilityMap

__all__ = ["feasibility_csv_text", "write_feasibility_map"]


def feasibility_csv_text(fmap: FeasibilityMap) -> str:
    """The text of feasibility.csv: the two keys, each target quantity's value and margin, feasible (0/1)."""
    rows = fmap.rows()
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: (int(v) if isinstance(v, bool) else f"{v:.9g}") for k, v in r.items()})
    return buf.getvalue()


def write_feasibility_map(fmap: FeasibilityMap, out_dir: str | Path) -> list[Path]:
    """Write ``feasibility.csv`` and ``feasibility.png`` into ``out_dir``; return their paths."""
    from matplotlib.figure import Figure

    out = Path(out_dir)
    csv_path, png_path = out / "feasibility.csv", out / "feasibility.png"
    write_text(csv_path, feasibility_csv_text(fmap))
    fig = Figure(figsize=(6.4, 4.8), dpi=100)
    ax = fig.add_subplot()
    k1, k2 = fmap.keys
    colours = ["C0", "C1", "C3", "C4", "C5", "C6", "C7", "C8", "C9"]
    for i, t in enumerate(fmap.targets):
        m = fmap.margins[str(t)]
        if m.min() < 0:  # each target's unmet side shaded with its own interpolation, as its line is drawn
            ax.contourf(fmap.x1, fmap.x2, m, levels=[float(m.min()) - 1.0, 0.0], colors=["0.5"], alpha=0.18)
        if m.min() < 0 < m.max():
            cs = ax.contour(fmap.x1, fmap.x2, m, levels=[0.0], colors=[colours[i % len(colours)]])
            ax.clabel(cs, fmt={0.0: str(t)}, fontsize=8)
    ax.set_xlabel(k1)
    ax.set_ylabel(k2)
    ax.set_title("white: every target met; grey: a target not met (darker: more); lines: margin = 0", fontsize=9)
    fig.subplots_adjust(left=0.14, right=0.97, bottom=0.12, top=0.92)
    save_figure(fig, png_path)
    return [csv_path, png_path]
