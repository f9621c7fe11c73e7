"""The ``satchain`` command line: thin wrappers that parse arguments, call the library and print."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table
from rich.text import Text

from satchain._cli_common import console, err_console, handle_errors, parse_numbers, print_warning, set_debug
from satchain._safety import (
    check_dir_outputs,
    check_disk,
    check_distinct_paths,
    check_inputs_outside,
    check_memory,
    check_output_files,
    check_sidecars,
)
from satchain.engine.memory import check_simulation_memory
from satchain.engine.stream import choose_streamed
from satchain.errors import ConfigError

app = typer.Typer(
    name="satchain",
    help="Satellite image-chain simulation and image-quality measurement.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

PresetOpt = Annotated[str | None, typer.Option("--preset", help="packaged system preset, e.g. ankarasat3")]
SystemOpt = Annotated[Path | None, typer.Option("--system", help="system TOML file")]


_handle_errors = handle_errors


@app.callback()
def _main(
    debug: Annotated[bool, typer.Option("--debug", help="show the traceback of an error (for bug reports)")] = False,
) -> None:
    """Satellite image-chain simulation and image-quality measurement."""
    set_debug(debug or os.environ.get("SATCHAIN_DEBUG", "") not in ("", "0"))


def _system(preset: str | None, system: Path | None):
    from satchain.system import load_preset, load_system

    if preset and system:
        raise ConfigError(f"--preset {preset!r} and --system {str(system)!r}: give one, not both")
    if system is not None:
        return load_system(system)
    return load_preset(preset or "ankarasat3")


def _parse_floats(name: str, text: str | None) -> list[float] | None:
    return None if text is None else parse_numbers(name, text, minimum=0.0)


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list):
        return ", ".join(_fmt(x) for x in v)
    return str(v)


def _print_budget(res: dict[str, Any]) -> None:
    t = Table(title=f"{res['system']}: derived quantities", show_header=True)
    t.add_column("quantity")
    t.add_column("value")
    for k, v in res["derived"].items():
        t.add_row(k, _fmt(v))
    console.print(t)
    for d in ("alt", "act"):
        name = "ALT (along-track, f_y)" if d == "alt" else "ACT (across-track, f_x)"
        comps = list(res["mtf"][d])
        t = Table(title=f"MTF and CTF budget, {name}")
        for c in ["f cy/mm", "f cy/px", "f cy/m gnd", *comps, "CTF Coltman", "CTF paper"]:
            t.add_column(c, justify="right")
        cols = [
            res["frequencies_cy_per_mm"],
            res["frequencies_cy_per_px"][d],
            res["frequencies_cy_per_m_ground"][d],
            *[res["mtf"][d][c] for c in comps],
            res["ctf"][d]["coltman"],
            res["ctf"][d]["fourier_synthesis"],
        ]
        for row in zip(*cols, strict=True):
            t.add_row(*[f"{v:.4f}" for v in row])
        console.print(t)
    ny = res["mtf_at_nyquist"]
    console.print(
        f"MTF at Nyquist: ALT {ny['alt']:.4f}, ACT {ny['act']:.4f}   "
        f"MTFA (0..Nyquist, cy/px): ALT {res['mtfa']['alt']:.4f}, ACT {res['mtfa']['act']:.4f}"
    )
    for key in ("radiometry", "quality"):
        if key in res:
            console.print(
                f"[bold]{key}[/]: "
                + ", ".join(f"{k}={_fmt(v)}" for k, v in res[key].items() if not isinstance(v, (list, dict)))
            )


def _budget(system_obj, freqs: list[float] | None) -> dict[str, Any]:
    from satchain.report.budget import budget_results

    return budget_results(system_obj, freqs)


@app.command()
@_handle_errors
def budget(
    preset: PresetOpt = None,
    system: SystemOpt = None,
    freqs: Annotated[
        str | None, typer.Option("--freqs", help="focal-plane frequencies in cy/mm, e.g. 10,42.5,85")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON instead of tables")] = False,
    out: Annotated[Path | None, typer.Option("-o", "--out", help="also write CSV tables, JSON and plots here")] = None,
) -> None:
    """Predicted MTF/CTF budget, derived quantities (GSD, Nyquist, Q, ...) of a system."""
    check_dir_outputs(out, ["*.json", "*.csv", "*.png"], {"--system": system})
    s = _system(preset, system)
    res = _budget(s, _parse_floats("--freqs", freqs))
    if out is not None:
        from satchain.report.budget import write_budget_outputs

        written = write_budget_outputs(s, res, out)
        if not as_json:
            console.print("wrote " + ", ".join(str(p) for p in written), markup=False, highlight=False)
    if as_json:
        print(json.dumps(res, indent=2))
    else:
        _print_budget(res)


def _progress(description: str):
    """A rich progress bar and the ``progress(done, total)`` callback that drives it."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    bar = Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=err_console,
        transient=False,
        disable=not err_console.is_terminal,  # no bar in logs and pipes: an error stays one line
    )
    task = bar.add_task(description, total=None)

    def update(done: int, total: int) -> None:
        bar.update(task, completed=done, total=total)

    return bar, update


@app.command()
@_handle_errors
def scene(
    layout: Annotated[str, typer.Option("--layout", help="'paper' or a scene file (.toml/.json)")] = "paper",
    pixel_m: Annotated[
        float | None, typer.Option("--pixel-m", help="ground pixel size, m (default: the layout's)")
    ] = None,
    window: Annotated[str | None, typer.Option("--window", help="X0,Y0,W,H in pixels (X0 = column)")] = None,
    out: Annotated[
        Path, typer.Option("-o", "--out", help="output TIFF; a .png preview and .truth.json go beside it")
    ] = ...,
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
    bar, update = _progress("rendering scene")
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


_IMAGE_SUFFIXES = (".tif", ".tiff", ".png", ".npy")
#: reflectance an image input may hold after scaling (glints above 1 allowed; 255 or 65535 are not reflectance)
REFLECTANCE_RANGE = (-0.5, 4.0)


def _ground_truth(input_: str, scene_pixel_m: float | None, input_scale: float | None = None):
    from satchain.engine.sources import SceneSource
    from satchain.scene import ImageScene, load_layout

    if Path(input_).suffix.lower() in _IMAGE_SUFFIXES:
        img = ImageScene(input_, pixel_m=scene_pixel_m, scale=input_scale, valid_range=REFLECTANCE_RANGE)
        return SceneSource(img), None
    if input_scale is not None:
        raise ConfigError(f"--input-scale {input_scale:g}: applies to image inputs only, not to scene {input_!r}")
    sc = load_layout(input_)
    return SceneSource(sc, pixel_m=scene_pixel_m), sc


@app.command()
@_handle_errors
def simulate(
    input_: Annotated[str, typer.Argument(metavar="INPUT", help="'paper', a scene file, or an image (TIFF/PNG/NPY)")],
    scene_pixel_m: Annotated[
        float | None, typer.Option("--scene-pixel-m", help="ground pixel size of INPUT, m")
    ] = None,
    preset: PresetOpt = None,
    system: SystemOpt = None,
    units_: Annotated[str, typer.Option("--units", help="dn | electrons | radiance | reflectance")] = "dn",
    no_noise: Annotated[bool, typer.Option("--no-noise", help="no noise (deterministic)")] = False,
    seed: Annotated[int, typer.Option("--seed", help="noise seed")] = 0,
    focal_plane: Annotated[Path | None, typer.Option("--focal-plane", help="also write the focal-plane image")] = None,
    fp_grid: Annotated[
        str, typer.Option("--focal-plane-grid", help="input: on the input grid (exact); coarse: every D-th pixel")
    ] = "input",
    scheduler: Annotated[str | None, typer.Option("--scheduler", help="Dask scheduler address, or 'local'")] = None,
    input_scale: Annotated[
        float | None,
        typer.Option(
            "--input-scale",
            help="multiply image values by this to get reflectance (default: integer images / (2^bits - 1), "
            "so 8-bit 255 and 16-bit 65535 are reflectance 1; float images as they are)",
        ),
    ] = None,
    out: Annotated[Path, typer.Option("-o", "--out", help="output TIFF")] = ...,
) -> None:
    """Simulate the satellite image of a scene or an image (exact, tiled, any size)."""
    import numpy as np

    from satchain import io
    from satchain._validate import check_choice
    from satchain.engine.sensor import OUTPUT_UNITS, sensor_from_system
    from satchain.engine.simulate import Simulator

    check_choice("--units", units_, OUTPUT_UNITS)
    check_choice("--focal-plane-grid", fp_grid, ("input", "coarse"))
    if seed < 0:
        raise ConfigError(f"--seed {seed}: must be >= 0")
    in_file = input_ if Path(input_).exists() else None
    check_output_files({"-o": out, "--focal-plane": focal_plane})
    check_distinct_paths(
        {"-o": out, "-o (preview)": out.with_suffix(".png"), "--focal-plane": focal_plane},
        {"INPUT": in_file, "--system": system},
    )
    check_sidecars({"-o (preview)": out.with_suffix(".png")})
    s = _system(preset, system)
    src, _ = _ground_truth(input_, scene_pixel_m, input_scale)
    sensor = sensor_from_system(s) if (units_ != "reflectance" or not no_noise) else None
    sim = Simulator(s, input_pixel_m=src.pixel_m, input_shape=src.shape_px)
    fp = fp_grid if focal_plane is not None else None
    streamed = choose_streamed(sim, focal_plane=fp)
    if not streamed:
        check_simulation_memory(sim, focal_plane=fp)
        sim.check_frame()
    if min(src.shape_px) < 8:
        raise ConfigError(
            f"INPUT {input_!r} at {src.pixel_m:g} m per pixel is only {src.shape_px[0]} x {src.shape_px[1]} px; a "
            "ground truth needs at least 8 px a side: check --scene-pixel-m"
        )
    out.parent.mkdir(parents=True, exist_ok=True)
    meta = {
        "system": s.name,
        "seed": seed,
        "noise": not no_noise,
        "gsd_act_m": s.gsd_act_m,
        "gsd_alt_m": s.gsd_alt_m,
        "input": str(input_),
        "input_pixel_m": src.pixel_m,
    }
    bits = sensor.bit_depth if sensor is not None else s.detector.bit_depth
    if streamed:
        _simulate_streamed(
            sim,
            src,
            out,
            sensor=sensor,
            units=units_,
            noise=not no_noise,
            seed=seed,
            bits=bits,
            meta=meta,
            scheduler=scheduler,
        )
        return
    if focal_plane is not None:
        focal_plane.parent.mkdir(parents=True, exist_ok=True)
    bar, update = _progress(f"simulating {src.shape_px[0]}x{src.shape_px[1]} px")
    with bar:
        if scheduler is not None:
            from satchain.engine.distributed import decimate_distributed

            coarse = decimate_distributed(sim, src, scheduler=scheduler, progress=update)
        else:
            coarse = sim.decimate(src, progress=update)
    img = sim.run(src, sensor=sensor, units=units_, noise=not no_noise, seed=seed, coarse=coarse)
    io.write_simulated(out, img, units=units_, bit_depth=bits, pixel_m=s.gsd_act_m, metadata=meta)
    console.print(
        f"wrote {out} ({img.shape[0]} x {img.shape[1]} px, {units_}) and {out.with_suffix('.png')}",
        markup=False,
        highlight=False,
    )
    if focal_plane is not None:
        fp = sim.focal_plane(coarse, grid=fp_grid)
        fp_pixel = src.pixel_m * (sim.D if fp_grid == "coarse" else 1)
        meta = {"units": "input (reflectance) filtered by the optics and motion", "system": s.name, "grid": fp_grid}
        io.write_tiff(focal_plane, fp.astype(np.float32), pixel_m=fp_pixel, metadata=meta)
        console.print(f"wrote {focal_plane} (focal-plane image, {fp_pixel:g} m samples)", markup=False, highlight=False)


def _simulate_streamed(sim, src, out: Path, *, sensor, units: str, noise: bool, seed: int, bits, meta, scheduler):
    """``satchain simulate`` for an input whose coarse frame does not fit in memory: the coarse grid on disk
    beside ``out``, stage 2 tile by tile, the image written band by band (:mod:`satchain.engine.stream`)."""
    from satchain._safety import check_disk, clean_stale, memory_limit_bytes
    from satchain.engine.stream import coarse_store, stream_bytes, stream_tile_px, write_streamed
    from satchain.io import simulated_dtype

    ny, nx = sim.n_coarse
    oy, ox = sim.output_shape
    image_bytes = float(oy) * ox * simulated_dtype(units, bits).itemsize
    check_disk(4.0 * ny * nx + image_bytes, [out], f"streaming {sim.input_shape[0]} x {sim.input_shape[1]} input px")
    clean_stale(out)  # scratch folders of killed runs
    t, m = stream_tile_px(sim), sim.params.stream_margin_px
    console.print(
        f"streamed: the full-frame path would exceed the memory limit ({memory_limit_bytes() / 2**30:.1f} GiB); "
        f"the coarse grid ({ny} x {nx}, {4.0 * ny * nx / 2**30:.2f} GiB) goes to disk beside {out}, the image is "
        f"formed in {t} x {t} px tiles with {m} px margins (about {stream_bytes(sim) / 2**30:.2f} GiB of memory)",
        markup=False,
        highlight=False,
    )
    with coarse_store(sim, out.parent, prefix=f".{out.name}.staging-") as coarse:
        bar, update = _progress(f"stage 1: {sim.input_shape[0]}x{sim.input_shape[1]} px")
        with bar:
            if scheduler is not None:
                from satchain.engine.distributed import decimate_distributed

                decimate_distributed(sim, src, scheduler=scheduler, progress=update, out=coarse)
            else:
                sim.decimate(src, progress=update, out=coarse)
        bar, update = _progress(f"stage 2: {oy}x{ox} px in {t}-px tiles")
        with bar:
            write_streamed(
                out,
                sim,
                coarse,
                sensor=sensor,
                units=units,
                noise=noise,
                seed=seed,
                bit_depth=bits,
                pixel_m=sim.system.gsd_act_m,
                metadata=meta,
                progress=update,
            )
    console.print(
        f"wrote {out} ({oy} x {ox} px, {units}, streamed) and {out.with_suffix('.png')} (subsampled preview)",
        markup=False,
        highlight=False,
    )


def _print_run(result) -> None:
    from satchain.comparison import row_texts

    c = result.comparison
    t = Table(title=f"{result.system.name}: measured vs predicted ({c.n_checked - c.n_failed}/{c.n_checked} pass)")
    cols = ("measured", "predicted", "error", "sigma", "z", "tolerance")
    t.add_column("figure of merit", justify="left")
    for col in (*cols, "result"):
        t.add_column(col, justify="right")
    for r in c.rows:
        cells = row_texts(r)
        style = {None: "", True: "green", False: "red"}[r.passed]
        verdict = Text(cells["result"], style=style)
        if r.tolerance_inside_noise:
            verdict.stylize("yellow", len(cells["result"].split(" (")[0]))
        t.add_row(Text(r.figure), *(cells[k] for k in cols), verdict)
    console.print(t)
    for r in c.rows:
        if r.passed is None and r.reason:
            err_console.print(Text("n/a: ", style="bold") + Text(f"{r.figure}: {r.reason}"), highlight=False)
    for w in result.warnings:
        print_warning(w)


@app.command()
@_handle_errors
def run(
    preset: PresetOpt = None,
    config: Annotated[Path | None, typer.Option("--config", help="run configuration TOML (see --print-config)")] = None,
    out: Annotated[Path, typer.Option("-o", "--out", help="output directory (replaced atomically)")] = Path(
        "satchain-run"
    ),
    print_config: Annotated[
        bool, typer.Option("--print-config", help="print the default configuration and exit")
    ] = False,
    exit_zero: Annotated[
        bool, typer.Option("--exit-zero", help="exit 0 even when a check fails (default: exit 1, to gate CI)")
    ] = False,
) -> None:
    """The main job: predict, simulate, measure, compare and report (report.html, results.json).

    Exit status: 0 when every check passes or is n/a, 1 when a check fails (unless --exit-zero), 2 on an error.
    """
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    import satchain
    from satchain.pipeline import STAGES
    from satchain.runconfig import DEFAULT_CONFIG_TOML, RunConfig, load_run_config

    if print_config:
        print(DEFAULT_CONFIG_TOML, end="")
        return
    cfg = load_run_config(config)
    check_inputs_outside(out, {"--config": config, "system.file": cfg.system_path()})
    if preset is not None:
        cfg = RunConfig.from_dict({**cfg.to_dict(), "system": {"preset": preset}}, base_dir=cfg.base_dir)
    bar = Progress(
        TextColumn("[bold]{task.description:<9}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeElapsedColumn(),
        console=err_console,
        disable=not err_console.is_terminal,
    )
    tasks = {name: bar.add_task(name, total=None, start=False) for name in STAGES}

    def update(stage: str, done: int, total: int) -> None:
        bar.start_task(tasks[stage])
        bar.update(tasks[stage], completed=done, total=total)

    with bar:
        result = satchain.run(cfg, out_dir=out, progress=update)
    _print_run(result)
    console.print(f"report: {out / 'report.html'}   results: {out / 'results.json'}", markup=False, highlight=False)
    if result.passed is False and not exit_zero:
        n = result.comparison.n_failed
        err_console.print(f"[bold red]{n} check(s) failed[/] (exit status 1; --exit-zero to ignore)")
        raise typer.Exit(1)


from satchain.cli_measure import measure_app  # noqa: E402

app.add_typer(measure_app, name="measure", help="Measure image quality: edge, star, bars, wedge, auto, find.")


def main() -> None:  # pragma: no cover
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
