"""Figures of a ``satchain run``: the scene (the paper's Figure 1), the simulated image with every region of
interest, the wedges at ground truth, focal plane and detector (the paper's Figure 4), and the measured vs
predicted comparisons (:mod:`satchain.report.compare_plots`). matplotlib's object API only (no pyplot)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from satchain.report import compare_plots as cp
from satchain.report._save import save_figure
from satchain.report._style import axis_band_in, place_grid, text_height_in, title_band_in
from satchain.report.compare_plots import rc_for
from satchain.report.kinds import EDGES, REPORT_KINDS, WEDGES

__all__ = [
    "plot_edges_overview",
    "plot_scene_overview",
    "draw_target_chain",
    "plot_target_chain",
    "target_chain_args",
    "render_scene_overview",
    "submit_edge_figures",
    "submit_measured_figures",
    "write_run_figures",
]


def render_scene_overview(scene, truth: dict, pixel_m: float, path: Path) -> None:
    """:func:`plot_scene_overview` of ``scene`` rendered at ``pixel_m`` (a job for a helper process)."""
    plot_scene_overview(scene.render(pixel_m=pixel_m), truth, pixel_m, path)


def plot_scene_overview(image: np.ndarray, truth: dict, pixel_m: float, path: Path) -> None:
    """The ground truth with every measurable target outlined and labelled (the paper's Figure 1)."""
    h, w = image.shape
    with matplotlib.rc_context(rc_for(8)):
        fig = Figure(figsize=(8, 8 * h / w + 0.8), dpi=100)  # a fixed layout in inches (_style.place_grid)
        ax = fig.add_axes((0, 0, 1, 1))
        ax.imshow(image, cmap="gray", vmin=0, vmax=1, extent=(0, w * pixel_m, h * pixel_m, 0), interpolation="nearest")
        for it in truth["items"]:
            if it["kind"] not in REPORT_KINDS:
                continue
            c = REPORT_KINDS[it["kind"]].colour
            x0, y0, x1, y1 = it["bbox_m"]
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec=c, lw=1))
            ax.text(x0, y0 - 1, it["id"], color=c, va="bottom")
        ax.set_xlabel("x, across-track (m)")
        ax.set_ylabel("y, along-track (m)")
        ax.set_title(f"Synthetic ground truth ({truth.get('scene', '')}), {truth['pixel_m'] * 100:g} cm pixels")
        place_grid(fig, [[ax]], top=title_band_in(), bottom=axis_band_in())
        save_figure(fig, path, dpi=100)


def _crop(image: np.ndarray, bbox_m, pixel_m: float) -> tuple[np.ndarray, tuple]:
    x0, y0, x1, y1 = bbox_m
    r0, c0 = max(int(y0 / pixel_m), 0), max(int(x0 / pixel_m), 0)
    r1, c1 = min(int(np.ceil(y1 / pixel_m)), image.shape[0]), min(int(np.ceil(x1 / pixel_m)), image.shape[1])
    return image[r0:r1, c0:c1], (c0 * pixel_m, c1 * pixel_m, r1 * pixel_m, r0 * pixel_m)


def plot_target_chain(ctx, item: dict, path: Path) -> None:
    """One target at ground truth, in the focal plane and on the detector (the paper's Figure 4a-c)."""
    draw_target_chain(*target_chain_args(ctx, item), path)


def target_chain_args(
    ctx, item: dict
) -> tuple[Any, dict, float, int, float, tuple[np.ndarray, tuple], tuple[np.ndarray, tuple]]:
    """The plain data :func:`draw_target_chain` needs (a job for a helper process): the scene (rendered there),
    the focal-plane and detector crops."""
    from satchain.report.gallery import _scene, mapped_box, panel_maps

    p, D, gsd = float(ctx.config.scene.pixel_m), int(ctx.simulator.D), float(ctx.image_gsd_m)
    maps = panel_maps(ctx)  # where each panel has the target (a pushbroom image's shear, scale or yaw)
    fp = _crop(ctx.focal_plane, mapped_box(maps["focal plane"], item["bbox_m"]), p * D)
    det = _crop(ctx.image, mapped_box(maps["detector"], item["bbox_m"]), gsd)
    return _scene(ctx), item, p, D, gsd, fp, det


def draw_target_chain(scene, item: dict, p: float, D: int, gsd: float, fp: tuple, det: tuple, path: Path) -> None:
    """:func:`plot_target_chain` from plain data (``fp``, ``det``: each crop with its extent)."""
    x0, y0, x1, y1 = item["bbox_m"]
    win = (int(y0 / p), int(x0 / p), max(int(np.ceil((y1 - y0) / p)), 1), max(int(np.ceil((x1 - x0) / p)), 1))
    gt = scene.render(win, pixel_m=p)
    gt_ext = (win[1] * p, (win[1] + win[3]) * p, (win[0] + win[2]) * p, win[0] * p)
    (fp, fp_ext), (det, det_ext) = fp, det
    aspect = (x1 - x0) / max(y1 - y0, 1e-9)
    with matplotlib.rc_context(rc_for(9)):
        # a fixed layout in inches (_style.place_grid)
        if aspect > 2:  # long targets (a wedge along x): panels one above the other
            fig = Figure(figsize=(9, 3 * min(9 / aspect, 4) + 1.6), dpi=100)
        elif aspect < 0.5:  # tall targets: side by side
            fig = Figure(figsize=(9, 7), dpi=100)
        else:
            fig = Figure(figsize=(9, 3.8), dpi=100)
        axes = [fig.add_axes((0, 0, 1, 1)) for _ in range(3)]
        panels = (
            (gt, gt_ext, f"(a) ground truth, {p * 100:g} cm"),
            (fp, fp_ext, f"(b) focal plane, {p * D * 100:g} cm samples"),
            (det, det_ext, f"(c) detector, GSD {gsd:.3g} m"),
        )
        for ax, (im, ext, title) in zip(axes, panels, strict=True):
            ax.imshow(im, cmap="gray", extent=ext, interpolation="nearest")
            ax.set_title(title)
            ax.set_xlabel("x (m)")
            ax.set_ylabel("y (m)")
        fig.suptitle(f"{item['kind'].replace('_', ' ')} {item['id']}")
        top = 0.02 * fig.get_figheight() + text_height_in("figure.titlesize") + title_band_in()
        grid = [[ax] for ax in axes] if aspect > 2 else [axes]
        place_grid(fig, grid, top=top, bottom=axis_band_in(), vgap=axis_band_in() + title_band_in())
        save_figure(fig, path, dpi=100)


def plot_edges_overview(edges: list[dict], path: Path) -> None:
    """Every slanted edge's measured e-SFR and predicted MTF on one plot."""
    with matplotlib.rc_context(rc_for(8)):
        fig = Figure(figsize=(8, 5), dpi=100)  # a fixed layout in inches (_style.place_grid)
        ax = fig.add_axes((0, 0, 1, 1))
        for i, e in enumerate(edges):
            c = f"C{i}"
            ax.plot(e["f_cy_per_px"], e["mtf_measured"], "-", color=c, label=f"{e['id']} measured")
            ax.plot(e["f_cy_per_px"], e["mtf_predicted"], "--", color=c, label=f"{e['id']} predicted")
        failed = [e for e in edges if e.get("pass") is False]
        if failed:  # each failing edge's measured MTF at Nyquist
            cp.mark_failed(ax, [0.5] * len(failed), [e.get("mtf_at_nyquist_measured") for e in failed],
                          "FAIL at Nyquist: " + ", ".join(str(e["id"]) for e in failed))  # fmt: skip
        ax.axvline(0.5, color="gray", lw=1)
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1.05)
        ax.set_xlabel("frequency along the edge normal (cycles/pixel)")
        ax.set_ylabel("MTF")
        ax.set_title("Slanted edges: measured (solid) vs predicted (dashed) MTF")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right")  # the MTFs fall from the top left
        place_grid(fig, [[ax]], top=title_band_in(), bottom=axis_band_in())
        save_figure(fig, path, dpi=100)


def submit_measured_figures(ctx, jobs) -> None:
    """Hand ``jobs`` the figures that the measurement alone decides (a run does so before it compares): the
    image with every measured region, and each measured wedge's chain (ground truth, focal plane, detector)."""
    from satchain.report.gallery import draw_image_with_rois, image_rois_args

    d = ctx.out / "figures"
    jobs.submit(draw_image_with_rois, *image_rois_args(ctx), d / "image_rois.png")
    measured = {w["id"] for w in (ctx.measured or {}).get(WEDGES.key, [])}  # each one is compared
    for item in ctx.truth["items"]:
        if item["kind"] == WEDGES.kind and item["id"] in measured:
            jobs.submit(draw_target_chain, *target_chain_args(ctx, item), d / f"fig4_wedge_{item['id']}.png")


def submit_edge_figures(ctx, edges: list[dict], jobs) -> None:
    """Hand ``jobs`` the slanted edges' figures: each edge's comparison (``edges``: its curves,
    :func:`satchain.report.curves.edge_curves`) and every edge's MTF on one plot. They read the edges' results
    alone, so a run hands them over before it compares the other targets."""
    d, tol = ctx.out / "figures", ctx.config.tolerances
    for c in edges:
        jobs.submit(cp.plot_edge_comparison, c, d / f"edge_{c['id']}.png", tol=tol.edge_mtf_at_nyquist)
    r = ctx.comparison["results"]
    if r.get(EDGES.key):
        jobs.submit(plot_edges_overview, r[EDGES.key], d / "edges_mtf.png")


def write_run_figures(ctx, curves: dict | None = None, *, jobs=None, measured_figures: bool = True,
                      edge_figures: bool = True) -> dict:  # fmt: skip
    """All run figures into ``ctx.out / "figures"``; returns the curves they show
    (:func:`satchain.report.curves.build_curves`, built here when not given). ``jobs``: a
    :class:`satchain.report._jobs.FigureJobs` that draws the figures made of plain data in helper processes (the
    caller waits for it); without it every figure is drawn here. ``measured_figures``, ``edge_figures``: False
    when :func:`submit_measured_figures`, :func:`submit_edge_figures` already handed those to ``jobs``."""
    from satchain.report._jobs import FigureJobs
    from satchain.report.curves import build_curves

    if jobs is None:
        with FigureJobs(0) as inline:
            return write_run_figures(
                ctx, curves, jobs=inline, measured_figures=measured_figures, edge_figures=edge_figures
            )
    d = ctx.out / "figures"
    curves = build_curves(ctx) if curves is None else curves
    tol = ctx.config.tolerances
    # plain data first: the helper processes start on them while the figures of live objects are drawn here
    if edge_figures:
        submit_edge_figures(ctx, curves["edges"], jobs)
    for st in curves["stars"]:
        jobs.submit(cp.plot_star_comparison, st, d / f"star_{st['id']}.png", tol=tol.star_mtf)
    for b in curves["bars"]:
        jobs.submit(cp.plot_bars_comparison, b, d / f"bars_{b['id']}.png", tol=tol.bar_ctf)
    for w in curves["wedges"]:
        jobs.submit(cp.plot_wedge_comparison, w, d / f"wedge_{w['id']}.png", tol_rel=tol.wedge_resolution_rel)
    tp = getattr(ctx.simulator, "time_path", None)
    if tp is not None:  # formed in time: the line of sight and each row's displacement
        from satchain.report.motion_plot import plot_line_of_sight

        measured = (ctx.measured or {}).get(EDGES.key, [])  # the summaries with per-line edge positions
        jobs.submit(plot_line_of_sight, tp, int(ctx.image.shape[0]), d / "line_of_sight.png", measured)
    if measured_figures:
        submit_measured_figures(ctx, jobs)
    jobs.start()
    return curves
