"""A band's offset from the reference (PAN) band in a run: measured by
:func:`satchain.measure.registration.measure_registration` and predicted from the budget
(:func:`satchain.prediction.budget.band_budgets`' ``registration``), over the whole image and in row strips.

**Measured.** The reference image is block-averaged onto the band's grid (``scale`` = band pitch / reference
pitch, an integer) and the band's content offset ``(dy_alt, dx_act)`` measured in the band's pixels, in the sign
convention of :mod:`satchain.measure.registration` (``image(y, x) = reference(y - dy, x - dx)``). The region
measured is the band's image less the rows and columns that the predicted offset, rounded to whole pixels
``(kr, kc)``, moves out of the reference; the reference is taken ``(kr, kc)`` band pixels earlier and the whole
pixels added back, so an offset of many pixels (the Earth's rotation over the arrays' distance: ~13 px ACT on
``ankarasat3-pms``) is measured as a subpixel one.

**Predicted** (band pixels): ``static_px`` (its ``registration_offset_px`` less the reference's) + the Earth's
rotation over the delay (``earth_rotation``) + the line-rate error's (``line_rate``) + each sinusoidal
oscillation's offset ``A sin(2 pi f t_c + phi)``
(``oscillations``) averaged over the reference rows the region uses, ``t_c = row x line time`` of the reference
(tests/engine/test_bands.py::test_oscillation_misregisters_bands_by_their_delay). Jitter PSDs and line-of-sight
logs over the delay are not predicted (the budget's ``not_predicted``): the checks are then n/a, the
measurement kept.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from satchain.errors import InputError

__all__ = [
    "MAX_AFFINE_DEPARTURE",
    "MIN_STRIP_ROWS",
    "N_STRIPS",
    "PAD_PX",
    "affine_departure",
    "measure_band_offset",
    "predicted_offset_px",
    "time_varying",
    "unpredicted_motion",
]

#: Row strips of a band whose line of sight moves in time (fewer when the image has too few rows for them).
N_STRIPS = 12
#: The fewest rows a strip fits.
MIN_STRIP_ROWS = 10
#: Rows of context beyond a region's fitted rows: the registration leaves half the offset, 3 sigma of its band limit,
#: half a pixel and a spline guard (4 px) out of its fit at the region's border (8 px for offsets below 1 px).
PAD_PX = 8
AXES = ("alt", "act")
#: Largest departure of a spectral scene's band reflectances from one affine function of the reference band's
#: (max |residual of the best line| / the band's range) at which a band's offset is measured: registration fits
#: ``band = gain x reference + bias``, and three materials off that line bias it (ankarasat3-pms, white and black
#: paint on dry grass: 14.6 % gives 0.096 px for blue, 7.7 % 0.052 px for green, 0.1 % 0.001 px for red).
MAX_AFFINE_DEPARTURE = 0.01


def _slot_values(layout) -> list[float]:
    """The grey reflectance of every material slot of a band's grey layout (the background first)."""
    from satchain.scene.spectral import MATERIAL_SLOTS

    out = [float(layout.background)]
    for it in layout.items:
        for slot in MATERIAL_SLOTS.get(getattr(it, "kind", ""), ()):
            v = getattr(it, slot, None)
            if v is None and hasattr(it, "amplitude"):  # a Siemens star: mean +- amplitude
                v = it.mean + (it.amplitude if slot == "bright" else -it.amplitude)
            out.append(float(v) if isinstance(v, int | float) else float("nan"))
    return out


def affine_departure(layout, system, ref: int, index: int) -> float:
    """How far band ``index`` of ``system`` sees ``layout``'s materials from one affine function of the reference
    band's: max |residual| of the least-squares line through the (reference, band) reflectance pairs of every
    material slot, over the band's range; 0 for a scene without materials (grey: every band sees the same)."""
    from satchain.engine.bands import band_response
    from satchain.scene.spectral import layout_for_band

    if not getattr(layout, "materials", ()):
        return 0.0
    a = np.asarray(_slot_values(layout_for_band(layout, *band_response(system, ref))))
    b = np.asarray(_slot_values(layout_for_band(layout, *band_response(system, index))))
    ok = np.isfinite(a) & np.isfinite(b)
    a, b = a[ok], b[ok]
    if a.size < 3 or np.ptp(b) <= 0:
        return 0.0
    design = np.vstack([a, np.ones_like(a)]).T
    coef, *_ = np.linalg.lstsq(design, b, rcond=None)
    return float(np.max(np.abs(b - design @ coef)) / np.ptp(b))


def unpredicted_motion(system) -> str | None:
    """Why the budget cannot predict the band's offset (a jitter PSD, a line-of-sight log), else None."""
    m = system.motion
    parts = [name for name, on in (("a jitter PSD ([motion.jitter_psd])", bool(m.jitter_psd)),
                                   ("a line-of-sight log ([motion.line_of_sight])", m.line_of_sight is not None))
             if on]  # fmt: skip
    if not parts:
        return None
    return (f"the budget does not predict what {' and '.join(parts)} adds to a band's offset over its delay "
            "(band_budgets' not_predicted)")  # fmt: skip


def time_varying(system) -> bool:
    """Whether the line of sight moves in time (oscillations, a jitter PSD, a log): the offset varies by row."""
    m = system.motion
    return bool(m.oscillation) or bool(m.jitter_psd) or m.line_of_sight is not None


def predicted_offset_px(entry: Mapping[str, Any], ref_rows: np.ndarray, ref_time: tuple[float, float], *,
                        weights: Mapping[str, np.ndarray] | None = None) -> dict[str, Any]:  # fmt: skip
    """The predicted offset of a band from the reference (band px, ``{"alt", "act"}``) over the reference rows
    ``ref_rows`` (each seen at its TDI window's centre ``t_c = (row + stages / 2) x line time``, ``ref_time =
    (line time s, TDI stages)`` of the reference: the budget's oscillation phase), with its parts (``static``,
    ``earth_rotation``, ``line_rate``, ``oscillations``). ``weights`` (per axis, one
    per reference row): the oscillations' offset averaged with them (what a least-squares registration of a
    region whose offset varies by row gives: its rows weighted by their gradient energy), else uniformly."""
    reg = entry["registration"]
    static = {d: float(reg["static_px"][d]) for d in AXES}
    earth, rate = reg.get("earth_rotation"), reg.get("line_rate")
    earth_px = {d: 0.0 if earth is None else float(earth[f"{d}_px"]) for d in AXES}
    rate_px = {d: 0.0 if rate is None else float(rate[f"{d}_px"]) for d in AXES}
    osc = {d: 0.0 for d in AXES}
    t_c = (np.asarray(ref_rows, dtype=float) + ref_time[1] / 2.0) * float(ref_time[0])
    for o in reg.get("oscillations") or ():
        if not t_c.size:
            continue
        d = o["axis"]
        phase = 2.0 * math.pi * float(o["frequency_hz"]) * t_c + math.radians(float(o["phase_deg"]))
        w = None if weights is None or not np.sum(weights[d]) > 0 else weights[d]
        osc[d] += float(np.average(float(o["amplitude_px"]) * np.sin(phase), weights=w))
    total = {d: static[d] + earth_px[d] + rate_px[d] + osc[d] for d in AXES}
    parts = {"static": static, "earth_rotation": earth_px, "line_rate": rate_px, "oscillations": osc}
    return {**total, "parts": parts}


def _span(n_band: int, n_ref: int, scale: int, k: int) -> tuple[int, int]:
    """Band pixels ``[lo, hi)`` along one axis whose reference, ``k`` band pixels earlier, lies in the reference."""
    return max(0, k), min(n_band, n_ref // scale + k)


def _gradient_weights(image: np.ndarray, rows: tuple[int, int], cols: tuple[int, int], scale: int) -> dict:
    """Per reference row (``scale`` per band row of ``rows``): the band image's gradient energy along each axis over
    ``cols``, band-limited as the registration's least squares sees it (Gaussian, 1 px)."""
    from scipy import ndimage as ndi

    from satchain.measure.registration import SMOOTH_PX

    a = ndi.gaussian_filter(np.asarray(image, dtype=float), SMOOTH_PX, mode="mirror")
    gy, gx = np.gradient(a)
    sl = (slice(*rows), slice(*cols))
    return {"alt": np.repeat((gy[sl] ** 2).sum(axis=1), scale), "act": np.repeat((gx[sl] ** 2).sum(axis=1), scale)}


def _measure(reference: np.ndarray, image: np.ndarray, scale: int, whole: tuple[int, int],
             rows: tuple[int, int] | None, entry: Mapping[str, Any],
             ref_time: tuple[float, float]) -> dict[str, Any]:  # fmt: skip
    """One measurement over the band rows ``rows`` (None: all), given :data:`PAD_PX` rows of context each side
    where the images have them (the registration leaves them out of its fit), beside its prediction over the
    rows fitted: ``{"measured_px", "sigma_px", "predicted_px", "parts", "rows", "correlation", "reason"}``."""
    from satchain.measure.registration import measure_registration

    kr, kc = whole
    r_lo, r_hi = _span(image.shape[0], reference.shape[0], scale, kr)
    c0, c1 = _span(image.shape[1], reference.shape[1], scale, kc)
    a, b = (r_lo + PAD_PX, r_hi - PAD_PX) if rows is None else rows
    lo, hi = max(r_lo, a - PAD_PX), min(r_hi, b + PAD_PX)
    fit = (lo + PAD_PX, hi - PAD_PX)  # the rows the fit uses
    out: dict[str, Any] = {"measured_px": None, "sigma_px": None, "rows": [int(fit[0]), int(fit[1])],
                           "correlation": None, "reason": None}  # fmt: skip
    ref_rows = np.arange(scale * (fit[0] - kr), scale * (max(fit) - kr))
    weights = None
    if fit[1] - fit[0] < 1 or c1 - c0 < 2 * PAD_PX + 8:
        out["reason"] = (f"the region both images cover ({max(hi - lo, 0)} x {max(c1 - c0, 0)} band px) leaves no "
                         f"rows to fit beside the registration's {PAD_PX} px border")  # fmt: skip
    else:
        weights = _gradient_weights(image, fit, (c0 + PAD_PX, c1 - PAD_PX), scale)
        ref = reference[scale * (lo - kr) : scale * (hi - kr), scale * (c0 - kc) : scale * (c1 - kc)]
        try:
            r = measure_registration(ref, image[lo:hi, c0:c1], scale=scale)
            out.update(measured_px={"alt": r.offset_px[0] + kr, "act": r.offset_px[1] + kc},
                       sigma_px={"alt": r.sigma_px[0], "act": r.sigma_px[1]}, correlation=r.correlation)  # fmt: skip
        except InputError as exc:
            out["reason"] = f"registration refused: {exc}"
    pred = predicted_offset_px(entry, ref_rows, ref_time, weights=weights)
    out["predicted_px"], out["parts"] = {d: pred[d] for d in AXES}, pred["parts"]
    return out


def measure_band_offset(reference: np.ndarray, image: np.ndarray, *, scale: int, entry: Mapping[str, Any],
                        ref_time: tuple[float, float], strips: bool) -> dict[str, Any]:  # fmt: skip
    """The band's offset from the reference over the whole image, and (``strips``) in up to :data:`N_STRIPS` row
    strips of at least :data:`MIN_STRIP_ROWS` rows, each beside its prediction: ``{"measured_px", "sigma_px",
    "predicted_px", "parts", "rows", "correlation", "reason", "whole_px", "strips": [...]}`` (``measured_px``
    None and ``reason`` when refused)."""
    guess = predicted_offset_px(entry, np.arange(reference.shape[0]), ref_time)
    whole = (int(round(guess["alt"])), int(round(guess["act"])))
    out = _measure(reference, image, scale, whole, None, entry, ref_time)
    out["whole_px"] = list(whole)
    out["strips"] = []
    if strips:
        r0, r1 = out["rows"]
        n = min(N_STRIPS, (r1 - r0) // MIN_STRIP_ROWS)
        cuts = np.linspace(r0, r1, n + 1).round().astype(int) if n >= 2 else np.array([], dtype=int)
        for a, b in zip(cuts[:-1], cuts[1:], strict=False):
            st = _measure(reference, image, scale, whole, (int(a), int(b)), entry, ref_time)
            out["strips"].append({k: st[k] for k in ("rows", "measured_px", "sigma_px", "predicted_px", "reason")})
    return out
