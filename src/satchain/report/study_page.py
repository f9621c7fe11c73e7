"""The page of a design study, ``DIR/study.html``: each figure of merit against each axis, a map over the first two
axes, and the case table with links to the cases' reports.

The page is one self-contained file: every plot is a PNG data URI (palette-quantised, as the run report's), and the
only links are to the cases' own files (``cases/c0001/report.html`` or ``cases/c0001/results.json``). Plots are
drawn by aggregate (one collection per line style, one scatter for the measured points), so a study of thousands of
cases draws in about the time of a few dozen small figures. Draws, never computes physics.
"""

from __future__ import annotations

import base64
import functools
import io
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain.errors import ConfigError
from satchain.report._save import write_text

if TYPE_CHECKING:
    from jinja2 import Environment
    from matplotlib.figure import Figure

__all__ = ["COMPACT_AFTER", "DEPTHS", "LEGEND_MAX", "REFERENCE_LABELS", "write_study_page"]

#: A study's depths: predictions only, or the whole chain per case.
DEPTHS = ("budget", "run")
#: With more plots than this on the page, they are laid out in a compact grid (smaller on screen; click to enlarge).
COMPACT_AFTER = 12
#: The most combinations of the other axes a plot's legend names one by one; beyond it, colours run along a
#: colour map and the legend names a few of them.
LEGEND_MAX = 10
#: How a reference line is labelled, by the column it draws (another column: its own name).
REFERENCE_LABELS = {
    "gsd_m": "GSD",
    "q": "Q",
    "snr": "SNR",
    "niirs": "NIIRS",
    "mtf_at_nyquist_act": "MTF at Nyquist ACT",
    "mtf_at_nyquist_alt": "MTF at Nyquist ALT",
}
#: The run-depth check kind whose figure gets the GSD line by default.
_WEDGE_KIND = "wedge_resolution"
#: A plot's width and the height of its axes (in), the map's size; figures at 100 dpi (1 px = 1 CSS px).
_PLOT_IN, _MAP_IN, _DPI = (6.4, 2.7), (5.6, 4.2), 100
#: The longest legend label set in two columns (characters).
_LEGEND_COL_CHARS = 36
#: The most grid nodes a map marks with dots (the cases).
_MAP_DOTS_MAX = 400
_STATUS_RANK = {"ok": 0, "failed": 1, "error": 2}


@dataclass(frozen=True)
class _Series:
    """One figure of merit's rows as arrays (NaN where a value is None)."""

    name: str
    kind: str
    unit: str
    x: dict[str, np.ndarray]  # each axis' value per row
    predicted: np.ndarray
    measured: np.ndarray
    sigma: np.ndarray
    ref: np.ndarray | None  # the reference column's value per row (e.g. gsd_m)
    ref_label: str


def write_study_page(path: Path, rows: Sequence[Mapping[str, Any]], *, axes: Mapping[str, Sequence[float]],
                     depth: str, held_fixed: Sequence[str] = (), findings: Sequence[tuple[str, str]] = (),
                     title: str = "satchain study", figure_lines: Mapping[str, str] | None = None) -> Path:  # fmt: skip
    """Write the study's page, self-contained, atomically; return its path.

    Parameters
    ----------
    path : Path
        The page to write (``DIR/study.html``); its directory is created. On any error nothing is written under
        this name (an earlier page stays as it was).
    rows : sequence of mappings
        The study table (the columns of ``DIR/study.csv``): one mapping per case x repeat x figure of merit, with
        one column per axis key, ``case``, ``repeat``, ``seed``, ``case_status`` ("ok", "failed" or "error"),
        ``message``, ``figure`` (None on an error case's one row), ``kind``, ``check_id``, ``unit``,
        ``measured``, ``predicted``, ``error``, ``sigma``, ``z``, ``pass``, the budget's ``gsd_m``, ``q``,
        ``mtf_at_nyquist_act``, ``mtf_at_nyquist_alt``, ``snr``, ``niirs``, and ``folder`` and ``report`` (paths
        relative to the page's directory, or None).
    axes : mapping of str to sequence of float
        Each axis key and its values, in the study's order.
    depth : {"budget", "run"}
        The study's depth; at budget depth only predictions are drawn.
    held_fixed : sequence of str
        One sentence per axis: what its variation holds fixed.
    findings : sequence of (str, str)
        (title, text) pairs shown at the top of the page.
    title : str
        The page's title.
    figure_lines : mapping of str to str, optional
        Figure of merit -> a column drawn dashed beside it as a reference (e.g. ``{"wedge wedge_h resolution
        (m, ALT)": "gsd_m"}``); added to the default, the GSD line of every wedge-resolution figure.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ConfigError
        An unknown depth, a row without an axis' column, or a reference column that no row has.

    Notes
    -----
    Each figure of merit is plotted against each axis: the prediction as a line, the measurement as points with
    1-sigma bars (every repeat's own point), one colour per combination of the other axes' values. With two or more
    axes a map over the first two shows the measured values (mean over repeats) where the figure was measured,
    else the predicted ones, the other axes held at their first value. A figure with no value at all is skipped.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> rows = [{"optics.aperture_diameter_m": a, "case": f"c{i + 1:04d}", "repeat": 1, "seed": i,
    ...          "case_status": "ok", "message": None, "figure": "niirs", "kind": "budget", "check_id": None,
    ...          "unit": "", "measured": None, "predicted": 4.0 + a, "error": None, "sigma": None, "z": None,
    ...          "pass": None, "gsd_m": 0.5, "q": 1.0, "mtf_at_nyquist_act": 0.1, "mtf_at_nyquist_alt": 0.1,
    ...          "snr": 50.0, "niirs": 4.0 + a, "folder": None, "report": None}
    ...         for i, a in enumerate([0.35, 0.5, 0.7])]
    >>> page = write_study_page(Path(tempfile.mkdtemp()) / "study.html", rows,
    ...                         axes={"optics.aperture_diameter_m": [0.35, 0.5, 0.7]}, depth="budget")
    >>> page.read_text().count('class="plot"')
    1
    """
    if depth not in DEPTHS:
        raise ConfigError(f"depth = {depth!r}: must be one of {', '.join(map(repr, DEPTHS))}")
    keys = list(axes)
    _check_axis_columns(rows, keys)
    series, skipped = _series(rows, keys, depth, _reference_lines(rows, figure_lines))
    plots, maps = _render_figures(series, keys, axes, depth)
    cases, counts = _case_table(rows, keys)
    html = _environment().get_template("study.html.j2").render(
        title=title, depth=depth, counts=counts, n_runs=len(cases), held_fixed=list(held_fixed),
        findings=list(findings), keys=keys, plots=plots, maps=maps, skipped=skipped, cases=cases,
        compact=sum(len(p) for p in plots.values()) + len(maps) > COMPACT_AFTER, version=_version(),
    )  # fmt: skip
    write_text(path, html)
    return Path(path)


def _version() -> str:
    import satchain

    return str(satchain.__version__)


@functools.lru_cache(maxsize=1)
def _environment() -> Environment:
    """The page's Jinja environment (autoescaping every value), made once per process."""
    from jinja2 import Environment, PackageLoader, select_autoescape

    return Environment(
        loader=PackageLoader("satchain.report", "templates"), autoescape=select_autoescape(["html", "j2"])
    )


def _check_axis_columns(rows: Sequence[Mapping[str, Any]], keys: Sequence[str]) -> None:
    for i, r in enumerate(rows):
        for k in keys:
            if k not in r:
                raise ConfigError(f"rows[{i}] (case {r.get('case')!r}): no column {k!r} (an axis of the study)")


def _reference_lines(rows: Sequence[Mapping[str, Any]], figure_lines: Mapping[str, str] | None) -> dict[str, str]:
    """Figure -> the column drawn as its reference line: the GSD for wedge resolutions, then ``figure_lines``."""
    out = {str(r["figure"]): "gsd_m" for r in rows if r.get("kind") == _WEDGE_KIND and r.get("figure") is not None}
    out.update(figure_lines or {})
    for fig, col in out.items():
        if not any(col in r for r in rows):
            raise ConfigError(f"figure_lines[{fig!r}] = {col!r}: no row has that column")
    return out


def _floats(rows: Sequence[Mapping[str, Any]], idx: Sequence[int], key: str) -> np.ndarray:
    """Column ``key`` of the rows ``idx`` as float64 (None and missing: NaN)."""
    return np.array([rows[i].get(key) for i in idx], dtype=float)


def _series(rows: Sequence[Mapping[str, Any]], keys: Sequence[str], depth: str,
            lines: Mapping[str, str]) -> tuple[list[_Series], list[str]]:  # fmt: skip
    """Each figure of merit's rows as arrays, in the order the figures first appear; and the figures skipped
    (no value at all)."""
    by_fig: dict[str, list[int]] = {}
    for i, r in enumerate(rows):
        if r.get("figure") is not None:
            by_fig.setdefault(str(r["figure"]), []).append(i)
    out, skipped = [], []
    for name, idx in by_fig.items():
        first = rows[idx[0]]
        pred = _floats(rows, idx, "predicted")
        meas = _floats(rows, idx, "measured") if depth == "run" else np.full(len(idx), np.nan)
        if not (np.isfinite(pred).any() or np.isfinite(meas).any()):
            skipped.append(name)
            continue
        col = lines.get(name)
        out.append(_Series(
            name=name, kind=str(first.get("kind") or ""), unit=str(first.get("unit") or ""),
            x={k: _floats(rows, idx, k) for k in keys}, predicted=pred, measured=meas,
            sigma=_floats(rows, idx, "sigma"), ref=None if col is None else _floats(rows, idx, col),
            ref_label=REFERENCE_LABELS.get(col, col) if col else "",
        ))  # fmt: skip
    return out, skipped


def _fmt(v: Any) -> str:
    return "–" if v is None or (isinstance(v, float) and not np.isfinite(v)) else f"{v:.6g}"


def _render_figures(series: Sequence[_Series], keys: Sequence[str], axes: Mapping[str, Sequence[float]],
                    depth: str) -> tuple[dict[str, list[dict[str, str]]], list[dict[str, str]]]:  # fmt: skip
    """Every plot (figure -> one per axis) and map, as data URIs with captions."""
    import matplotlib

    from satchain.report.compare_plots import rc_for

    plots: dict[str, list[dict[str, str]]] = {}
    maps: list[dict[str, str]] = []
    with matplotlib.rc_context(rc_for(_PLOT_IN[0])):
        for s in series:
            plots[s.name] = [
                {"axis": k, "uri": _plot_against(s, k, keys, depth), "caption": _plot_caption(s, k, keys, depth)}
                for k in keys
            ]
            if len(keys) >= 2:
                m = _map_png(s, keys, axes)
                if m is not None:
                    maps.append({"figure": s.name, **m})
    return plots, maps


def _plot_caption(s: _Series, axis: str, keys: Sequence[str], depth: str) -> str:
    parts = [f"{s.name} against {axis}: lines predicted"]
    if depth == "run" and np.isfinite(s.measured).any():
        parts.append("points measured (each repeat its own point) with 1-sigma bars")
    if s.ref is not None:
        parts.append(f"dashed: {s.ref_label}")
    others = [k for k in keys if k != axis]
    if others:
        parts.append(f"one colour per combination of {', '.join(others)}")
    return "; ".join(parts) + "."


def _data_uri(fig: Figure) -> str:
    """``fig`` drawn by Agg and encoded as a palette PNG data URI (as the run report's figures)."""
    from PIL import Image

    from satchain.io.images import PNG_COMPRESS_LEVEL
    from satchain.report._save import PNG_COLOURS, _render_rgb

    rgb = _render_rgb(fig, None)
    q = rgb.quantize(colors=PNG_COLOURS, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)
    buf = io.BytesIO()
    q.save(buf, format="PNG", compress_level=PNG_COMPRESS_LEVEL)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _combinations(s: _Series, others: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Each row's combination of the ``others`` axes' values (an index, sorted by the values) and the
    combinations' values (one row each)."""
    n = s.predicted.size
    if not others:
        return np.zeros(n, dtype=np.intp), np.zeros((1, 0))
    values, inv = np.unique(np.column_stack([s.x[k] for k in others]), axis=0, return_inverse=True)
    return inv.reshape(-1), values


def _colours(n: int) -> np.ndarray:
    """RGBA colours of ``n`` combinations: the house's tab10 while a legend can name them all, else viridis."""
    from matplotlib import colormaps

    if n == 1:
        return np.array([[0.0, 0.0, 0.0, 1.0]])
    if n <= LEGEND_MAX:
        return np.asarray(colormaps["tab10"](np.arange(n)))
    return np.asarray(colormaps["viridis"](np.linspace(0.0, 0.92, n)))


def _lines(combo: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """Polylines of ``y`` against ``x``, one per combination (repeats averaged, sorted by x, NaN dropped), and the
    combination of each."""
    ok = np.isfinite(x) & np.isfinite(y)
    if not ok.any():
        return [], np.zeros(0, dtype=np.intp)
    keys, inv = np.unique(np.column_stack([combo[ok], x[ok]]), axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    mean = np.bincount(inv, weights=y[ok], minlength=len(keys)) / np.bincount(inv, minlength=len(keys))
    cut = np.flatnonzero(np.diff(keys[:, 0])) + 1
    xs, ys, cs = np.split(keys[:, 1], cut), np.split(mean, cut), np.split(keys[:, 0], cut)
    return [np.column_stack([a, b]) for a, b in zip(xs, ys, strict=True)], np.array([c[0] for c in cs], np.intp)


def _legend_entries(others: Sequence[str], values: np.ndarray, colours: np.ndarray, *, measured: bool,
                    ref_label: str | None) -> tuple[list[Any], list[str]]:  # fmt: skip
    """The legend of a plot: the combinations of the other axes (all, or 5 of many), then the line styles."""
    from matplotlib.lines import Line2D

    n = len(values)
    shown = [int(i) for i in np.unique(np.linspace(0, n - 1, 5).round())] if n > LEGEND_MAX else list(range(n))
    handles: list[Any] = [Line2D([], [], color=colours[i], lw=1.6) for i in shown] if others else []
    labels = [", ".join(f"{k} = {v:.6g}" for k, v in zip(others, values[i], strict=True)) for i in shown]
    labels = labels if others else []
    if others and n > LEGEND_MAX:
        labels[-1] += f" ({n} combinations, {len(shown)} named)"
    grey = "0.3"
    handles.append(Line2D([], [], color=grey, lw=1.6, marker="o", ms=3))
    labels.append("predicted")
    if measured:
        handles.append(Line2D([], [], color=grey, ls="none", marker="D", ms=4))
        labels.append("measured ± 1σ")
    if ref_label is not None:
        handles.append(Line2D([], [], color=grey, lw=1.1, ls="--"))
        labels.append(ref_label)
    return handles, labels


def _plot_against(s: _Series, axis: str, keys: Sequence[str], depth: str) -> str:
    """The figure ``s`` against ``axis`` (predicted lines, measured points with 1-sigma bars, the reference line
    dashed), one colour per combination of the other axes, the legend below; a PNG data URI."""
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    from satchain.report._style import axis_band_in, legend_height_in, place_grid, title_band_in

    others = [k for k in keys if k != axis]
    combo, values = _combinations(s, others)
    colours = _colours(len(values))
    x = s.x[axis]
    measured = depth == "run" and bool((np.isfinite(x) & np.isfinite(s.measured)).any())
    handles, labels = _legend_entries(others, values, colours, measured=measured,
                                      ref_label=None if s.ref is None else s.ref_label)  # fmt: skip
    ncol = 2 if max(map(len, labels)) <= _LEGEND_COL_CHARS else 1
    legend_in = legend_height_in(-(-len(labels) // ncol))
    top, bottom = title_band_in(), axis_band_in() + legend_in
    fig = Figure(figsize=(_PLOT_IN[0], _PLOT_IN[1] + top + bottom), dpi=_DPI)
    ax = fig.add_axes((0.1, 0.15, 0.8, 0.75))
    polys, which = _lines(combo, x, s.predicted)
    if polys:
        ax.add_collection(LineCollection(polys, colors=colours[which], linewidths=1.6))
        pts = np.concatenate(polys)
        ax.scatter(pts[:, 0], pts[:, 1], s=9, c=colours[np.repeat(which, [len(p) for p in polys])], zorder=2)
    if s.ref is not None:
        refs, rwhich = _lines(combo, x, s.ref)
        if refs:
            ax.add_collection(LineCollection(refs, colors=colours[rwhich], linewidths=1.1, linestyles="--"))
    if measured:
        _measured_points(ax, x, s, colours[combo])
    ax.autoscale_view()
    ax.set_xlabel(axis)
    ax.set_ylabel(s.unit or "value")
    ax.set_title(s.name)
    ax.grid(alpha=0.3)
    fig.legend(handles, labels, loc="lower center", ncol=ncol, frameon=False)
    place_grid(fig, [[ax]], top=top, bottom=bottom)
    return _data_uri(fig)


def _measured_points(ax: Any, x: np.ndarray, s: _Series, colours: np.ndarray) -> None:
    """Draw the measured points with their 1-sigma bars (one scatter, one collection)."""
    from matplotlib.collections import LineCollection

    ok = np.isfinite(x) & np.isfinite(s.measured)
    ax.scatter(x[ok], s.measured[ok], s=22, marker="D", c=colours[ok], edgecolors="black", linewidths=0.5, zorder=3)
    bar = ok & np.isfinite(s.sigma)
    if bar.any():
        xb, yb, sb = x[bar], s.measured[bar], np.abs(s.sigma[bar])
        segs = np.stack([np.column_stack([xb, yb - sb]), np.column_stack([xb, yb + sb])], axis=1)
        ax.add_collection(LineCollection(list(segs), colors=colours[bar], linewidths=1.0, zorder=2.5))


def _edges(v: np.ndarray) -> np.ndarray:
    """Cell edges around sorted centres ``v`` (midpoints; a single centre gets a cell of half its size)."""
    if v.size == 1:
        h = 0.25 * abs(float(v[0])) or 0.5
        return np.array([v[0] - h, v[0] + h])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])


def _grid(s: _Series, keys: Sequence[str], axes: Mapping[str, Sequence[float]],
          values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """``values`` on the grid of the first two axes (mean over repeats; NaN where none), the other axes at their
    first value."""
    xs, ys = (np.unique(np.asarray(axes[k], float)) for k in keys[:2])
    keep = np.isfinite(values)
    for k in keys[2:]:
        keep &= np.isclose(s.x[k], float(axes[k][0]))
    ix = np.clip(np.searchsorted(xs, s.x[keys[0]]), 0, xs.size - 1)
    iy = np.clip(np.searchsorted(ys, s.x[keys[1]]), 0, ys.size - 1)
    keep &= np.isclose(xs[ix], s.x[keys[0]]) & np.isclose(ys[iy], s.x[keys[1]])
    flat = (iy * xs.size + ix)[keep]
    total = np.bincount(flat, weights=values[keep], minlength=xs.size * ys.size)
    count = np.bincount(flat, minlength=xs.size * ys.size)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = np.where(count > 0, total / np.maximum(count, 1), np.nan)
    return xs, ys, z.reshape(ys.size, xs.size)


def _map_png(s: _Series, keys: Sequence[str], axes: Mapping[str, Sequence[float]]) -> dict[str, str] | None:
    """The map of ``s`` over the first two axes (filled contours, or cells when the grid is too small or has
    holes): ``{"uri", "caption", "shows"}``, or None when it has no value there."""
    from matplotlib.figure import Figure

    from satchain.report._style import axis_band_in, place_grid, title_band_in

    shows = "measured" if np.isfinite(s.measured).any() else "predicted"
    xs, ys, z = _grid(s, keys, axes, s.measured if shows == "measured" else s.predicted)
    if not np.isfinite(z).any():
        return None
    fig = Figure(figsize=_MAP_IN, dpi=_DPI)
    ax = fig.add_axes((0.12, 0.12, 0.6, 0.75))
    finite = np.isfinite(z)
    contour = xs.size >= 3 and ys.size >= 3 and finite.all() and float(np.ptp(z)) > 0
    mappable: Any
    if contour:
        mappable = ax.contourf(xs, ys, z, levels=12, cmap="viridis")
        ax.contour(xs, ys, z, levels=mappable.levels, colors="white", linewidths=0.4, alpha=0.6)
        if xs.size * ys.size <= _MAP_DOTS_MAX:  # the cases, where the grid is not too dense to show them
            gx, gy = np.meshgrid(xs, ys)
            ax.plot(gx.ravel(), gy.ravel(), "k.", ms=2)
    else:
        mappable = ax.pcolormesh(_edges(xs), _edges(ys), np.ma.masked_invalid(z), cmap="viridis")
    ax.set_xlabel(keys[0])
    ax.set_ylabel(keys[1])
    ax.set_title(f"{s.name} ({shows})")
    place_grid(fig, [[ax]], top=title_band_in(), bottom=axis_band_in(), right=1.45)
    left, bottom, width, height = ax.get_position().bounds
    cax = fig.add_axes((left + width + 0.15 / _MAP_IN[0], bottom, 0.18 / _MAP_IN[0], height))
    fig.colorbar(mappable, cax=cax, label=s.unit or s.name)
    held = "; ".join(f"{k} = {float(axes[k][0]):.6g}" for k in keys[2:])
    caption = (f"{s.name} over {keys[0]} and {keys[1]}: {shows} values (mean over repeats), "
               f"{'filled contours' if contour else 'one cell per case'}"
               + (f"; the other axes held at their first value ({held})" if held else "") + ".")  # fmt: skip
    return {"uri": _data_uri(fig), "caption": caption, "shows": shows}


def _case_href(r: Mapping[str, Any]) -> str | None:
    if r.get("report"):
        return str(r["report"])
    if r.get("folder"):
        return f"{r['folder']}/results.json"
    return None


def _case_table(rows: Sequence[Mapping[str, Any]],
                keys: Sequence[str]) -> tuple[list[dict[str, Any]], dict[str, int]]:  # fmt: skip
    """One row per (case, repeat): the axes' values, link, status, checks passed / failed, the message; and the
    number of cases per status (a case's status: the worst of its repeats')."""
    runs: dict[tuple[str, Any], dict[str, Any]] = {}
    for r in rows:
        run = runs.get((str(r.get("case")), r.get("repeat")))
        if run is None:
            run = runs[(str(r.get("case")), r.get("repeat"))] = {
                "case": str(r.get("case")), "repeat": r.get("repeat"), "seed": r.get("seed"),
                "values": [_fmt(r.get(k)) for k in keys], "status": str(r.get("case_status") or "ok"),
                "href": _case_href(r), "n_pass": 0, "n_fail": 0, "message": r.get("message"),
            }  # fmt: skip
        run["n_pass"] += r.get("pass") is True
        run["n_fail"] += r.get("pass") is False
        run["message"] = run["message"] or r.get("message")
        run["href"] = run["href"] or _case_href(r)
        if _STATUS_RANK.get(str(r.get("case_status")), 0) > _STATUS_RANK.get(run["status"], 0):
            run["status"] = str(r.get("case_status"))
    worst: dict[str, str] = {}
    for run in runs.values():
        st = worst.get(run["case"], "ok")
        worst[run["case"]] = max(st, run["status"], key=lambda v: _STATUS_RANK.get(v, 0))
    counts = {st: sum(v == st for v in worst.values()) for st in _STATUS_RANK}
    counts["total"] = len(worst)
    return list(runs.values()), counts
