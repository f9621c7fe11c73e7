"""The options satchain's commands share (those of ``satchain measure``; ``--preset`` / ``--system`` of budget,
simulate and run), defined once (as rasterio's ``rio/options.py``).

Each shared option is an ``Annotated`` type carrying its one :class:`typer.models.OptionInfo` (name, flags,
help text); a command declares ``roi: RoiOpt = None`` and gets the same option as every other command.  The
values are parsed by the functions below, called inside the command (within
:func:`satchain.cli._common.handle_errors`), so that a bad value is one line on stderr and exit status 2::

    region = parse_roi("--roi", roi)             # "X0,Y0,X1,Y1" -> (x0, y0, x1, y1) or None
    data, pixel_m, meta = load_image(image, pixel_m)

``tests/test_cli_options.py`` checks that every command uses these objects (not a local copy) and that an
option name means one thing (one help text) across the commands.
"""

from __future__ import annotations

import contextlib
import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from satchain.cli._common import parse_numbers
from satchain.errors import ConfigError, SatchainIOError

if TYPE_CHECKING:
    import numpy as np

__all__ = [
    "SHARED_OPTIONS",
    "BandOpt",
    "BandsOpt",
    "FitDegreeOpt",
    "FrequencyAxisOpt",
    "FullScaleOpt",
    "ImageArg",
    "JsonOpt",
    "NodataOpt",
    "OriginOpt",
    "OutOpt",
    "PixelOpt",
    "PresetOpt",
    "RoiOpt",
    "SystemOpt",
    "ThresholdOpt",
    "TruthOpt",
    "TruthRequiredOpt",
    "load_image",
    "ground_fields",
    "measuring",
    "parse_fit_degree",
    "parse_frequency_axis",
    "parse_full_scale",
    "parse_valid",
    "parse_origin",
    "parse_roi",
    "read_truth",
]

# ----------------------------------------------------------------------------------------------- the options

ImageArg = Annotated[Path, typer.Argument(help="image: .tif/.tiff (float or integer), .png (8/16-bit) or .npy")]
RoiOpt = Annotated[
    str | None, typer.Option("--roi", help="region X0,Y0,X1,Y1 in pixels (x = column, y = row; half-open)")
]
PixelOpt = Annotated[
    float | None, typer.Option("--pixel-m", help="ground pixel size (m); default: the file's metadata")
]
JsonOpt = Annotated[bool, typer.Option("--json", help="print JSON instead of tables")]
OutOpt = Annotated[Path | None, typer.Option("-o", "--out", help="write the results JSON and a figure here")]

_TRUTH_HELP = "the scene's truth JSON (written with the render): the targets' geometry comes from there"
#: ``--truth`` where the command needs it (``measure auto``) ...
TruthRequiredOpt = Annotated[Path, typer.Option("--truth", help=_TRUTH_HELP)]
#: ... and where it is one way to give the geometry (``measure wedge``): the same option, optional.
TruthOpt = Annotated[Path | None, typer.Option("--truth", help=_TRUTH_HELP)]
OriginOpt = Annotated[
    str | None, typer.Option("--origin-m", help="scene X,Y (m) of the image's top-left corner; default: metadata")
]
ThresholdOpt = Annotated[float, typer.Option("--threshold", help="wedge contrast where the lines stop resolving")]
FitDegreeOpt = Annotated[
    str,
    typer.Option(
        "--fit-degree",
        help="degree of the edge-position fit: auto (chosen from the data; follows curved edges), 1, 2 or 3",
    ),
]

FullScaleOpt = Annotated[
    float | None,
    typer.Option(
        "--full-scale",
        help="the sensor's full scale in the image's units (DN): pixels at it are clipped; default: 2**bits - 1 "
        "of an integer image (its stated bit depth, else its type); clipping is otherwise named only on evidence",
    ),
]

BandOpt = Annotated[
    int | None, typer.Option("--band", help="band of a multiband raster, from 1 (default: 1, with a warning)")
]
BandsOpt = Annotated[
    int | None,
    typer.Option(
        "--band",
        help="only band N, counted from 1: of the system's \\[\\[bands]] (in their order) with a banded "
        "system, else of a multiband raster (default: every band, each simulated)",
    ),
]
NodataOpt = Annotated[
    float | None,
    typer.Option(
        "--nodata",
        help="pixels equal to this value are excluded (e.g. 0 outside an area of interest): never edges, "
        "clipping or noise; default: the file's nodata value or mask, if any",
    ),
]

FrequencyAxisOpt = Annotated[
    str,
    typer.Option(
        "--frequency-axis",
        help="normal: the MTF along each edge's normal (ISO 12233); row: along the image row (ACT) or column "
        "(ALT), MTF_Estimator's convention, whose frequencies are cos(tilt) x the normal ones (4.3 % lower at "
        "16.8 deg)",
    ),
]

#: The system a command models (budget, simulate; run takes --preset over its configuration's system)
PresetOpt = Annotated[str | None, typer.Option("--preset", help="packaged system preset, e.g. ankarasat3")]
SystemOpt = Annotated[Path | None, typer.Option("--system", help="system TOML file")]

#: Every shared option, by its long name (``--truth`` has two forms: required and optional).
SHARED_OPTIONS: dict[str, tuple] = {
    "--roi": (RoiOpt,),
    "--pixel-m": (PixelOpt,),
    "--json": (JsonOpt,),
    "--out": (OutOpt,),
    "--truth": (TruthRequiredOpt, TruthOpt),
    "--origin-m": (OriginOpt,),
    "--threshold": (ThresholdOpt,),
    "--fit-degree": (FitDegreeOpt,),
    "--full-scale": (FullScaleOpt,),
    "--nodata": (NodataOpt,),
    "--band": (BandOpt, BandsOpt),
    "--frequency-axis": (FrequencyAxisOpt,),
    "--preset": (PresetOpt,),
    "--system": (SystemOpt,),
}

# ------------------------------------------------------------------------------------------- their parsing


def parse_roi(name: str, text: str | None) -> tuple[int, int, int, int] | None:
    """``X0,Y0,X1,Y1`` -> a tuple of 4 ints (or None).

    Examples
    --------
    >>> parse_roi("--roi", "10, 20,110,120")
    (10, 20, 110, 120)
    >>> parse_roi("--roi", None) is None
    True
    """
    if text is None:
        return None
    vals = parse_numbers(name, text, 4)
    if any(v != int(v) for v in vals):
        raise ConfigError(f"{name} = {text!r}: must be four integers X0,Y0,X1,Y1 (pixels)")
    return tuple(int(v) for v in vals)  # type: ignore[return-value]


def parse_fit_degree(text: str) -> str:
    """``--fit-degree``: ``auto``, ``1``, ``2`` or ``3`` (case and spaces ignored)."""
    value = text.strip().lower()
    if value not in ("auto", "1", "2", "3"):
        raise ConfigError(f"--fit-degree = {text!r}: must be auto, 1, 2 or 3")
    return value


def parse_frequency_axis(text: str) -> str:
    """``--frequency-axis``: ``normal`` or ``row`` (case and spaces ignored).

    Examples
    --------
    >>> parse_frequency_axis(" Row ")
    'row'
    """
    from satchain.measure.edge._axis import FREQUENCY_AXES

    value = str(text).strip().lower()
    if value not in FREQUENCY_AXES:
        raise ConfigError(f"--frequency-axis = {text!r}: must be one of {', '.join(FREQUENCY_AXES)}")
    return value


def parse_full_scale(value: float | None, image, meta: dict) -> float | None:
    """``--full-scale`` (finite), else ``2**bits - 1`` of an unsigned integer image (the file's stated
    ``bit_depth``, else its type: 255, 65535), else None (unknown: clipping is named only on evidence).

    Examples
    --------
    >>> import numpy as np
    >>> parse_full_scale(None, np.zeros(2, np.uint16), {"bit_depth": 12}), parse_full_scale(None, np.zeros(2), {})
    (4095.0, None)
    """
    import numpy as np

    from satchain._validate import check_range
    from satchain.io.images import integer_scale

    if value is not None:
        return check_range("--full-scale", value, None, None)
    dt = np.asarray(image).dtype
    if dt.kind != "u":
        return None
    return float(round(1.0 / integer_scale(dt, meta)))


def parse_origin(text: str | None, meta: dict) -> tuple[float, float] | None:
    """``--origin-m X,Y`` (m), else the image metadata's ``origin_m``, else None."""
    if text is not None:
        return tuple(parse_numbers("--origin-m", text, 2))  # type: ignore[return-value]
    o = meta.get("origin_m")
    return None if o is None else tuple(float(v) for v in o)  # type: ignore[return-value]


def read_truth(path: Path) -> dict:
    """The scene truth JSON named by ``--truth``."""
    try:
        return json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SatchainIOError(f"--truth = {str(path)!r}: no such file") from None
    except OSError as exc:
        raise SatchainIOError(f"--truth = {str(path)!r}: cannot read: {exc}") from None
    except json.JSONDecodeError as exc:
        raise ConfigError(f"--truth = {str(path)!r}: not JSON: {exc}") from None


def parse_valid(image, nodata: float | None, meta: dict, path: Path | None = None) -> np.ndarray | None:
    """The mask of the pixels to measure (None: all): ``--nodata`` (else the file's ``nodata``) and the
    file's own mask (``meta["valid"]``, a boolean array of the image's shape, where the reader gives one).
    A mask that excludes every pixel is refused, naming ``path`` (the IMAGE) where given.

    Examples
    --------
    >>> import numpy as np
    >>> parse_valid(np.array([[0, 3]]), 0.0, {}).tolist()
    [[False, True]]
    >>> parse_valid(np.array([[0, 3]]), None, {}) is None
    True
    """
    from satchain.measure._common import valid_mask

    nd = nodata if nodata is not None else meta.get("nodata")
    return valid_mask(image, meta.get("valid"), nd, name="IMAGE" if path is None else f"IMAGE {str(path)!r}")


def load_image(path: Path, pixel_m: float | None, band: int | None = None):
    """Read IMAGE (band ``--band`` of a multiband raster); returns (array, pixel_m or None, metadata):
    ``--pixel-m`` wins over the file's metadata; the file's own mask (nodata, internal mask, alpha) is
    ``metadata["valid"]`` (see :func:`parse_valid`)."""
    from satchain._validate import check_positive
    from satchain.io.images import GDAL_SUFFIXES, read_image

    if band is not None and (isinstance(band, bool) or band < 1):
        raise ConfigError(f"--band = {band!r}: bands are numbered from 1")
    if band is None and Path(path).suffix.lower() in GDAL_SUFFIXES and Path(path).is_file():
        from satchain.io.raster import open_raster

        with open_raster(path) as r:  # a measurement is of one band, never a blend of bands: band 1 by default
            if r.count > 1:
                import warnings

                from satchain.errors import SatchainWarning

                warnings.warn(f"image = {str(path)!r}: has {r.count} bands; band 1 is measured (--band N: "
                              f"1..{r.count})", SatchainWarning, stacklevel=2)  # fmt: skip
                band = 1
    image, valid, meta = read_image(path, band=band, mask=True)
    if valid is not None:
        meta = {**meta, "valid": valid}
    if pixel_m is not None:
        pixel_m = check_positive("--pixel-m", pixel_m)
        if Path(path).suffix.lower() in GDAL_SUFFIXES and not meta.get("pixel_m_xy"):  # as simulate's
            from satchain.engine.raster_input import check_pixel_m

            pixel_m = check_pixel_m(path, pixel_m, lambda _: "--pixel-m")  # a contradiction of the file's refused
    elif meta.get("pixel_m_xy"):  # not square: no one ground frequency per cy/px; said, not guessed
        sx, sy = meta["pixel_m_xy"]
        meta = {**meta, "pixel_m_note": f"IMAGE {str(path)!r}: its pixels are {sx:.6g} x {sy:.6g} m (not square): "
                "no ground frequency is given (cy/px only); give --pixel-m for cy/m"}  # fmt: skip
    elif meta.get("pixel_m") is not None:
        pixel_m = float(meta["pixel_m"])
    elif "invalid_pixel_m" in meta:  # a bad pixel size in the file is refused, never silently dropped
        raise ConfigError(f"IMAGE {str(path)!r}: its pixel size {meta['invalid_pixel_m']!r} is not a ground pixel "
                          "size in (0, 1e6] m; give --pixel-m")  # fmt: skip
    else:
        meta = {**meta, "pixel_m_note": f"IMAGE {str(path)!r} states no ground pixel size (no metric georeference): "
                "frequencies in cy/px only; give --pixel-m for cy/m"}  # fmt: skip
    return image, pixel_m, meta


def ground_fields(pixel_m: float | None, meta: dict) -> dict:
    """The ground units every measurement result carries: ``pixel_m`` and the Nyquist frequency in cy/m on
    the ground, or ``pixel_m`` None and ``pixel_m_note`` saying why (no metric georeference, non-square pixels).

    Examples
    --------
    >>> ground_fields(0.5, {})
    {'pixel_m': 0.5, 'nyquist_cy_per_m_ground': 1.0}
    >>> ground_fields(None, {"pixel_m_note": "no georeference"})
    {'pixel_m': None, 'pixel_m_note': 'no georeference'}
    """
    if pixel_m:
        return {"pixel_m": pixel_m, "nyquist_cy_per_m_ground": 0.5 / pixel_m}
    return {"pixel_m": None, "pixel_m_note": meta.get("pixel_m_note", "no ground pixel size: cy/px only")}


@contextlib.contextmanager
def measuring(path: Path, valid: np.ndarray | None):
    """Name IMAGE in a measurement's refusal, and the share of its pixels the mask or nodata excludes where
    one does (a mask that leaves no usable edge is the file's problem, not the tool's): one line, exit 2."""
    from satchain.errors import InputError

    try:
        yield
    except InputError as exc:
        msg = str(exc)
        for prefix in ("image: ", "IMAGE: ", "image "):
            msg = msg.removeprefix(prefix)
        import numpy as np

        if valid is not None and not np.all(valid):
            msg += (f" (the mask / nodata excludes {100 * (1 - np.count_nonzero(valid) / valid.size):.0f} % of "
                    "the pixels)")  # fmt: skip
        raise InputError(f"IMAGE {str(path)!r}: {msg}") from None
