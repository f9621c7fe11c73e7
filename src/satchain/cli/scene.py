"""``satchain scene``: render a synthetic ground-truth scene exactly (area coverage), tile by tile, to a TIFF with
a ``.png`` preview and a ``.truth.json`` beside it (:func:`satchain.scene.render_scene_to_file`).

Registered on the app by :mod:`satchain.cli.main`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from satchain._safety import check_disk, check_distinct_paths, check_memory, check_output_files, check_sidecars
from satchain.cli._common import console, handle_errors, progress_bar
from satchain.errors import ConfigError

__all__ = ["scene"]


@handle_errors
def scene(
    layout: Annotated[str, typer.Option("--layout", help="'paper' or a scene file (.toml/.json)")] = "paper",
    pixel_m: Annotated[
        float | None,
        typer.Option(
            "--pixel-m",
            help="ground pixel size, m (default: the layout's); objects smaller than "
            "the GSD need about GSD/28 for 1e-3 of their image's peak",
        ),
    ] = None,
    window: Annotated[str | None, typer.Option("--window", help="X0,Y0,W,H in pixels (X0 = column)")] = None,
    *,
    out: Annotated[Path, typer.Option("-o", "--out", help="output TIFF; a .png preview and .truth.json go beside it")],
) -> None:
    """Render a synthetic ground-truth scene exactly (area coverage), tile by tile."""
    from satchain.scene import parse_cli_window, render_scene_to_file

    win = parse_cli_window(window) if window else None
    stem = out.with_suffix("") if out.suffix.lower() in (".tif", ".tiff") else out
    layout_file = None if layout == "paper" else layout
    check_output_files({"-o": out})
    check_distinct_paths(
        {"-o": out, "-o (preview)": f"{stem}.png", "-o (truth)": f"{stem}.truth.json"}, {"--layout": layout_file}
    )
    check_sidecars({"-o (preview)": f"{stem}.png", "-o (truth)": f"{stem}.truth.json"})
    _check_scene_size(layout, pixel_m, win, out)
    out.parent.mkdir(parents=True, exist_ok=True)
    bar, update = progress_bar("rendering scene")
    with bar:
        written = render_scene_to_file(layout, out, pixel_m=pixel_m, window=win, progress=update)
    for kind, path in written.items():
        console.print(f"wrote {kind}: {path}", markup=False, highlight=False)


def _check_scene_size(layout: str, pixel_m: float | None, win, out: Path) -> None:
    """Refuse a render that cannot fit (the TIFF on disk, its tile index in memory) before writing anything."""
    from satchain._validate import check_positive
    from satchain.scene import load_layout

    sc = load_layout(layout)
    p = sc.pixel_m if pixel_m is None else check_positive("--pixel-m", pixel_m)
    full = sc.shape_px(p)
    if win is not None and (win[0] < 0 or win[1] < 0 or win[0] + win[2] > full[0] or win[1] + win[3] > full[1]):
        raise ConfigError(
            f"--window {win[1]},{win[0]},{win[3]},{win[2]} (X0,Y0,W,H): outside the scene, which is {full[1]} x "
            f"{full[0]} px (W x H) at --pixel-m {p:g}"
        )
    rows, cols = full if win is None else win[2:]
    what = f"scene {rows} x {cols} px at --pixel-m {p:g}"
    fix = "use a larger --pixel-m or a --window"
    check_memory(4096.0 * (rows / 256 + 1) * (cols / 256 + 1) + 8 * 2**20, what, fix=fix)  # tile index
    check_disk(4.0 * rows * cols, [out], what, fix=fix)
