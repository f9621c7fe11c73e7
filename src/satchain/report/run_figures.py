"""Figures of a ``satchain run``: the scene (paper's Figure 1), each target at ground truth, focal plane and
detector (Figure 4 for the wedges), and measured-vs-predicted plots."""

from __future__ import annotations

from pathlib import Path

import numpy as np  # noqa: E402

from satchain.report._save import figure_api as plt  # no pyplot: no backend switch at import
from satchain.report._save import save_figure  # noqa: E402

__all__ = ["plot_scene_overview", "plot_target_chain", "write_run_figures"]

_KIND_COLOURS = {
    "slanted_edge": "tab:red",
    "bar_target": "tab:orange",
    "hyperbolic_wedge": "tab:green",
    "siemens_star": "tab:blue",
}


def plot_scene_overview(image: np.ndarray, truth: dict, pixel_m: float, path: Path) -> None:
    """The ground truth with every measurable target outlined and labelled (the paper's Figure 1)."""
    h, w = image.shape
    fig, ax = plt.subplots(figsize=(7, 7 * h / w + 0.6))
    ax.imshow(image, cmap="gray", vmin=0, vmax=1, extent=(0, w * pixel_m, h * pixel_m, 0), interpolation="nearest")
    for it in truth["items"]:
        c = _KIND_COLOURS.get(it["kind"])
        if c is None:
            continue
        x0, y0, x1, y1 = it["bbox_m"]
        ax.add_patch(plt.Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec=c, lw=1))
        ax.text(x0, y0 - 1, it["id"], color=c, fontsize=6, va="bottom")
    ax.set_xlabel("x, across-track (m)")
    ax.set_ylabel("y, along-track (m)")
    ax.set_title(f"Synthetic ground truth ({truth.get('scene', '')}), {truth['pixel_m'] * 100:g} cm pixels")
    fig.tight_layout()
    save_figure(fig, path, dpi=120)


def _crop(image: np.ndarray, bbox_m, pixel_m: float) -> tuple[np.ndarray, tuple]:
    x0, y0, x1, y1 = bbox_m
    r0, c0 = max(int(y0 / pixel_m), 0), max(int(x0 / pixel_m), 0)
    r1, c1 = min(int(np.ceil(y1 / pixel_m)), image.shape[0]), min(int(np.ceil(x1 / pixel_m)), image.shape[1])
    return image[r0:r1, c0:c1], (c0 * pixel_m, c1 * pixel_m, r1 * pixel_m, r0 * pixel_m)


def plot_target_chain(ctx, item: dict, path: Path) -> None:
    """One target at ground truth, in the focal plane and on the detector (the paper's Figure 4a-c)."""
    sc = ctx.config.scene
    x0, y0, x1, y1 = item["bbox_m"]
    p = sc.pixel_m
    win = (int(y0 / p), int(x0 / p), max(int(np.ceil((y1 - y0) / p)), 1), max(int(np.ceil((x1 - x0) / p)), 1))
    gt = ctx.scene.render(win, pixel_m=p)
    gt_ext = (win[1] * p, (win[1] + win[3]) * p, (win[0] + win[2]) * p, win[0] * p)
    fp, fp_ext = _crop(ctx.focal_plane, item["bbox_m"], p * ctx.simulator.D)
    det, det_ext = _crop(ctx.image, item["bbox_m"], ctx.system.gsd_act_m)
    aspect = (x1 - x0) / max(y1 - y0, 1e-9)
    if aspect > 2:  # long targets (a wedge along x): panels one above the other
        fig, axes = plt.subplots(3, 1, figsize=(11, 3 * min(11 / aspect, 4) + 1.2))
    else:
        fig, axes = plt.subplots(1, 3, figsize=(12, 4.2))
    panels = (
        (gt, gt_ext, f"(a) ground truth, {p * 100:g} cm"),
        (fp, fp_ext, f"(b) focal plane, {p * ctx.simulator.D * 100:g} cm samples"),
        (det, det_ext, f"(c) detector, GSD {ctx.system.gsd_act_m:.3g} m"),
    )
    for ax, (im, ext, title) in zip(axes, panels, strict=True):
        ax.imshow(im, cmap="gray", extent=ext, interpolation="nearest")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("x (m)")
    for ax in axes:
        ax.set_ylabel("y (m)")
    fig.suptitle(f"{item['kind']} {item['id']}")
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def _finish(fig, ax, path: Path, *, xlabel: str, ylabel: str, title: str, nyquist: bool = True, **legend) -> None:
    """Common decoration (Nyquist line, labels, grid, legend) and an atomic save."""
    if nyquist:
        ax.axvline(0.5, color="gray", lw=1)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, **legend)
    if fig is not None:
        fig.tight_layout()
        save_figure(fig, path, dpi=120)


def _plot_edges(edges: list[dict], path: Path) -> None:
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for i, e in enumerate(edges):
        c = f"C{i}"
        ax.plot(e["f_cy_per_px"], e["mtf_measured"], "-", color=c, label=f"{e['id']} measured")
        ax.plot(e["f_cy_per_px"], e["mtf_predicted"], "--", color=c, label=f"{e['id']} predicted")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.05)
    _finish(
        fig,
        ax,
        path,
        xlabel="frequency along the edge normal (cycles/pixel)",
        ylabel="MTF",
        title="Slanted edges: measured vs predicted MTF",
    )


def _plot_stars(stars: list[dict], path: Path) -> None:
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for st in stars:
        f = st["f_cy_per_px"]
        for i, (d, curve) in enumerate(st["mtf_measured"].items()):
            ax.plot(f, curve, ".", color=f"C{i}", ms=3, label=f"{d} measured")
            ax.plot(f, st["directions"][d]["mtf_predicted"], "-", color=f"C{i}", label=f"{d} predicted")
    ax.set_xlim(0, 0.8)
    ax.set_ylim(-0.05, 1.05)
    _finish(
        fig,
        ax,
        path,
        xlabel="frequency (cycles/pixel)",
        ylabel="MTF",
        title="Siemens star: MTF per direction, measured vs predicted",
        ncol=2,
    )


def _plot_bars(bars: list[dict], path: Path) -> None:
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    for i, b in enumerate(bars):
        c = f"C{i}"
        ax2.plot(
            b["f_cy_per_px"], b["mtf_from_ctf_measured"], "s", color=c, label=f"{b['id']} from CTF (inverse Coltman)"
        )
        ax2.plot(b["f_cy_per_px"], b["mtf_predicted"], "-", color=c, label=f"{b['id']} predicted MTF")
    _finish(
        None,
        ax2,
        path,
        xlabel="bar frequency (cycles/pixel)",
        ylabel="MTF",
        title="Bar targets: MTF derived from the measured CTF",
    )
    for i, b in enumerate(bars):
        c = f"C{i}"
        ax.plot(b["f_cy_per_px"], b["ctf_measured"], "o", color=c, label=f"{b['id']} measured CTF")
        ax.plot(
            b["f_cy_per_px"],
            b["ctf_coltman_predicted"],
            "-",
            color=c,
            label=f"{b['id']} Coltman CTF (predicted)",
        )
        ax.plot(
            b["f_cy_per_px"],
            b["ctf_fourier_synthesis_predicted"],
            ":",
            color=c,
            label=f"{b['id']} paper's method",
        )
    _finish(
        fig,
        ax,
        path,
        xlabel="bar frequency (cycles/pixel)",
        ylabel="CTF",
        title="Bar targets: measured vs predicted square-wave response",
    )


def _plot_wedges(wedges: list[dict], path: Path) -> None:
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for i, w in enumerate(wedges):
        if w.get("contrast") is None:
            continue
        x = w.get("position_m") or list(range(len(w["contrast"])))
        ax.plot(
            x,
            w["contrast"],
            color=f"C{i}",
            label=f"{w['id']} ({w['axis']}): {w['resolution_m'] or float('nan'):.3g} m",
        )
    if wedges:
        ax.axhline(wedges[0].get("threshold") or 0.15, color="k", ls="--", lw=1, label="threshold")
    _finish(
        fig,
        ax,
        path,
        xlabel="position along the wedge (m)",
        ylabel="contrast across the stripes",
        title="Hyperbolic wedges: the paper's contrast scan",
        nyquist=False,
    )


def write_run_figures(ctx) -> None:
    """All run figures into ``ctx.out / "figures"``."""
    d = ctx.out / "figures"
    r = ctx.comparison["results"]
    measured_ids = {
        e["id"] for key in ("slanted_edges", "siemens_star", "bar_targets", "hyperbolic_wedge") for e in r[key]
    }
    for item in ctx.truth["items"]:
        if item["id"] in measured_ids:
            name = "fig4_wedge_" + item["id"] if item["kind"] == "hyperbolic_wedge" else "target_" + item["id"]
            plot_target_chain(ctx, item, d / f"{name}.png")
    if r["slanted_edges"]:
        _plot_edges(r["slanted_edges"], d / "edges_mtf.png")
    if r["siemens_star"]:
        _plot_stars(r["siemens_star"], d / "star_mtf.png")
    if r["bar_targets"]:
        _plot_bars(r["bar_targets"], d / "bars_ctf.png")
    if r["hyperbolic_wedge"]:
        _plot_wedges(r["hyperbolic_wedge"], d / "wedge_contrast.png")
