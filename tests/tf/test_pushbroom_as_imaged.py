"""The budget's prediction of an edge measured as imaged over a ROI's rows (issue 29, item 11):
:meth:`PushbroomTerms.as_imaged_otf` against direct time-domain averages of the motion, computed here."""

from __future__ import annotations

import numpy as np
import pytest

from satchain import load_preset
from satchain.tf.pushbroom import PushbroomTerms, oscillation_otf

SYSTEM = load_preset("ankarasat3")
DT, N = SYSTEM.line_time_s, SYSTEM.detector.tdi_stages
NU = np.array([0.25, 0.5])


def _direct(paths: np.ndarray, signed: bool = False) -> np.ndarray:
    """|mean over rows and window samples of exp(2 pi i nu (x - L))|, L the straight line through the rows' means
    (``paths``: rows x samples of each row's window); ``signed``: the complex mean."""
    d = paths.mean(axis=1)
    i = np.arange(d.size)
    r = paths - np.polyval(np.polyfit(i, d, 1), i)[:, None]
    cf = np.exp(2j * np.pi * NU[:, None] * r.ravel()[None, :]).mean(axis=1)
    return cf if signed else np.abs(cf)


def _window_times(first: int, n: int, k: int = 400) -> np.ndarray:
    return (first + np.arange(n))[:, None] * DT + ((np.arange(k) + 0.5) * N * DT / k)[None, :]


CASES = [(0.3, 0.0, 0, 100), (0.3, 90.0, 37, 100), (0.5, 0.0, 5, 400), (0.09, 45.0, 0, 800)]


@pytest.mark.parametrize(("cycles", "phase_deg", "first", "n"), CASES)
def test_oscillation_as_imaged_equals_the_time_average(cycles, phase_deg, first, n):
    f = cycles / (N * DT)
    osc = {"axis": "act", "amplitude_px": 1.0, "frequency_hz": f, "phase_deg": phase_deg}
    t = PushbroomTerms(SYSTEM.replace({"motion.oscillation": [osc]}))
    x = np.sin(2 * np.pi * f * _window_times(first, n) + np.radians(phase_deg))
    np.testing.assert_allclose(t.as_imaged_otf(NU, "act", first_line=first, n_lines=n), _direct(x), atol=2e-3)
    # the per-row term is the budget's component (phase-averaged)
    np.testing.assert_allclose(t.per_row_otf(NU, "act").real, oscillation_otf(NU, amplitude_px=1.0,
                                                                                cycles_per_window=cycles))  # fmt: skip


def test_jitter_band_as_imaged_is_the_gaussian_expectation():
    """50-800 Hz of 1 px rms: the mean over Gaussian realisations (sums of sinusoids with Gaussian coefficients)
    of the as-imaged factor over a 200-row ROI (the expectation: one ROI's realised factor scatters about it)."""
    psd = {"axis": "act", "frequency_hz": [50.0, 800.0], "psd_px2_per_hz": [1.0 / 750.0] * 2}
    t = PushbroomTerms(SYSTEM.replace({"motion.jitter_psd": [psd]}))
    rng = np.random.default_rng(11)
    fk = np.linspace(50.0, 800.0, 61)
    fk = 0.5 * (fk[1:] + fk[:-1])
    tt = _window_times(0, 200, 24)
    c, s = np.cos(2 * np.pi * fk[:, None, None] * tt), np.sin(2 * np.pi * fk[:, None, None] * tt)
    sd = np.sqrt(1.0 / 750.0 * (fk[1] - fk[0]))
    a, b = (rng.normal(0, sd, (150, fk.size)) for _ in range(2))
    runs = [_direct(np.tensordot(a[k], c, 1) + np.tensordot(b[k], s, 1), signed=True) for k in range(150)]
    mean = np.mean(runs, axis=0)
    np.testing.assert_allclose(t.as_imaged_otf(NU, "act", first_line=0, n_lines=200), mean.real, atol=0.02)
