"""Optics transfer function: diffraction of an obscured pupil, spiders, aberrations, polychromatic weighting.

Two independent routes to the diffraction OTF, which agree within 1e-3 where both apply:

* :func:`annular_mtf` -- the closed form for a circular pupil with a central obscuration (O'Neill 1956;
  reproduced in Schroeder, *Astronomical Optics*, 2nd ed., 2000);
* :class:`PupilOTF` / :func:`pupil_otf` -- the autocorrelation of a sampled pupil function computed by FFT,
  i.e. the Fourier transform of the PSF of the reference paper's eq. 1,
  ``PSF = |FT{p}|^2 / ((lambda f)^2 * integral p)``. It handles spider vanes and a wavefront given as Zernike
  coefficients (Noll 1976), which the closed form cannot.

Modules (every public name is re-exported here): :mod:`satchain.tf.annular` (the closed form and Shannon's
ATF), :mod:`satchain.tf.pupil` (pupil-FFT OTF and PSF, spiders) with :mod:`satchain.tf.zernike` (Noll-ordered
Zernike polynomials); this module combines them over wavelength (:class:`DiffractionOTF`).

Conventions. Frequencies are focal-plane cycles per mm, ``x`` = across-track (ACT, array columns), ``y`` =
along-track (ALT, array rows). A pupil displacement ``s`` (m) corresponds to the focal-plane frequency
``f = s / (lambda * focal_length)``, so the incoherent cutoff is ``1 / (lambda F#)``. The OTF is the Fourier
transform of the PSF with the kernel ``exp(-2 pi i f.x)``; the pupil function is ``T(u) exp(+2 pi i W(u))``
with ``W`` in waves, so a positive x tilt (Noll 2) moves the PSF towards +x.

Examples
--------
>>> round(float(annular_mtf(50.0, wavelength_m=650e-9, f_number=9.72, obscuration_ratio=0.33)), 4)
0.4353
"""

from __future__ import annotations

import functools
import math

import numpy as np

from satchain.tf.annular import SHANNON_W0_WAVES, _oneill, annular_mtf, optical_cutoff_cy_per_mm, shannon_atf
from satchain.tf.pupil import PupilOTF, PupilParams, PupilPSF, _broadcast_freqs, pupil_otf, pupil_psf
from satchain.tf.zernike import noll_to_nm, zernike_noll

__all__ = [
    "SHANNON_W0_WAVES",
    "DiffractionOTF",
    "PupilOTF",
    "PupilPSF",
    "PupilParams",
    "annular_mtf",
    "diffraction_otf",
    "make_diffraction_otf",
    "noll_to_nm",
    "optical_cutoff_cy_per_mm",
    "pupil_otf",
    "pupil_psf",
    "shannon_atf",
    "zernike_noll",
]


#: :class:`DiffractionOTF` evaluates the closed form on its radial table for calls on at least this many points.
RADIAL_TABLE_MIN_POINTS = 1 << 16
#: Steps of :class:`DiffractionOTF`'s radial table per lowest cutoff: between 0 and the highest cutoff it has this
#: times ``highest / lowest cutoff``, rounded up (:func:`radial_table_intervals`), so that every wavelength's step in
#: ``v`` is at most ``1 / RADIAL_TABLE_STEPS``.
RADIAL_TABLE_STEPS = 1 << 17


def radial_table_intervals(cutoffs) -> int:
    """The steps of :class:`DiffractionOTF`'s radial table for wavelengths of these cutoffs (cy/mm).

    Examples
    --------
    >>> radial_table_intervals([200.0]) == RADIAL_TABLE_STEPS, radial_table_intervals([100.0, 250.0]) / 2**17
    (True, 2.5)
    """
    c = [float(x) for x in cutoffs]
    return math.ceil(RADIAL_TABLE_STEPS * max(c) / min(c) - 1e-6)


class DiffractionOTF:
    """Polychromatic optics OTF of a :class:`satchain.config.system.Optics`, precomputed and callable at (fx, fy).

    ``OTF(f) = sum_i w_i OTF_i(f) ATF_i(f)`` over the optics' wavelengths with normalised weights ``w_i``.
    ``OTF_i`` is the closed form :func:`annular_mtf` when ``optics.needs_pupil_fft`` is False, else a
    :class:`PupilOTF`; ``ATF_i`` is :func:`shannon_atf` for ``optics.wfe_rms_waves`` (1 when 0).

    With ``radial_table`` (the bands' engine asks for it: :func:`satchain.engine.bands_shared.band_otf`; by default
    every value is the closed form itself): the closed form depends on ``|f|`` alone, so a call on at least
    :data:`RADIAL_TABLE_MIN_POINTS` distinct radii
    (the engine's whole spectra; an outer grid's ``-fy`` and ``+fy`` rows count once) interpolates the
    polychromatic sum linearly on a table of :func:`radial_table_intervals` equal steps of ``|f|`` up to the
    highest cutoff, made once per instance from a table of the one-wavelength closed form
    (:data:`MONO_TABLE_INTERVALS` steps of ``v``, once per obscuration): one lookup per frequency instead of the
    closed form per wavelength. Every wavelength's step in ``v`` is at most ``1 / RADIAL_TABLE_STEPS``, so it is
    within 2e-8 of the closed form for obscurations up to 0.5 and 1e-6 up to 0.95 (linear interpolation of the
    ``(1 - v)^(3/2)`` and ``sqrt`` behaviours at ``v`` = 1, ``eps`` and ``(1 -+ eps) / 2``:
    tests/tf/test_optics_table.py), and exactly 0 at and beyond the highest cutoff. A wavelength whose
    scaled wavefront error exceeds Shannon's 0.18 waves (its ATF clipped to 0, a kink) keeps the closed form.

    Wavefront errors (``zernike_rms_waves``, ``wfe_rms_waves``) are optical path differences expressed in
    waves at the effective (weight-averaged) wavelength; at wavelength ``lambda_i`` they are scaled by
    ``lambda_eff / lambda_i``. For one wavelength this is the plain value.

    Examples
    --------
    >>> from satchain.config.system import load_preset
    >>> otf = make_diffraction_otf(load_preset("ankarasat3").optics)
    >>> round(float(otf(0.0, 0.0)), 6), float(otf(0.0, 200.0))
    (1.0, 0.0)
    """

    def __init__(self, optics, *, params: PupilParams = PupilParams(), radial_table: bool = False) -> None:  # noqa: B008
        self.radial_table = bool(radial_table)
        self.weights = np.asarray(optics.weights, dtype=float)
        self.wavelengths_m = tuple(float(w) for w in optics.wavelengths_m)
        self.f_number = float(optics.f_number)
        self.obscuration_ratio = float(optics.obscuration_ratio)
        lam_eff = float(optics.effective_wavelength_m)
        self.wfe_rms_waves = tuple(float(optics.wfe_rms_waves) * lam_eff / lam for lam in self.wavelengths_m)
        self.pupils: tuple[PupilOTF, ...] | None = None
        self._table: tuple[float, np.ndarray] | None = None  # (highest cutoff, radial table): _radial_lookup
        if optics.needs_pupil_fft:
            self.pupils = tuple(
                PupilOTF(
                    wavelength_m=lam,
                    f_number=optics.f_number,
                    aperture_diameter_m=optics.aperture_diameter_m,
                    obscuration_ratio=optics.obscuration_ratio,
                    spiders=optics.spiders,
                    zernike_rms_waves={j: c * lam_eff / lam for j, c in optics.wavefront_zernikes_waves.items()},
                    params=params,
                )
                for lam in self.wavelengths_m
            )

    @property
    def is_real(self) -> bool:
        """True when the OTF has no phase (no wavefront terms), so it is returned as a real array."""
        return self.pupils is None or all(p.is_real for p in self.pupils)

    def __call__(self, fx_cy_per_mm, fy_cy_per_mm) -> np.ndarray:
        """Polychromatic OTF at focal-plane frequencies (cy/mm); real when :attr:`is_real`."""
        fx, fy = _broadcast_freqs(fx_cy_per_mm, fy_cy_per_mm)
        rows = _radial_rows(fx, fy) if self.pupils is None else None
        # a clear (or obscured) pupil's OTF depends on |f| only: on an outer grid, once per distinct |fy| row
        fr = np.hypot(fx, fy) if rows is None else np.hypot(rows[0][None, :], rows[1][:, None])
        big = self.radial_table and self.pupils is None and fr.size >= RADIAL_TABLE_MIN_POINTS
        out = self._radial_lookup(fr) if big else None
        if out is None:
            out = self._sum(fr, fx, fy)
        return out if rows is None else out[rows[2]]

    def _sum(self, fr: np.ndarray, fx=None, fy=None) -> np.ndarray:
        """The polychromatic sum at radial frequencies ``fr`` (a pupil's OTF at ``fx``, ``fy``)."""
        out = np.zeros(fr.shape, dtype=np.float64 if self.is_real else np.complex128)
        for i, (w, lam) in enumerate(zip(self.weights, self.wavelengths_m, strict=True)):
            if w == 0:
                continue
            cutoff = optical_cutoff_cy_per_mm(lam, self.f_number)
            if self.pupils is None:
                mono = _oneill(fr / cutoff, self.obscuration_ratio)
            else:
                mono = self.pupils[i](fx, fy)
                mono = mono.real if self.is_real else mono
            if self.wfe_rms_waves[i] > 0:
                mono = mono * shannon_atf(fr / cutoff, self.wfe_rms_waves[i])
            out += w * mono
        return out

    def _radial_lookup(self, fr: np.ndarray) -> np.ndarray | None:
        """The closed-form sum at ``fr`` interpolated on the radial table (class docstring); None where the table
        does not apply: a wavelength whose Shannon ATF is clipped (its kink would be smoothed), or a radius the
        table cannot index (the closed form then says what it gives)."""
        if self._table is None:
            if any(w > SHANNON_W0_WAVES for w in self.wfe_rms_waves):
                return None
            nodes = [(w, lam) for w, lam in zip(self.weights, self.wavelengths_m, strict=True) if w != 0]
            cuts = [optical_cutoff_cy_per_mm(lam, self.f_number) for _, lam in nodes]
            if not cuts:
                return None
            top, n = max(cuts), radial_table_intervals(cuts)
            f = np.linspace(0.0, top, n + 1)
            table = np.zeros(f.size + 1)  # the extra 0: beyond the cutoff
            mono = _mono_table(self.obscuration_ratio)
            for w, lam in nodes:
                i = self.wavelengths_m.index(lam)
                cutoff = optical_cutoff_cy_per_mm(lam, self.f_number)
                v = f / cutoff
                term = _lookup(mono, v * MONO_TABLE_INTERVALS, MONO_TABLE_INTERVALS)
                if self.wfe_rms_waves[i] > 0:
                    term *= shannon_atf(v, self.wfe_rms_waves[i])
                table[:-1] += w * term
            self._table = (top, table)
        top, table = self._table
        n = table.size - 2
        with np.errstate(over="ignore", invalid="ignore"):
            x = fr * (n / top)
        if not np.isfinite(x).all():
            return None
        out = _lookup(table, x, n)
        out[fr >= top] = 0.0  # exactly 0 at and beyond the cutoff (not a rounding residue of the last step)
        return out


#: Steps in ``v = |f| / cutoff`` of the one-wavelength closed form :class:`DiffractionOTF`'s radial table is made
#: from (per obscuration ratio, once per process).
MONO_TABLE_INTERVALS = 1 << 20


@functools.lru_cache(maxsize=8)
def _mono_table(eps: float) -> np.ndarray:
    """:func:`_oneill` at ``v = k / MONO_TABLE_INTERVALS`` (k = 0 .. intervals) and a 0 beyond."""
    return np.append(_oneill(np.linspace(0.0, 1.0, MONO_TABLE_INTERVALS + 1), eps), 0.0)


def _lookup(table: np.ndarray, x: np.ndarray, n: int) -> np.ndarray:
    """Linear interpolation of ``table`` (``n + 2`` values: steps 0 .. n, then 0) at step positions ``x`` >= 0
    (overwritten); positions beyond ``n`` give 0."""
    np.minimum(x, n + 0.5, out=x)  # beyond the last step: between the two zeros
    i = x.astype(np.intp)
    x -= i
    lo = table[i]
    return lo + (table[i + 1] - lo) * x


def _radial_rows(fx: np.ndarray, fy: np.ndarray):
    """On an outer grid (``fx`` varying along the last axis only and ``fy`` along the first only, as
    broadcast views give them) with repeated ``|fy|`` (a centred spectrum's -f and +f rows): ``(fx row,
    distinct |fy|, the distinct row of each row)``; None otherwise."""
    if fx.ndim != 2 or fx.shape[0] < 8 or fx.strides[0] != 0 or fy.strides[1] != 0:
        return None
    distinct, index = np.unique(np.abs(fy[:, 0]), return_inverse=True)
    if distinct.size > 0.75 * fy.shape[0]:
        return None
    return fx[0], distinct, index


def make_diffraction_otf(
    optics,
    *,
    params: PupilParams = PupilParams(),  # noqa: B008
    radial_table: bool = False,
) -> DiffractionOTF:
    """Precompute the polychromatic optics OTF of ``optics`` (a :class:`satchain.config.system.Optics`);
    ``radial_table``: see :class:`DiffractionOTF`.

    Examples
    --------
    >>> from satchain.config.system import load_preset
    >>> otf = make_diffraction_otf(load_preset("ankarasat3").optics)
    >>> otf(np.zeros(3), np.array([0.0, 50.0, 100.0])).shape
    (3,)
    """
    return DiffractionOTF(optics, params=params, radial_table=radial_table)


def diffraction_otf(fx_cy_per_mm, fy_cy_per_mm, optics, *, params: PupilParams = PupilParams()):  # noqa: B008
    """Polychromatic optics OTF of ``optics`` at focal-plane frequencies (cy/mm); see :class:`DiffractionOTF`.

    Examples
    --------
    >>> from satchain.config.system import Optics
    >>> o = Optics(aperture_diameter_m=0.1, f_number=10.0, wavelengths_m=(500e-9,))
    >>> round(float(diffraction_otf(100.0, 0.0, o)), 6)  # v = 0.5 of the clear circular pupil
    0.391002
    """
    return DiffractionOTF(optics, params=params)(fx_cy_per_mm, fy_cy_per_mm)
