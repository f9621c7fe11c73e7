"""Line-of-sight motion from a long straight edge: frequencies and amplitudes of its line-by-line positions.

A pushbroom camera forms each image line at its own instant; a line-of-sight oscillation shifts whole lines,
so a straight near-vertical (ACT) edge wobbles in x.  :func:`measure_jitter` measures where every line crosses
the edge (the same positions as ``measure_edge(...).edge_position_px``: :mod:`satchain.measure.edge._crossings`),
removes the edge's tilt and finds the significant sinusoids (:mod:`satchain.measure._jitter_fit`).

Conventions
-----------
* Line ``i`` (image row, ``roi`` offset included) is at time ``t_i = i * line_time_s``; a peak is
  ``x(t) = amplitude_px * sin(2 pi frequency_hz t + phase_deg)`` added to the edge's x position.  The camera
  convention (README, pushbroom motion): a line-of-sight offset ``+a`` moves image features by ``-a``, and row
  ``i`` integrates over ``[i dt, i dt + T]`` (``T = tdi_stages * dt``): an oscillation ``A sin(2 pi f t + p)``
  of the line of sight appears as ``A |sinc(f T)|`` at phase ``p + 180 deg + pi f T`` (mod 360; sinc < 0 adds
  180 deg).
* A near-vertical edge tilted by ``theta`` sees the ACT motion plus ``tan(theta)`` times the ALT motion.
* Frequencies are measured up to the line-rate Nyquist ``1 / (2 line_time_s)``: a motion at ``f`` above it
  appears at ``|f - n / line_time_s|`` (``aliases_hz`` lists the nearest two).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from satchain._validate import check_positive, check_range
from satchain.errors import ConfigError, InputError
from satchain.measure._clipping import resolve_full_scale
from satchain.measure._common import ResultMixin, to_jsonable, unmask
from satchain.measure._jitter_fit import baluev_fap as _fap
from satchain.measure._jitter_fit import (
    fit_sinusoids,
    frequency_grid,
    nuisance_basis,
    periodogram,
    threshold_z,
)
from satchain.measure.edge._checks import check_saturation
from satchain.measure.edge._crossings import edge_line_fields, rough_line
from satchain.measure.edge._locate import edge_region

__all__ = ["JitterPeak", "JitterResult", "measure_jitter"]

MIN_LINES = 16
_FEW_CYCLES = 2.0  # a peak seen over fewer cycles of the record is flagged


@dataclass(frozen=True)
class JitterPeak(ResultMixin):
    """One significant sinusoid of the edge positions: ``x(t) = amplitude_px sin(2 pi frequency_hz t +
    phase_deg)``, each with its 1-sigma; ``false_alarm_probability`` of its periodogram peak; ``cycles`` seen
    over the record; ``aliases_hz`` the nearest frequencies that fold onto it; ``flags``."""

    frequency_hz: float
    frequency_sigma_hz: float
    amplitude_px: float
    amplitude_sigma_px: float
    phase_deg: float
    phase_sigma_deg: float
    false_alarm_probability: float
    cycles: float
    aliases_hz: tuple[float, float]
    flags: tuple[str, ...] = ()


@dataclass(frozen=True)
class JitterResult(ResultMixin):
    """Result of :func:`measure_jitter`.

    ``lines``, ``edge_position_px`` (x, image pixels, NaN where a line is not measured) and
    ``edge_position_sigma_px`` cover every line of the region; ``detrended_px`` is the position minus the
    edge's tilt (and the phase-locked nuisance terms), ``model_px`` the fitted sinusoids.  ``rms_px`` is the
    rms of ``detrended_px``, ``line_to_line_rms_px`` that of the change between consecutive lines (less its
    mean, the tilt); the ``*_motion_*`` values remove the position noise (``position_noise_px``, the lines'
    rms 1-sigma) from them.  ``residual_rms_px`` is left after the peaks; ``detection_limit_px`` the amplitude a
    further sinusoid needs to reach the ``false_alarm`` probability.  ``periodogram_amplitude_px`` is the
    least-squares sinusoid amplitude at each ``periodogram_frequency_hz`` before any peak is removed.
    """

    line_time_s: float
    nyquist_hz: float
    direction: str
    angle_deg: float
    peaks: tuple[JitterPeak, ...]
    lines: np.ndarray
    edge_position_px: np.ndarray
    edge_position_sigma_px: np.ndarray
    detrended_px: np.ndarray
    model_px: np.ndarray
    periodogram_frequency_hz: np.ndarray
    periodogram_amplitude_px: np.ndarray
    detection_limit_px: float
    false_alarm: float
    rms_px: float
    rms_motion_px: float
    line_to_line_rms_px: float
    line_to_line_motion_rms_px: float
    position_noise_px: float
    residual_rms_px: float
    n_lines_used: int
    flags: tuple[str, ...]
    warnings: tuple[str, ...]

    def to_dict(self) -> dict:
        out = super().to_dict()
        out["peaks"] = [p.to_dict() for p in self.peaks]
        return to_jsonable(out)


def measure_jitter(
    image,
    *,
    line_time_s: float,
    roi=None,
    max_peaks: int = 3,
    false_alarm: float = 1e-3,
    min_amplitude_px: float = 0.002,
    valid=None,
    nodata: float | None = None,
    full_scale: float | None = None,
) -> JitterResult:
    """Frequencies, amplitudes and phases of the line-of-sight motion seen by a long straight ACT edge.

    Parameters
    ----------
    image : array_like, 2-D
        Pushbroom image (rows = lines in time) holding one long near-vertical straight edge; a numpy masked
        array's masked pixels are excluded as ``valid = False`` ones are.
    line_time_s : float
        Time between consecutive lines (s), > 0.
    roi : (x0, y0, x1, y1), optional
        Half-open pixel region holding the edge; the whole image by default.
    max_peaks : int
        Most sinusoids fitted (1-10); fewer when the next is not significant.
    false_alarm : float
        Probability, in (0, 0.5), that noise alone makes a peak as high anywhere in the band: peaks above it
        are not reported (flag ``no_peak`` when none is).
    min_amplitude_px : float
        Smallest amplitude reported (>= 0): below it a significant peak is left out (the positions' own
        accuracy on noise-free images).
    valid, nodata, full_scale
        As :func:`satchain.measure.measure_edge`: lines whose edge window touches an excluded or clipped
        pixel are not measured.

    Returns
    -------
    JitterResult

    Raises
    ------
    InputError
        A near-horizontal (ALT) edge (its crossing columns are imaged at one instant), no edge (the two sides of
        the lines do not differ), fewer than 16 lines measured.

    Examples
    --------
    >>> from scipy.special import ndtr
    >>> y, x = np.mgrid[0:400, 0:40].astype(float)
    >>> xe = 15.3 + 0.05 * y + 1.5 * np.sin(2 * np.pi * 25.0 * y * 1e-3 + 0.4)
    >>> r = measure_jitter(0.2 + 0.6 * ndtr((x - xe) / 0.7), line_time_s=1e-3)
    >>> p = r.peaks[0]
    >>> round(p.frequency_hz, 2), round(p.amplitude_px, 3), round(p.phase_deg, 1)
    (25.0, 1.5, 22.9)
    """
    image, valid = unmask(image, valid)
    dt, n_max, alpha, a_min = _check_args(line_time_s, max_peaks, false_alarm, min_amplitude_px)
    fs = resolve_full_scale(image, full_scale, None)
    data, ok, flags = edge_region(image, roi, valid, nodata)
    flags += check_saturation(data, fs, ok)
    sign = _act_sign(data)
    work = data * sign
    lines, pos, sig = edge_line_fields(work, rough_line(work, ok), ok, (fs, sign), False, roi)
    use = np.isfinite(pos)
    if np.count_nonzero(use) < MIN_LINES:
        raise InputError(f"image: {np.count_nonzero(use)} line(s) measured across the edge (< {MIN_LINES})")
    t, y = lines[use] * dt, pos[use]
    freqs = frequency_grid(t, dt)
    fit, fap, first, basis = _find_peaks(t, y, lines[use].astype(float), freqs, (n_max, alpha, a_min))
    z_thr = threshold_z(alpha, t, freqs[-1], basis.shape[1] + 3 * (0 if fit is None else fit.freq_hz.size))
    return _result(
        (lines, pos, sig, use), (t, y, basis, fit, fap), (freqs, first, z_thr), (dt, alpha, "ACT", flags),
    )  # fmt: skip


#: The line times accepted (s): a line rate of 1 mHz to 1 GHz; far outside, the fit's frequencies overflow.
LINE_TIME_RANGE_S = (1e-9, 1e3)


def check_line_time(name: str, value) -> float:
    """``value`` as a line time in :data:`LINE_TIME_RANGE_S`, else a ConfigError naming ``name`` and the range."""
    lo, hi = LINE_TIME_RANGE_S
    try:
        dt = check_positive(name, value)
    except ConfigError:  # one message, with the real range, for 0, a negative, NaN or a non-number too
        dt = None
    if dt is None or not lo <= dt <= hi:
        raise ConfigError(f"{name} = {value!r}: must be in [{lo:g}, {hi:g}] s (a line rate of 1 mHz to 1 GHz)")
    return dt


def _check_args(line_time_s, max_peaks, false_alarm, min_amplitude_px):
    """The checked options of :func:`measure_jitter`."""
    dt = check_line_time("line_time_s", line_time_s)
    n = check_range("max_peaks", max_peaks, 1, 10)
    if n != int(n):
        raise ConfigError(f"max_peaks = {max_peaks!r}: must be an integer in [1, 10]")
    alpha = check_range("false_alarm", false_alarm, 0.0, 0.5, lo_open=True, hi_open=True)
    a_min = check_range("min_amplitude_px", min_amplitude_px, 0.0)
    return dt, int(n), alpha, a_min


def _find_peaks(t, y, lines, freqs, opts):
    """Prewhitening: (joint fit or None, false-alarm probability of each peak, first periodogram amplitude, the
    nuisance basis).  The phase-locked terms follow the model's positions (the tilt, then with the peaks found),
    never the measured ones: terms built from the noise would absorb it and make noise peaks significant."""
    n_max, alpha, a_min = opts
    fit, faps, first = None, [], None
    found: list[float] = []
    basis = nuisance_basis(lines, np.polyval(np.polyfit(lines, y, 1), lines))
    for _ in range(n_max):
        null = basis if fit is None else np.concatenate([basis, _sines(t, fit)], axis=1)
        z, amp, _ = periodogram(t, y, null, freqs)
        if first is None:
            first = amp
        j = int(np.argmax(z))
        fap = _fap(float(z[j]), t, float(freqs[-1]), basis.shape[1] + 3 * len(found))
        if fap > alpha:
            break
        trial = fit_sinusoids(t, y, basis, [*found, float(freqs[j])])
        span = float(np.ptp(t))
        fs = np.sort(trial.freq_hz)
        if np.any(np.diff(fs) < 0.5 / span) or trial.amp_px[-1] < a_min:
            break
        basis = nuisance_basis(lines, y - trial.residual_px - _phase_part(trial, basis))
        fit, found = fit_sinusoids(t, y, basis, trial.freq_hz), [float(f) for f in trial.freq_hz]
        faps.append(fap)
    return fit, faps, first, basis


def _act_sign(data: np.ndarray) -> float:
    """+1 / -1 making the edge rise along +x; refuses a region whose two sides (the outer eighths of each line)
    do not differ, and a near-horizontal edge (its rows' ends differ less, on average, than its columns')."""
    q = max(2, min(data.shape) // 8)
    rows = data[:, -q:].mean(axis=1) - data[:, :q].mean(axis=1)
    cols = data[-q:, :].mean(axis=0) - data[:q, :].mean(axis=0)

    def significant(d):
        return abs(float(np.mean(d))) > 5.0 * float(np.std(d)) / np.sqrt(d.size)

    if not (significant(rows) or significant(cols)):
        raise InputError("image: no edge found (the two sides of the region's lines do not differ)")
    if np.mean(np.abs(cols)) > abs(float(np.mean(rows))):
        raise InputError(
            "image: the edge is near-horizontal (ALT): the columns crossing it are imaged at the same instants, "
            "so their positions do not sample the motion in time; give a near-vertical (ACT) edge"
        )
    return 1.0 if np.mean(rows) >= 0 else -1.0


def _phase_part(fit, basis) -> np.ndarray:
    """The phase-locked part of a fit's nuisance model (all but its first two columns, offset and tilt)."""
    return basis[:, 2:] @ fit.basis_coef[2:]


def _sines(t, fit) -> np.ndarray:
    """The sin and cos columns of the frequencies fitted so far (the null model of the next peak)."""
    arg = 2 * np.pi * t[:, None] * fit.freq_hz[None, :]
    return np.concatenate([np.sin(arg), np.cos(arg)], axis=1)


def _peak(fit, i: int, fap: float, ctx) -> JitterPeak:
    """One :class:`JitterPeak` with its flags; ``ctx = (line time, record span s, phase frequencies)``."""
    dt, span, f_phase = ctx
    f = float(fit.freq_hz[i])
    cycles = f * (span + dt)
    flags = []
    if cycles < _FEW_CYCLES:
        flags.append("few_cycles")
    if np.any(np.abs(f - f_phase) < 2.0 / (span + dt)):
        flags.append("phase_locked")
    if f > 0.45 / dt:
        flags.append("near_nyquist")
    return JitterPeak(
        frequency_hz=f,
        frequency_sigma_hz=float(fit.freq_sigma_hz[i]),
        amplitude_px=float(fit.amp_px[i]),
        amplitude_sigma_px=float(fit.amp_sigma_px[i]),
        phase_deg=float(np.degrees(fit.phase_rad[i])),
        phase_sigma_deg=float(np.degrees(fit.phase_sigma_rad[i])),
        false_alarm_probability=float(fap),
        cycles=float(cycles),
        aliases_hz=(1.0 / dt - f, 1.0 / dt + f),
        flags=tuple(flags),
    )


_PEAK_WORDS = {
    "few_cycles": "seen over fewer than {c:g} cycles: its amplitude and frequency correlate with the edge's tilt "
    "(their sigmas include it)",
    "phase_locked": "within 2 / record of the edge's sub-pixel phase frequency or a harmonic: a motion there cannot "
    "be told from the edge profile (amplitude may be absorbed); use an edge at another tilt",
    "near_nyquist": "close to the line-rate Nyquist frequency",
}


def _result(posn, model, spec, meta) -> JitterResult:
    """Assemble the :class:`JitterResult`: ``posn = (lines, positions, sigma, used)``, ``model = (t, y, basis,
    fit, peak false-alarm probabilities)``, ``spec = (freqs, first periodogram amplitude, threshold z)``,
    ``meta = (line time, false alarm, direction, flags)``."""
    lines, pos, sig, use = posn
    t, y, basis, fit, faps = model
    freqs, first, z_thr = spec
    dt, alpha, direction, flags = meta
    n = y.size
    coef = np.linalg.lstsq(basis, y, rcond=None)[0] if fit is None else fit.basis_coef
    nuis = basis @ coef
    angle = float(np.degrees(np.arctan(coef[1] / max(np.ptp(t) / dt, 1.0))))  # the tilt term of the joint fit
    sines = np.zeros(n) if fit is None else fit.sines_px
    resid = y - nuis - sines
    span = float(np.ptp(t))
    det = np.full(pos.shape, np.nan)
    det[use] = y - nuis
    mdl = np.full(pos.shape, np.nan)
    mdl[use] = sines
    noise = float(np.sqrt(np.mean(sig[use] ** 2)))
    rms = float(np.sqrt(np.mean((y - nuis) ** 2)))
    l2l, l2l_noise = _line_to_line(lines, det, sig)
    rss = float(resid @ resid)
    n_par = basis.shape[1] if fit is None else fit.n_params
    res_rms = float(np.sqrt(rss / max(n - n_par, 1)))
    # phase frequencies |h tan(theta)| / dt (harmonics 1-10) folded into [0, Nyquist]
    f_ph = np.array([h * abs(np.tan(np.radians(angle))) / dt for h in range(1, 11)])  # a staircase: up to 10
    f_ph = np.abs(f_ph - np.round(f_ph * dt) / dt)
    peaks = () if fit is None else tuple(_peak(fit, i, faps[i], (dt, span, f_ph)) for i in range(len(faps)))
    flags = list(flags) + _result_flags(peaks, (res_rms, noise, n), np.sqrt(2 * z_thr * rss / n), (dt, span))
    return JitterResult(
        line_time_s=dt,
        nyquist_hz=0.5 / dt,
        direction=direction,
        angle_deg=angle,
        peaks=peaks,
        lines=lines,
        edge_position_px=pos,
        edge_position_sigma_px=sig,
        detrended_px=det,
        model_px=mdl,
        periodogram_frequency_hz=freqs,
        periodogram_amplitude_px=first,
        detection_limit_px=float(np.sqrt(2 * z_thr * rss / n)),
        false_alarm=alpha,
        rms_px=rms,
        rms_motion_px=float(np.sqrt(max(rms**2 - noise**2, 0.0))),
        line_to_line_rms_px=l2l,
        line_to_line_motion_rms_px=float(np.sqrt(max(l2l**2 - l2l_noise**2, 0.0))) if np.isfinite(l2l) else l2l,
        position_noise_px=noise,
        residual_rms_px=res_rms,
        n_lines_used=int(n),
        flags=tuple(c for c, _ in flags),
        warnings=tuple(w for _, w in flags),
    )


def _line_to_line(lines, det, sig):
    """(rms of the change between consecutive measured lines less its mean, its noise part)."""
    d = np.diff(det)
    ok = np.isfinite(d) & (np.diff(lines) == 1)
    if np.count_nonzero(ok) < 2:
        return float("nan"), float("nan")
    dd = d[ok] - d[ok].mean()
    noise2 = (sig[:-1] ** 2 + sig[1:] ** 2)[ok]
    return float(np.sqrt(np.mean(dd**2))), float(np.sqrt(np.mean(noise2)))


def _result_flags(peaks, stats, limit: float, timing) -> list:
    """``no_peak``, ``aliasing``, ``unexplained_motion`` and the peaks' own flags, with their sentences;
    ``timing = (line time, record span)``.  ``aliasing`` only for a peak that could be an alias: fitted above the
    line-rate Nyquist ``1 / (2 dt)`` or within the record's frequency resolution ``1 / span`` below it, where a
    motion just above Nyquist folds to (any other peak's aliases_hz still list the frequencies that fold onto
    it, which the lines cannot tell apart)."""
    res_rms, noise, n = stats
    dt, span = timing
    nyq = 0.5 / dt
    out = []
    if not peaks:
        out.append(("no_peak", f"no periodic motion above the detection limit {limit:.3g} px"))
    near = [p.frequency_hz for p in peaks if p.frequency_hz > nyq - 1.0 / (span + dt)]
    if near:
        out.append(
            (
                "aliasing",
                f"peak(s) at {', '.join(f'{f:.6g}' for f in near)} Hz lie within the record's resolution "
                f"{1.0 / (span + dt):.3g} Hz of the line-rate Nyquist {nyq:.6g} Hz (or above it): the motion may "
                f"be above Nyquist, folded (its aliases_hz)",
            )
        )
    if noise > 0 and res_rms**2 > noise**2 * (1.0 + 5.0 * np.sqrt(2.0 / n)) and res_rms > 1e-3:
        out.append(
            (
                "unexplained_motion",
                f"the residual rms {res_rms:.3g} px exceeds the position noise {noise:.3g} px: random or unresolved "
                f"motion of about {np.sqrt(res_rms**2 - noise**2):.3g} px rms remains",
            )
        )
    for p in peaks:
        for code in p.flags:
            out.append((code, f"peak at {p.frequency_hz:.6g} Hz: " + _PEAK_WORDS[code].format(c=_FEW_CYCLES)))
    return out
