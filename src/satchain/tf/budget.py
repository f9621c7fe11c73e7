"""The MTF budget: the system OTF as a product of named physical components, its ACT/ALT cuts,
MTF at Nyquist and MTF area.

The components of an :class:`~satchain.config.system.ImagingSystem`, in order:

``diffraction``
    polychromatic diffraction of the (obscured, possibly aberrated) pupil (:mod:`satchain.tf.optics`)
``detector``
    pixel aperture (paper eq. 2)
``charge_diffusion``, ``tdi_sync``
    only when the detector has them
``smear``
    linear motion along-track (paper eq. 3) and across-track, when non-zero
``jitter``
    Gaussian line-of-sight jitter, when non-zero
``turbulence``, ``aerosol``
    atmospheric blur (:mod:`satchain.tf.atmosphere`), when the system's ``[atmosphere]`` enables them
``oscillation_1``, ..., ``jitter_psd_act``, ``jitter_psd_alt``, ``tdi_drift``
    pushbroom TDI motion averaged over the TDI window (:mod:`satchain.tf.pushbroom`), when the system has
    ``[[motion.oscillation]]``, ``[motion.jitter_psd]``, ``motion.line_rate_error`` or ``orbit.earth_rotation``

Examples
--------
>>> from satchain import load_preset
>>> b = mtf_budget(load_preset("ankarasat3"), [0.0, 85.034])
>>> [round(float(v), 3) for v in b.alt["system"]]
[1.0, 0.123]
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from satchain._validate import as_float_array, check_choice
from satchain.config.system import ImagingSystem
from satchain.errors import ConfigError
from satchain.tf import detector as _det
from satchain.tf import motion as _mot
from satchain.tf import optics as _opt

__all__ = [
    "MTFBudget",
    "SystemOTF",
    "default_frequencies_cy_per_mm",
    "mtf_at_nyquist",
    "mtf_budget",
    "mtfa",
]

DIRECTIONS = ("alt", "act")


class SystemOTF:
    """The system OTF of an ImagingSystem as a callable of 2-D focal-plane frequency (cy/mm).

    The diffraction part is precomputed once (a pupil FFT when the pupil needs one), so evaluating many
    frequency grids -- as the simulation engine does, tile after tile -- costs only the products.

    Parameters
    ----------
    system : ImagingSystem
    params : satchain.tf.optics.PupilParams, optional
        Accuracy knobs of the pupil FFT.
    radial_table : bool
        The diffraction's closed form interpolated on a radial table on calls of many frequencies
        (:class:`satchain.tf.optics.DiffractionOTF`: within 2e-8 of it); default False: the closed form itself.

    Examples
    --------
    >>> from satchain import load_preset
    >>> otf = SystemOTF(load_preset("ankarasat3"))
    >>> sorted(otf.component_names)
    ['detector', 'diffraction', 'smear']
    >>> round(float(abs(otf(0.0, 0.0))), 12)
    1.0
    """

    def __init__(self, system: ImagingSystem, *, params: Any = None, radial_table: bool = False):
        from satchain._argcheck import check_argument

        check_argument("SystemOTF", "system", system)  # None or a file name: one line naming it
        self.system = system
        self._diffraction = (
            _opt.make_diffraction_otf(system.optics, radial_table=radial_table)
            if params is None
            else _opt.make_diffraction_otf(system.optics, params=params, radial_table=radial_table)
        )
        self._components = self._build()

    def _build(self) -> dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]]:
        s, det, mot = self.system, self.system.detector, self.system.motion
        comps: dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {
            "diffraction": self._diffraction,
            "detector": lambda fx, fy: _det.pixel_otf(
                fx, fy, active_width_x_m=det.active_width_x_m, active_width_y_m=det.active_width_y_m
            ),
        }
        if det.charge_diffusion_length_m > 0:
            comps["charge_diffusion"] = lambda fx, fy: _det.charge_diffusion_otf(
                fx, fy, diffusion_length_m=det.charge_diffusion_length_m
            )
        if det.tdi_stages > 1 and det.tdi_sync_error != 0:
            comps["tdi_sync"] = lambda fx, fy: _det.tdi_sync_otf(
                fx, fy, stages=det.tdi_stages, sync_error=det.tdi_sync_error, pitch_y_m=det.pitch_y_m
            )
        if mot.smear_px > 0 or mot.smear_act_px > 0:
            comps["smear"] = lambda fx, fy: _mot.smear_otf(
                fx, fy, smear_alt_m=mot.smear_px * det.pitch_y_m, smear_act_m=mot.smear_act_px * det.pitch_x_m
            )
        atm = s.atmosphere
        if atm.turbulence:
            from satchain.tf import atmosphere as _atm

            lam = s.optics.effective_wavelength_m
            r0 = atm.r0_m or _atm.fried_r0_m(
                lam,
                altitude_m=s.orbit.altitude_m,
                zenith_deg=atm.view_zenith_deg,
                cn2=lambda h: _atm.hufnagel_valley_cn2(
                    h, wind_m_per_s=atm.hv_wind_m_per_s, ground_cn2=atm.hv_ground_cn2
                ),
            )
            comps["turbulence"] = lambda fx, fy: _atm.turbulence_otf(
                fx, fy, wavelength_m=lam, focal_length_m=s.focal_length_m, r0_m=r0
            )
        if atm.aerosol_scattered_fraction > 0:
            from satchain.tf import atmosphere as _atm

            kx, ky = (s.focal_cy_per_mm_per_ground_cy_per_m(a) for a in ("act", "alt"))
            comps["aerosol"] = lambda fx, fy: _atm.aerosol_otf(
                np.hypot(fx / kx, fy / ky),  # ground cy/m (the adjacency PSF is isotropic on the ground)
                scattered_fraction=atm.aerosol_scattered_fraction,
                psf_scale_m=atm.aerosol_psf_scale_m,
            )
        if mot.jitter_rms_px > 0:
            comps["jitter"] = lambda fx, fy: _mot.jitter_otf(
                fx, fy, rms_x_m=mot.jitter_rms_px * det.pitch_x_m, rms_y_m=mot.jitter_rms_px * det.pitch_y_m
            )
        self.pushbroom = None
        if mot.line_rate_error != 0 or mot.time_varying or s.orbit.earth_rotation:
            from satchain.tf.pushbroom import PushbroomTerms

            self.pushbroom = PushbroomTerms(s)  # exposure-averaged over the TDI window; geometry in .geometry()
            comps.update(self.pushbroom.components())
        return comps

    @property
    def component_names(self) -> tuple[str, ...]:
        return tuple(self._components)

    def components(self, fx_cy_per_mm, fy_cy_per_mm) -> dict[str, np.ndarray]:
        """Each named component's OTF at the given frequencies (broadcast)."""
        fx, fy = np.broadcast_arrays(
            as_float_array("fx_cy_per_mm", fx_cy_per_mm), as_float_array("fy_cy_per_mm", fy_cy_per_mm)
        )
        return {name: np.asarray(fn(fx, fy)) for name, fn in self._components.items()}

    def __call__(self, fx_cy_per_mm, fy_cy_per_mm, *, exclude: tuple[str, ...] = ()) -> np.ndarray:
        """The product of the components (all but ``exclude``): the system OTF, complex when the pupil is
        aberrated. The simulation engine excludes ``"detector"``, whose aperture it integrates exactly in
        space."""
        unknown = set(exclude) - set(self._components)
        if unknown:
            raise ConfigError(f"exclude = {sorted(unknown)!r}: not components of this system ({self.component_names})")
        fx, fy = np.broadcast_arrays(
            as_float_array("fx_cy_per_mm", fx_cy_per_mm), as_float_array("fy_cy_per_mm", fy_cy_per_mm)
        )
        out = None
        for name, fn in self._components.items():
            if name not in exclude:  # an excluded component is not evaluated at all
                v = np.asarray(fn(fx, fy))
                out = v if out is None else out * v
        if out is None:
            out = np.ones(np.broadcast_shapes(np.shape(fx_cy_per_mm), np.shape(fy_cy_per_mm)))
        return out

    @property
    def cutoff_cy_per_mm(self) -> float:
        """Frequency beyond which the system OTF is exactly zero (the largest diffraction cutoff)."""
        return float(np.max(self.system.optical_cutoff_cy_per_mm))


@dataclass(frozen=True)
class MTFBudget:
    """Component-by-component MTF along the ALT (f_y) and ACT (f_x) axes.

    ``alt`` and ``act`` map each component name, and ``"system"``, to its transfer at ``f_cy_per_mm`` (on the
    detector's pixel axis): the MTF (modulus of the OTF), except the pushbroom motion terms
    (:mod:`satchain.tf.pushbroom`: ``oscillation_*``, ``jitter_psd_*``, ``tdi_drift``), given as their **signed**
    expected OTF where it is real (past its first zero an oscillation's is negative: -0.237 is a contrast
    reversal, not 0.237; a line-of-sight log's, complex, stays its modulus).  ``"system"`` is the system MTF.
    """

    f_cy_per_mm: np.ndarray
    alt: dict[str, np.ndarray]
    act: dict[str, np.ndarray]
    nyquist_cy_per_mm: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
            "frequencies_cy_per_mm": self.f_cy_per_mm.tolist(),
            "mtf": {d: {k: v.tolist() for k, v in getattr(self, d).items()} for d in DIRECTIONS},
        }


def _cut(direction: str, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    check_choice("direction", direction, DIRECTIONS)
    z = np.zeros_like(f)
    return (z, f) if direction == "alt" else (f, z)


def mtf_budget(system: ImagingSystem, f_cy_per_mm=None, *, otf: SystemOTF | None = None) -> MTFBudget:
    """MTF of every component and of the system along-track and across-track.

    Parameters
    ----------
    system : ImagingSystem
    f_cy_per_mm : array_like, optional
        Focal-plane frequencies (cy/mm, >= 0). Default: :func:`default_frequencies_cy_per_mm`.
    otf : SystemOTF, optional
        A prebuilt system OTF (saves the pupil FFT when called repeatedly).

    Examples
    --------
    >>> from satchain import load_preset
    >>> b = mtf_budget(load_preset("ankarasat3"), [85.034])
    >>> round(float(b.alt["detector"][0]), 4), round(float(b.act["smear"][0]), 4)
    (0.6366, 1.0)
    """
    f = default_frequencies_cy_per_mm(system) if f_cy_per_mm is None else as_float_array("f_cy_per_mm", f_cy_per_mm)
    f = np.atleast_1d(f)
    if np.any(f < 0):
        raise ConfigError(f"f_cy_per_mm: must be >= 0, got minimum {f.min()!r}")
    otf = SystemOTF(system) if otf is None else otf
    out: dict[str, dict[str, np.ndarray]] = {}
    pb = getattr(otf, "pushbroom", None)
    motion = set() if pb is None else set(pb.components())  # the terms whose expected OTF is printed signed
    for d in DIRECTIONS:
        comps = otf.components(*_cut(d, f))
        mtfs = {k: _signed(v) if k in motion else np.abs(v) for k, v in comps.items()}
        mtfs["system"] = np.abs(np.prod(np.stack(list(comps.values())), axis=0))
        out[d] = mtfs
    ny = {"alt": system.nyquist_alt_cy_per_mm, "act": system.nyquist_act_cy_per_mm}
    return MTFBudget(f_cy_per_mm=f, alt=out["alt"], act=out["act"], nyquist_cy_per_mm=ny)


def _signed(otf: np.ndarray) -> np.ndarray:
    """The OTF as a real array: its real part where it is real (to 1e-9 of its largest value), else |OTF|."""
    o = np.asarray(otf)
    if not np.iscomplexobj(o):
        return o.astype(float, copy=False)
    if np.max(np.abs(o.imag), initial=0.0) <= 1e-9 * max(float(np.max(np.abs(o), initial=0.0)), 1e-300):
        return o.real.copy()
    return np.abs(o)


def mtf_at_nyquist(system: ImagingSystem, *, otf: SystemOTF | None = None) -> dict[str, float]:
    """System MTF at the detector Nyquist frequency, along-track and across-track.

    Examples
    --------
    >>> from satchain import load_preset
    >>> {k: round(v, 3) for k, v in mtf_at_nyquist(load_preset("ankarasat3")).items()}
    {'alt': 0.123, 'act': 0.199}
    """
    otf = SystemOTF(system) if otf is None else otf
    ny = {"alt": system.nyquist_alt_cy_per_mm, "act": system.nyquist_act_cy_per_mm}
    return {d: float(np.abs(otf(*_cut(d, np.array([ny[d]]))))[0]) for d in DIRECTIONS}


def default_frequencies_cy_per_mm(system: ImagingSystem, *, n_per_nyquist: int = 8) -> np.ndarray:
    """A grid from 0 to the larger of the optical cutoff and twice Nyquist, containing both Nyquists.

    The step is ``Nyquist / n_per_nyquist`` (ALT Nyquist), so Nyquist is on the grid.

    Examples
    --------
    >>> from satchain import load_preset
    >>> f = default_frequencies_cy_per_mm(load_preset("ankarasat3"))
    >>> round(float(f[8]), 3), round(float(f[-1]), 1)
    (85.034, 170.1)
    """
    ny = system.nyquist_alt_cy_per_mm
    top = max(float(np.max(system.optical_cutoff_cy_per_mm)), 2 * ny, 2 * system.nyquist_act_cy_per_mm)
    step = ny / n_per_nyquist
    f = np.arange(0.0, top + 0.5 * step, step)
    return np.unique(np.concatenate([f, [system.nyquist_act_cy_per_mm]]))


def mtfa(f_cy_per_px, mtf, *, f_max_cy_per_px: float = 0.5, threshold=None) -> float:
    """MTF area: the area between the MTF and a threshold modulation curve, from 0 to ``f_max``.

    ``MTFA = integral_0^fmax max(MTF(f) - T(f), 0) df`` with frequencies in cycles/pixel, so a perfect
    system gives 0.5 up to Nyquist (Snyder 1973; Schott, *Remote Sensing*, 2007, sec. 13.2). ``threshold``
    is a constant or an array on ``f_cy_per_px`` (the noise-equivalent modulation); default 0.

    Examples
    --------
    >>> f = np.linspace(0, 0.5, 101)
    >>> round(mtfa(f, np.ones_like(f)), 6)
    0.5
    """
    f = as_float_array("f_cy_per_px", f_cy_per_px, ndim=1)
    m = as_float_array("mtf", mtf, ndim=1)
    if f.shape != m.shape or f.size < 2:
        raise ConfigError(f"f_cy_per_px and mtf: must be 1-D of equal length >= 2, got {f.shape} and {m.shape}")
    if np.any(np.diff(f) <= 0):
        raise ConfigError("f_cy_per_px: must be strictly increasing")
    if not f[0] <= f_max_cy_per_px <= f[-1]:
        raise ConfigError(f"f_max_cy_per_px = {f_max_cy_per_px!r}: must be within [{f[0]:g}, {f[-1]:g}]")
    t = np.zeros_like(m) if threshold is None else np.broadcast_to(np.asarray(threshold, float), m.shape)
    g = np.clip(m - t, 0.0, None)
    keep = f < f_max_cy_per_px
    fx = np.concatenate([f[keep], [f_max_cy_per_px]])
    gx = np.concatenate([g[keep], [np.interp(f_max_cy_per_px, f, g)]])
    return float(np.trapezoid(gx, fx))
