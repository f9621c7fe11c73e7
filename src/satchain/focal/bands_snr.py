"""A band's SNR in a run: the signal SNR of the scene's clear background measured on the band's image, against the
band's budget at the background's reflectance in that band (:func:`satchain.radiometry.radiometric_budget` of the
band's system: the budget's ``snr``, whose scene reflectance is ``illumination.reflectance``).

**Measured** (the method of tests/engine/test_bands.py::test_every_band_snr_matches_its_budget, on the pixels of a
run's scene that no target touches): the background pixels are those at least :data:`MARGIN_PX` band pixels and
:data:`MARGIN_M` metres from every item's ``bbox_m`` (the optics' tails kept out). The noise is the standard
deviation of those pixels about a plane fitted to them (a slow shading taken out; fixed-pattern PRNU, shot, dark,
read and quantisation noise stay, as the budget's noise holds them); the signal is the pixels' mean, less the dark
level and offset, in electrons (:func:`to_electrons`). SNR = signal / noise. Its 1-sigma: ``SNR / sqrt(2 (n - 3))``
for ``n`` pixels (the standard deviation's own sampling error; the mean's is ~1/SNR of it).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["MARGIN_M", "MARGIN_PX", "MIN_PIXELS", "measure_background_snr", "predicted_background_snr", "to_electrons"]

#: Band pixels, and metres, kept clear of every item's bounding box (the optics' tails): the larger of the two.
MARGIN_PX = 4
MARGIN_M = 8.0
#: The fewest background pixels an SNR is measured from (its 1-sigma then <= 2.2 %).
MIN_PIXELS = 1000


def to_electrons(value: float, sensor, units: str) -> float:
    """The signal electrons (dark level and offset removed) of a mean image value in ``units``."""
    if units == "electrons":
        return value - sensor.dark_e - sensor.offset_e
    if units == "dn":  # DN = floor(e / g): its mean is e / g - 1/2
        return (value + 0.5) * sensor.gain_e_per_dn - sensor.dark_e - sensor.offset_e
    if units == "radiance":
        value = (value - sensor.radiance_offset) / sensor.radiance_per_unit
    return value * sensor.electrons_per_unit


def electrons_per_unit(sensor, units: str) -> float:
    """Electrons per unit of the image's ``units`` (a noise's scale)."""
    if units == "electrons":
        return 1.0
    if units == "dn":
        return float(sensor.gain_e_per_dn)
    k = float(sensor.electrons_per_unit)
    return k / float(sensor.radiance_per_unit) if units == "radiance" else k


def _background_mask(shape: tuple[int, int], truth: dict, to_pixel) -> np.ndarray:
    """Pixels at least :data:`MARGIN_PX` and :data:`MARGIN_M` from every item's ``bbox_m`` (``to_pixel(x, y) -> (col,
    row)``: scene metres to the image's continuous pixel coordinates, pixel edges at integers)."""
    ok = np.ones(shape, dtype=bool)
    x0, y0 = to_pixel(0.0, 0.0)
    x1, y1 = to_pixel(MARGIN_M, MARGIN_M)
    margin = (max(MARGIN_PX, math.ceil(abs(y1 - y0))), max(MARGIN_PX, math.ceil(abs(x1 - x0))))
    for it in truth.get("items", []):
        box = it.get("bbox_m")
        if box is None:
            continue
        cols, rows = zip(*(to_pixel(x, y) for x in (box[0], box[2]) for y in (box[1], box[3])), strict=True)
        c0, c1 = int(math.floor(min(cols))) - margin[1], int(math.ceil(max(cols))) + margin[1]
        r0, r1 = int(math.floor(min(rows))) - margin[0], int(math.ceil(max(rows))) + margin[0]
        ok[max(r0, 0) : max(r1, 0), max(c0, 0) : max(c1, 0)] = False
    ok[: margin[0]], ok[-margin[0] :], ok[:, : margin[1]], ok[:, -margin[1] :] = False, False, False, False
    return ok


def measure_background_snr(image: np.ndarray, truth: dict, *, to_pixel, sensor, units: str) -> dict[str, Any]:
    """``{"snr", "sigma", "signal_e", "noise_e", "n_pixels", "reason"}`` of the clear background (see the module;
    ``to_pixel``: as :func:`_background_mask`'s)."""
    a = np.asarray(image, dtype=float)
    mask = _background_mask(a.shape, truth, to_pixel)
    n = int(mask.sum())
    if n < MIN_PIXELS:
        return {"snr": None, "sigma": None, "n_pixels": n,
                "reason": f"the clear background (at least {MARGIN_PX} band px and {MARGIN_M:g} m from every target) "
                f"holds {n} pixels; the SNR needs at least {MIN_PIXELS}"}  # fmt: skip
    rows, cols = np.nonzero(mask)
    v = a[mask]
    design = np.stack([np.ones(n), rows - rows.mean(), cols - cols.mean()], axis=1)
    coef, *_ = np.linalg.lstsq(design, v, rcond=None)
    k = electrons_per_unit(sensor, units)
    noise_e = float(np.sqrt(np.sum((v - design @ coef) ** 2) / (n - 3))) * k
    signal_e = to_electrons(float(v.mean()), sensor, units)
    if not noise_e > 0:
        return {"snr": None, "sigma": None, "n_pixels": n, "reason": "the background has no noise"}
    snr = signal_e / noise_e
    return {"snr": snr, "sigma": abs(snr) / math.sqrt(2.0 * (n - 3)), "signal_e": signal_e, "noise_e": noise_e,
            "n_pixels": n, "reason": None}  # fmt: skip


def predicted_background_snr(system, entry: dict, reflectance: float) -> float:
    """The band budget's signal SNR (``entry["snr"]``) when ``reflectance`` is the budget's scene reflectance,
    else the band's radiometric budget at ``reflectance`` (``system``: the band's)."""
    if abs(reflectance - system.illumination.reflectance) <= 1e-9:
        return float(entry["snr"])
    from satchain.radiometry import radiometric_budget

    return float(radiometric_budget(system.replace({"illumination.reflectance": reflectance})).snr)
