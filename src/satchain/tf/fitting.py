"""Estimate unknown system parameters from a measured MTF curve by least squares.

The model is the modulus of the system OTF of an :class:`~satchain.config.system.ImagingSystem` cut along
one axis; the unknowns are addressed by dotted keys (``"optics.obscuration_ratio"``,
``"motion.smear_px"``; ``"optics.wavelength_m"`` sets a single effective wavelength). Uncertainties
come from the Jacobian at the solution, ``cov = s^2 (J^T J)^-1`` with ``s^2 = SSR / (n - p)`` (or
from the given per-point sigmas), as in ``scipy.optimize.curve_fit``.

Examples
--------
>>> from satchain import load_preset
>>> truth = load_preset("ankarasat3")
>>> f = np.linspace(5, 160, 24)
>>> m = mtf_budget(truth, f).alt["system"]
>>> start = truth.replace({"motion.smear_px": 0.5})
>>> r = fit_mtf(f, m, start, parameters=["motion.smear_px"])
>>> round(r.values["motion.smear_px"], 4)
1.0325
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from satchain._validate import as_float_array, check_choice
from satchain.config.system import ImagingSystem
from satchain.errors import ConfigError, InputError
from satchain.tf.budget import DIRECTIONS, SystemOTF, _cut, mtf_budget

__all__ = ["DEFAULT_BOUNDS", "MTFFit", "fit_mtf"]

#: Physical bounds used when the caller gives none.
DEFAULT_BOUNDS: dict[str, tuple[float, float]] = {
    "optics.wavelength_m": (2.0e-7, 2.5e-6),
    "optics.obscuration_ratio": (0.0, 0.95),
    "optics.f_number": (0.5, 100.0),
    "optics.focal_length_m": (0.01, 100.0),
    "optics.wfe_rms_waves": (0.0, 0.25),
    "detector.fill_factor": (0.05, 1.0),
    "detector.charge_diffusion_length_m": (0.0, 50e-6),
    "detector.tdi_sync_error": (0.0, 0.5),
    "motion.smear_px": (0.0, 20.0),
    "motion.smear_act_px": (0.0, 20.0),
    "motion.jitter_rms_px": (0.0, 5.0),
}


@dataclass(frozen=True)
class MTFFit:
    """Result of :func:`fit_mtf`.

    Attributes
    ----------
    values, stderr : dict
        Best-fit value and one-sigma standard error of each fitted parameter.
    system : ImagingSystem
        The input system with the fitted values.
    f_cy_per_mm, mtf_measured, mtf_model, residuals : ndarray
        The data, the fitted model at the same frequencies and ``model - measured``.
    covariance : ndarray
        Parameter covariance matrix (order of ``parameters``).
    """

    parameters: tuple[str, ...]
    values: dict[str, float]
    stderr: dict[str, float]
    covariance: np.ndarray
    system: ImagingSystem
    direction: str
    f_cy_per_mm: np.ndarray
    mtf_measured: np.ndarray
    mtf_model: np.ndarray
    residuals: np.ndarray
    success: bool
    message: str

    @property
    def max_abs_residual(self) -> float:
        return float(np.max(np.abs(self.residuals)))

    @property
    def rms_residual(self) -> float:
        return float(np.sqrt(np.mean(self.residuals**2)))

    def to_dict(self) -> dict[str, Any]:
        return {
            "parameters": list(self.parameters),
            "values": self.values,
            "stderr": self.stderr,
            "direction": self.direction,
            "f_cy_per_mm": self.f_cy_per_mm.tolist(),
            "mtf_measured": self.mtf_measured.tolist(),
            "mtf_model": self.mtf_model.tolist(),
            "residuals": self.residuals.tolist(),
            "max_abs_residual": self.max_abs_residual,
            "rms_residual": self.rms_residual,
            "success": self.success,
        }


def _current_value(system: ImagingSystem, key: str) -> float:
    section, _, name = key.partition(".")
    if key == "optics.wavelength_m":
        return system.optics.effective_wavelength_m
    if key == "detector.fill_factor":
        return system.detector.fill_factor
    try:
        return float(getattr(getattr(system, section), name))
    except (AttributeError, TypeError):
        raise ConfigError(f"parameters: {key!r} is not a scalar system parameter") from None


def fit_mtf(
    f_cy_per_mm,
    mtf,
    system: ImagingSystem,
    *,
    parameters: Sequence[str],
    direction: str = "alt",
    bounds: Mapping[str, tuple[float, float]] | None = None,
    sigma=None,
) -> MTFFit:
    """Fit chosen parameters of ``system`` so its MTF along ``direction`` matches a measured curve.

    Parameters
    ----------
    f_cy_per_mm, mtf : array_like
        Measured MTF at focal-plane frequencies (cy/mm).
    system : ImagingSystem
        Known parameters, and the starting values of the unknown ones.
    parameters : sequence of str
        Dotted keys of the unknowns, e.g. ``["optics.wavelength_m", "optics.obscuration_ratio",
        "motion.smear_px"]``.
    direction : {"alt", "act"}
        Axis of the measured curve.
    bounds : mapping, optional
        ``key -> (lo, hi)``; defaults from :data:`DEFAULT_BOUNDS`.
    sigma : array_like, optional
        One-sigma uncertainty of each MTF point; weights the fit and scales the covariance absolutely.
    """
    check_choice("direction", direction, DIRECTIONS)
    f = np.atleast_1d(as_float_array("f_cy_per_mm", f_cy_per_mm, ndim=None))
    m = np.atleast_1d(as_float_array("mtf", mtf))
    if f.shape != m.shape or f.ndim != 1:
        raise InputError(f"f_cy_per_mm and mtf: must be 1-D of equal length, got {f.shape} and {m.shape}")
    keys = tuple(parameters)
    if not keys:
        raise ConfigError("parameters: give at least one parameter to fit")
    if len(set(keys)) != len(keys):
        raise ConfigError(f"parameters = {list(keys)!r}: contains duplicates")
    if f.size <= len(keys):
        raise InputError(f"mtf: {f.size} points cannot determine {len(keys)} parameters; need more points")
    w = np.ones_like(m) if sigma is None else 1.0 / as_float_array("sigma", np.broadcast_to(sigma, m.shape))
    if np.any(~np.isfinite(w)) or np.any(w <= 0):
        raise InputError("sigma: must be finite and > 0")
    bnds = dict(DEFAULT_BOUNDS, **(bounds or {}))
    lo, hi = [], []
    for k in keys:
        if k not in bnds:
            raise ConfigError(f"bounds: no bounds for {k!r}; give bounds={{{k!r}: (lo, hi)}}")
        lo.append(bnds[k][0])
        hi.append(bnds[k][1])
    x0 = np.clip([_current_value(system, k) for k in keys], lo, hi)
    axes = _cut(direction, f)

    def model(x: np.ndarray) -> np.ndarray:
        s = system.replace(dict(zip(keys, map(float, x), strict=True)))
        return np.abs(SystemOTF(s)(*axes))

    def residuals(x: np.ndarray) -> np.ndarray:
        return (model(x) - m) * w

    # scipy documents diff_step as array_like (a scalar applies to every parameter); scipy-stubs allow only 1-D
    res = least_squares(residuals, x0, bounds=(lo, hi), x_scale="jac", diff_step=1e-6)  # type: ignore[arg-type]
    fitted = system.replace(dict(zip(keys, map(float, res.x), strict=True)))
    n, p = m.size, len(keys)
    jac = np.asarray(res.jac)  # dense: the default finite-difference Jacobian
    jtj = jac.T @ jac
    try:
        cov = np.linalg.inv(jtj)
    except np.linalg.LinAlgError:
        cov = np.full((p, p), np.inf)
    if sigma is None:
        cov = cov * (2.0 * res.cost / max(n - p, 1))
    model_m = getattr(mtf_budget(fitted, f), direction)["system"]
    err = np.sqrt(np.clip(np.diag(cov), 0, None))
    return MTFFit(
        parameters=keys,
        values={k: float(v) for k, v in zip(keys, res.x, strict=True)},
        stderr={k: float(e) for k, e in zip(keys, err, strict=True)},
        covariance=cov,
        system=fitted,
        direction=direction,
        f_cy_per_mm=f,
        mtf_measured=m,
        mtf_model=model_m,
        residuals=model_m - m,
        success=bool(res.success),
        message=str(res.message),
    )
