"""Measured vs predicted figures of a run, each with a residual panel and its tolerance band.

One figure per slanted edge (ESF, LSF, MTF with MTF50, MTF10 and Nyquist marked), per Siemens star (one
style per direction), per bar target (compared and not-compared groups, the cut-off drawn) and per wedge
(contrast against line width, the 15 % crossing marked). Inputs are :func:`satchain.report.curves.build_curves`
output and the tolerances of the run. Figures use matplotlib's object API (no pyplot state) and fonts of at
least 9 pt at the size the report shows them (about 100 px per inch).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from satchain.report._save import save_figure
from satchain.report._style import grid_axes, pin_titles

__all__ = [
    "PRINT_WIDTH_IN",
    "mark_failed",
    "RC",
    "rc_for",
    "with_rc",
    "plot_bars_comparison",
    "plot_edge_comparison",
    "plot_star_comparison",
    "plot_wedge_comparison",
]

#: Font sizes of every report figure (points at the displayed size, which is about the saved size).
RC = {
    "font.size": 10.5,
    "axes.titlesize": 11,
    "axes.labelsize": 10.5,
    "legend.fontsize": 9.5,
    "xtick.labelsize": 9.5,
    "ytick.labelsize": 9.5,
    "figure.titlesize": 12,
}
DPI = 100
#: Width of an A4 page's text block (in): a figure wider than this is scaled down when printed.
PRINT_WIDTH_IN = 7.2


def rc_for(width_in: float) -> dict:
    """Font sizes for a figure ``width_in`` wide that stay >= 9 pt on screen (1 figure px = 1 CSS px) and when
    the figure is scaled down to an A4 text block."""
    k = max(1.0, width_in / PRINT_WIDTH_IN)
    small = round(9.3 * k, 1)
    return {
        **RC,
        "font.size": small + 0.5,
        "axes.labelsize": small + 0.5,
        "axes.titlesize": small + 1,
        "legend.fontsize": small,
        "xtick.labelsize": small,
        "ytick.labelsize": small,
        "figure.titlesize": small + 2,
    }


MEAS, PRED, TOL = "black", "tab:red", "tab:green"
#: The prediction for the camera as built (a run with ``[as_built]``) and the mark of a failing point.
AS_BUILT, FAIL = "tab:purple", "#d40000"
_AB_LS = (0, (6, 2, 1.5, 2))  # dash-dot: the as-built prediction


def mark_failed(ax, x, y, label: str | None = None) -> None:
    """A failing point: a large red cross behind the measured marker (distinct from every measured marker, which
    stays visible on it), with its label."""
    x, y = np.atleast_1d(np.asarray(x, float)), np.atleast_1d(np.asarray(y, float))
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.any():
        ax.plot(x[ok], y[ok], "X", color=FAIL, mec="white", mew=0.8, ms=15, zorder=1.9, alpha=0.85, label=label)


def _residual_limits(ax, values, sigmas, tol: float | None, pad: float = 0.12) -> None:
    """y limits of a residual panel from its data: every residual with its error bar and the tolerance band."""
    v, sg = np.asarray(values, float).ravel(), np.nan_to_num(np.asarray(sigmas, float).ravel())
    ok = np.isfinite(v)
    ext = [abs(tol)] if tol is not None and np.isfinite(tol) else []
    if ok.any():
        ext.append(float(np.max(np.abs(v[ok]) + sg[ok])))
    top = max(ext + [1e-3]) * (1 + pad)
    ax.set_ylim(-top, top)


_DIR_STYLE = {
    "ACT": dict(color="tab:blue", marker="o", ls="-"),
    "ALT": dict(color="tab:red", marker="s", ls="--"),
    "D45": dict(color="tab:green", marker="^", ls="-."),
    "D135": dict(color="tab:purple", marker="v", ls=":"),
}


def with_rc(width_in: float):
    """Decorator: run a plotting function with :func:`rc_for` fonts for a figure ``width_in`` wide."""
    import functools

    def deco(fn):
        @functools.wraps(fn)
        def wrapper(*args, **kwargs):
            with matplotlib.rc_context(rc_for(width_in)):
                return fn(*args, **kwargs)

        return wrapper

    return deco


def _figure(w: float, h: float, n_cols: int = 1) -> tuple[Figure, list, list]:
    """A plot above its residual panel, ``n_cols`` side by side (a fixed layout in inches, see
    :func:`grid_axes`)."""
    fig = Figure(figsize=(w, h), dpi=DPI)
    left, right, gap = 0.95, 0.15, 0.95
    col = (w - left - right - gap * (n_cols - 1)) / n_cols
    tall = h - 0.45 - 0.3 - 0.62
    g = grid_axes(fig, [(0.0, tall * 3 / 4.25), (0.3, tall * 1.25 / 4.25)], [(0.0 if i == 0 else gap, col)
                  for i in range(n_cols)], left=left, top=0.45)  # fmt: skip
    top = [fig.add_axes(g[0][i]) for i in range(n_cols)]
    bottom = [fig.add_axes(g[1][i], sharex=top[i]) for i in range(n_cols)]
    _gridded_pairs(top, bottom)
    return fig, top, bottom


def _gridded_pairs(top: list, bottom: list) -> None:
    """Grids on every panel; each plot's x tick labels left to the residual panel below, which shares its axis."""
    for ax in top + bottom:
        ax.grid(alpha=0.3)
    for ax in top:
        ax.tick_params(labelbottom=False)


def _band(ax, tol: float | None, *, x=None, label: str = "tolerance") -> None:
    ax.axhline(0, color="gray", lw=0.8)
    if tol is not None and np.isfinite(tol):
        if x is None:
            ax.axhspan(-tol, tol, color=TOL, alpha=0.15, label=f"{label} ±{tol:g}")
        else:
            ax.fill_between(x, -tol, tol, color=TOL, alpha=0.15, label=f"{label} ±{tol:g}")


def _save(fig: Figure, path: Path) -> None:
    pin_titles(*fig.axes)  # drawing then does not measure the tick labels again to place the titles
    save_figure(fig, path, dpi=DPI)


def _mark(ax, x: float, text: str, y: float = 0.5) -> None:
    """A vertical text label beside a vertical line, inside the axes (never over the title)."""
    ax.text(
        x,
        y,
        f" {text}",
        color="0.35",
        fontsize=matplotlib.rcParams["legend.fontsize"],
        rotation=90,
        ha="right",
        va="center",
        transform=ax.get_xaxis_transform(),
    )


def _vline(ax, x, color, ls, label=None):
    if x is not None and np.isfinite(x):
        ax.axvline(x, color=color, ls=ls, lw=1, label=label)


def _edge_figure() -> tuple[Figure, list, list]:
    """ESF | LSF above, the MTF full width below, each with its residual panel underneath (a fixed layout in
    inches: labels at 9.3 pt fit, see :func:`grid_axes`)."""
    fig = Figure(figsize=(PRINT_WIDTH_IN, 9.0), dpi=DPI)
    left, gap = 1.0, 0.95
    col = (PRINT_WIDTH_IN - left - 0.12 - gap) / 2
    g = grid_axes(fig, [(0.0, 2.2), (0.3, 0.78), (0.82, 2.45), (0.3, 0.93)], [(0.0, col), (gap, col)], left=left,
                  top=0.62)  # fmt: skip
    full = [(x, y, 2 * w + gap / PRINT_WIDTH_IN, h) for (x, y, w, h), _ in (g[2], g[3])]
    top = [fig.add_axes(g[0][0]), fig.add_axes(g[0][1]), fig.add_axes(full[0])]
    bot = [fig.add_axes(g[1][i], sharex=top[i]) for i in range(2)] + [fig.add_axes(full[1], sharex=top[2])]
    _gridded_pairs(top, bot)
    return fig, top, bot


def plot_edge_comparison(c: dict, path: Path, *, tol: float | None) -> None:
    """ESF, LSF and MTF of one edge, measured vs predicted, with residuals (measured - predicted) below."""
    with matplotlib.rc_context(rc_for(PRINT_WIDTH_IN)):
        fig, top, bot = _edge_figure()
        x, near = c["x_px"], np.abs(c["x_px"]) <= 6
        for ax, r, key, lab, where in (  # fixed legend corners: "best" searches every point (slow)
            (top[0], bot[0], "esf", "ESF (normalised)", "upper left"),
            (top[1], bot[1], "lsf", "LSF (1/px)", "upper right"),
        ):
            ax.plot(x[near], c[key + "_measured"][near], color=MEAS, lw=1.4, label="measured")
            ax.plot(x[near], c[key + "_predicted"][near], color=PRED, ls="--", lw=1.4, label="predicted")
            ax.set_ylabel(lab)
            ax.legend(loc=where)
            r.plot(x[near], c[key + "_measured"][near] - c[key + "_predicted"][near], color=MEAS, lw=1)
            _band(r, None)
            r.set_xlabel("distance from edge (px)")
            r.set_ylabel("meas. - pred.")
        f, mm, mp = c["f_cy_per_px"], c["mtf_measured"], c["mtf_predicted"]
        ax = top[2]
        ax.plot(f, mm, color=MEAS, lw=1.4, label="measured (e-SFR)")
        sig = np.asarray(c.get("mtf_sigma", np.full(f.size, np.nan)), float)
        if np.isfinite(sig).any():
            ax.fill_between(f, mm - 2 * sig, mm + 2 * sig, color=MEAS, alpha=0.2, lw=0, label="measured ± 2σ (noise)")
        ax.plot(f, mp, color=PRED, ls="--", lw=1.4, label="predicted" + (" (design)" if "mtf_predicted_as_built" in c
                                                                        else ""))  # fmt: skip
        mab = np.asarray(c.get("mtf_predicted_as_built", np.full(f.size, np.nan)), float)
        if np.isfinite(mab).any():
            ax.plot(f, mab, color=AS_BUILT, ls=_AB_LS, lw=1.4, label="predicted as built")
        ax.axvline(0.5, color="gray", lw=1)
        _mark(ax, 0.5, "Nyquist", 0.72)
        nm, npred = c["nyquist"]
        failed = c.get("passed") is False and nm is not None and npred is not None
        if failed:
            mark_failed(ax, 0.5, nm, "FAIL: outside the tolerance at Nyquist")
        for (fm, fp), lvl, mk, name in (
            (c["mtf50"], 0.5, "o", "MTF50"),
            (c["mtf10"], 0.1, "s", "MTF10"),
            ((0.5, 0.5), None, "D", "at Nyquist"),
        ):
            ys = (nm, npred) if lvl is None else (lvl, lvl)
            for fv, yv, col in ((fm, ys[0], MEAS), (fp, ys[1], PRED)):
                if fv is not None and yv is not None:
                    ax.plot([fv], [yv], mk, color=col, mfc="none", ms=8, mew=1.5)
            ax.plot([], [], mk, color="0.3", mfc="none", ms=8, label=name)
        ax.set_xlim(0, min(1.0, float(f.max())))
        ax.set_ylim(0, 1.08)
        ax.set_ylabel("MTF")
        ax.legend(loc="upper right")
        r = bot[2]
        ok = f <= 1.0
        r.plot(f[ok], (mm - mp)[ok], color=MEAS, lw=1)
        if np.isfinite(sig).any():
            r.fill_between(f[ok], (mm - mp - 2 * sig)[ok], (mm - mp + 2 * sig)[ok], color=MEAS, alpha=0.2, lw=0)
        if np.isfinite(mab).any():
            r.plot(f[ok], (mm - mab)[ok], color=AS_BUILT, ls=_AB_LS, lw=1, label="meas. - as built")
        if failed:
            mark_failed(r, 0.5, nm - npred)
        _band(r, tol, label="tol. at Nyquist")
        r.axvline(0.5, color="gray", lw=1)
        r.set_xlabel("frequency along the edge normal (cy/px)")
        r.set_ylabel("meas. - pred.")
        r.legend(loc="lower left")
        for ax, t in zip(top, ("edge spread function", "line spread function", "MTF along the normal"), strict=True):
            ax.set_title(t)
        ang = c.get("angle_deg")
        fig.suptitle(f"Slanted edge {c['id']} ({c['direction']}{'' if ang is None else f', {ang:.2f}°'})")
        _save(fig, path)


def plot_star_comparison(st: dict, path: Path, *, tol: float | None) -> None:
    """Siemens-star MTF per direction: measured (markers), predicted (lines: the star measured on its noise-free
    predicted image), the system MTF (grey dots, where it differs), residuals with the band."""
    with matplotlib.rc_context(rc_for(8.5)):
        fig, (ax,), (r,) = _figure(8.5, 6.4)
        f = np.asarray(st["f_cy_per_px"], float)
        x_max = min(0.8, float(np.nanmax(f)) if f.size else 0.8)
        shown_model = shown_ab = False
        res_all, sig_all, handles = [], [], {}
        for d, curve in (st.get("mtf_measured") or {}).items():
            sty = _DIR_STYLE.get(d, dict(color="gray", marker="x", ls="-"))
            meas = np.asarray(curve, float)
            pred = np.asarray(st["directions"][d]["mtf_predicted"], float)
            (hm,) = ax.plot(f, meas, sty["marker"], color=sty["color"], ms=4, mfc="none")
            (hp,) = ax.plot(f, pred, ls=sty["ls"], color=sty["color"], lw=1.4)
            handles[f"{d} measured / predicted"] = (hm, hp)
            model = st["directions"][d].get("mtf_model")
            if model is not None and not np.allclose(np.asarray(model, float), pred, equal_nan=True):
                lab = "system MTF (model)" if not shown_model else None
                ax.plot(f, np.asarray(model, float), ls=(0, (1, 2)), color="0.35", lw=0.9, label=lab)
                shown_model = True
            ab = (((st.get("as_built") or {}).get("directions") or {}).get(d) or {}).get("mtf_predicted")
            if ab is not None and len(ab) == f.size:
                if not shown_ab:  # one legend entry for the four (each in its direction's colour)
                    ax.plot([], [], ls=_AB_LS, color="0.3", lw=0.9, label="predicted as built")
                ax.plot(f, np.asarray(ab, float), ls=_AB_LS, color=sty["color"], lw=0.9, alpha=0.8)
                shown_ab = True
            std = _per_group((st.get("mtf_std_measured") or {}).get(d), f.size)
            r.errorbar(f, meas - pred, yerr=np.nan_to_num(std), ls=sty["ls"], marker=sty["marker"], ms=3,
                       color=sty["color"], lw=1, elinewidth=0.8, capsize=0)  # fmt: skip
            shown = f <= x_max
            res_all.append((meas - pred)[shown])
            sig_all.append(std[shown])
        lo, hi = 0.05, 0.5
        r.fill_between([lo, hi], -(tol or 0), tol or 0, color=TOL, alpha=0.15, label=f"tolerance ±{tol:g} (checked)")
        r.axhline(0, color="gray", lw=0.8)
        if st.get("pass") is False and st.get("error") is not None:
            lab = f"FAIL: largest difference {st['error']:+.3f} ({st.get('worst_direction')})"
            mark_failed(ax, st.get("worst_f_cy_per_px"), st.get("measured_at_worst"), lab)
            mark_failed(r, st.get("worst_f_cy_per_px"), st["error"])
        for a in (ax, r):
            a.axvline(0.5, color="gray", lw=1)
        _mark(ax, 0.5, "Nyquist", 0.45)
        ax.set_xlim(0, x_max)
        ax.set_ylim(-0.05, 1.08)
        ax.set_ylabel("MTF")
        ax.set_title(f"Siemens star {st['id']}: MTF per direction")
        extra, extra_labels = ax.get_legend_handles_labels()  # the model, the as-built lines, the failing point
        ax.legend([*handles.values(), *extra], [*handles, *extra_labels], ncol=2, loc="upper right")
        _residual_limits(r, np.concatenate(res_all or [np.zeros(0)]), np.concatenate(sig_all or [np.zeros(0)]), tol)
        r.set_xlabel("frequency along the direction (cy/px)")
        r.set_ylabel("meas. - pred.")
        r.legend(loc="lower left")
        _save(fig, path)


def _per_group(values, n: int) -> np.ndarray:
    """A per-group list (None = NaN) as floats; all-NaN when absent or of the wrong length."""
    if not values or len(values) != n:
        return np.full(n, np.nan)
    return np.array([np.nan if v is None else v for v in values], float)


def plot_bars_comparison(b: dict, path: Path, *, tol: float | None) -> None:
    """Bar-target CTF: compared groups (filled), groups beyond the cut-off (hollow, not compared), each with
    its 1-sigma (``ctf_std_measured``) as an error bar, the raw modulation before the square-wave correction
    (crosses), the cut-off, Coltman's prediction and the paper's method (a pushbroom image's prediction at its
    placement, diamonds, is what is compared when given); residuals of the compared groups with their error bars
    and the band."""
    with matplotlib.rc_context(rc_for(8.5)):
        fig, (ax,), (r,) = _figure(8.5, 6.4)
        f = np.asarray(b["f_cy_per_px"], float)
        order = np.argsort(f)
        f = f[order]
        meas = np.asarray(b["ctf_measured"], float)[order]
        col = np.asarray(b["ctf_coltman_predicted"], float)[order]
        pap = np.asarray(b["ctf_fourier_synthesis_predicted"], float)[order]
        lim = float(b.get("compared_up_to_cy_per_px") or 0.2)
        cmp_ = f <= lim
        ax.plot(f, col, "-", color=PRED, lw=1.4, label="predicted CTF (Coltman)")
        ax.plot(f, pap, ":", color="tab:blue", lw=1.4, label="predicted, the paper's method")
        placed = _per_group(b.get("ctf_predicted_at_placement"), f.size)[order]  # a pushbroom image's, compared
        if np.isfinite(placed).any():
            ax.plot(f, placed, "D", color=PRED, mfc="none", ms=8, label="predicted at the image's placement (compared)")
            col = np.where(np.isfinite(placed), placed, col)
        ab = _per_group((b.get("as_built") or {}).get("ctf_coltman_predicted"), f.size)[order]
        if np.isfinite(ab).any():
            ax.plot(f, ab, ls=_AB_LS, color=AS_BUILT, lw=1.4, label="predicted as built (Coltman)")
        std = _per_group(b.get("ctf_std_measured"), f.size)[order]
        raw = _per_group(b.get("ctf_raw_measured"), f.size)[order]
        if np.isfinite(raw).any() and not np.allclose(raw, meas, equal_nan=True):
            ax.plot(f, raw, "x", color="0.35", ms=7, mew=1.5, label="measured raw (before the model correction)")
        ax.errorbar(f[cmp_], meas[cmp_], yerr=np.nan_to_num(std[cmp_]), fmt="o", color=MEAS, ms=7, capsize=3,
                    label="measured, corrected, compared (±1σ)")  # fmt: skip
        if (~cmp_).any():
            ax.errorbar(f[~cmp_], meas[~cmp_], yerr=np.nan_to_num(std[~cmp_]), fmt="o", color="gray", mfc="none",
                        ms=7, capsize=3, label="measured, not compared")  # fmt: skip
        for a in (ax, r):
            a.axvline(lim, color="tab:orange", ls="--", lw=1.2)
            a.axvspan(lim, max(0.55, float(f.max()) * 1.05), color="0.9", zorder=0)
            a.axvline(0.5, color="gray", lw=1)
        ax.text(
            lim,
            0.02,
            f"cut-off {lim:g} cy/px ({1 / lim:g} px per period):\nfiner groups are not compared ",
            color="tab:orange",
            va="bottom",
            ha="right",
        )
        _mark(ax, 0.5, "Nyquist", 0.4)
        groups = _per_group(b.get("group") or list(range(f.size)), f.size)[order]
        for fi, yi, g in zip(f, meas, groups, strict=True):  # each group by its index in the target's design
            if np.isfinite(yi) and np.isfinite(g):
                ax.annotate(f"g{int(g)}", (fi, yi), xytext=(0, 9), textcoords="offset points", ha="center",
                            color="0.3")  # fmt: skip
        bad = cmp_ & np.isfinite(meas) & (np.abs(meas - col) > (tol if tol is not None else np.inf))
        if bad.any():
            mark_failed(ax, f[bad], meas[bad], "FAIL: group outside the tolerance")
        ax.set_xlim(0, max(0.55, float(f.max()) * 1.05))
        ax.set_ylim(0, 1.15)
        ax.set_ylabel("CTF (bar modulation)")
        ax.set_title(f"Bar target {b['id']} ({b.get('direction', '')}): CTF per bar group")
        ax.legend(loc="upper right")
        r.errorbar(f[cmp_], (meas - col)[cmp_], yerr=np.nan_to_num(std[cmp_]), fmt="o", color=MEAS, ms=6, capsize=3)
        if (~cmp_).any():
            r.errorbar(f[~cmp_], (meas - col)[~cmp_], yerr=np.nan_to_num(std[~cmp_]), fmt="o", color="gray",
                       mfc="none", ms=6, capsize=3)  # fmt: skip
        r.fill_between([0, lim], -(tol or 0), tol or 0, color=TOL, alpha=0.15, label=f"tolerance ±{tol:g}")
        r.axhline(0, color="gray", lw=0.8)
        if bad.any():
            mark_failed(r, f[bad], (meas - col)[bad])
        _residual_limits(r, meas - col, std, tol)
        r.set_xlabel("bar frequency = 1 / period (cy/px)")
        r.set_ylabel("meas. - predicted" if np.isfinite(placed).any() else "meas. - Coltman")
        r.legend(loc="lower left")
        _save(fig, path)


def plot_wedge_comparison(w: dict, path: Path, *, tol_rel: float | None) -> None:
    """Wedge contrast against line width (wide end left), the threshold, the measured and predicted crossings
    and the tolerance band around the predicted resolution; the contrast residual below."""
    with matplotlib.rc_context(rc_for(8.5)):
        fig, (ax,), (r,) = _figure(8.5, 6.4)
        lw, meas, pred = w["line_width_m"], w["contrast_measured"], w["contrast_predicted"]
        thr, res, rp = w["threshold"], w.get("resolution_m"), w.get("resolution_predicted_m")
        ax.plot(lw, meas, color=MEAS, lw=1.4, label="measured contrast across the stripes")
        ax.plot(lw, pred, color=PRED, ls="--", lw=1.4, label="predicted (the same scan, noise-free predicted image)")
        ax.plot(lw, w["ctf_coltman_predicted"], color="gray", ls=":", lw=1, label="Coltman CTF (infinite square wave)")
        pab, rab = w.get("contrast_predicted_as_built"), w.get("resolution_predicted_as_built_m")
        if pab is not None and np.isfinite(np.asarray(pab, float)).any():
            lab = "predicted as built" + ("" if rab is None else f", resolution {rab * 100:.1f} cm")
            ax.plot(lw, pab, color=AS_BUILT, ls=_AB_LS, lw=1.4, label=lab)
            if rab is not None:
                ax.plot([rab], [thr], "D", color=AS_BUILT, mfc="none", ms=8)
        ax.axhline(thr, color="tab:orange", lw=1.2, label=f"threshold {thr:.0%}")
        for a in (ax, r):
            if rp is not None and np.isfinite(rp) and tol_rel:
                a.axvspan(rp * (1 - tol_rel), rp * (1 + tol_rel), color=TOL, alpha=0.15)
            _vline(a, rp, PRED, "--")
            _vline(a, res, MEAS, "-")
            a.axvline(w["gsd_m"], color="gray", lw=1, ls=":")
        if res is not None:
            ax.plot([res], [thr], "o", color=MEAS, ms=8, label=f"measured resolution {res * 100:.1f} cm")
        if rp is not None and np.isfinite(rp):
            lab = f"predicted {rp * 100:.1f} cm" + (f", band ±{tol_rel:.0%}" if tol_rel else "")
            ax.plot([rp], [thr], "D", color=PRED, mfc="none", ms=8, label=lab)
        if w.get("passed") is False and res is not None:
            mark_failed(ax, res, thr, "FAIL: resolution outside the band")
        _mark(ax, w["gsd_m"], f"GSD {w['gsd_m'] * 100:.0f} cm", 0.45)
        ax.set_xlim(float(np.max(lw)), float(np.min(lw)))
        ax.set_ylim(0, 1.05)
        ax.set_ylabel("contrast")
        ax.set_title(f"Hyperbolic wedge {w['id']} ({w.get('axis', '')}): the paper's contrast scan")
        ax.legend(loc="upper right")
        r.plot(lw, meas - pred, color=MEAS, lw=1)
        if pab is not None and np.isfinite(np.asarray(pab, float)).any():
            r.plot(lw, np.asarray(meas, float) - np.asarray(pab, float), color=AS_BUILT, ls=_AB_LS, lw=1)
        r.axhline(0, color="gray", lw=0.8)
        r.set_xlabel("line width (m); the scan runs from the wide end (left)")
        r.set_ylabel("meas. - pred.")
        _save(fig, path)
