"""``satchain simulate``: the satellite image of a scene or an image (exact, tiled, any size), its preview and
optionally its focal-plane image, written together (all or none); with several inputs or ``--sweep``, one image per
case into a directory (:mod:`satchain.cli.sweep`); with a banded system (``[[bands]]`` with spectral responses) and
a scene, every band (:func:`satchain.engine.bands.simulate_bands`) into a directory: one GeoTIFF per pixel grid and
the RGB / false-colour previews (:func:`satchain.engine.bands.write_band_rasters`), all or none. A GDAL raster
whose bands state their centre wavelengths (or ``--wavelengths-nm``) is a reflectance cube: every band is formed
from it alike (:func:`satchain.engine.cube.simulate_cube`), georeferenced as the cube. Other image inputs keep
their band-by-band path (a GDAL raster needs one band per ``[[bands]]``: another count is refused naming both).

Registered on the app by :mod:`satchain.cli.main`.
"""

from __future__ import annotations

import contextlib
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
from satchain.errors import ConfigError

if TYPE_CHECKING:
    from collections.abc import Callable

    from rich.progress import Progress

    from satchain.config.system import ImagingSystem

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
    wavelengths_nm: Annotated[
        str | None,
        typer.Option(
            "--wavelengths-nm",
            help="centre wavelength of each band of a multiband INPUT, nm, comma-separated (e.g. 490,560,665,842): "
            "a reflectance cube from which a banded system forms every band (default: the file's band metadata)",
        ),
    ] = None,
    sweep: Annotated[
        list[str] | None,
        typer.Option(
            "--sweep",
            help="KEY=V1,V2,...: one case per value of a system key, e.g. motion.smear_px=0.5,1,2 (repeat for "
            "the cartesian product); -o is then a directory with one image per case and a manifest",
        ),
    ] = None,
    *,
    out: Annotated[
        Path,
        typer.Option("-o", "--out", help="output TIFF (a directory with several inputs, --sweep or a banded system)"),
    ],
) -> None:
    """Simulate the satellite image of a scene or an image (exact, tiled, any size); with several inputs or
    --sweep, one image per case into the -o directory, with manifest.json / manifest.csv; with a banded system
    (e.g. --preset ankarasat3-pms) and a scene, every band into the -o directory (pan.tif, ms.tif, previews)."""
    from satchain.engine._malloc import keep_freed_memory
    from satchain.engine.files import simulate_file

    keep_freed_memory()  # this process is ours: tile buffers reused, not faulted in anew

    system_obj = system_from_options(preset, system)
    if wavelengths_nm is not None and (len(inputs) > 1 or sweep):
        raise ConfigError(f"--wavelengths-nm {wavelengths_nm}: applies to one reflectance cube input, without --sweep")
    if len(inputs) > 1 or sweep:
        from satchain.cli.sweep import simulate_cases

        options = dict(scene_pixel_m=scene_pixel_m, input_scale=input_scale, units=units_, noise=not no_noise,
                       scheduler=scheduler, band=band)  # fmt: skip
        return simulate_cases(inputs, out, system_obj, sweep_texts=sweep or [], seed=seed,
                              focal_plane=focal_plane, options=options, names=_SIMULATE_OPTIONS)  # fmt: skip
    input_ = inputs[0]
    if _is_cube(system_obj, input_, wavelengths_nm):  # every band from one reflectance cube, as from a scene
        if focal_plane is not None or scheduler is not None:
            what = f"--focal-plane {focal_plane}" if focal_plane is not None else f"--scheduler {scheduler}"
            raise ConfigError(f"{what}: not used by a banded system's simulation of a reflectance cube")
        return _simulate_cube(input_, out, system_obj, wavelengths=wavelengths_nm, scene_pixel_m=scene_pixel_m,
                              input_scale=input_scale, units=units_, noise=not no_noise, seed=seed,
                              band=band)  # fmt: skip
    if _is_banded_layout(system_obj, input_):  # every band from the spectral scene, one raster per pixel grid
        unused = {"--focal-plane": focal_plane, "--scheduler": scheduler, "--input-scale": input_scale}
        given = [f"{k} {v}" for k, v in unused.items() if v is not None]
        if given:
            raise ConfigError(f"{given[0]}: not used by a banded system's simulation of a scene (-o is a directory "
                              "of one raster per pixel grid)")  # fmt: skip
        return _simulate_bands(input_, out, system_obj, scene_pixel_m=scene_pixel_m, units=units_,
                               noise=not no_noise, seed=seed, band=band)  # fmt: skip
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
    "wavelengths_nm": "--wavelengths-nm",
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


# ---------------------------------------------------------------------------------------------- banded systems
#: What a banded simulation writes into its -o directory: ``<band>.tif`` / ``ms*.tif`` and the two previews.
_BAND_OUTPUTS = ("*.tif", "rgb.png", "false_colour.png")


def _is_banded_layout(system: ImagingSystem, input_: str) -> bool:
    """A system whose ``[[bands]]`` carry spectral responses, and a scene input (``paper`` or a layout file):
    every band is formed from the scene (an image input keeps its band-by-band path)."""
    from satchain.engine.files import IMAGE_SUFFIXES

    responses = any(b.spectral_response is not None for b in system.bands)
    return responses and Path(input_).suffix.lower() not in IMAGE_SUFFIXES


def _check_band_dir(out: Path) -> list[Path]:
    """``-o`` of a banded simulation: a directory that is missing, empty, or holds only the files of an earlier
    banded simulation (its GeoTIFFs and previews, which satchain wrote); anything else is refused before any work.
    Returns those earlier files (the ones this simulation does not replace are removed once it is written)."""
    import fnmatch
    import re

    from satchain._safety import clean_stale_temp_files

    if out.exists() and not out.is_dir():
        raise ConfigError(f"-o {str(out)!r}: is a file; a banded system writes one raster per pixel grid into a "
                          "directory: give a new or empty directory")  # fmt: skip
    if out.suffix.lower() in (".tif", ".tiff", ".png") and not out.exists():
        raise ConfigError(f"-o {str(out)!r}: a banded system writes one raster per pixel grid into a directory; "
                          f"give a directory, e.g. -o {out.with_suffix('')}")  # fmt: skip
    if not out.is_dir():
        return []
    for p in out.glob(".*.tmp"):  # a killed simulation's temporary files (.NAME.<pid>.*.tmp, their process gone)
        m = re.fullmatch(r"\.(.+?\.(?:tif|png))\.\d+\..*\.tmp", p.name)
        if m:
            clean_stale_temp_files(out / m.group(1))
    earlier = []
    for p in sorted(out.iterdir()):
        ours = p.is_file() and not p.is_symlink() and any(fnmatch.fnmatch(p.name, pat) for pat in _BAND_OUTPUTS)
        if not (ours and _written_by_satchain(p)):
            raise ConfigError(f"-o {str(out)!r}: holds {p.name!r}, which a banded simulation did not write; give a "
                              "new or empty directory")  # fmt: skip
        earlier.append(p)
    return earlier


def _written_by_satchain(path: Path) -> bool:
    """A preview with satchain's PNG text, or a GeoTIFF of bands whose description is satchain's JSON."""
    import json

    from satchain._safety import _written_by_satchain as png_or_json

    if path.suffix.lower() != ".tif":
        return png_or_json(path)
    try:
        import tifffile

        with tifffile.TiffFile(path) as tif:
            meta = json.loads(str(tif.pages[0].description))["satchain"]
        return isinstance(meta, dict) and "band_names" in meta
    except Exception:  # unreadable: not ours
        return False


def _simulate_bands(input_: str, out: Path, system: ImagingSystem, *, scene_pixel_m: float | None, units: str,
                    noise: bool, seed: int, band: int | None) -> None:  # fmt: skip
    """Every band of ``system`` (or ``--band``'s) formed from the scene ``input_`` and written into ``out``."""
    from satchain.engine.bands import simulate_bands, write_band_rasters
    from satchain.engine.files import ground_truth_source
    from satchain.scene.layout import check_scene_pixel

    _check_band_options(system, units=units, seed=seed, band=band)
    earlier = _check_band_dir(out)
    src, scene = ground_truth_source(input_, pixel_m=scene_pixel_m, names=_SIMULATE_OPTIONS)
    assert scene is not None  # a layout input
    check_scene_pixel(scene, src.pixel_m, name="the layout's pixel_m" if scene_pixel_m is None else "--scene-pixel-m")
    _check_band_grids(system, src, band)
    result = simulate_bands(scene, system, pixel_m=src.pixel_m, bands=None if band is None else [band - 1],
                            units=units, noise=noise, seed=seed)  # fmt: skip
    _write_band_dir(result, out, earlier, units, write_band_rasters)


def _write_band_dir(result, out: Path, earlier: list[Path], units: str, write: Callable) -> None:
    """``write(result, out)`` (one raster per pixel grid and the previews) into the directory ``out``, all files or
    none; the ``earlier`` banded simulation's files it does not replace are removed; what was written is said."""
    from satchain.io._commit import committed_together

    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    try:
        with terminate_as_interrupt() as received, committed_together(received.check):  # all files or none
            paths = write(result, out)
    except BaseException:
        if created:
            with contextlib.suppress(OSError):
                out.rmdir()
        raise
    stale = [p for p in earlier if p not in paths.values()]
    for p in stale:  # an earlier banded simulation's files not replaced: the folder holds this one's alone
        p.unlink(missing_ok=True)
    tifs = [p for p in paths.values() if p.suffix == ".tif"]  # in the order of result.grids()
    for p, g in zip(tifs, result.grids(), strict=True):
        b0 = g[0]
        names = ", ".join(b.name for b in g)
        say(f"wrote {p} ({b0.image.shape[0]} x {b0.image.shape[1]} px x {len(g)} band(s): {names}; "
            f"{b0.gsd_m:g} m, {units})")  # fmt: skip
    previews = [str(p) for p in paths.values() if p.suffix == ".png"]
    if previews:
        say(f"wrote {' and '.join(previews)} (previews)")
    if stale:
        say(f"removed {', '.join(str(p) for p in stale)} (an earlier banded simulation's files not written now)")


def _is_cube(system: ImagingSystem, input_: str, wavelengths_nm: str | None) -> bool:
    """A GDAL raster with its bands' centre wavelengths (stated, or ``--wavelengths-nm``) and a system whose
    ``[[bands]]`` carry spectral responses: a reflectance cube; ``--wavelengths-nm`` otherwise is refused."""
    from satchain.engine.cube import states_wavelengths
    from satchain.io.images import GDAL_SUFFIXES

    responses = any(b.spectral_response is not None for b in system.bands)
    raster = Path(input_).suffix.lower() in GDAL_SUFFIXES
    if wavelengths_nm is not None and not (responses and raster):
        why = "a GDAL raster input (a reflectance cube)" if responses else ("a banded system ([[bands]] with "
                                                                           "spectral responses)")  # fmt: skip
        raise ConfigError(f"--wavelengths-nm {wavelengths_nm}: applies to {why}")
    return responses and raster and (wavelengths_nm is not None or (Path(input_).is_file()
                                                                    and states_wavelengths(input_)))  # fmt: skip


def _simulate_cube(input_: str, out: Path, system: ImagingSystem, *, wavelengths: str | None,
                   scene_pixel_m: float | None, input_scale: float | None, units: str, noise: bool, seed: int,
                   band: int | None) -> None:  # fmt: skip
    """Every band of ``system`` (or ``--band``'s) formed from the reflectance cube ``input_`` into ``out``."""
    from functools import partial

    from satchain.engine.cube import ReflectanceCube, simulate_cube, write_cube_rasters
    from satchain.engine.sources import SceneSource

    _check_band_options(system, units=units, seed=seed, band=band)
    lam = None
    if wavelengths is not None:
        try:
            lam = [float(v) for v in wavelengths.split(",")]
        except ValueError:
            raise ConfigError(f"--wavelengths-nm {wavelengths}: give numbers in nm, comma-separated, e.g. "
                              "490,560,665,842") from None  # fmt: skip
    earlier = _check_band_dir(out)
    with ReflectanceCube(input_, wavelengths_nm=lam, scene_pixel_m=scene_pixel_m, input_scale=input_scale,
                         names=_SIMULATE_OPTIONS) as cube:  # fmt: skip
        which = list(range(len(system.bands))) if band is None else [band - 1]
        _check_band_grids(system, SceneSource(cube.band_scene(system, which[0])), band)
        result = simulate_cube(cube, system, bands=which, units=units, noise=noise, seed=seed)
        _write_band_dir(result, out, earlier, units, partial(write_cube_rasters, cube=cube))


def _check_band_grids(system: ImagingSystem, src, band: int | None) -> None:
    """Before any work: the scene is at least MIN_INPUT_PX a side, and every band's simulation fits in memory
    (the banded path is not streamed)."""
    from satchain.engine.memory import check_simulation_memory
    from satchain.engine.raster_input import MIN_INPUT_PX
    from satchain.engine.simulate import Simulator
    from satchain.engine.stream import choose_streamed

    if min(src.shape_px) < MIN_INPUT_PX:
        raise ConfigError(f"INPUT at {src.pixel_m:g} m per pixel is only {src.shape_px[0]} x {src.shape_px[1]} px; "
                          f"a ground truth needs at least {MIN_INPUT_PX} px a side: check --scene-pixel-m")  # fmt: skip
    for i in range(len(system.bands)) if band is None else [band - 1]:
        sim = Simulator(system.for_band(i), input_pixel_m=src.pixel_m, input_shape=src.shape_px)
        if choose_streamed(sim, focal_plane=None):
            raise ConfigError(f"INPUT at --scene-pixel-m {src.pixel_m:g}: {src.shape_px[0]} x {src.shape_px[1]} px "
                              "is too large for a banded simulation, which holds each band in memory; give a "
                              "smaller scene or a coarser --scene-pixel-m")  # fmt: skip
        check_simulation_memory(sim, focal_plane=None)


def _check_band_options(system: ImagingSystem, *, units: str, seed: int, band: int | None) -> None:
    """``--units``, ``--seed`` and ``--band`` (1-based, within the system's ``[[bands]]``) of a banded simulation."""
    from satchain._validate import check_choice
    from satchain.engine.sensor import OUTPUT_UNITS

    check_choice("--units", units, OUTPUT_UNITS)
    if seed < 0:
        raise ConfigError(f"--seed {seed}: must be an integer >= 0")
    n = len(system.bands)
    if band is not None and not 1 <= band <= n:
        raise ConfigError(f"--band {band}: the system {system.name!r} has {n} bands ({', '.join(system.band_names)})"
                          f"; give 1 to {n}")  # fmt: skip
