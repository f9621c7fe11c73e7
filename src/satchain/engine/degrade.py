"""One call from imagery to the satellite's image, in memory: :func:`simulate_image`.

The Python form of ``satchain simulate`` on a raster, for work that degrades many images (ML-robustness tests,
as pyBSM / nrtk users do): give an array (with its pixel size or affine transform) or a raster path, get the
image at the camera's GSD with its transform, CRS and validity. The geometry, nodata and band rules are those
of :mod:`satchain.engine.georaster` (output pixel (i, j) covers input pixels ``[i k_y, (i+1) k_y) x [j k_x,
(j+1) k_x)``, ``T_out = T_in @ Affine.scale(k_x, k_y)``; NaN or masked input pixels are filled with the band's
valid mean and every output pixel whose cell touches one is invalid), so an image from here equals the file
``satchain simulate`` writes of the same input.

Examples
--------
>>> import numpy as np
>>> from satchain import load_preset
>>> r = simulate_image(np.full((140, 140), 0.3), load_preset("ankarasat3"), pixel_m=0.098)
>>> r.image.shape, round(float(r.image.mean()), 6), round(r.transform.a, 4)
((28, 28), 0.3, 0.49)
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from satchain.engine.tiling import Window
from satchain.errors import ConfigError, InputError

__all__ = ["SimulatedImage", "simulate_image"]


@dataclass(frozen=True)
class SimulatedImage:
    """What :func:`simulate_image` returns: ``image`` ((rows, cols) for one band, (bands, rows, cols) for
    several; float64 in ``units``, DN rounded and clipped as in the file; a numpy masked array, masked where
    ``valid`` is False, when the source is one), ``valid`` (same shape, False where the output pixel touches
    invalid input; None when every pixel is valid), the affine ``transform`` and
    ``crs`` (the input's; None without one) and the output pixel size ``pixel_m`` = (ACT, ALT) GSD in m."""

    image: np.ndarray
    valid: np.ndarray | None
    transform: Any
    crs: Any
    units: str
    pixel_m: tuple[float, float]


class _ArrayBand:
    """One band of an array as ground truth (NaN = invalid, filled with the band's finite mean)."""

    def __init__(self, a: np.ndarray, pixel_m: float, gain: float):
        self.a, self.pixel_m, self.gain = a, float(pixel_m), float(gain)
        self.shape_px = (int(a.shape[0]), int(a.shape[1]))
        finite = np.isfinite(a)
        self.masked = not bool(finite.all())
        if not finite.any():
            raise InputError("image: every pixel is NaN or masked (no data); nothing to simulate")
        self.fill = float(a[finite].mean()) * self.gain

    def read(self, window: Window) -> np.ndarray:
        v = np.asarray(self.a[window.rows, window.cols], dtype=np.float64) * self.gain
        if self.masked:
            v[~np.isfinite(v)] = self.fill
        return v

    def valid(self, window: Window) -> np.ndarray | None:
        return np.isfinite(self.a[window.rows, window.cols]) if self.masked else None


def _source_values(source, input_scale) -> tuple[np.ndarray, float]:
    """(the array, the gain that turns its stored values into reflectance: the one rule of
    :func:`satchain.engine.sources.reflectance_gain`, which refuses integers wider than 16 bits without
    ``input_scale``): a numpy masked array's masked pixels NaN (no data, as NaN is); a boolean array is refused."""
    from satchain._validate import masked_as_nan, split_mask
    from satchain.engine.sources import reflectance_gain

    gain = reflectance_gain(np.asarray(split_mask("image", source)[0]).dtype, input_scale)
    return np.asarray(masked_as_nan("image", source)), gain


def _as_affine(transform):
    """``transform`` as an ``affine.Affine``: one already, or a sequence of 6 real numbers in its order (a, b, c,
    d, e, f), as ``tuple(affine)[:6]``; anything else is refused, naming its type (a GDAL geotransform's order
    (c, a, b, f, d, e) is named when the numbers read in it give square pixels and in Affine's order do not)."""
    from affine import Affine

    from satchain.errors import ParameterTypeError

    if transform is None or isinstance(transform, Affine):
        return transform
    seq = isinstance(transform, (list, tuple, np.ndarray)) and np.ndim(transform) == 1 and len(transform) == 6
    if not (seq and all(isinstance(v, (int, float, np.integer, np.floating)) for v in transform)):
        shown = repr(transform) if len(repr(transform)) <= 60 else repr(transform)[:57] + "..."
        raise ParameterTypeError(
            f"simulate_image(): transform = {shown} ({type(transform).__name__}): must be an affine.Affine, or a "
            "sequence of 6 numbers in its order (a, b, c, d, e, f) (for a GDAL geotransform: Affine.from_gdal(*gt))"
        )
    v = [float(x) for x in transform]
    if not all(map(math.isfinite, v)):
        raise ConfigError(f"transform = {tuple(v)!r}: its 6 numbers must be finite")
    t, g = Affine(*v), Affine.from_gdal(*v)
    if not _square(t) and _square(g):
        raise ConfigError(
            f"transform = {tuple(v)!r}: in affine.Affine's order (a, b, c, d, e, f) its pixels are not square; "
            "it reads as a GDAL geotransform (c, a, b, f, d, e): give Affine.from_gdal(*transform)"
        )
    return t


def _square(t) -> bool:
    sx, sy = math.hypot(t.a, t.d), math.hypot(t.b, t.e)
    return sx > 0 and math.isclose(sx, sy, rel_tol=1e-6)


def _array_bands(source, pixel_m, transform, input_scale) -> tuple[list, Any, float]:
    from affine import Affine

    transform = _as_affine(transform)
    a, gain = _source_values(source, input_scale)
    if a.ndim not in (2, 3) or min(a.shape) < 1 or a.dtype.kind not in "biuf":
        raise InputError(f"image: must be a real 2-D (rows, cols) or 3-D (bands, rows, cols) array, got "
                         f"shape {a.shape}, dtype {a.dtype}")  # fmt: skip
    if transform is not None:
        sx, sy = math.hypot(transform.a, transform.d), math.hypot(transform.b, transform.e)
        if pixel_m is None and not math.isclose(sx, sy, rel_tol=1e-6):
            raise ConfigError(f"transform: pixels {sx:.6g} x {sy:.6g}, not square; give pixel_m or resample")
        pixel_m, given = (sx, None) if pixel_m is None else (pixel_m, pixel_m)
    if pixel_m is None:
        raise ConfigError("pixel_m = None: an array states no pixel size; give pixel_m (m) or transform")
    if not (isinstance(pixel_m, (int, float)) and 0 < pixel_m <= 1e6):
        raise ConfigError(f"pixel_m = {pixel_m!r}: must be a ground pixel size in (0, 1e6] m")
    if transform is not None and given is not None and not math.isclose(given, sx, rel_tol=1e-3):
        raise ConfigError(f"pixel_m = {given!r}: contradicts transform, whose pixels are {sx:.6g} m (the output "
                          "keeps the transform); give one of them, or both agreeing")  # fmt: skip
    pixel_m = sx if transform is not None else pixel_m  # agreeing: the transform's, so the output's stays exact
    t = transform if transform is not None else Affine(pixel_m, 0.0, 0.0, 0.0, -pixel_m, 0.0)
    planes = a if a.ndim == 3 else a[None]
    return [_ArrayBand(p, pixel_m, gain) for p in planes], t, float(pixel_m)


def simulate_image(
    source,
    system,
    *,
    pixel_m: float | None = None,
    transform=None,
    crs=None,
    band: int | None = None,
    input_scale: float | None = None,
    units: str = "reflectance",
    noise: bool = False,
    seed: int = 0,
) -> SimulatedImage:
    """The satellite image of ``source`` (an array of reflectance, or a raster path) by ``system``, in memory.

    Parameters
    ----------
    source : ndarray or path
        A (rows, cols) or (bands, rows, cols) array (NaN = no data, as are a numpy masked array's masked
        pixels: the result's ``image`` is then a masked array, masked where ``valid`` is False; uint8 / uint16
        (int8 / int16) DN scaled by ``1 / (2**bits - 1)`` (``2**(bits - 1) - 1``) unless ``input_scale``; wider
        integers need ``input_scale``; a boolean array is refused), or any GDAL raster (every band, or
        ``band``; its georeference, nodata, mask, scale and offset used as ``satchain simulate`` uses them).
    pixel_m, transform, crs : an array's ground pixel size (m), affine transform (an ``affine.Affine``, or a
        sequence of 6 numbers in its order (a, b, c, d, e, f); a GDAL geotransform through ``Affine.from_gdal``;
        default: north up, origin (0, 0), ``pixel_m``) and CRS. ``pixel_m`` with a ``transform`` (or a path
        whose georeference states a pixel size) must agree with its pixel size to 0.1 % (the output keeps the
        transform): one that contradicts it is refused.
    units, noise, seed : as :func:`satchain.engine.files.simulate_file` (band i > 1 draws from a seed derived
        from ``(seed, i)``).

    Raises
    ------
    ConfigError, InputError, ResourceLimitError
        A bad argument or input, or an image that does not fit in memory (use ``satchain simulate``, which
        streams).
    """
    from satchain._validate import check_choice
    from satchain.engine import georaster as g
    from satchain.engine.memory import check_simulation_memory
    from satchain.engine.sensor import OUTPUT_UNITS, sensor_from_system
    from satchain.engine.simulate import Simulator

    check_choice("units", units, OUTPUT_UNITS)
    if isinstance(source, (str, os.PathLike)):
        g.check_scales(pixel_m, input_scale, lambda k: {"scene_pixel_m": "pixel_m"}.get(k, k))
        plan = g._plan_input(Path(source), band, pixel_m, lambda k: k)
        idx = [band] if band is not None else list(range(1, plan.count + 1))
        srcs, t, px, crs = [g._band_source(plan, b, input_scale) for b in idx], plan.transform, plan.pixel_m, plan.crs
        count, squeeze = plan.count, len(idx) == 1
    else:
        srcs, t, px = _array_bands(source, pixel_m, transform, input_scale)
        idx, count, squeeze = list(range(1, len(srcs) + 1)), len(srcs), np.ndim(source) == 2
    if system.bands and len(system.bands) != count:
        raise ConfigError(f"source has {count} bands but the system describes {len(system.bands)} ([[bands]])")
    images, valids = [], []
    for i, src in enumerate(srcs):
        s = system.for_band(idx[i] - 1)
        sim = Simulator(s, input_pixel_m=px, input_shape=src.shape_px, motion_seed=seed)  # one motion, every band
        check_simulation_memory(sim)
        sensor = sensor_from_system(s) if (units != "reflectance" or noise) else None
        img = sim.run(src, sensor=sensor, units=units, noise=noise, seed=g._seed(seed, i))
        if units == "dn":
            assert sensor is not None  # DN: formed by the sensor made above
            img = np.clip(np.round(img), 0, 2.0**sensor.bit_depth - 1)
        bad = g.invalid_cells(src, sim, (0, sim.output_shape[0])) if src.masked else None
        images.append(img)
        valids.append(np.ones(img.shape, bool) if bad is None else ~bad)
    valid = np.stack(valids)
    out_t = g.image_transform(t, sim, px)  # through the image map (pushbroom geometry), as the file path
    image = np.stack(images)
    if squeeze:
        image, valid = image[0], valid[0]
    if isinstance(source, np.ma.MaskedArray):  # masked in, masked out: every output pixel a masked pixel touches
        image = np.ma.masked_array(image, mask=~valid)
    return SimulatedImage(image, None if valid.all() else valid, out_t, crs, units,
                          (system.gsd_act_m, system.gsd_alt_m))  # fmt: skip
