"""The predicted budget of a system: its derived quantities, MTF/CTF per component, MTF at Nyquist, MTFA,
radiometry and GIQE image quality, as one JSON-ready dict (:func:`budget_results`, what ``satchain budget --json``
prints) and as a typed result with the figures a design study sweeps (:func:`budget`, :class:`SystemBudget`).

The physics is here; :mod:`satchain.report.budget` only writes it out (CSV tables, JSON, figures).

Examples
--------
>>> from satchain import load_preset
>>> b = budget(load_preset("ankarasat3"))
>>> round(b.gsd_m, 3), round(b.q, 3), round(b.mtf_at_nyquist_alt, 3), round(b.niirs, 2)
(0.49, 1.074, 0.123, 5.2)
>>> b.to_dict()["mtf_at_nyquist"]["alt"] == b.mtf_at_nyquist_alt
True
"""

from __future__ import annotations

import copy
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from satchain import units
from satchain._argcheck import checked
from satchain.errors import ParameterTypeError
from satchain.tf import ctf as _ctf
from satchain.tf.budget import DIRECTIONS, SystemOTF, _cut, mtf_at_nyquist, mtf_budget, mtfa

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from satchain.config.system import ImagingSystem
    from satchain.prediction.cfa_budget import CFABudget

__all__ = ["BandBudget", "DirectionalMTF", "SystemBudget", "band_budgets", "budget", "budget_results"]


class DirectionalMTF:
    """The system MTF along one axis as a callable of focal-plane frequency (cy/mm), with its cutoff."""

    def __init__(self, otf: SystemOTF, direction: str):
        self._otf, self.direction = otf, direction
        self.cutoff = float(np.max(otf.system.optical_cutoff_cy_per_mm))

    def __call__(self, f_cy_per_mm) -> np.ndarray:
        f = np.asarray(f_cy_per_mm, dtype=float)
        return np.abs(self._otf(*_cut(self.direction, f)))


def _pitch(system: ImagingSystem, d: str) -> float:
    return system.detector.pitch_y_m if d == "alt" else system.detector.pitch_x_m


def budget_results(system: ImagingSystem, f_cy_per_mm=None, *, otf: SystemOTF | None = None) -> dict[str, Any]:
    """Derived quantities, MTF per component, CTF (Coltman and the paper's synthesis), MTF at Nyquist, MTFA,
    radiometry and GIQE quality: the dict ``satchain budget --json`` prints (JSON-ready).

    ``f_cy_per_mm``: the focal-plane frequencies of the tables (default:
    :func:`satchain.tf.budget.default_frequencies_cy_per_mm`); ``otf``: a prebuilt :class:`SystemOTF` of ``system``.
    """
    otf = SystemOTF(system) if otf is None else otf
    b = mtf_budget(system, f_cy_per_mm, otf=otf)
    f = b.f_cy_per_mm
    out: dict[str, Any] = {"system": system.name, "derived": system.derived()}
    out.update(b.to_dict())
    out["frequencies_cy_per_px"] = {
        d: units.cy_per_mm_to_cy_per_px(f, pitch_m=_pitch(system, d)).tolist() for d in DIRECTIONS
    }
    out["frequencies_cy_per_m_ground"] = {
        d: (f / system.focal_cy_per_mm_per_ground_cy_per_m(d)).tolist() for d in DIRECTIONS
    }
    out["ctf"] = {}
    out["mtfa"] = {}
    for d in DIRECTIONS:
        m = DirectionalMTF(otf, d)
        out["ctf"][d] = {
            "coltman": np.asarray(_ctf.coltman_ctf(f, m)).tolist(),
            "fourier_synthesis": np.asarray(_ctf.ctf_fourier_synthesis(f, m)).tolist(),
        }
        fpx = np.linspace(0.0, 0.5, 257)
        fmm = units.cy_per_px_to_cy_per_mm(fpx, pitch_m=_pitch(system, d))
        out["mtfa"][d] = mtfa(fpx, m(fmm), f_max_cy_per_px=0.5)
    out["mtf_at_nyquist"] = mtf_at_nyquist(system, otf=otf)
    pb = getattr(otf, "pushbroom", None)
    geometry = pb.geometry() if pb is not None else None
    if geometry is not None:
        out["motion_geometry"] = geometry  # line displacement, TDI drift, Earth-rotation shear/scale/rotation
    from satchain.prediction.quality import predict_quality
    from satchain.radiometry import radiometric_budget

    out["radiometry"] = radiometric_budget(system).to_dict()
    out["quality"] = predict_quality(system, otf=otf).to_dict()
    if system.bands:
        out["bands"] = band_budgets(system)
    if system.detector.layout == "staggered":
        out["staggered"] = staggered_budget(system, otf=otf)
    if system.detector.cfa is not None:  # each colour plane on its own sampling grid
        from satchain.prediction.cfa_budget import cfa_budget

        out["cfa"] = cfa_budget(system)
    out["frequency_axis"] = (
        "the detector pixel's axis (cy/mm on the focal plane, cy/px of the detector pitch, cy/m at the design GSD); "
        "an image with a line-rate error or Earth rotation has its rows motion_geometry.alt_scale detector px "
        "apart on the ground, and `run` predicts on the image's axis (f_y / alt_scale); the pushbroom motion "
        "terms are their signed expected OTF"
    )
    out["ctf_notes"] = (
        "coltman: the square-wave (bar) response by Coltman's series (physical, -> 1 at low frequency, "
        "4/pi*MTF near cutoff); fourier_synthesis: the reference paper's method (10 odd harmonics, modulation of "
        "the degraded truncated series / modulation of the input truncated series), which divides by the "
        "Gibbs overshoot of the truncated input (~1.18)."
    )
    return out


def staggered_budget(system: ImagingSystem, *, otf: SystemOTF | None = None) -> dict[str, Any]:
    """Two arrays half a pixel apart along and across track, combined onto the ``p / 2`` grid
    (:mod:`satchain.tf.staggered`): the combined grid's pitch and GSD, its Nyquist (``1/p`` along each axis,
    ``1/(sqrt(2) p)`` along the diagonals, against ``1/(2p)`` for one array), and per axis the MTF after the
    combination (system MTF x the quincunx-bilinear fill's transfer function) at the combined and at the single
    array's Nyquist. JSON-ready."""
    from satchain.tf.staggered import combination_otf, nyquist_cy_per_mm

    otf = SystemOTF(system) if otf is None else otf
    p = system.detector.pitch_x_m  # square: the configuration checks it
    out: dict[str, Any] = {
        "combination": "quincunx_bilinear: each missing point of the p/2 grid is the mean of its 4 neighbours",
        "combined_pitch_m": p / 2,
        "combined_gsd_m": {d: system.derived()[f"gsd_{d}_m"] / 2 for d in DIRECTIONS},
        "nyquist_cy_per_mm": {"axis": nyquist_cy_per_mm(p), "diagonal": nyquist_cy_per_mm(p, direction="diagonal"),
                              "single_array": nyquist_cy_per_mm(p) / 2},  # fmt: skip
        "aliasing": "unaliased inside |f_x| + |f_y| < 1/p; the first alias copies at (+-1/p, +-1/p)",
    }
    at = (("mtf_at_combined_nyquist", nyquist_cy_per_mm(p)), ("mtf_at_single_nyquist", nyquist_cy_per_mm(p) / 2))
    for key, f in at:
        out[key] = {}
        for d in DIRECTIONS:
            fx, fy = (f, 0.0) if d == "act" else (0.0, f)
            out[key][d] = float(DirectionalMTF(otf, d)(f) * combination_otf(fx, fy, pitch_m=p))
    return out


def _pan_index(system: ImagingSystem) -> int:
    """The band whose name is "pan" (case-insensitive), else the first."""
    names = [n.casefold() for n in system.band_names]
    return names.index("pan") if "pan" in names else 0


def band_budgets(system: ImagingSystem) -> list[dict[str, Any]]:
    """Every ``[[bands]]`` entry's budget (JSON-ready, one dict per band, in order): its name, centre wavelength,
    GSD, Nyquist (cy/mm, cy/px), system MTF at its own Nyquist, signal and SNR (its own band, QE, TDI and pixel),
    GIQE 5 NIIRS for the PAN band (named "pan", else the first), and its predicted registration offset from the PAN
    band. [] for a system without bands.

    Registration: a band ``offset_alt_mm`` along-track from the system's own detector sees a ground point
    ``delay_s = offset_alt / v`` after it (``v = pitch_y / line_time``: the image's speed on the focal plane),
    ``offset_alt / pitch`` lines later; registered by that nominal delay (and its ``offset_act_mm`` / pitch
    columns), its static offset from the PAN band is the injected ``registration_offset_px`` (the part that
    ``oscillations`` gives what each ``[[motion.oscillation]]`` adds (:func:`_oscillation_offsets`),
    ``earth_rotation`` what the Earth's rotation adds (:func:`_earth_offset`), ``line_rate`` what
    ``motion.line_rate_error`` adds (:func:`_line_rate_offset`: the ground crosses the arrays' distance in ``1 / (1 +
    e)`` of the nominal lines, so a band ``L`` lines behind shows ``L (1 / (1 + e) - 1)`` lines; 0.2 MS px for blue at
    ``e`` = 1e-3); jitter PSDs and line-of-sight logs over the delay are not predicted here yet.

    Examples
    --------
    >>> from satchain import load_preset
    >>> b = band_budgets(load_preset("ankarasat3-pms"))
    >>> [(x["name"], round(x["gsd_m"], 2)) for x in b][:2]
    [('pan', 0.49), ('blue', 1.96)]
    """
    from satchain.prediction.quality import predict_quality
    from satchain.radiometry import radiometric_budget

    pan = _pan_index(system)
    ref = system.for_band(pan)
    speed_m_per_s = system.detector.pitch_y_m / system.line_time_s  # the image on the focal plane
    pb = SystemOTF(ref).pushbroom if system.orbit.earth_rotation or system.motion.line_rate_error else None
    geometry = (pb.geometry() or {}) if pb is not None else {}
    earth = geometry.get("earth_rotation")
    out = []
    for i, band in enumerate(system.bands):
        s = system.for_band(i)
        otf = SystemOTF(s)
        ny = mtf_at_nyquist(s, otf=otf)
        rad = radiometric_budget(s)
        offset_m = (band.offset_alt_mm - system.bands[pan].offset_alt_mm) / units.MM_PER_M
        static = band.registration_offset_px
        ref_static = system.bands[pan].registration_offset_px
        px = {d: static[k] - ref_static[k] * _pitch(ref, d) / _pitch(s, d) for k, d in enumerate(("alt", "act"))}
        entry: dict[str, Any] = {
            "index": i,
            "name": system.band_names[i],
            "center_wavelength_m": band.center_wavelength_m,
            "wavelengths_m": list(s.optics.wavelengths_m),
            "band_m": list(s.radiometry.band_m),
            "pitch_m": s.detector.pitch_x_m,
            "tdi_stages": s.detector.tdi_stages,
            "gsd_m": s.gsd_m,
            "gsd_act_m": s.gsd_act_m,
            "gsd_alt_m": s.gsd_alt_m,
            "nyquist_cy_per_mm": {"act": s.nyquist_act_cy_per_mm, "alt": s.nyquist_alt_cy_per_mm},
            "nyquist_cy_per_px": 0.5,
            "mtf_at_nyquist": ny,
            "signal_e": rad.signal_e,
            "snr": rad.snr,
            "contrast_snr": rad.contrast_snr,
            "saturated": rad.saturated,
            "niirs": predict_quality(s, otf=otf).giqe5 if i == pan else None,
            "registration": {
                "reference_band": system.band_names[pan],
                "offset_alt_mm": band.offset_alt_mm,
                "offset_act_mm": band.offset_act_mm,
                "delay_s": offset_m / speed_m_per_s,
                "delay_lines": offset_m / s.detector.pitch_y_m,
                "static_px": px,
                "static_m": {d: px[d] * (s.gsd_alt_m if d == "alt" else s.gsd_act_m) for d in ("alt", "act")},
                "static_reference_px": {d: px[d] * _pitch(s, d) / _pitch(ref, d) for d in ("alt", "act")},
                "oscillations": _oscillation_offsets(system, ref, s, offset_m / speed_m_per_s),
                "oscillation_form": "amplitude_px sin(2 pi frequency_hz t_c + phase_deg), t_c: the reference row's "
                "TDI window centre (s)",
                "earth_rotation": None if earth is None else _earth_offset(earth, ref, s, offset_m),
                "line_rate": _line_rate_offset(system, geometry, earth, ref, s, offset_m),
                "not_predicted": "jitter PSDs and line-of-sight logs over delay_s",
            },
        }
        out.append(entry)
    return out


def _oscillation_offsets(system: ImagingSystem, ref: ImagingSystem, band: ImagingSystem, delay_s: float) -> list:
    """The offset (band minus reference band) each sinusoidal line-of-sight oscillation adds: a row's displacement
    is the mean of ``A sin(2 pi f t + phi)`` over its TDI window (``A sinc(f T) sin(2 pi f t_c + phi)``, ``t_c`` the
    window's centre: :mod:`satchain.tf.pushbroom`), and the band sees the ground point ``delay_s`` after the
    reference, so the offset is ``A |z| sin(2 pi f t_c + phi + arg z)`` with ``z = sinc(f T_b) e^(2 pi i f delay)
    - sinc(f T_ref)``, ``t_c`` the reference row's window centre. Amplitudes in the band's own pixels. The offset is
    that of the band's content, as :func:`satchain.measure.registration.measure_registration` gives it: a pixel
    sees ``x = j + LOS(t)``, so content moves against the line of sight -- the phase is the line of sight's + 180
    degrees."""
    out = []
    for o in system.motion.oscillation:
        f = o.frequency_hz
        t_ref = ref.detector.tdi_stages * ref.line_time_s
        t_band = band.detector.tdi_stages * band.line_time_s
        z = np.sinc(f * t_band) * np.exp(2j * np.pi * f * delay_s) - np.sinc(f * t_ref)
        to_band = _pitch(system, o.axis) / _pitch(band, o.axis)
        amp = float(o.amplitude_px * abs(z) * to_band)
        out.append({
            "axis": o.axis,
            "frequency_hz": f,
            "amplitude_px": amp,
            "rms_px": amp / math.sqrt(2.0),
            "phase_deg": float((o.phase_deg + np.degrees(np.angle(z)) + 180.0 + 180.0) % 360.0 - 180.0),
        })  # fmt: skip
    return out


def _earth_offset(earth: Mapping[str, Any], ref: ImagingSystem, band: ImagingSystem, offset_m: float) -> dict:
    """Where the band images a ground point, minus where the reference band and the nominal delay place it, under the
    Earth's rotation (:mod:`satchain.tf.pushbroom`: per reference line the ground moves ``(sigma, a)`` px, ACT and
    ALT): the image crosses the ``L = offset / pitch`` lines in ``L / a`` line times, not ``L``, and meanwhile
    drifts ``sigma L / a`` px across track -- ``act_px`` (+x columns) and ``alt_px`` (later rows), band pixels;
    ``delay_s``: the actual delay. With ``orbit.yaw_steering`` the detector's columns follow the relative motion
    ``(x, y)`` m a line: ``sigma = 0`` and ``a = |(x, y)| / g`` in the detector's frame (``earth``'s ``alt_scale``
    and ``shear_act_px_per_line`` are those), so the ACT offset vanishes and the ALT one, ``L (1 / a - 1)``, stays
    (the line rate is not matched to the relative speed: ``|a - 1| ~ 1e-2``, ``sigma^2 / 2`` more than without yaw
    steering)."""
    lines = offset_m / ref.detector.pitch_y_m
    a, sigma = float(earth["alt_scale"]), float(earth["shear_act_px_per_line"])
    return {
        "delay_s": lines / a * ref.line_time_s,
        "act_px": -sigma * lines / a * ref.gsd_act_m / band.gsd_act_m,
        "alt_px": lines * (1.0 / a - 1.0) * ref.line_time_s / band.line_time_s,
    }


def _line_rate_offset(system: ImagingSystem, geometry: Mapping[str, Any], earth: Mapping[str, Any] | None,
                      ref: ImagingSystem, band: ImagingSystem, offset_m: float) -> dict | None:  # fmt: skip
    """What ``motion.line_rate_error`` adds to the band's offset: :func:`_earth_offset` of the whole drift (the
    pushbroom geometry's ``alt_scale``, the Earth's and the line rate's, and its shear) less that of the Earth's
    alone, so that ``static + earth_rotation + line_rate`` is the band's offset exactly. None without it."""
    e = system.motion.line_rate_error
    if not e:
        return None
    drift = {"alt_scale": geometry["alt_scale"], "shear_act_px_per_line": geometry["shear_act_px_per_line"]}
    total = _earth_offset(drift, ref, band, offset_m)
    alone = _earth_offset(earth, ref, band, offset_m) if earth is not None else {"alt_px": 0.0, "act_px": 0.0}
    return {"line_rate_error": float(e), "delay_s": total["delay_s"], "alt_px": total["alt_px"] - alone["alt_px"],
            "act_px": total["act_px"] - alone["act_px"] + 0.0}  # fmt: skip (+ 0.0: no -0.0 without a shear)


@dataclass(frozen=True)
class BandBudget:
    """One band's budget (:func:`band_budgets`), typed: ``name``, ``center_wavelength_m``, ``gsd_m``,
    ``nyquist_act_cy_per_mm`` / ``nyquist_alt_cy_per_mm``, ``mtf_at_nyquist_act`` / ``_alt`` (at its own Nyquist),
    ``signal_e``, ``snr`` (its scene's mean signal), ``niirs`` (the PAN band's; None for the others),
    ``delay_s`` (when it sees the ground after the PAN band), ``registration_alt_px`` / ``_act_px`` (its predicted
    static offset from the PAN band, in its own pixels), ``earth_rotation_alt_px`` / ``_act_px`` (what the
    Earth's rotation adds over the delay; None without it) and ``line_rate_alt_px`` / ``_act_px`` (what
    ``motion.line_rate_error`` adds; None without it)."""

    name: str
    center_wavelength_m: float
    gsd_m: float
    nyquist_act_cy_per_mm: float
    nyquist_alt_cy_per_mm: float
    mtf_at_nyquist_act: float
    mtf_at_nyquist_alt: float
    signal_e: float
    snr: float
    niirs: float | None
    delay_s: float
    registration_alt_px: float
    registration_act_px: float
    earth_rotation_alt_px: float | None = None
    earth_rotation_act_px: float | None = None
    line_rate_alt_px: float | None = None
    line_rate_act_px: float | None = None

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> BandBudget:
        reg = d["registration"]
        earth, rate = reg.get("earth_rotation"), reg.get("line_rate")
        return cls(
            name=str(d["name"]),
            center_wavelength_m=float(d["center_wavelength_m"]),
            gsd_m=float(d["gsd_m"]),
            nyquist_act_cy_per_mm=float(d["nyquist_cy_per_mm"]["act"]),
            nyquist_alt_cy_per_mm=float(d["nyquist_cy_per_mm"]["alt"]),
            mtf_at_nyquist_act=float(d["mtf_at_nyquist"]["act"]),
            mtf_at_nyquist_alt=float(d["mtf_at_nyquist"]["alt"]),
            signal_e=float(d["signal_e"]),
            snr=float(d["snr"]),
            niirs=None if d["niirs"] is None else float(d["niirs"]),
            delay_s=float(reg["delay_s"]),
            registration_alt_px=float(reg["static_px"]["alt"]),
            registration_act_px=float(reg["static_px"]["act"]),
            earth_rotation_alt_px=None if earth is None else float(earth["alt_px"]),
            earth_rotation_act_px=None if earth is None else float(earth["act_px"]),
            line_rate_alt_px=None if rate is None else float(rate["alt_px"]),
            line_rate_act_px=None if rate is None else float(rate["act_px"]),
        )


@dataclass(frozen=True, repr=False)
class SystemBudget:
    """The predicted budget of one system, typed: the figures a design study sweeps, and the whole budget.

    ``system_name``; ``gsd_m``, ``gsd_act_m``, ``gsd_alt_m`` (ground sample distance at nadir, m);
    ``f_number``; ``q``: the sampling ratio ``Q = lambda F# / p`` at the effective wavelength (geometric-mean
    pitch; Q < 2: detector limited); ``limited_by`` (``"detector"`` or ``"optics"``); ``nyquist_act_cy_per_mm``,
    ``nyquist_alt_cy_per_mm``; ``mtf_at_nyquist_act``, ``mtf_at_nyquist_alt`` (system MTF at the detector
    Nyquist); ``mtfa_act``, ``mtfa_alt`` (area under the MTF, 0 to Nyquist, cy/px); ``rer``, ``rer_act``,
    ``rer_alt`` (relative edge response, geometric mean and per axis); ``snr``: the GIQE contrast SNR;
    ``signal_snr``: the SNR of the scene's mean signal (radiometry); ``niirs``: GIQE 5 NIIRS; ``bands``: each
    ``[[bands]]`` entry's :class:`BandBudget` (() without bands).
    ``system``: the :class:`~satchain.config.system.ImagingSystem`; :meth:`to_dict`: the whole budget, exactly
    as ``satchain budget --json`` prints it (MTF/CTF tables, radiometry, every GIQE).
    """

    system_name: str
    gsd_m: float
    gsd_act_m: float
    gsd_alt_m: float
    f_number: float
    q: float
    limited_by: str
    nyquist_act_cy_per_mm: float
    nyquist_alt_cy_per_mm: float
    mtf_at_nyquist_act: float
    mtf_at_nyquist_alt: float
    mtfa_act: float
    mtfa_alt: float
    rer: float
    rer_act: float
    rer_alt: float
    snr: float
    signal_snr: float
    niirs: float
    system: ImagingSystem = field(compare=False)
    results: Mapping[str, Any] = field(compare=False)

    @classmethod
    def from_results(cls, system: ImagingSystem, results: Mapping[str, Any]) -> SystemBudget:
        """The typed budget of :func:`budget_results`' dict (kept whole for :meth:`to_dict`)."""
        d, q, r = results["derived"], results["quality"], results["radiometry"]
        ny, area = results["mtf_at_nyquist"], results["mtfa"]
        return cls(
            system_name=str(results["system"]),
            gsd_m=float(d["gsd_m"]),
            gsd_act_m=float(d["gsd_act_m"]),
            gsd_alt_m=float(d["gsd_alt_m"]),
            f_number=float(d["f_number"]),
            q=float(d["q_effective"]),
            limited_by=str(d["limited_by"]),
            nyquist_act_cy_per_mm=float(d["nyquist_act_cy_per_mm"]),
            nyquist_alt_cy_per_mm=float(d["nyquist_alt_cy_per_mm"]),
            mtf_at_nyquist_act=float(ny["act"]),
            mtf_at_nyquist_alt=float(ny["alt"]),
            mtfa_act=float(area["act"]),
            mtfa_alt=float(area["alt"]),
            rer=float(q["rer"]),
            rer_act=float(q["rer_act"]),
            rer_alt=float(q["rer_alt"]),
            snr=float(q["snr"]),
            signal_snr=float(r["snr"]),
            niirs=float(q["giqe5"]),
            system=system,
            results=copy.deepcopy(dict(results)),
        )

    @property
    def cfa(self) -> CFABudget | None:
        """A colour filter array's planes, each on its own sampling grid, typed
        (:func:`satchain.prediction.cfa_budget.cfa_budget`); None for a monochrome array."""
        from satchain.prediction.cfa_budget import CFABudget

        d = self.results.get("cfa")
        return None if d is None else CFABudget.from_dict(d)

    @property
    def bands(self) -> tuple[BandBudget, ...]:
        """Each ``[[bands]]`` entry's budget, typed (:func:`band_budgets`); () for a system without bands."""
        return tuple(BandBudget.from_dict(b) for b in self.results.get("bands", ()))

    def to_dict(self) -> dict[str, Any]:
        """The whole budget as ``satchain budget --json`` prints it (a copy: JSON-ready, free to change)."""
        return copy.deepcopy(dict(self.results))

    def __repr__(self) -> str:
        return (
            f"SystemBudget({self.system_name!r}: GSD {self.gsd_m:.4g} m, Q {self.q:.4g}, MTF at Nyquist "
            f"ACT {self.mtf_at_nyquist_act:.4f} / ALT {self.mtf_at_nyquist_alt:.4f}, RER {self.rer:.4f}, "
            f"SNR {self.snr:.4g}, NIIRS {self.niirs:.3f})"
        )


@checked
def budget(system: ImagingSystem, f_cy_per_mm: ArrayLike | None = None) -> SystemBudget:
    """The predicted budget of ``system``, typed: what ``satchain budget --json`` prints, in Python.

    Parameters
    ----------
    system : ImagingSystem
        The camera (:func:`satchain.load_preset`, :func:`satchain.load_system`, ``ImagingSystem.replace``).
    f_cy_per_mm : array_like of float, optional
        Focal-plane frequencies (cy/mm, >= 0) of the MTF/CTF tables in :meth:`SystemBudget.to_dict`
        (``satchain budget --freqs``); the scalar figures do not depend on them. Default: 0 to the larger of the
        optical cutoff and twice Nyquist, through both Nyquists.

    Returns
    -------
    SystemBudget
        GSD, Q, MTF at Nyquist, MTFA, RER, SNR, GIQE 5 NIIRS as attributes; the whole budget by ``to_dict()``.

    Examples
    --------
    >>> import satchain
    >>> s = satchain.load_preset("ankarasat3")
    >>> [round(satchain.budget(s.replace({"optics.wfe_rms_waves": w})).mtf_at_nyquist_act, 3) for w in (0.0, 0.1)]
    [0.199, 0.138]
    """
    if isinstance(f_cy_per_mm, (str, bytes, os.PathLike, Mapping, bool, np.bool_)):
        shown = repr(f_cy_per_mm)
        raise ParameterTypeError(
            f"budget(): f_cy_per_mm = {shown if len(shown) <= 60 else shown[:57] + '...'}: must be a sequence or "
            f"array of focal-plane frequencies in cy/mm (numbers >= 0), or None"
        )
    otf = SystemOTF(system)
    return SystemBudget.from_results(system, budget_results(system, f_cy_per_mm, otf=otf))
