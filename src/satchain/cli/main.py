"""The ``satchain`` command line: thin wrappers that parse arguments, call the library and print."""

from __future__ import annotations

import satchain.cli._startup  # noqa: F401 (first: SIGTERM answered from the first import on)

# isort: split
import json
import os
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table
from rich.text import Text

from satchain.cli._common import (
    ReflowGroup,
    console,
    err_console,
    handle_errors,
    parse_numbers,
    print_warning,
    set_debug,
)
from satchain._safety import (
    check_dir_outputs,
    check_disk,
    check_distinct_paths,
    check_inputs_outside,
    check_memory,
    check_output_files,
    check_run_dir,
    check_sidecars,
    terminate_as_interrupt,
)
from satchain.cli.options import BandsOpt
from satchain.errors import ConfigError

app = typer.Typer(
    name="satchain",
    help="Satellite image-chain simulation and image-quality measurement.",
    cls=ReflowGroup,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

PresetOpt = Annotated[str | None, typer.Option("--preset", help="packaged system preset, e.g. ankarasat3")]
SystemOpt = Annotated[Path | None, typer.Option("--system", help="system TOML file")]


_handle_errors = handle_errors


def _handles_interrupts(fn):
    """A command that answers SIGTERM itself once it writes (satchain._safety.terminate_as_interrupt): the
    start-up's answer ("nothing was written") stays until then."""
    fn.handles_interrupts = True
    return fn


@app.callback()
def _main(
    ctx: typer.Context,
    debug: Annotated[bool, typer.Option("--debug", help="show the traceback of an error (for bug reports)")] = False,
) -> None:
    """Satellite image-chain simulation and image-quality measurement."""
    set_debug(debug or os.environ.get("SATCHAIN_DEBUG", "") not in ("", "0"))
    _show_warnings(ctx)


def _show_warnings(ctx: typer.Context) -> None:
    """While a command runs, print satchain's warnings (an input used other than as it stands) as one
    ``warning: ...`` line each, once; other warnings as Python shows them."""
    import warnings

    from satchain.errors import SatchainWarning

    previous, seen = warnings.showwarning, set()

    def show(message, category, filename, lineno, file=None, line=None):
        if not issubclass(category, SatchainWarning):
            return previous(message, category, filename, lineno, file, line)
        if str(message) not in seen:
            seen.add(str(message))
            print_warning(str(message))

    warnings.showwarning = show
    ctx.call_on_close(lambda: setattr(warnings, "showwarning", previous))


def _system(preset: str | None, system: Path | None):
    from satchain.config.system import load_preset, load_system

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
        # the detector pixel's axis (an image with a line-rate error or Earth rotation has its rows alt_scale px
        # apart: motion_geometry; `run` predicts on the image's axis); motion terms are signed expected OTFs
        t = Table(title=f"MTF and CTF budget, {name}; f on the detector pixel's axis, motion terms signed")
        for c in ["f cy/mm", "f cy/det px", "f cy/m gnd", *comps, "CTF Coltman", "CTF paper"]:
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
    if "motion_geometry" in res:
        _print_motion_geometry(res["motion_geometry"])
    for key in ("radiometry", "quality"):
        if key in res:
            console.print(
                f"[bold]{key}[/]: "
                + ", ".join(f"{k}={_fmt(v)}" for k, v in res[key].items() if not isinstance(v, (list, dict)))
            )


def _print_motion_geometry(g: dict[str, Any]) -> None:
    """The pushbroom motion's geometry (satchain.tf.pushbroom): one row per quantity, nested ones flattened."""
    t = Table(title="pushbroom motion geometry (TDI window, line displacement, Earth rotation)")
    t.add_column("quantity")
    t.add_column("value")

    def rows(prefix: str, v: Any) -> None:
        if isinstance(v, dict):
            for k, item in v.items():
                rows(f"{prefix}.{k}" if prefix else k, item)
        elif isinstance(v, list):
            for i, item in enumerate(v):
                rows(f"{prefix}[{i}]", item)
        else:
            t.add_row(prefix, _fmt(v))

    rows("", g)
    console.print(t)


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
    if out is not None:
        check_run_dir(out, kind="budget")  # a user's folder (their budget.json) is refused, never overwritten
    s = _system(preset, system)
    res = _budget(s, _parse_floats("--freqs", freqs))
    if out is not None:
        from satchain._safety import write_run_marker
        from satchain.report.budget import write_budget_outputs

        out.mkdir(parents=True, exist_ok=True)
        write_run_marker(out, kind="budget")  # satchain's own: a later budget -o may write here again
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
        float | None,
        typer.Option(
            "--pixel-m",
            help="ground pixel size, m (default: the layout's); objects smaller than "
            "the GSD need about GSD/28 for 1e-3 of their image's peak",
        ),
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


class _StageBars:
    """``progress(stage, done, total)`` shown as one rich progress bar per stage (see :func:`_progress`)."""

    def __init__(self) -> None:
        self._stage: str | None = None
        self._bar = self._update = None

    def __call__(self, stage: str, done: int, total: int) -> None:
        if stage != self._stage:
            self.close()
            self._bar, self._update = _progress(stage)
            self._bar.start()
            self._stage = stage
        self._update(done, total)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()
        self._stage, self._bar = None, None


@app.command()
@_handle_errors
@_handles_interrupts
def simulate(
    inputs: Annotated[
        list[str],
        typer.Argument(metavar="INPUT", help="'paper', a scene file, or an image (TIFF/PNG/NPY); one or more"),
    ],
    scene_pixel_m: Annotated[
        float | None,
        typer.Option(
            "--scene-pixel-m",
            help="ground pixel size of INPUT, m; a scene's objects smaller than "
            "the GSD need about GSD/28 for 1e-3 of their image's peak",
        ),
    ] = None,
    preset: PresetOpt = None,
    system: SystemOpt = None,
    units_: Annotated[str, typer.Option("--units", help="dn | electrons | radiance | reflectance")] = "dn",
    no_noise: Annotated[bool, typer.Option("--no-noise", help="no noise (deterministic)")] = False,
    seed: Annotated[int, typer.Option("--seed", help="noise seed (a sweep derives one per case from it)")] = 0,
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
    band: BandsOpt = None,
    sweep: Annotated[
        list[str] | None,
        typer.Option(
            "--sweep",
            help="KEY=V1,V2,...: one case per value of a system key, e.g. motion.smear_px=0.5,1,2 (repeat for "
            "the cartesian product); -o is then a directory with one image per case and a manifest",
        ),
    ] = None,
    out: Annotated[
        Path, typer.Option("-o", "--out", help="output TIFF (a directory with several inputs or --sweep)")
    ] = ...,
) -> None:
    """Simulate the satellite image of a scene or an image (exact, tiled, any size); with several inputs or
    --sweep, one image per case into the -o directory, with manifest.json / manifest.csv."""
    from satchain.engine._malloc import keep_freed_memory
    from satchain.engine.files import simulate_file

    keep_freed_memory()  # this process is ours: tile buffers reused, not faulted in anew

    system_obj = _system(preset, system)
    if len(inputs) > 1 or sweep:
        from satchain.cli.sweep import simulate_cases

        options = dict(scene_pixel_m=scene_pixel_m, input_scale=input_scale, units=units_, noise=not no_noise,
                       scheduler=scheduler, band=band)  # fmt: skip
        return simulate_cases(inputs, out, system_obj, sweep_texts=sweep or [], seed=seed,
                              focal_plane=focal_plane, options=options, names=_SIMULATE_OPTIONS)  # fmt: skip
    input_ = inputs[0]
    check_distinct_paths({"-o": out, "--focal-plane": focal_plane}, {"--system": system})
    from satchain.io._commit import CommitState, committed_together

    bars, commit = _StageBars(), CommitState()
    try:
        with terminate_as_interrupt() as received:  # SIGTERM as Ctrl-C: the staging files are removed, as by run

            def progress(stage: str, done: int, total: int) -> None:
                received.check()  # a signal whose exception library code swallowed stops it here
                bars(stage, done, total)

            with committed_together(received.check) as commit:  # image, preview, focal plane: all or none
                r = simulate_file(
                    input_, out, system_obj, scene_pixel_m=scene_pixel_m, input_scale=input_scale,
                    units=units_, noise=not no_noise, seed=seed, focal_plane=focal_plane, focal_plane_grid=fp_grid,
                    scheduler=scheduler, progress=progress, notify=_say, names=_SIMULATE_OPTIONS, band=band,
                )  # fmt: skip
    except KeyboardInterrupt as exc:
        bars.close()
        outputs = [out, out.with_suffix(".png"), *([focal_plane] if focal_plane is not None else [])]
        raise typer.Exit(_interrupted_simulation(exc, outputs, commit.committed)) from None
    finally:
        bars.close()
    how = ", streamed" if r.streamed else ""
    preview = " (subsampled preview)" if r.streamed else ""
    bands = f" x {r.count} bands" if r.count > 1 else ""
    geo = f", {r.crs.to_string() or 'CRS'}" if r.crs is not None else ""
    _say(f"wrote {r.path} ({r.shape_px[0]} x {r.shape_px[1]} px{bands}, {r.units}{geo}{how}) and {r.preview}{preview}")
    if r.focal_plane_path is not None:
        _say(f"wrote {r.focal_plane_path} (focal-plane image, {r.focal_plane_pixel_m:g} m samples)")


#: satchain.engine.files.simulate_file's parameters as `satchain simulate` names them in its messages
_SIMULATE_OPTIONS = {
    "input": "INPUT",
    "out": "-o",
    "focal_plane": "--focal-plane",
    "focal_plane_grid": "--focal-plane-grid",
    "scene_pixel_m": "--scene-pixel-m",
    "input_scale": "--input-scale",
    "units": "--units",
    "seed": "--seed",
    "band": "--band",
}


def _interrupted_simulation(exc: KeyboardInterrupt, outputs: list[Path], committed: bool) -> int:
    """Say what an interrupted single-file simulation did with its ``outputs`` (committed together: all were
    written, or none was replaced); the exit status 128 + signal."""
    import signal

    signum = getattr(exc, "signum", signal.SIGINT)
    exec("pass")  # noqa: S102 (resets CPython's unhandled-KeyboardInterrupt flag: see _interrupted)
    names = ", ".join(repr(str(p)) for p in outputs)
    if committed:
        what = f"the simulation had finished: {names} were written"
    else:
        old = [repr(str(p)) for p in outputs if p.exists()]
        kept = (
            f": the previous {', '.join(old)} {'is' if len(old) == 1 else 'are'} unchanged" if old else f" to {names}"
        )
        what = f"the simulation stopped and its staging files were removed; nothing was written{kept}"
    err_console.print(Text(f"interrupted ({signal.Signals(signum).name}): ", style="bold red") + Text(what),
                      highlight=False, soft_wrap=True)  # fmt: skip
    return 128 + int(signum)


def _say(message: str) -> None:
    console.print(message, markup=False, highlight=False)


def _print_run(result) -> None:
    from satchain.comparison import row_texts

    c = result.comparison
    n_na = len(c.rows) - c.n_checked  # n/a rows are counted apart: neither passed nor failed
    na = f", {n_na} n/a" if n_na else ""
    t = Table(title=f"{result.system.name}: measured vs predicted ({c.n_checked - c.n_failed}/{c.n_checked} pass{na})")
    cols = ("measured", "predicted", "error", "sigma", "z", "tolerance")
    if any(r.as_built is not None for r in c.rows):  # simulated as built: its prediction and z beside the design's
        cols = (*cols[:5], "predicted as built", "z as built", cols[5])
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
@_handles_interrupts
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

    Exit status: 0 when every check made passes (n/a rows aside), 1 when a check fails or none could be made
    (unless --exit-zero), 2 on an error.
    """
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    import satchain
    from satchain.pipeline import STAGES
    from satchain.config.run import DEFAULT_CONFIG_TOML, RunConfig, load_run_config

    if print_config:
        print(DEFAULT_CONFIG_TOML, end="")
        return
    cfg = load_run_config(config)
    check_inputs_outside(
        out, {"--config": config, "system.file": cfg.system_path(), "as_built.file": cfg.as_built_path()}
    )
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

    previous = out.is_dir() and any(out.iterdir())
    try:
        with bar:
            result = satchain.run(cfg, out_dir=out, progress=update)
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM (satchain._safety.Interrupted)
        raise typer.Exit(_interrupted(exc, out, previous)) from None
    _print_run(result)
    console.print(f"report: {out / 'report.html'}   results: {out / 'results.json'}", markup=False, highlight=False)
    if result.kept_files:  # the user's files in the folder this run replaced
        n, shown = len(result.kept_files), ", ".join(result.kept_files[:5])
        more = f", ... ({n} in all)" if n > 5 else ""
        _say(f"kept {n} file{'s' if n != 1 else ''} satchain did not write in {str(out)!r}: {shown}{more}")
    if result.passed is False and not exit_zero:
        n = result.comparison.n_failed
        err_console.print(f"[bold red]{n} check(s) failed[/] (exit status 1; --exit-zero to ignore)")
        raise typer.Exit(1)
    if result.comparison.n_checked == 0 and not exit_zero:  # a gate that checked nothing must not pass
        err_console.print(
            "[bold red]no check could be made[/]: every row is n/a (see the reasons above; "
            "exit status 1; --exit-zero to ignore)"
        )
        raise typer.Exit(1)


def _interrupted(exc: KeyboardInterrupt, out: Path, previous: bool, *, what: str = "run",
                 kind: str = "staging folder") -> int:  # fmt: skip
    """Say what an interrupted run (or ``what``) left (its staging ``kind`` is already removed); the exit status
    128 + signal."""
    import signal

    signum = getattr(exc, "signum", signal.SIGINT)
    # CPython sets an "unhandled KeyboardInterrupt" flag whenever one escapes an exec() of a string (scipy's
    # array_api_compat runs one while it is imported), even though this one was handled; under `python -m` the
    # flag then makes the interpreter kill itself with SIGINT (exit -2) instead of exiting 128 + signum.  Any
    # exec() of a string that completes resets it.
    exec("pass")  # noqa: S102 (a constant: resets the flag, see above)
    kept = (
        f"the previous results in {str(out)!r} were kept unchanged"
        if previous
        else f"nothing was written to {str(out)!r}"
    )
    removed = "were" if kind.endswith("s") else "was"
    err_console.print(
        Text(f"interrupted ({signal.Signals(signum).name}): ", style="bold red")
        + Text(f"the {what} stopped and its {kind} {removed} removed; {kept}"),
        highlight=False,
        soft_wrap=True,
    )
    return 128 + int(signum)


from satchain.cli.measure import measure_app  # noqa: E402

app.add_typer(measure_app, name="measure", help="Measure image quality: edge, star, bars, wedge, auto, find, jitter.")

from satchain.cli.schema import schema  # noqa: E402

app.command("schema")(schema)


def main() -> None:  # pragma: no cover
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
