"""Image-quality prediction: edge response from the MTF, RER, overshoot H, noise gain G and GIQE NIIRS.

The General Image Quality Equation predicts the NIIRS rating of an image from its scale (GSD, in
**inches**), sharpness (the relative edge response RER and, for sharpened imagery, the edge overshoot H)
and noise (the contrast SNR and the noise gain G of the sharpening kernel):

* GIQE 3 (IBSM, eq. 3-56): ``NIIRS = 11.81 + 3.32 log10(RER / GSD) - 1.48 H - G / SNR``;
* GIQE 4 (Leachtenauer, Malila, Irvine, Colburn & Salvaggio, "General Image-Quality Equation: GIQE",
  Applied Optics 36(32), 8322-8328, 1997):
  ``NIIRS = 10.251 - a log10(GSD) + b log10(RER) - 0.656 H - 0.344 G / SNR`` with ``a = 3.32, b = 1.559``
  if ``RER >= 0.9`` else ``a = 3.16, b = 2.817``; GSD, RER and H are geometric means of the two image axes;
* GIQE 5 (NGA, "General Image Quality Equation (GIQE) Version 5.0", 16 Sep 2015):
  ``NIIRS = 9.57 - 3.32 log10(GSD) + 3.32 (1 - exp(-1.9 / SNR)) log10(RER) - 2 log10(RER)^4 - 1.8 / SNR``;
  no H and G terms (the equation assumes its own optimal processing and takes RER and SNR of the
  unsharpened image); published check value NIIRS 5.0 at RER 0.35, GSD 20.8 in, SNR 50.

ACT/ALT and off-nadir conventions (as the AFRL/Kitware pyBSM implementation reads the sources; satchain
systems look at nadir, elevation 90 deg): GIQE 4 uses the ground-plane geometric-mean GSD,
``GSD / sqrt(sin(elevation))``; GIQE 5 the geometric mean of the image-plane and ground-plane GSDs,
``GSD / sin(elevation)^(1/4)``, and the weighted RER ``(RER_max RER_min^2)^(1/3)``.

The edge response of a real, symmetric system (Fiete 2010, sec. 12.4; IBSM eq. 3-63) is
``ER(x) = 1/2 + (1/pi) integral_0^inf OTF(f) sin(2 pi f x) / f df`` with ``x`` in pixels from the edge and
``f`` in cycles/pixel; ``RER = ER(+0.5) - ER(-0.5)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from satchain._argcheck import checked
from satchain._validate import as_float_array, check_positive, check_range
from satchain.errors import ConfigError, InputError

__all__ = [
    "QualityResult",
    "complete_quality",
    "edge_response_from_mtf",
    "giqe3",
    "giqe4",
    "giqe5",
    "giqe5_rer",
    "kernel_transfer",
    "noise_gain",
    "overshoot",
    "predict_quality",
    "rer",
]

OVERSHOOT_X_PX = np.arange(1.0, 3.0 + 1e-9, 0.25)  # Leachtenauer 1997: 1.0 to 3.0 px in 0.25 px steps


def _otf_on_grid(f_cy_per_px, otf) -> tuple[np.ndarray, np.ndarray]:
    f = as_float_array("f_cy_per_px", f_cy_per_px, ndim=1)
    o = np.asarray(otf)
    if np.iscomplexobj(o):
        if o.size and np.max(np.abs(o.imag)) > 1e-9 * max(np.max(np.abs(o)), 1e-300):
            raise InputError(
                "mtf: complex OTF with a non-zero phase; pass np.abs(otf) (the MTF, as the GIQE uses) or its real part"
            )
        o = o.real
    m = as_float_array("mtf", o, ndim=1)
    if f.shape != m.shape or f.size < 2:
        raise InputError(f"f_cy_per_px and mtf: must be 1-D of equal length >= 2, got {f.shape} and {m.shape}")
    if f[0] != 0.0 or np.any(np.diff(f) <= 0):
        raise InputError("f_cy_per_px: must start at 0 and increase strictly")
    if abs(m[0] - 1.0) > 1e-6:
        raise InputError(f"mtf[0] = {m[0]!r}: must be 1 (normalise the MTF to its zero-frequency value)")
    return f, m


def edge_response_from_mtf(f_cy_per_px, mtf, x_px) -> np.ndarray:
    """Edge response at ``x_px`` pixels from an ideal edge, from a real (signed) OTF or an MTF.

    ``ER(x) = 1/2 + integral_0^F MTF(f) sin(2 pi f x) / (pi f) df``: the edge response of a system with a
    symmetric line-spread function whose OTF is ``mtf`` (IBSM eq. 3-63; Fiete 2010 sec. 12.4). A signed
    OTF (e.g. a sinc with negative lobes) is used as given; an MTF means its phase is taken as zero. The
    integral is a trapezoid on ``f_cy_per_px``, which must start at 0 and reach where the MTF has fallen to
    ~0 (the optical cutoff), with steps well below ``1 / |x|``.

    Parameters
    ----------
    f_cy_per_px : (n,) array_like
        Frequencies, cycles per pixel, from 0, strictly increasing.
    mtf : (n,) array_like
        OTF (real) or MTF on ``f_cy_per_px``, with ``mtf[0] == 1``.
    x_px : array_like
        Positions from the edge, pixels (ALT or ACT, whichever axis ``mtf`` belongs to).

    Examples
    --------
    >>> f = np.linspace(0, 400, 400001)
    >>> er = edge_response_from_mtf(f, np.sinc(f), [-0.5, 0.0, 0.25])  # ideal pixel: a linear ramp
    >>> [round(float(v), 3) for v in er]
    [0.0, 0.5, 0.75]
    """
    f, m = _otf_on_grid(f_cy_per_px, mtf)
    x = as_float_array("x_px", x_px)
    xmax = float(np.max(np.abs(x))) if x.size else 0.0
    if xmax > 0 and np.max(np.diff(f)) > 0.125 / xmax:
        raise InputError(
            f"f_cy_per_px: step {np.max(np.diff(f)):.3g} cy/px is too coarse for |x| up to {xmax:g} px "
            f"(need <= {0.125 / xmax:.3g})"
        )
    xs = x.reshape(-1, 1)
    integrand = m * 2.0 * xs * np.sinc(2.0 * f * xs)  # = MTF sin(2 pi f x) / (pi f), finite at f = 0
    return (0.5 + np.trapezoid(integrand, f, axis=-1)).reshape(x.shape)


def rer(f_cy_per_px, mtf) -> float:
    """Relative edge response ``ER(+0.5 px) - ER(-0.5 px)`` along one axis (Leachtenauer 1997).

    Examples
    --------
    >>> f = np.linspace(0, 400, 400001)
    >>> round(rer(f, np.sinc(f)), 3)  # an ideal 100 %-fill pixel, nothing else
    1.0
    """
    er = edge_response_from_mtf(f_cy_per_px, mtf, [-0.5, 0.5])
    return float(er[1] - er[0])


def overshoot(f_cy_per_px, mtf) -> float:
    """Edge overshoot H along one axis (GIQE 4, Leachtenauer 1997).

    "Measured over the range of 1.0 to 3.0 pixels from the edge in 0.25-pixel increments. If the edge is
    monotonically increasing, it is defined as the value at 1.25 pixels from the edge" -- otherwise the
    maximum of the edge response there. The edge response is normalised to 0 -> 1, so an unsharpened
    system has H just below 1.

    Examples
    --------
    >>> f = np.linspace(0, 2, 4001)
    >>> gauss = np.exp(-2 * (np.pi * 0.5 * f) ** 2)  # Gaussian LSF, sigma 0.5 px: monotone edge
    >>> round(overshoot(f, gauss), 4)
    0.9938
    """
    er = edge_response_from_mtf(f_cy_per_px, mtf, OVERSHOOT_X_PX)
    if np.all(np.diff(er) > 0):
        return float(er[1])
    return float(np.max(er))


def noise_gain(kernel=None) -> float:
    """Noise gain of a sharpening (MTFC) kernel: ``G = sqrt(sum k^2)`` of the kernel normalised to unit
    sum (unit DC gain) -- the rms gain of white noise (Leachtenauer 1997). ``None`` (no MTFC) gives 1.

    Examples
    --------
    >>> noise_gain(None), noise_gain([[0, 0, 0], [0, 1, 0], [0, 0, 0]])
    (1.0, 1.0)
    >>> round(noise_gain([-0.5, 2.0, -0.5]), 4)
    2.1213
    """
    if kernel is None:
        return 1.0
    k = as_float_array("kernel", kernel)
    s = float(k.sum())
    if k.size == 0 or abs(s) < 1e-12:
        raise InputError(f"kernel: its weights must have a non-zero sum (got {s!r})")
    return float(np.sqrt(np.sum((k / s) ** 2)))


def kernel_transfer(kernel, f_cy_per_px, *, axis: str) -> np.ndarray:
    """Transfer function of a centred 2-D kernel ``[row, col] = [y, x]`` along ``axis`` ("act" = f_x,
    "alt" = f_y), normalised to unit DC gain: ``H(f) = sum_k w_k exp(-2 pi i f d_k)`` (real part: the
    kernel is assumed symmetric).

    Examples
    --------
    >>> [round(float(v), 3) for v in kernel_transfer([[-0.5, 2.0, -0.5]], [0.0, 0.5], axis="act")]
    [1.0, 3.0]
    """
    k = np.atleast_2d(as_float_array("kernel", kernel))
    k = k / k.sum()
    f = as_float_array("f_cy_per_px", f_cy_per_px)
    w = k.sum(axis=0) if axis == "act" else k.sum(axis=1)
    d = np.arange(w.size) - (w.size - 1) / 2.0
    return np.cos(2.0 * np.pi * np.multiply.outer(f, d)) @ w


def _check_common(gsd_in: float, rer_value: float, snr: float, elevation_deg: float) -> tuple[float, ...]:
    return (
        check_positive("gsd_in", gsd_in),
        check_positive("rer", rer_value),
        check_positive("snr", snr),
        math.sin(math.radians(check_range("elevation_deg", elevation_deg, 0.0, 90.0, lo_open=True))),
    )


def giqe3(*, gsd_in: float, rer: float, overshoot: float, noise_gain: float = 1.0, snr: float) -> float:
    """GIQE 3 NIIRS: ``11.81 + 3.32 log10(RER / GSD) - 1.48 H - G / SNR`` (IBSM eq. 3-56; GSD in inches,
    geometric means).

    Examples
    --------
    >>> round(giqe3(gsd_in=10.0, rer=1.0, overshoot=1.0, noise_gain=1.0, snr=100.0), 4)
    7.0
    """
    g, r, s, _ = _check_common(gsd_in, rer, snr, 90.0)
    h = check_range("overshoot", overshoot, 0.0, None)
    n = check_positive("noise_gain", noise_gain)
    return 11.81 + 3.32 * math.log10(r / g) - 1.48 * h - n / s


def giqe4(
    *,
    gsd_in: float,
    rer: float,
    overshoot: float,
    noise_gain: float = 1.0,
    snr: float,
    elevation_deg: float = 90.0,
) -> float:
    """GIQE 4 NIIRS (Leachtenauer et al. 1997, Applied Optics 36(32) 8322).

    ``NIIRS = 10.251 - a log10(GSD) + b log10(RER) - 0.656 H - 0.344 G / SNR``, ``a = 3.32, b = 1.559`` for
    ``RER >= 0.9``, else ``a = 3.16, b = 2.817``. ``gsd_in``: geometric-mean GSD in inches, perpendicular
    to the line of sight; off nadir it is projected to the ground, ``GSD / sqrt(sin(elevation))``.
    ``rer``, ``overshoot``: geometric means of the two axes; ``snr``: the contrast SNR
    (:func:`satchain.radiometry.contrast_snr`).

    Examples
    --------
    >>> round(giqe4(gsd_in=10.0, rer=0.5, overshoot=0.9, noise_gain=1.0, snr=50.0), 4)
    5.6457
    """
    g, r, s, sin_e = _check_common(gsd_in, rer, snr, elevation_deg)
    h = check_range("overshoot", overshoot, 0.0, None)
    n = check_positive("noise_gain", noise_gain)
    a, b = (3.32, 1.559) if r >= 0.9 else (3.16, 2.817)
    return 10.251 - a * math.log10(g / math.sqrt(sin_e)) + b * math.log10(r) - 0.656 * h - 0.344 * n / s


def giqe5(*, gsd_in: float, rer: float, snr: float, elevation_deg: float = 90.0) -> float:
    """GIQE 5 NIIRS (NGA, "General Image Quality Equation (GIQE) Version 5.0", 2015).

    ``NIIRS = 9.57 - 3.32 log10(GSD) + 3.32 (1 - exp(-1.9 / SNR)) log10(RER) - 2 log10(RER)^4 - 1.8 / SNR``
    with ``GSD = gsd_in / sin(elevation)^(1/4)`` (inches; the geometric mean of the image-plane and
    ground-plane GSDs), ``rer`` the unsharpened RER (combine axes with :func:`giqe5_rer`) and ``snr`` the
    contrast SNR of the unsharpened image.

    Examples
    --------
    >>> round(giqe5(gsd_in=20.8, rer=0.35, snr=50.0), 2)  # NGA's published check case
    5.02
    """
    g, r, s, sin_e = _check_common(gsd_in, rer, snr, elevation_deg)
    lr = math.log10(r)
    return 9.57 - 3.32 * math.log10(g / sin_e**0.25) + 3.32 * (1 - math.exp(-1.9 / s)) * lr - 2 * lr**4 - 1.8 / s


def giqe5_rer(rer_act: float, rer_alt: float) -> float:
    """GIQE 5 combination of the two axes' RER, ``(RER_max RER_min^2)^(1/3)`` (weights the worse axis; as
    implemented by pyBSM from the NGA 2015 document). Equal axes give that value.

    Examples
    --------
    >>> giqe5_rer(0.5, 0.5), round(giqe5_rer(0.8, 0.4), 4)
    (0.5, 0.504)
    """
    a = check_positive("rer_act", rer_act)
    b = check_positive("rer_alt", rer_alt)
    return (max(a, b) * min(a, b) ** 2) ** (1.0 / 3.0)


# ---------------------------------------------------------------------------- a whole system
@dataclass(frozen=True)
class QualityResult:
    """Predicted image quality of an ImagingSystem (nadir view).

    ``rer_act``/``rer_alt``, ``overshoot_act``/``overshoot_alt``: per axis, from the system OTF (after
    the sharpening kernel, if any, for the GIQE 3/4 terms); ``rer``: their geometric mean; ``rer_giqe5``:
    the GIQE 5 combination of the *unsharpened* RERs; ``snr``: the contrast SNR; ``otf_kind``: whether the
    signed OTF or its modulus (an aberrated, complex OTF) was used.
    """

    gsd_m: float
    gsd_in: float
    rer_act: float
    rer_alt: float
    rer: float
    rer_giqe5: float
    overshoot_act: float
    overshoot_alt: float
    overshoot: float
    noise_gain: float
    snr: float
    giqe3: float
    giqe4: float
    giqe5: float
    mtfa_act: float
    mtfa_alt: float
    otf_kind: str

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (names carry units; RER, H, G, SNR and NIIRS are unitless, MTFA in cy/px)."""
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def _axis_otf(system, otf, axis: str, f_px: np.ndarray) -> np.ndarray:
    from satchain.units import cy_per_px_to_cy_per_mm

    pitch = system.detector.pitch_x_m if axis == "act" else system.detector.pitch_y_m
    f_mm = cy_per_px_to_cy_per_mm(f_px, pitch_m=pitch)
    z = np.zeros_like(f_mm)
    return np.asarray(otf(f_mm, z) if axis == "act" else otf(z, f_mm))


def _axis_terms(system, otf, axis: str, kernel, df: float) -> dict[str, Any]:
    """RER (raw and after ``kernel``), overshoot and MTFA along one axis, from 0 to the optical cutoff."""
    from satchain.tf.budget import mtfa
    from satchain.units import cy_per_mm_to_cy_per_px

    pitch = system.detector.pitch_x_m if axis == "act" else system.detector.pitch_y_m
    cutoff = float(np.max(cy_per_mm_to_cy_per_px(system.optical_cutoff_cy_per_mm, pitch_m=pitch)))
    f = np.arange(0.0, max(cutoff, 0.5) * 1.0001 + df, df)
    o = _axis_otf(system, otf, axis, f)
    if np.iscomplexobj(o) and np.max(np.abs(o.imag)) > 1e-9:
        o, kind = np.abs(o), "mtf"
    else:
        o, kind = np.real(o), "signed_otf"
    o = o / o[0]
    sharp = o if kernel is None else o * kernel_transfer(kernel, f, axis=axis)
    return {
        "rer_raw": rer(f, o),
        "rer": rer(f, sharp),
        "h": overshoot(f, sharp),
        "mtfa": mtfa(f, np.abs(o), f_max_cy_per_px=0.5),
        "kind": kind,
    }


#: frequency samples the edge-response integrals may use per axis, and the bytes each costs (measured:
#: ~380 per sample with the OTF's wavelengths and the 9 overshoot positions)
MAX_GRID_POINTS = 1_000_000
_BYTES_PER_GRID_POINT = 400


def _check_grid(system, df: float) -> None:
    """Refuse a frequency step whose grid (0 to the optical cutoff) would be too large, before allocating."""
    from satchain._safety import check_memory
    from satchain.errors import ResourceLimitError
    from satchain.units import cy_per_mm_to_cy_per_px

    pitch = min(system.detector.pitch_x_m, system.detector.pitch_y_m)
    f_top = max(float(np.max(cy_per_mm_to_cy_per_px(system.optical_cutoff_cy_per_mm, pitch_m=pitch))), 0.5) * 1.0001
    n = f_top / df
    need = n * _BYTES_PER_GRID_POINT
    if n > MAX_GRID_POINTS:
        raise ResourceLimitError(
            f"df_cy_per_px = {df:g}: the frequency grid to the optical cutoff ({f_top:.3g} cy/px) would hold "
            f"{n:.3g} points and need about {need / 2**30:.3g} GiB of memory; must be >= "
            f"{f_top / MAX_GRID_POINTS:.2g} (at most {MAX_GRID_POINTS:,} points; the default 0.002 is accurate)"
        )
    check_memory(need, f"df_cy_per_px = {df:g}", fix="use a larger df_cy_per_px")


@checked
def predict_quality(system, *, otf=None, kernel=None, df_cy_per_px: float = 0.002) -> QualityResult:
    """RER, overshoot, noise gain, contrast SNR, MTFA and GIQE 3/4/5 NIIRS of ``system`` at nadir.

    The edge responses come from the ACT (``f_y = 0``) and ALT (``f_x = 0``) cuts of the system OTF
    (:class:`satchain.tf.budget.SystemOTF`) from 0 to the optical cutoff of the shortest MTF wavelength;
    the signed OTF is used when it is real, its modulus when aberrations make it complex. ``kernel``: an
    optional sharpening (MTFC) kernel ``[row, col] = [y, x]``, applied to the GIQE 3/4 RER and H and
    giving their noise gain G; GIQE 5 takes the unsharpened RER. The SNR is
    :func:`satchain.radiometry.contrast_snr`. MTFA (:func:`satchain.tf.budget.mtfa`) is the area under the
    MTF from 0 to Nyquist in cycles/pixel, per axis.

    Examples
    --------
    >>> from satchain import load_preset
    >>> q = predict_quality(load_preset("ankarasat3"))
    >>> q.rer_act > q.rer_alt, 3 < q.giqe5 < 8
    (True, True)
    """
    from satchain.radiometry import contrast_snr
    from satchain.tf.budget import SystemOTF
    from satchain.units import m_to_inches

    df = check_range("df_cy_per_px", df_cy_per_px, 0.0, 0.02, lo_open=True)
    _check_grid(system, df)
    otf = SystemOTF(system) if otf is None else otf
    per_axis = {axis: _axis_terms(system, otf, axis, kernel, df) for axis in ("act", "alt")}
    a, b = per_axis["act"], per_axis["alt"]
    rer_gm = math.sqrt(a["rer"] * b["rer"])
    h_gm = math.sqrt(a["h"] * b["h"])
    g = noise_gain(kernel)
    snr = contrast_snr(system)
    gsd_in = float(m_to_inches(system.gsd_los_m))  # the GIQE projects it to the ground by the elevation
    elev = system.orbit.elevation_deg
    r5 = giqe5_rer(a["rer_raw"], b["rer_raw"])
    return QualityResult(
        gsd_m=system.gsd_m,
        gsd_in=gsd_in,
        rer_act=a["rer"],
        rer_alt=b["rer"],
        rer=rer_gm,
        rer_giqe5=r5,
        overshoot_act=a["h"],
        overshoot_alt=b["h"],
        overshoot=h_gm,
        noise_gain=g,
        snr=snr,
        giqe3=giqe3(gsd_in=float(m_to_inches(system.gsd_m)), rer=rer_gm, overshoot=h_gm, noise_gain=g, snr=snr),
        giqe4=giqe4(gsd_in=gsd_in, rer=rer_gm, overshoot=h_gm, noise_gain=g, snr=snr, elevation_deg=elev),
        giqe5=giqe5(gsd_in=gsd_in, rer=r5, snr=snr, elevation_deg=elev),
        mtfa_act=a["mtfa"],
        mtfa_alt=b["mtfa"],
        otf_kind="mtf" if "mtf" in (a["kind"], b["kind"]) else "signed_otf",
    )


#: the figures of a quality mapping that a prediction uses (:func:`satchain.prediction.core.predict`)
QUALITY_USED = ("giqe5", "rer_giqe5", "snr")


def _refuse_unused(given: dict[str, Any], own: dict[str, Any]) -> None:
    """Refuse a figure of ``given`` that is not used (not in :data:`QUALITY_USED`) and differs from the system's
    own (``own``): it would be ignored without a word."""
    for k, v in given.items():
        mine = own[k]
        if k in QUALITY_USED or v == mine:
            continue
        try:
            same = not isinstance(mine, str) and (math.isclose(float(v), mine, rel_tol=1e-9) or
                                                  (math.isnan(float(v)) and math.isnan(mine)))  # fmt: skip
        except (TypeError, ValueError):
            same = False
        if not same:
            raise ConfigError(
                f"quality[{k!r}] = {v!r}: predict does not use it (it uses {', '.join(QUALITY_USED)}: the NIIRS "
                f"given, or that of the RER and SNR used), and it is not this system's ({mine!r}); leave it out, "
                "or give the figure used (an RER as 'rer_giqe5')"
            )


def complete_quality(system, quality=None, *, otf=None) -> dict[str, Any]:
    """A quality mapping with every figure it does not give taken from :func:`predict_quality` (``system``).

    ``quality`` (None: all predicted) gives ``giqe5``, ``rer_giqe5`` and ``snr``, the figures that are used, or
    some of them; another of :class:`QualityResult`'s fields is taken only as the system's own value (a whole
    ``predict_quality(system).to_dict()``), as it is not used: one that differs (``{"rer": 0.3}``) is refused,
    naming the figures used. Without ``giqe5`` the NIIRS is that of the RER and SNR used (:func:`giqe5`), so
    ``{"snr": 50}`` gives the system's NIIRS at SNR 50. A key that is no field is refused naming it and the
    allowed ones, as is a used figure that is no finite number (> 0 for the RER and SNR).

    Examples
    --------
    >>> from satchain import load_preset
    >>> s = load_preset("ankarasat3")
    >>> q = complete_quality(s, {"snr": 50.0})
    >>> q["snr"], q["rer_giqe5"] == predict_quality(s).rer_giqe5, q["giqe5"] > predict_quality(s).giqe5
    (50.0, True, True)
    """
    allowed = tuple(QualityResult.__dataclass_fields__)
    given = {} if quality is None else dict(quality)
    unknown = [k for k in given if k not in allowed]
    if unknown:
        raise ConfigError(
            f"quality: unknown key(s) {', '.join(map(repr, unknown))}; allowed: {', '.join(allowed)} (the fields "
            f"of predict_quality(...).to_dict(); {', '.join(QUALITY_USED)} are used)"
        )
    for k in QUALITY_USED:
        if k in given:
            lo = None if k == "giqe5" else 0.0
            given[k] = check_range(f"quality[{k!r}]", given[k], lo, None, lo_open=True)
    if set(given) == set(QUALITY_USED):
        return given
    own = predict_quality(system, otf=otf).to_dict()
    _refuse_unused(given, own)
    out = {**own, **given}
    if "giqe5" not in given:
        elev = system.orbit.elevation_deg
        out["giqe5"] = giqe5(gsd_in=out["gsd_in"], rer=out["rer_giqe5"], snr=out["snr"], elevation_deg=elev)
    return out
