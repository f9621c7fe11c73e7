"""``satchain simulate``: the satellite image of a scene or an image (exact, tiled, any size), its preview and
optionally its focal-plane image, written together (all or none); with several inputs or ``--sweep``, one image per
case into a directory (:mod:`satchain.cli.sweep`).

Registered on the app by :mod:`satchain.cli.main`.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.text import Text

from satchain._safety import check_distinct_paths, terminate_as_interrupt
from satchain.cli._common import (
    err_console,
    handle_errors,
    handles_interrupts,
    progress_bar,
    say,
    system_from_options,
)
from satchain.cli.options import BandsOpt, PresetOpt, SystemOpt

if TYPE_CHECKING:
    from collections.abc import Callable

    from rich.progress import Progress

__all__ = ["simulate"]


class _StageBars:
    """``progress(stage, done, total)`` shown as one rich progress bar per stage (see
    :func:`satchain.cli._common.progress_bar`)."""

    def __init__(self) -> None:
        self._stage: str | None = None
        self._bar: Progress | None = None
        self._update: Callable[[int, int], None] | None = None

    def __call__(self, stage: str, done: int, total: int) -> None:
        if stage != self._stage or self._update is None:
            self.close()
            self._bar, self._update = progress_bar(stage)
            self._bar.start()
            self._stage = stage
        self._update(done, total)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()
        self._stage, self._bar = None, None


@handle_errors
@handles_interrupts
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
    *,
    out: Annotated[Path, typer.Option("-o", "--out", help="output TIFF (a directory with several inputs or --sweep)")],
) -> None:
    """Simulate the satellite image of a scene or an image (exact, tiled, any size); with several inputs or
    --sweep, one image per case into the -o directory, with manifest.json / manifest.csv."""
    from satchain.engine._malloc import keep_freed_memory
    from satchain.engine.files import simulate_file

    keep_freed_memory()  # this process is ours: tile buffers reused, not faulted in anew

    system_obj = system_from_options(preset, system)
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
                    scheduler=scheduler, progress=progress, notify=say, names=_SIMULATE_OPTIONS, band=band,
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
    say(f"wrote {r.path} ({r.shape_px[0]} x {r.shape_px[1]} px{bands}, {r.units}{geo}{how}) and {r.preview}{preview}")
    if r.focal_plane_path is not None:
        say(f"wrote {r.focal_plane_path} (focal-plane image, {r.focal_plane_pixel_m:g} m samples)")


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
    exec("pass")  # noqa: S102 (resets CPython's unhandled-KeyboardInterrupt flag: see satchain.cli._common.interrupted)
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
