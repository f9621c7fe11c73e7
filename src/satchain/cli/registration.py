"""``satchain measure registration``: the subpixel offset between two bands (band-to-band registration).

Registered on the ``measure`` sub-app by :mod:`satchain.cli.measure`; the shared options come from
:mod:`satchain.cli.options`, the printing and writing from :mod:`satchain.cli.output`; the measurement is
:func:`satchain.measure.registration.measure_registration` (its sign convention: ``offset_px`` is where the
band's content lies relative to the reference's).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Annotated

import typer

from satchain._safety import check_dir_outputs
from satchain.cli._common import handle_errors, print_warning
from satchain.cli.options import (
    BandOpt,
    ImageArg,
    JsonOpt,
    NodataOpt,
    OutOpt,
    PixelOpt,
    RoiOpt,
    ground_fields,
    load_image,
    measuring,
    parse_roi,
    parse_valid,
)
from satchain.cli.output import emit, kv_table, print_ground, wide_console
from satchain.errors import ConfigError, InputError

__all__ = ["registration"]

RefOpt = Annotated[int, typer.Option("--ref", help="the reference band of IMAGE, from 1")]
WithOpt = Annotated[
    Path | None,
    typer.Option(
        "--with",
        help="a second image file holding --band (e.g. the MS file against a PAN IMAGE; its pitch an integer "
        "multiple or fraction of IMAGE's, both georeferenced on one CRS); default: --band of IMAGE",
    ),
]
_TOL = 1e-3  # of a pixel: how closely two grids' pitches and corners must agree


def _grid(meta: dict) -> tuple[float, float, float, float] | None:
    """(x0, y0, pitch_x, pitch_y) of a north-up georeference, None without one; a rotated one is refused."""
    t = meta.get("transform")
    if not t:
        return None
    x0, a, b, y0, d, e = (float(v) for v in t)
    if b or d:
        raise ConfigError(f"transform = {list(t)!r}: a rotated grid; registration needs north-up rasters")
    return x0, y0, a, e


def _pitch_ratio(fine: tuple, coarse: tuple, names: tuple[str, str]) -> int:
    ratios = (coarse[2] / fine[2], coarse[3] / fine[3])
    k = round(ratios[0])
    if k < 1 or any(abs(q - k) > _TOL * k for q in ratios):
        raise ConfigError(f"{names[1]}: its pixel is {ratios[0]:.6g} x {ratios[1]:.6g} of {names[0]}'s; the two "
                          "images' pitches must be in an integer ratio (1, 2, 4 ...)")  # fmt: skip
    return int(k)


def _common_grid(ref, img, m_ref: dict, m_img: dict, names: tuple[str, str]):
    """Both images (and masks) cut to one grid: ``(fine, coarse, fine_valid, coarse_valid, scale, swapped)``;
    ``swapped``: the reference (IMAGE) is the coarser one. Without georeference both are taken as one grid."""
    (a, va), (b, vb) = ref, img
    g_ref, g_img = _grid(m_ref), _grid(m_img)
    if g_ref is None or g_img is None:
        if a.shape != b.shape:
            raise ConfigError(f"{names[1]}: its shape {b.shape} differs from {names[0]}'s {a.shape} and the two are "
                              "not both georeferenced: give them on one grid, or georeferenced (an integer pitch "
                              "ratio)")  # fmt: skip
        return a, b, va, vb, 1, False
    if m_ref.get("crs") and m_img.get("crs") and m_ref["crs"] != m_img["crs"]:
        raise ConfigError(f"{names[1]}: its CRS {m_img['crs']!r} differs from {names[0]}'s {m_ref['crs']!r}")
    swapped = abs(g_img[2]) < abs(g_ref[2]) * (1 - _TOL)
    if swapped:
        (a, va, g_ref), (b, vb, g_img) = (b, vb, g_img), (a, va, g_ref)
        names = (names[1], names[0])
    k = _pitch_ratio(g_ref, g_img, names)
    off = ((g_img[1] - g_ref[1]) / g_ref[3], (g_img[0] - g_ref[0]) / g_ref[2])  # coarse corner, fine pixels
    o = tuple(round(v) for v in off)
    if any(abs(v - w) > _TOL for v, w in zip(off, o, strict=True)) or min(o) < 0:
        raise ConfigError(f"{names[1]}: its top-left corner is at ({off[0]:.4g}, {off[1]:.4g}) pixels (row, col) "
                          f"of {names[0]}; registration needs it on a pixel corner inside {names[0]}")  # fmt: skip
    ny, nx = (min(nc, (nf - oo) // k) for nc, nf, oo in zip(b.shape, a.shape, o, strict=True))
    if ny < 16 or nx < 16:
        raise InputError(f"{names[1]}: overlaps {names[0]} by only {ny} x {nx} of its pixels; at least 16 x 16")
    cut = (slice(o[0], o[0] + ny * k), slice(o[1], o[1] + nx * k))
    a, va = a[cut], (None if va is None else va[cut])
    b, vb = b[:ny, :nx], (None if vb is None else vb[:ny, :nx])
    return a, b, va, vb, k, swapped


def _swap(r):
    """The result of (IMAGE's band against --with's) read as (--with's band against IMAGE's reference)."""
    neg = (-r.offset_px[0], -r.offset_px[1])
    return dataclasses.replace(
        r, offset_px=neg, phase_offset_px=(-r.phase_offset_px[0], -r.phase_offset_px[1]),
        gain=1.0 / r.gain if r.gain else math.nan, bias=-r.bias / r.gain if r.gain else math.nan,
    )  # fmt: skip


def _tables(d: dict, name: str, p: float | None, note: str | None) -> None:
    c = wide_console()
    (dy, dx), (sy, sx) = d["offset_px"], d["sigma_px"]
    unit = f" (x {d['scale']} = {dy * d['scale']:.4g}, {dx * d['scale']:.4g} reference px)" if d["scale"] > 1 else ""
    rows = [
        ("reference", f"band {d['ref_band']} of {name}"),
        ("band", f"band {d['band']} of {Path(d['with'] or name).name}"),
        ("offset ALT dy (px)", f"{dy:.4f} ± {sy:.2g}"),
        ("offset ACT dx (px)", f"{dx:.4f} ± {sx:.2g}{unit}"),
        *([("offset ALT, ACT (m ground)", f"{d['offset_m'][0]:.4g}, {d['offset_m'][1]:.4g}")] if p else []),
        ("sign", "the band's content relative to the reference's: band(y, x) = reference(y - dy, x - dx)"),
        ("correlation of the aligned bands", f"{d['correlation']:.4f} (phase-correlation peak {d['phase_peak']:.3f})"),
        ("gain, bias (reference = gain x band + bias)", f"{d['gain']:.4g}, {d['bias']:.4g}"),
        ("pixels used", f"{d['n_pixels']} ({100 * d['usable_fraction']:.0f} % of the region)"),
        ("quality flags", ", ".join(d["flags"]) if d["flags"] else "none"),
        ("method", d["method"]),
    ]
    c.print(kv_table(f"band-to-band registration: {name}", rows))
    print_ground(p, note)
    if "inverted_contrast" in d["flags"]:
        print_warning("the band's contrast is inverted against the reference's (negative gain)", c)


@handle_errors
def registration(
    image: ImageArg,
    band: BandOpt = None,
    ref: RefOpt = 1,
    with_image: WithOpt = None,
    roi: RoiOpt = None,
    pixel_m: PixelOpt = None,
    nodata: NodataOpt = None,
    as_json: JsonOpt = False,
    out: OutOpt = None,
) -> None:
    """Band-to-band registration: the subpixel offset of --band from the reference band --ref, with its 1-sigma.

    The offset (dy ALT, dx ACT) is where the band's content lies relative to the reference's: a feature at column
    x in the reference is at x + dx in the band. Measured by phase correlation, refined by least squares (gain
    and bias free, so bands of different radiometry register); the 1-sigma from the residual noise and the
    images' gradients. With --with, the band is read from a second file (an MS file against its PAN): the finer
    image is averaged over the coarser one's pixels and the offset is in the coarser image's pixels, as --roi
    is. A flat region, a single straight edge (the offset along it is undetermined) and NaN outside the nodata
    mask are refused. -o DIR writes registration.json.
    """
    from satchain.measure.registration import measure_registration

    check_dir_outputs(out, ["registration.json"], {"IMAGE": image})
    if isinstance(ref, bool) or ref < 1:
        raise ConfigError(f"--ref = {ref!r}: bands are numbered from 1")
    if with_image is None and band is None:
        raise ConfigError("--band: give the band to register against --ref (bands are numbered from 1)")
    region = parse_roi("--roi", roi)
    a, p, meta_a = load_image(image, pixel_m, ref)
    second = image if with_image is None else with_image
    b, p_b, meta_b = load_image(second, pixel_m if with_image is None else None, band)
    va = parse_valid(a, nodata, meta_a, image)
    vb = parse_valid(b, nodata, meta_b, second)
    names = (f"IMAGE {str(image)!r}", f"--with {str(second)!r}")
    fine, coarse, vf, vc, scale, swapped = _common_grid((a, va), (b, vb), meta_a, meta_b, names)
    with measuring(image if not swapped else second, vc):
        r = measure_registration(fine, coarse, roi=region, mask=(vf, vc), scale=scale)
    if swapped:
        r = _swap(r)
    p_grid = p_b if (scale > 1 and not swapped) else p
    ground = ground_fields(p_grid, meta_b if (scale > 1 and not swapped) else meta_a)
    payload = {"image": str(image), "with": None if with_image is None else str(with_image), "ref_band": ref,
               "band": band if band is not None else 1, "roi": region, **ground, **r.to_dict()}  # fmt: skip
    if p_grid:
        payload["offset_m"] = [v * p_grid for v in r.offset_px]
    emit(
        payload,
        as_json,
        out,
        "registration",
        lambda d: [],
        lambda: _tables(payload, image.name, p_grid, ground.get("pixel_m_note")),
    )
