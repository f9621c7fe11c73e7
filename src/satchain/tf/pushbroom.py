"""Line-of-sight motion of a pushbroom TDI camera averaged over the TDI window: exact exposure-averaged
transfer functions and the geometry each term leaves in the image.

Each image row integrates over its TDI window ``T = N dt`` (``N`` stages, ``dt`` the line time): row ``i`` over
``[i dt, i dt + T]``, ``t = 0`` at the start of row 0's window. A motion ``x(t)`` (px) splits, row by row, into
the **window mean** ``d_i`` -- the row's displacement, geometry -- and the motion **about** that mean, which blurs.
The transfer functions here are the expectation, over the rows, of the blur's OTF about the mean (what an
edge measurement sees after it locates each row); the displacement is reported as geometry (rms, row to row).
Frequencies ``nu`` are in cycles per detector pixel of the motion's axis.

``oscillation_otf``
    ``x = A sin(2 pi f t + phi)``, ``c = f T`` cycles per window, ``a = 2 pi nu A``, ``b = a sinc(c)``. Averaged
    over the phase ``psi`` at mid-window (the rows see all phases), Jacobi-Anger gives the exact series
    ``J0(a) J0(b) + 2 sum_k J_k(a) J_k(b) sinc(k c)`` -- ``J0(2 pi nu A)`` for whole cycles (``b = 0``), ``1`` for
    a slow one (``c -> 0``: it only displaces). The rows' displacement is ``A sinc(c) sin(psi)``.
``jitter_psd_otf``
    a stationary Gaussian motion of one-sided PSD ``S(f)``: at offset ``s`` from mid-window the motion about
    the mean has variance ``v(s) = int S(f) [1 + sinc^2(f T) - 2 sinc(f T) cos(2 pi f s)] df`` and the
    expected OTF is exactly ``(1/T) int exp(-2 pi^2 nu^2 v(s)) ds``: ``exp(-2 pi^2 sigma^2 nu^2)`` for the part of
    the PSD far above ``1/T`` (``v -> sigma^2``), no blur for the part far below it (it displaces rows by
    ``int S sinc^2(f T) df`` in variance).
``drift_otf``
    a constant drift of the image relative to the TDI charge of ``(dx, dy)`` px per stage (a line-rate error,
    the Earth's rotation): a linear smear ``N (dx, dy)``, ``sinc(N (dx nu_x + dy nu_y))``; ``sinc(N e nu)``
    along-track for a line-rate error ``e``.

References: Wulich & Kopeika, "Image resolution limits resulting from mechanical vibrations", Opt. Eng. 26
(1987); Hadar, Dror & Kopeika, "Numerical calculation of image motion and vibration modulation transfer
functions", Opt. Eng. 33 (1994); Holst, *CMOS/CCD Sensors and Camera Systems* (2011), TDI.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from satchain.tf.pushbroom_otf import (  # noqa: F401 (the primitives, named here as before)
    PSDWindow,
    _frequency_nodes,
    drift_otf,
    jitter_psd_otf,
    log_otf,
    log_windows,
    oscillation_displacement_px,
    oscillation_otf,
    psd_window,
    window_means,
)
from satchain.tf.pushbroom_roi import as_imaged_otf, per_row_otf

__all__ = [
    "PSDWindow",
    "drift_otf",
    "jitter_psd_otf",
    "log_otf",
    "log_windows",
    "oscillation_displacement_px",
    "oscillation_otf",
    "psd_window",
    "window_means",
    "yaw_pivot_m",
]


def _on_axis_signed(axis: str, pitch_mm: float, fn: Callable[[np.ndarray], np.ndarray]):
    """As :func:`_on_axis` for a complex ``fn`` (no symmetry assumed): once per distinct signed value."""
    k = 0 if axis == "act" else 1

    def comp(fx, fy):
        v = np.asarray(np.broadcast_arrays(fx, fy)[k], dtype=float) * pitch_mm
        u, inv = np.unique(v, return_inverse=True)
        return fn(u)[inv.reshape(v.shape)]

    return comp


def on_one_axis(values: np.ndarray, fn: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """``fn`` of ``|values|`` evaluated once per distinct value: on the 1-D slice of a broadcast grid (a
    zero stride), then on its unique values."""
    v = np.asarray(values, dtype=float)
    index = tuple(slice(0, 1) if st == 0 and n > 1 else slice(None) for st, n in zip(v.strides, v.shape, strict=True))
    core = np.abs(v[index])
    u, inv = np.unique(core, return_inverse=True)
    return np.broadcast_to(np.asarray(fn(u))[inv.reshape(core.shape)], v.shape)


class PushbroomTerms:
    """The pushbroom motion of an :class:`~satchain.config.system.ImagingSystem` over its TDI window: the transfer
    function of each term (:meth:`components`, focal-plane cy/mm like every SystemOTF component) and the
    geometry the terms leave in the image (:meth:`geometry`). Empty (no components, no geometry) for a system
    without ``motion.line_rate_error``, ``[[motion.oscillation]]``, ``[motion.jitter_psd]`` or
    ``orbit.earth_rotation``.

    Components: ``oscillation_1``, ``oscillation_2``, ... (one per ``[[motion.oscillation]]``, in order; several
    on one axis multiply, which leaves out their cross terms ``J_k(b1) J_l(b2)``: exact when each has whole
    cycles in the window or is slow), ``jitter_psd_act`` / ``jitter_psd_alt`` (all tables of an axis together,
    exact), ``tdi_drift`` (line-rate error and Earth rotation together, exact).

    Examples
    --------
    >>> from satchain import load_preset
    >>> t = PushbroomTerms(load_preset("ankarasat3").replace({"motion.line_rate_error": 0.05}))
    >>> list(t.components()), round(t.geometry()["tdi_drift_px"]["alt"], 3)
    (['tdi_drift'], 0.8)
    """

    def __init__(self, system) -> None:
        self.system = system
        det, mot = system.detector, system.motion
        self.stages = det.tdi_stages
        self.line_time_s = system.line_time_s
        self.window_s = self.stages * self.line_time_s
        self._pitch_mm = {"act": det.pitch_x_m * 1e3, "alt": det.pitch_y_m * 1e3}
        self.earth = _earth_rotation(system) if system.orbit.earth_rotation else None
        e = mot.line_rate_error
        if self.earth is None:
            self.drift_px = (0.0, e) if e != 0 else None
        else:
            self.drift_px = (self.earth["tdi_drift_px_per_stage"][0], self.earth["tdi_drift_px_per_stage"][1] + e)
        self.psd: dict[str, PSDWindow] = {}
        f_top = max((t.frequency_hz[-1] for t in mot.jitter_psd), default=0.0)
        n_s = int(min(4096, math.ceil(2.0 * f_top * self.window_s) + 64))  # one node set: the tables of an axis add
        for table in mot.jitter_psd:
            w = psd_window(
                table.frequency_hz, table.psd_px2_per_hz, window_s=self.window_s, line_time_s=self.line_time_s, n_s=n_s
            )
            self.psd[table.axis] = self.psd[table.axis] + w if table.axis in self.psd else w
        # the [motion.line_of_sight] log on the time grid, per axis (log_windows), made once
        self.log = {} if mot.line_of_sight is None else {a: log_windows(system, a) for a in ("act", "alt")}

    @property
    def active(self) -> bool:
        return bool(self.drift_px is not None or self.system.motion.time_varying)

    def components(self) -> dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]]:
        """Name -> OTF(fx_cy_per_mm, fy_cy_per_mm) of each term (see the class docstring)."""
        comps: dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {}
        c_of = self.window_s
        for i, osc in enumerate(self.system.motion.oscillation, start=1):
            fn = _osc_fn(osc.amplitude_px, osc.frequency_hz * c_of)
            comps[f"oscillation_{i}"] = _on_axis(osc.axis, self._pitch_mm[osc.axis], fn)
        for axis in ("act", "alt"):
            if axis in self.psd:
                comps[f"jitter_psd_{axis}"] = _on_axis(axis, self._pitch_mm[axis], _psd_fn(self.psd[axis]))
        for axis, (x, m, k) in self.log.items():
            if np.ptp(x) > 0:
                comps[f"los_log_{axis}"] = _on_axis_signed(axis, self._pitch_mm[axis], _log_fn(x, m, k))
        if self.drift_px is not None:
            dx, dy = self.drift_px
            px, py = self._pitch_mm["act"], self._pitch_mm["alt"]
            comps["tdi_drift"] = lambda fx, fy: drift_otf(
                np.asarray(fx) * px, np.asarray(fy) * py, stages=self.stages, drift_x_px=dx, drift_y_px=dy
            )
        return comps

    def per_row_otf(self, nu_cy_per_px, axis: str) -> np.ndarray:
        """The budget's motion terms on ``axis`` (cy/px of it), complex
        (:func:`satchain.tf.pushbroom_roi.per_row_otf`)."""
        return per_row_otf(self, nu_cy_per_px, axis)

    def as_imaged_otf(self, nu_cy_per_px, axis: str, *, first_line: int, n_lines: int, about_line: bool = True,
                      degree: int = 1):  # fmt: skip
        """The motion's OTF on ``axis`` of an edge measured as imaged over the image rows ``first_line ..
        first_line + n_lines - 1`` (about a fitted polynomial of ``degree``): :func:`satchain.tf.pushbroom_roi.
        as_imaged_otf`."""
        return as_imaged_otf(
            self, nu_cy_per_px, axis, first_line=first_line, n_lines=n_lines, about_line=about_line, degree=degree
        )

    def image_affine(self, shape: tuple[int, int] | None = None, *, origin_m: tuple[float, float] = (0.0, 0.0)):
        """The mean map from ground metres (x ACT, y ALT, from the scene's origin) to image pixel coordinates
        ``(col, row)`` with pixel centres at integers, as ``affine.Affine``: the static grid (pixel ``(i, j)``
        centred on ``origin_m + ((j + 0.5) gsd_act, (i + 0.5) gsd_alt)``; ``origin_m``: the detector grid's corner
        on the ground, the engine's ``SimParams.phase_px`` times the input pixel), moved by the drifts averaged
        over each row's TDI window (``(sigma, eps) (i + N / 2)`` px; :mod:`satchain.engine.timepath`) and, with
        yaw steering, turned by ``rotation_deg`` about :func:`yaw_pivot_m` of the static output grid of ``shape =
        (rows, cols)`` (required then; the engine turns the ground about the same point, :mod:`satchain.engine.yaw`).
        Oscillations and jitter average to zero over the scan and are left out (they are the line-to-line
        displacement of :meth:`geometry`)."""
        from affine import Affine

        sys_ = self.system
        g_x, g_y = sys_.gsd_act_m, sys_.gsd_alt_m
        n_half = self.stages / 2.0
        sigma, eps = self.drift_px if self.drift_px is not None else (0.0, 0.0)
        rot = self.earth["rotation_deg"] if self.earth is not None else 0.0
        # ground px (x, y) of the window-mean position of pixel (col j, row i), before any rotation:
        #   y = i + 0.5 + eps (i + N/2),  x = j + 0.5 + sigma (i + N/2)
        fwd = Affine.scale(g_x, g_y) @ Affine(1.0, sigma, 0.5 + sigma * n_half, 0.0, 1.0 + eps, 0.5 + eps * n_half)
        fwd = Affine.translation(float(origin_m[0]), float(origin_m[1])) @ fwd
        if rot:
            if shape is None:
                raise ValueError("shape: the image's (rows, cols) is needed to place the yaw rotation's centre")
            fwd = Affine.rotation(-rot, pivot=yaw_pivot_m(shape, (g_x, g_y), origin_m)) @ fwd
        return ~fwd

    def geometry(self) -> dict | None:
        """What the terms do to the image's geometry (JSON-ready), or None without any term."""
        if not self.active:
            return None
        mot = self.system.motion
        var = {"act": 0.0, "alt": 0.0}
        step = {"act": 0.0, "alt": 0.0}
        oscs = []
        for osc in mot.oscillation:
            c = osc.frequency_hz * self.window_s
            g = oscillation_displacement_px(osc.amplitude_px, c, cycles_per_line=osc.frequency_hz * self.line_time_s)
            var[osc.axis] += g["rms_px"] ** 2
            step[osc.axis] += g["line_to_line_rms_px"] ** 2
            entry = {"axis": osc.axis, "frequency_hz": osc.frequency_hz, "cycles_per_window": c}
            entry["line_displacement_amplitude_px"] = g["amplitude_px"]
            entry["line_displacement_rms_px"] = g["rms_px"]
            entry["line_to_line_rms_px"] = g["line_to_line_rms_px"]
            oscs.append(entry)
        psd = {}
        for axis, w in self.psd.items():
            var[axis] += w.displacement_variance_px2
            step[axis] += w.line_to_line_variance_px2
            psd[axis] = {
                "sigma_px": math.sqrt(w.variance_px2),
                "sigma_blur_px": math.sqrt(w.blur_variance_px2),
                "line_displacement_rms_px": math.sqrt(w.displacement_variance_px2),
                "line_to_line_rms_px": math.sqrt(w.line_to_line_variance_px2),
            }
        log = {}
        for axis, (x, m, k) in self.log.items():
            d = window_means(x, m, k)
            lv, sv = float(np.var(d)), float(np.mean(np.diff(d) ** 2)) if d.size > 1 else 0.0
            var[axis] += lv
            step[axis] += sv
            log[axis] = {"line_displacement_rms_px": math.sqrt(lv), "line_to_line_rms_px": math.sqrt(sv),
                         "rows_averaged": int(d.size)}  # fmt: skip
        out = {
            "line_time_s": self.line_time_s,
            "tdi_stages": self.stages,
            "window_s": self.window_s,
            "line_rate_error": mot.line_rate_error,
            "line_displacement_rms_px": {a: math.sqrt(v) for a, v in var.items()},
            "line_to_line_rms_px": {a: math.sqrt(v) for a, v in step.items()},
            "tdi_drift_px": {"act": 0.0, "alt": 0.0}
            if self.drift_px is None
            else {"act": self.stages * self.drift_px[0], "alt": self.stages * self.drift_px[1]},
            "alt_scale": 1.0 + mot.line_rate_error,
            "shear_act_px_per_line": 0.0,
            "shear_deg": 0.0,
            "rotation_deg": 0.0,
        }
        if oscs:
            out["oscillations"] = oscs
        if psd:
            out["jitter_psd"] = psd
        if log:
            out["line_of_sight_log"] = log
        if self.earth is not None:
            e = {k: v for k, v in self.earth.items() if k != "tdi_drift_px_per_stage"}
            out["earth_rotation"] = e
            out["alt_scale"] = e["alt_scale"] + mot.line_rate_error
            for key in ("shear_act_px_per_line", "shear_deg", "rotation_deg"):
                out[key] = e[key]
        return out


def yaw_pivot_m(shape: tuple[int, int], gsd_m: tuple[float, float], origin_m=(0.0, 0.0)) -> tuple[float, float]:
    """The ground point ``(x, y)`` (m) a yaw turns the image about: the centre of the static output grid of
    ``shape = (rows, cols)`` pixels of ``gsd_m = (ACT, ALT)`` whose corner lies at ``origin_m`` (the detector
    grid's offset on the ground truth). The one definition :meth:`PushbroomTerms.image_affine` and the engine's
    rotation (:func:`satchain.engine.yaw.rotated_frame`) both use.

    Examples
    --------
    >>> yaw_pivot_m((100, 80), (0.5, 0.5), origin_m=(0.25, 0.0))
    (20.25, 25.0)
    """
    return float(origin_m[0]) + shape[1] * gsd_m[0] / 2.0, float(origin_m[1]) + shape[0] * gsd_m[1] / 2.0


def _osc_fn(amplitude_px: float, c: float) -> Callable[[np.ndarray], np.ndarray]:
    return lambda nu: oscillation_otf(nu, amplitude_px=amplitude_px, cycles_per_window=c)


def _psd_fn(window: PSDWindow) -> Callable[[np.ndarray], np.ndarray]:
    return lambda nu: jitter_psd_otf(nu, window)


def _log_fn(x: np.ndarray, m: int, k: int) -> Callable[[np.ndarray], np.ndarray]:
    return lambda nu: log_otf(nu, x, m, k)


def _on_axis(axis: str, pitch_mm: float, fn: Callable[[np.ndarray], np.ndarray]):
    """A component of (fx, fy) in cy/mm that depends on one axis only, in cy/px of that axis."""
    k = 0 if axis == "act" else 1

    def scaled(f_cy_per_mm: np.ndarray) -> np.ndarray:
        return fn(f_cy_per_mm * pitch_mm)

    return lambda fx, fy: on_one_axis(np.broadcast_arrays(fx, fy)[k], scaled)  # keeps a broadcast grid's 0 strides


def _earth_rotation(system) -> dict:
    """The Earth's rotation under the scan (README, "Pushbroom TDI motion"): per line, the ground a row covers
    moves ``(sigma, 1 + eps)`` px (ACT, ALT) with ``sigma = dt v_e cos(Az) / gsd_act`` and ``eps = -omega R cos(i) /
    v_g``; ``x`` (ACT, the columns) points left of the ground track seen from above, so the image is the ground
    seen from above, unmirrored, with the track running down the rows."""
    from satchain.config.sections import EARTH_RADIUS_M, EARTH_ROTATION_RAD_PER_S
    from satchain.config.sections_motion import cos_heading

    orb = system.orbit
    v_g, dt = orb.ground_speed_m_per_s, system.line_time_s
    v_e = EARTH_ROTATION_RAD_PER_S * EARTH_RADIUS_M * math.cos(math.radians(orb.latitude_deg))
    east, north = cos_heading(orb)
    along, across = v_e * east, -v_e * north  # the Earth's velocity on the track's (y, x) unit vectors
    # Per line: the ground under row i + 1 lies (x, y) px from the one under row i, in the track frame.
    x_m, y_m = -across * dt, (v_g - along) * dt
    g_act, g_alt = system.gsd_act_m, system.gsd_alt_m
    out = {
        "latitude_deg": orb.latitude_deg,
        "inclination_deg": orb.inclination_deg,
        "pass_direction": orb.pass_direction,
        "yaw_steering": orb.yaw_steering,
        "earth_surface_speed_m_per_s": v_e,
        "track_heading_deg": math.degrees(math.atan2(east, north)),
        "earth_velocity_along_track_m_per_s": along,
        "earth_velocity_act_m_per_s": across,
    }
    if orb.yaw_steering:  # the detector turned by gamma: rows follow the relative motion, no ACT drift
        speed = math.hypot(x_m, y_m)
        gamma = math.degrees(math.atan2(x_m, y_m))
        out.update(alt_scale=speed / g_alt, shear_act_px_per_line=0.0, shear_deg=0.0, rotation_deg=gamma)
        out["tdi_drift_px_per_stage"] = (0.0, speed / g_alt - 1.0)
    else:
        sigma = x_m / g_act
        out.update(alt_scale=y_m / g_alt, shear_act_px_per_line=sigma, shear_deg=math.degrees(math.atan(sigma)))
        out["rotation_deg"] = 0.0
        out["tdi_drift_px_per_stage"] = (sigma, y_m / g_alt - 1.0)
    return out
