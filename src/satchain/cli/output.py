"""How the ``satchain measure`` commands print and write: tables, numbers, flags, ``--json`` and ``-o DIR``."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from satchain.errors import SatchainIOError

__all__ = [
    "axis_words",
    "curve_table",
    "emit",
    "fmt",
    "kv_table",
    "one_plot",
    "pm",
    "print_flags",
    "print_ground",
    "renamed_json_keys",
    "wide_console",
    "with_renamed_keys",
]


def renamed_json_keys() -> dict[str, dict[str, dict[str, str]]]:
    """JSON keys renamed in an output, written beside their new name with its value until
    :data:`~satchain._deprecate.REMOVED_IN`: {output: {where: {old key: new key}}}. The output is the JSON file's
    stem (``measure edge`` writes edge.json, ``measure auto`` auto.json, their ``--json`` prints the same); where is
    ``""`` for the top level, else the key of a list whose every item carries the key (auto.json's slanted edges,
    named by the measure layer's registry, imported when first asked for, so that ``satchain --help`` stays
    fast)."""
    from satchain.measure._keys import RESULT_KEY
    from satchain.scene.targets import SlantedEdge

    return {
        "edge": {"": {"edge_angle_deg": "angle_deg", "mtf_at_nyquist_std": "mtf_at_nyquist_sigma"}},
        "auto": {RESULT_KEY[SlantedEdge.kind]: {"mtf_at_nyquist_std": "mtf_at_nyquist_sigma"}},
    }


def _beside(d: dict, renamed: dict[str, str]) -> dict:
    """``d`` with each old key right after its new one (same value), where the new one is there and the old not."""
    out: dict[str, Any] = {}
    for key, value in d.items():
        out[key] = value
        for old, new in renamed.items():
            if key == new and old not in d:
                out[old] = value
    return out


def with_renamed_keys(output: str, payload: dict) -> dict:
    """The JSON ``payload`` of ``output`` with every renamed key of :func:`renamed_json_keys` beside its new
    name (a new dict; ``payload`` is left as it is).

    Examples
    --------
    >>> with_renamed_keys("edge", {"angle_deg": 5.0, "mtf_at_nyquist_sigma": 0.01})
    {'angle_deg': 5.0, 'edge_angle_deg': 5.0, 'mtf_at_nyquist_sigma': 0.01, 'mtf_at_nyquist_std': 0.01}
    >>> with_renamed_keys("find", {"angle_deg": 5.0})
    {'angle_deg': 5.0}
    """
    out = dict(payload)
    for where, renamed in renamed_json_keys().get(output, {}).items():
        if where == "":
            out = _beside(out, renamed)
        elif isinstance(out.get(where), list):
            out[where] = [_beside(it, renamed) if isinstance(it, dict) else it for it in out[where]]
    return out


def wide_console() -> Console:
    """A console at least 110 columns wide (the measurement tables need it)."""
    return Console(width=max(shutil.get_terminal_size((120, 40)).columns, 110))


def emit(payload: dict, as_json: bool, out: Path | None, name: str, plot, table) -> None:
    """Print (JSON or tables) and write ``out/name.json`` + the figures ``plot(out)`` returns (atomically); a
    renamed key is written beside its new name until satchain 0.2 (:func:`with_renamed_keys`)."""
    text = json.dumps(with_renamed_keys(name, payload), indent=2, allow_nan=False)
    written = []
    if out is not None:
        from satchain.report._save import write_text

        try:
            out.mkdir(parents=True, exist_ok=True)
            write_text(out / f"{name}.json", text + "\n")
            written = [out / f"{name}.json", *plot(out)]
        except OSError as exc:
            raise SatchainIOError(f"--out = {str(out)!r}: cannot write: {exc}") from None
    if as_json:
        print(text)
        return
    table()
    if written:
        wide_console().print("wrote " + ", ".join(str(p) for p in written), highlight=False)


def one_plot(plot_fn, result, path: Path, **kwargs) -> list[Path]:
    """``plot_fn(result, path, **kwargs)``; returns ``[path]`` (the ``plot`` argument of :func:`emit`)."""
    plot_fn(result, path, **kwargs)
    return [path]


def fmt(v: Any) -> str:
    """A table cell: ``-`` for None, 4 significant digits for floats.

    Examples
    --------
    >>> fmt(None), fmt(0.123456), fmt(3)
    ('-', '0.1235', '3')
    """
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def pm(value, std) -> str:
    """``value ± std`` (4 significant digits), ``-`` for None.

    Examples
    --------
    >>> pm(0.51234, 0.0123), pm(None, 0.1), pm(0.5, None)
    ('0.5123 ± 0.012', '-', '0.5')
    """
    if value is None:
        return "-"
    if std is None or not isinstance(std, float) or std != std:
        return fmt(float(value))
    return f"{value:.4g} ± {std:.2g}"


def kv_table(title: str, rows: list[tuple[str, Any]]) -> Table:
    """A two-column (quantity, value) table."""
    t = Table(title=title)
    t.add_column("quantity")
    t.add_column("value", justify="right")
    for k, v in rows:
        t.add_row(k, fmt(v))
    return t


def curve_table(title: str, f, columns: dict, pixel_m: float | None, step: float = 0.1) -> Table:
    """A few rows of curves sampled at multiples of ``step`` cy/px."""
    import numpy as np

    f = np.asarray(f, dtype=float)
    t = Table(title=title)
    t.add_column("f cy/px", justify="right")
    if pixel_m:
        t.add_column("f cy/m ground", justify="right")
    for k in columns:
        t.add_column(k, justify="right")
    for fk in np.arange(step, f.max() + 1e-9, step):
        if fk < f.min() - 1e-9:
            continue
        vals = [float(np.interp(fk, f, np.asarray(c, dtype=float))) for c in columns.values()]
        cells = [f"{fk:.2f}", *([f"{fk / pixel_m:.3f}"] if pixel_m else []), *[f"{v:.4f}" for v in vals]]
        t.add_row(*cells)
    return t


def print_flags(flags) -> None:
    """Quality flags of a star/bars/wedge measurement, one yellow line each."""
    for f in flags:
        wide_console().print(f"[yellow]flag: {f}[/]", highlight=False)


def print_ground(pixel_m: float | None, note: str | None = None) -> None:
    """One line: the ground pixel size and Nyquist in cy/m, or why frequencies are in cy/px only."""
    if pixel_m:
        text = f"ground: pixel {pixel_m:.6g} m, Nyquist {0.5 / pixel_m:.6g} cy/m (cy/m = cy/px / {pixel_m:.6g})"
    else:
        text = f"ground: not given: {note or 'no ground pixel size'}"
    wide_console().print(text, highlight=False, markup=False)


def axis_words(axis: str, scale: float, angle_deg: float | None = None) -> str:
    """The frequency axis in words, with the factor of MTF_Estimator's row axis.

    Examples
    --------
    >>> axis_words("row", 0.9573, 16.8)
    'image row/column (MTF_Estimator): f_row = 0.9573 f_normal = cos(16.80 deg) f_normal'
    >>> axis_words("normal", 1.0)
    'edge normal (ISO 12233)'
    """
    if axis == "normal":
        return "edge normal (ISO 12233)"
    tilt = "" if angle_deg is None else f" = cos({min(abs(angle_deg), 90 - abs(angle_deg)):.2f} deg) f_normal"
    return f"image row/column (MTF_Estimator): f_row = {scale:.4f} f_normal{tilt}"
