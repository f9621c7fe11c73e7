"""Slanted-edge numerics: ESF binning on the natural sample lattice, MTF with exact noise propagation.

Used by :mod:`satchain.measure.edge`.  All distances are in pixels along the edge normal.

Binning.  The projected samples of row ``r`` sit at ``d = (col - x_e(r)) cos t``: a lattice of period ``cos t``
shifted by the row's phase ``frac(-x_e(r))``.  At most tilts the phases of many rows fill the period and the
ISO bins of ``1/oversampling`` px are all populated.  Near ``atan(1/n)`` (45, 26.57, 18.43 deg ...) or on
short edges the phases gather in ``n`` clusters and whole bins stay empty; filling them by interpolation is
what makes plain ISO 9-42 % low there.  Instead, the bins are then put on the natural lattice of the clusters
(spacing ``cos t / n``, centred on them), so every bin holds real samples and the ESF is sampled uniformly at
the spacing the data actually have.

MTF.  The LSF is the first difference of the binned ESF (transfer ``sinc(f w)``, corrected), kept raw inside a
Tukey window and taken from a Gaussian-smoothed ESF outside it.  Every step is linear in the bin values, so
the noise of the MTF at each frequency is propagated exactly (first order, including the normalisation at
f = 0) from the per-bin noise ``sigma^2 / n``.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import convolve1d, correlate1d

from satchain.measure._common import median
from satchain.measure.edge._locate import MIN_ROWS

__all__ = ["adaptive_mtf", "bin_esf", "choose_bins", "flatten_rows", "rise_width", "trim_ends", "window_mtf"]

_W_MIN_PX = 5.0  # smallest half-width of the raw-LSF window (px)
_W_MIN_RISE = 2.5  # ... and in units of the 10-90 % rise distance
_ENDS: dict = {}  # kernel -> the smoothing's end matrices (:meth:`_Lsf._s_ends`), a few kernels per run
_TRANSFER: dict = {}  # (kernel, bin width, frequencies) -> the kernel's transfer (:func:`_transfer`)
_CHUNK_F = 48  # frequencies per chunk of the noise propagation (arrays of 48 x bins stay in cache)
_TAIL_SMOOTH_PX = 1.25  # Gaussian smoothing of the ESF outside the window (px); 0.75 doubled the noise at 0.25 cy/px


def choose_bins(row_phase: np.ndarray, cos_t: float, oversampling: int):
    """Bin width and origin (px along the normal) from the rows' sub-pixel phases.

    Parameters
    ----------
    row_phase : ndarray
        ``frac(-x_e(r))`` of every row used (px along the row, in [0, 1)).
    cos_t : float
        Cosine of the edge tilt (the lattice period along the normal).
    oversampling : int
        ISO bins per pixel.

    Returns
    -------
    (width_px, origin_px, mode) with mode ``"iso"`` (1/oversampling bins), ``"lattice"`` (the natural lattice
    of n phase clusters) or ``"gap"`` (bins just wider than the largest phase gap).
    """
    w_iso = 1.0 / oversampling
    p = np.sort(np.mod(row_phase, 1.0))
    gaps = np.diff(np.concatenate([p, [p[0] + 1.0]]))
    g_max = float(gaps.max())
    big = gaps >= 0.5 * g_max
    n = int(np.count_nonzero(big))
    # n clusters (each narrower than half their spacing, gaps alike): the natural lattice
    tight = (1.0 - gaps[big].sum()) < 0.5 and np.ptp(gaps[big]) < 0.5 / n
    if n <= 2 * oversampling and tight and p.size >= 2 * n:
        z = np.mean(np.exp(2j * np.pi * n * p))
        phi0 = float(np.angle(z) / (2 * np.pi * n)) % (1.0 / n)
        return cos_t / n, phi0 * cos_t, "lattice"
    if g_max * cos_t <= 0.8 * w_iso:
        return w_iso, 0.0, "iso"
    return 1.05 * g_max * cos_t, 0.0, "gap"


def bin_esf(d: np.ndarray, v: np.ndarray, w: float, origin: float = 0.0):
    """ESF at the centres ``origin + k w`` of bins of width ``w``, corrected for the sample positions.

    A bin's plain average is the ESF at the bin centre plus ``E' <u> + E'' <u^2> / 2`` (``u`` = offsets of
    its samples from the centre); these terms are removed with derivatives from the binned ESF itself (three
    fixed-point passes).  Empty bins (only possible at the ends of the ESF, where the region's corners cut
    rows short) are filled linearly.  Returns bin centres, ESF and counts.
    """
    k = np.rint((d - origin) / w).astype(int)
    k0 = k.min()
    idx = k - k0
    counts = np.bincount(idx)
    ok = counts > 0
    n = np.maximum(counts, 1)
    u = d - origin - k * w
    mean_v = np.bincount(idx, weights=v) / n
    m1 = np.bincount(idx, weights=u) / n
    m2 = np.bincount(idx, weights=u * u) / n
    x = origin + (np.arange(counts.size) + k0) * w
    esf = mean_v.copy()
    holes = not ok.all()
    kernel = _gauss_kernel_nd(max(0.5, 0.125 / w))
    for _ in range(3):
        if holes:
            esf[~ok] = np.interp(x[~ok], x[ok], esf[ok])
        es = correlate1d(esf, kernel, mode="nearest")  # = gaussian_filter1d, its kernel made once
        d1 = _gradient(es, w)
        d2 = _gradient(d1, w)
        esf = mean_v - d1 * m1 - 0.5 * d2 * m2
    if holes:
        esf[~ok] = np.interp(x[~ok], x[ok], esf[ok])
    return x, esf, counts


def _gauss_kernel_nd(sigma: float) -> np.ndarray:
    """``scipy.ndimage.gaussian_filter1d``'s own kernel (truncated at 4 sigma), the same floats."""
    radius = int(4.0 * sigma + 0.5)
    phi = np.exp(-0.5 / (sigma * sigma) * np.arange(-radius, radius + 1) ** 2)
    return phi / phi.sum()


def _gradient(f: np.ndarray, step: float) -> np.ndarray:
    """``np.gradient(f, step)`` of a 1-D array (central differences, one-sided at the ends), the same floats
    without its overhead."""
    out = np.empty_like(f)
    out[1:-1] = (f[2:] - f[:-2]) / (2.0 * step)
    out[0] = (f[1] - f[0]) / step
    out[-1] = (f[-1] - f[-2]) / step
    return out


def _tukey(x: np.ndarray, half_width: float | np.ndarray) -> np.ndarray:
    """Tukey window: 1 for |x| <= W/2, cosine taper to 0 at |x| = W."""
    a = np.clip((np.abs(x) - 0.5 * half_width) / (0.5 * half_width), 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(np.pi * a))


def _gauss_kernel(sigma_bins: float) -> np.ndarray:
    """Normalised Gaussian kernel truncated at 4 sigma (odd length)."""
    r = max(1, int(4.0 * sigma_bins + 0.5))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma_bins) ** 2)
    return k / k.sum()


class _Lsf:
    """The linear map bin ESF -> windowed LSF at the bin midpoints, and its spectrum's noise.

    ``lsf = win g + S((1 - win) g)`` with ``g`` the first difference of the ESF, ``win`` the Tukey window and
    ``S`` a Gaussian smoothing with mirror ends (it keeps the mass of what it smooths).  Only the tails are
    smoothed: the core's mass stays where it is.  (Smoothing the whole ESF and taking its tails, the earlier
    form, spread the core's mass into the tails whenever the window was short: at SNR <= 100 the window
    shrank to 5 px and a Gaussian-like PSF read 0.02 low at 0.1-0.15 cy/px.)  The total mass, the MTF's
    normalisation at f = 0, is that of the raw LSF, long (diffraction) tails included.

    ``half_w`` may be an array of half-widths (one map per row of ``win``: :meth:`apply` then gives one LSF per
    half-width).
    """

    def __init__(self, x: np.ndarray, half_w, w: float):
        self.w = w
        self.xm = 0.5 * (x[1:] + x[:-1])
        self.win = _tukey(self.xm, np.asarray(half_w, dtype=float)[..., None])
        if self.win.ndim == 2 and self.win.shape[0] == 1:
            self.win = self.win[0]
        self.kernel = _gauss_kernel(_TAIL_SMOOTH_PX / w)

    def _s(self, y: np.ndarray) -> np.ndarray:
        """Gaussian smoothing along the last axis, mirror ends (symmetric: its own transpose)."""
        return convolve1d(y, self.kernel, axis=-1, mode="reflect")

    def apply(self, esf: np.ndarray) -> np.ndarray:
        g = np.diff(esf) / self.w
        return self.win * g + self._s((1 - self.win) * g)

    def fourier(self, f: np.ndarray) -> np.ndarray:
        """``exp(-2 pi i f xm)``, shape (f, K - 1); on a uniform grid of ``f`` from 0 by powers of one row."""
        f = np.asarray(f, dtype=float)
        n, b = f.size, 16
        if n > 2 * b and f[0] == 0.0 and np.allclose(np.diff(f), f[1], rtol=0.0, atol=1e-12):
            # f_j = (b p + q) df: exp(-2 pi i b p df xm) exp(-2 pi i q df xm), 1 / b of the exponentials
            lo = np.exp(-2j * np.pi * np.outer(np.arange(b) * f[1], self.xm))
            hi = np.exp(-2j * np.pi * np.outer(np.arange(-(-n // b)) * (b * f[1]), self.xm))
            return (hi[:, None, :] * lo[None, :, :]).reshape(-1, self.xm.size)[:n]
        return np.exp(-2j * np.pi * np.outer(f, self.xm))

    def fourier_chunks(self, f: np.ndarray, rows: int = _CHUNK_F):
        """(slice of ``f``, :meth:`fourier` of those frequencies) in chunks of ``rows`` frequencies (the same
        values as one :meth:`fourier`): the arrays of the noise propagation then stay small (in cache, and
        reused by the allocator instead of fresh pages)."""
        f = np.asarray(f, dtype=float)
        n, b = f.size, 16
        if n > 2 * b and f[0] == 0.0 and np.allclose(np.diff(f), f[1], rtol=0.0, atol=1e-12):
            lo = np.exp(-2j * np.pi * np.outer(np.arange(b) * f[1], self.xm))
            hi = np.exp(-2j * np.pi * np.outer(np.arange(-(-n // b)) * (b * f[1]), self.xm))
            step = max(1, rows // b)
            for k in range(0, hi.shape[0], step):
                sl = slice(k * b, min(n, (k + step) * b))
                yield sl, (hi[k : k + step, None, :] * lo[None, :, :]).reshape(-1, self.xm.size)[: sl.stop - sl.start]
        else:
            yield slice(0, n), np.exp(-2j * np.pi * np.outer(f, self.xm))

    def spectrum(self, lsf: np.ndarray, f: np.ndarray, e: np.ndarray | None = None) -> np.ndarray:
        e = self.fourier(f) if e is None else e
        if lsf.ndim > 1:
            return (lsf @ e.real.T + 1j * (lsf @ e.imag.T)) * self.w
        return (e.real @ lsf + 1j * (e.imag @ lsf)) * self.w  # real products: complex BLAS is far slower here

    def _y0(self, win: np.ndarray) -> np.ndarray:
        """The LSF map's response to a constant difference ``w`` (the sensitivity of the spectrum at f = 0)."""
        y0 = getattr(self, "_y0_cache", None)
        if y0 is None or y0.shape != win.shape:
            y0 = self._y0_cache = win * self.w + (1 - win) * self._s(np.full(self.xm.size, self.w))
        return y0

    def _s_fourier(self, p: np.ndarray, f: np.ndarray, out=None) -> np.ndarray:
        """``S`` of rows ``p_f = Re(c_f exp(-2 pi i f xm))``: inside the kernel's reach of the ends a complex
        exponential goes through the convolution multiplied by the kernel's (real) transfer ``H(f)``; the
        ``r`` samples at each end, where the mirror enters, are convolved directly."""
        k = self.kernel
        r = k.size // 2
        m = p.shape[-1]
        if m <= 4 * r + 2:
            if out is None:
                return self._s(p)
            out[...] = self._s(p)
            return out
        out = np.multiply(_transfer(k, self.w, f)[:, None], p, out=out)
        left, right = self._s_ends()
        out[:, :r] = p[:, : 2 * r + 1] @ left
        out[:, -r:] = p[:, -(2 * r + 1) :] @ right
        return out

    def _s_ends(self):
        """The matrices of :meth:`_s` from the ``2 r + 1`` samples at each end to the ``r`` outputs there (the
        mirror's reach; linear, so read off the response to the unit vectors)."""
        key = self.kernel.tobytes()
        ends = _ENDS.get(key)
        if ends is None:
            r = self.kernel.size // 2
            s_eye = self._s(np.eye(2 * r + 1))
            ends = _ENDS[key] = (s_eye[:, :r].copy(), s_eye[:, -r:].copy())
            if len(_ENDS) > 64:
                _ENDS.pop(next(iter(_ENDS)))
        return ends

    def mtf_sigma(self, spec: np.ndarray, f: np.ndarray, e: np.ndarray, var_bins, corr, m0=None) -> np.ndarray:
        """First-order standard deviation of the normalised MTF ``|spec(f)| / spec(0) / corr`` (magnitude and
        normalisation noise) from independent bin noise ``var_bins``; ``e`` = :meth:`fourier` of ``f``.

        ``d |spec(f)| / d esf = Re(u d spec / d esf)`` with ``u = conj(spec) / |spec|``; the derivative of the
        spectrum is the adjoint of the (real) LSF map applied to the Fourier kernel, so the real part can be
        taken first: one real pass ``win q + (1 - win) S(q)`` then the adjoint of the difference.
        ``m0`` is the spectrum at f = 0 (default: the first column of ``spec``, whose ``f`` then start at 0).
        """
        spec2 = np.atleast_2d(spec)  # (windows, f)
        win = self.win if self.win.ndim == 2 else self.win[None]
        m0 = spec2[:, :1].real if m0 is None else np.reshape(np.asarray(m0, dtype=float), (-1, 1))
        mag = np.abs(spec2)
        u = np.where(mag > 0, np.conj(spec2) / np.maximum(mag, 1e-300), 1.0) * (self.w / m0)
        # few large temporaries, updated in place (each fresh (windows, f, bins) array costs page faults)
        y = np.multiply(u.real[..., None], e.real)  # p = Re(u e) w / m0
        tmp = np.multiply(u.imag[..., None], e.imag)
        y -= tmp
        p2, t2 = y.reshape(-1, y.shape[-1]), tmp.reshape(-1, y.shape[-1])
        self._s_fourier(p2, np.tile(f, spec2.shape[0]), out=t2)  # S(p)
        y -= tmp  # y = S(p) + win (p - S(p)) = win p + (1 - win) S(p)
        y *= win[:, None, :]
        y += tmp
        y0 = self._y0(win)  # sensitivity at f = 0
        np.multiply((mag / m0**2)[..., None], y0[:, None, :], out=tmp)
        y -= tmp
        # c = adjoint of diff(.) / w applied to y: c_k = (y_{k-1} - y_k) / w with zero ends
        d = np.empty(y.shape[:-1] + (y.shape[-1] + 1,))
        d[..., 0] = -y[..., 0]
        d[..., -1] = y[..., -1]
        np.subtract(y[..., :-1], y[..., 1:], out=d[..., 1:-1])
        d *= d
        out = np.sqrt(d @ var_bins) / abs(self.w) / corr
        return out if spec.ndim == 2 else out[0]


def _transfer(kernel: np.ndarray, w: float, f: np.ndarray) -> np.ndarray:
    """The symmetric ``kernel``'s transfer at ``f`` (cy/px) on bins of ``w`` px: ``k_0 + 2 sum_t k_t cos(2 pi f t
    w)``, kept per (kernel, w, f): the edges of a chart share their bins and frequencies (read-only)."""
    key = (kernel.tobytes(), float(w), f.tobytes())
    h = _TRANSFER.get(key)
    if h is None:
        r = kernel.size // 2
        h = kernel[r] + 2.0 * np.cos(2 * np.pi * np.outer(f, np.arange(1, r + 1) * w)) @ kernel[r + 1 :]
        h.flags.writeable = False
        _TRANSFER[key] = h
        if len(_TRANSFER) > 64:
            _TRANSFER.pop(next(iter(_TRANSFER)))
    return h


def _fourier_at(f: np.ndarray, xm: np.ndarray) -> np.ndarray:
    """``exp(-2 pi i f xm)``, shape (f, xm), for ``f`` uniform from 0 (:meth:`_Lsf.fourier`'s factorisation)."""
    n, b = f.size, 16
    lo = np.exp(-2j * np.pi * np.outer(np.arange(b) * f[1], xm))
    hi = np.exp(-2j * np.pi * np.outer(np.arange(-(-n // b)) * (b * f[1]), xm))
    return (hi[:, None, :] * lo[None, :, :]).reshape(-1, xm.size)[:n]


def _dft_rows(rows: np.ndarray, step: float, n_out: int) -> np.ndarray:
    """``sum_k rows[:, k] exp(-2 pi i j step k)`` for ``j < n_out``: a real FFT where ``1 / step`` is a whole
    number at least the rows' length (the ISO bins on the 0.005 cy/px grid), else Bluestein's chirp-z (``jk =
    (j^2 + k^2 - (j - k)^2) / 2``: a convolution by FFTs, the direct sum to ~1e-13; with the matrix DFT a 100-line edge
    near atan(1/5) took 22 ms, not 10, at 45 deg 18 ms, not 5; scipy.signal's chirp-z would import scipy.stats,
    about a second of start-up)."""
    n = 1.0 / step
    big = int(round(n))
    m = rows.shape[-1]
    if abs(n - big) <= 1e-9 * n and big >= m and big // 2 + 1 >= n_out:
        return np.fft.rfft(rows, n=big, axis=-1)[:, :n_out]
    k = np.arange(max(m, n_out), dtype=float)
    chirp = np.exp(-1j * np.pi * step * k * k)  # exp(-2 pi i step k^2 / 2)
    size = 1 << int(np.ceil(np.log2(m + n_out - 1)))
    kernel = np.zeros(size, complex)
    kernel[:n_out] = np.conj(chirp[:n_out])
    kernel[size - m + 1 :] = np.conj(chirp[1:m][::-1])
    conv = np.fft.ifft(np.fft.fft(rows * chirp[:m], n=size, axis=-1) * np.fft.fft(kernel), axis=-1)
    return conv[:, :n_out] * chirp[:n_out]


def spectrum_sigma(op: _Lsf, lsf: np.ndarray, f: np.ndarray, var_bins: np.ndarray, corr: np.ndarray):
    """The spectrum of ``lsf`` at ``f`` and the MTF's 1-sigma, as :meth:`_Lsf.spectrum` and
    :meth:`_Lsf.mtf_sigma` (normalised by ``|spec(0)|``) give them, in closed form; ``op`` has one window.

    Inside the smoothing's reach of the ends the adjoint at frequency ``f`` of bin ``j`` is
    ``A_j cos th_j + B_j sin th_j`` (``th_j = 2 pi f xm_j``) with ``A_j, B_j`` linear in ``(1, win_{j-1},
    win_j - win_{j-1})``: its noise ``sum_j var_j (.)^2`` is a quadratic form in weighted sums of the products
    of those three times ``1, cos 2 th_j, sin 2 th_j``, i.e. six Fourier sums at ``2 f`` (one transform for all
    frequencies, with the spectrum's own).  The ``r + 1`` bins at each end, where the mirror enters, are
    propagated directly.  Falls back to the direct pass off a uniform grid from 0 or on short ESFs.
    """
    k = op.kernel
    r, m, nf = k.size // 2, op.xm.size, f.size
    win = op.win
    uniform = nf > 2 and f[0] == 0.0 and float(np.abs(f[1:] - f[:-1] - f[1]).max()) <= 1e-12
    if not uniform or m <= 4 * r + 2 or win.ndim != 1:
        return _spectrum_sigma_direct(op, lsf, f, var_bins, corr)
    w, df = op.w, float(f[1])
    j = np.arange(r + 1, m - r)  # the bins whose adjoint is the interior form
    wp, dw = win[j - 1], win[j] - win[j - 1]
    rows = np.zeros((7, m))
    rows[0] = lsf
    rows[1:, j] = var_bins[j] * np.stack([np.ones_like(wp), wp, dw, wp * wp, wp * dw, dw * dw])
    z = _dft_rows(rows, df * w, 2 * nf - 1)
    spec = w * np.exp(-2j * np.pi * f * op.xm[0]) * z[0, :nf]
    z2 = np.exp(-4j * np.pi * f * op.xm[0]) * z[1:, ::2]  # (6, f): sums against exp(-2 i th_j)
    m0 = float(spec[0].real)
    sgn, m0a = np.sign(m0), abs(m0)
    mag = np.abs(spec)
    u = np.where(mag > 0, np.conj(spec * sgn) / np.maximum(mag, 1e-300), 1.0) * (w / m0a)
    ur, ui, g = u.real, u.imag, mag / m0a**2
    h = _transfer(k, w, f)
    q = 1.0 - h
    ph = 2 * np.pi * f * w
    cp, sp = np.cos(ph), np.sin(ph)
    al, be = ur * cp - ui * sp - ur, ur * sp + ui * cp - ui  # u exp(i ph) - u
    a_c = np.stack([al * h, al * q, -q * ur])  # A_j = a_c . (1, win_{j-1}, dwin_j)
    b_c = np.stack([be * h, be * q, -q * ui])
    s0 = rows[1:].sum(axis=1)[:, None]  # sums against 1: cos^2 = (1 + cos 2th) / 2, sin^2 = (1 - cos 2th) / 2
    total = _quad(a_c, a_c, 0.5 * (s0 + z2.real)) + _quad(b_c, b_c, 0.5 * (s0 - z2.real)) - _quad(a_c, b_c, z2.imag)
    total += _ends_noise(op, f, (ur, ui, g, h), var_bins)
    return spec, np.sqrt(np.maximum(total, 0.0)) / abs(w) / corr


def _quad(x, y, mom):
    """``sum_lm x_l y_m M_lm`` per frequency, ``M`` symmetric 3 x 3 given as its six moments (00, 01, 02, 11,
    12, 22)."""
    return (
        x[0] * y[0] * mom[0]
        + (x[0] * y[1] + x[1] * y[0]) * mom[1]
        + (x[0] * y[2] + x[2] * y[0]) * mom[2]
        + x[1] * y[1] * mom[3]
        + (x[1] * y[2] + x[2] * y[1]) * mom[4]
        + x[2] * y[2] * mom[5]
    )


def _ends_noise(op: _Lsf, f, coefs, var_bins) -> np.ndarray:
    """``sum_j var_j d_j^2`` over the ``r + 1`` bins at each end (:meth:`_Lsf.mtf_sigma`'s pass on them)."""
    ur, ui, g, h = coefs
    r, m = op.kernel.size // 2, op.xm.size
    left, right = op._s_ends()
    y0 = op._y0(op.win)
    cols = np.concatenate([np.arange(2 * r + 1), np.arange(m - 2 * r - 1, m)])
    e = _fourier_at(f, op.xm[cols])
    p = ur[:, None] * e.real - ui[:, None] * e.imag  # Re(u e)
    # y only at the r + 1 bins of each end (the smoothing's mirror inside r of them, the plain form at bin r)
    need = np.concatenate([np.arange(r + 1), np.arange(cols.size - r - 1, cols.size)])
    s = np.empty((f.size, 2 * r + 2))
    s[:, :r] = p[:, : 2 * r + 1] @ left
    s[:, r] = h * p[:, r]
    s[:, r + 1] = h * p[:, -(r + 1)]
    s[:, -r:] = p[:, 2 * r + 1 :] @ right
    win = op.win[cols[need]]
    y = win * p[:, need] + (1 - win) * s - g[:, None] * y0[cols[need]]
    yl, yr = y[:, : r + 1], y[:, -(r + 1) :]  # y_0..y_r and y_{m-r-1}..y_{m-1}
    dl = np.concatenate([-yl[:, :1], yl[:, :-1] - yl[:, 1:]], axis=1)  # d_0..d_r
    dr = np.concatenate([yr[:, :-1] - yr[:, 1:], yr[:, -1:]], axis=1)  # d_{m-r}..d_m
    return (dl * dl) @ var_bins[: r + 1] + (dr * dr) @ var_bins[m - r :]


def _spectrum_sigma_direct(op: _Lsf, lsf, f, var_bins, corr):
    """:func:`spectrum_sigma` by the direct pass (the Fourier kernel in chunks)."""
    spec, sig = np.empty(f.size, dtype=complex), np.empty(f.size)
    m0 = None
    for sl, e in op.fourier_chunks(f):  # f[0] = 0 is in the first chunk
        spec[sl] = op.spectrum(lsf, f[sl], e)
        m0 = spec[0].real if m0 is None else m0
        sig[sl] = op.mtf_sigma(spec[sl] * np.sign(m0), f[sl], e, var_bins, corr[sl], m0=abs(m0))
    return spec, sig


def adaptive_mtf(x, esf, counts, sigma, f, noise_target):
    """MTF from the binned ESF with the noise-adaptive window.

    The window half-width ``W`` is the largest of ``W_max 0.85^k`` (down to the larger of 5 px and 2.5 rise
    distances) whose predicted noise of the MTF at Nyquist is below ``noise_target``.

    Returns
    -------
    (mtf, mtf_sigma, W, lsf at the bin midpoints, midpoints)
    """
    w = float(x[1] - x[0])
    var_bins = sigma**2 / np.maximum(counts, 1).astype(float)
    corr = np.sinc(f * w)
    nyq = np.array([0.0, 0.5])
    w_max = float(min(-x[0], x[-1]))
    w_min = min(max(_W_MIN_PX, _W_MIN_RISE * rise_width(x, esf)), w_max)
    # candidate half-widths w_max * 0.85^k down to w_min; the first meeting the target, found by bisection
    # (the predicted noise falls monotonically as the window shrinks) over the noise of all candidates at once
    ws = [w_max]
    while ws[-1] * 0.85 > w_min:
        ws.append(ws[-1] * 0.85)
    if ws[-1] > w_min:
        ws.append(w_min)
    ops = _Lsf(x, np.array(ws), w)
    lsfs = np.atleast_2d(ops.apply(esf))
    e_nyq = ops.fourier(nyq)
    specs = ops.spectrum(lsfs, nyq, e_nyq)
    noise = ops.mtf_sigma(specs, nyq, e_nyq, var_bins, np.sinc(nyq * w))[:, 1]

    def meets(k: int) -> bool:
        return bool(noise[k] <= noise_target)

    lo, hi = -1, len(ws) - 1
    if meets(0):
        hi = 0
    else:
        lo = 0
        while hi - lo > 1:
            mid = (lo + hi) // 2
            lo, hi = (lo, mid) if meets(mid) else (mid, hi)
    op, lsf = _row(ops, hi), lsfs[hi]
    half_w = ws[hi]
    spec, sig = spectrum_sigma(op, lsf, f, var_bins, corr)
    m0 = spec[0].real
    mtf = np.abs(spec) / abs(m0) / corr
    return mtf, sig, half_w, lsf / abs(m0), op.xm


def _row(ops: _Lsf, k: int) -> _Lsf:
    """The single-window map of row ``k`` of a batched :class:`_Lsf`."""
    op = object.__new__(_Lsf)
    op.w, op.xm, op.kernel = ops.w, ops.xm, ops.kernel
    y0 = getattr(ops, "_y0_cache", None)  # the batch's sensitivity rows (each row's own, computed alike)
    op._y0_cache = None if y0 is None or y0.ndim != 2 else y0[k]
    op.win = ops.win[k] if ops.win.ndim == 2 else ops.win
    return op


def window_mtf(x, esf, half_w: float, f) -> np.ndarray:
    """MTF at ``f`` of the binned ESF through the LSF map of :func:`adaptive_mtf` with a given half-width."""
    w = float(x[1] - x[0])
    op = _Lsf(x, half_w, w)
    spec = op.spectrum(op.apply(esf), np.concatenate([[0.0], np.asarray(f, dtype=float)]))
    return np.abs(spec[1:]) / abs(spec[0].real) / np.sinc(np.asarray(f) * w)


def rise_width(x: np.ndarray, esf: np.ndarray) -> float:
    """10-90 % rise distance (px) of the ESF, levels from its two outer quarters.

    The 10 % (90 %) level is read at the bin nearest it among the two around its crossing nearest the edge on
    the dark (bright) side, within 10 px (the region's end within 10 px where the ESF does not reach it there).
    The bin nearest the level anywhere in those 10 px (the same bin on a clean monotonic ESF) could be a plateau
    bin that noise brings near the level: an ideal edge seen by the pixel rises by 1 px in four 1/4-px bins,
    none within 0.07 of 10 %, so one dark bin 3 sigma up at SNR 50 read a rise of 10 px and the region was
    refused for having no plateau."""
    q = max(2, x.size // 4)
    lo, hi = median(esf[:q]), median(esf[-q:])
    e = (esf - lo) / (hi - lo) if hi != lo else esf * 0
    inside = np.abs(x) < 10
    xs, es = x[inside], e[inside]
    if xs.size < 2:
        return 1.0
    i0 = int(np.searchsorted(xs, 0.0))  # the bins x < 0 are the dark side
    dark = np.flatnonzero(es[:i0] <= 0.1)
    bright = np.flatnonzero(es[i0:] >= 0.9)
    j = int(dark[-1]) if dark.size else 0  # the last dark bin below 10 % ... or the one after it
    if dark.size and j + 1 < xs.size and abs(es[j + 1] - 0.1) < abs(es[j] - 0.1):
        j += 1
    m = i0 + int(bright[0]) if bright.size else xs.size - 1  # the first bright bin above 90 % or the one before
    if bright.size and m > 0 and abs(es[m - 1] - 0.9) <= abs(es[m] - 0.9):
        m -= 1
    return float(abs(xs[m] - xs[j]))


def trim_ends(x, esf, counts, frac: float = 0.3):
    """Keep the central run of bins holding >= ``frac`` x the typical count (the region's corners cut the
    outer bins to a few samples, whose noise would otherwise dominate the smoothed tails).  The counts are
    compared as means over 2 px: near a critical tilt the rows' phases bunch, so neighbouring bins alternate
    between many samples and few, which is not a corner (at 44.5 deg in a 60 px region it cut one side to
    nothing)."""
    step = median(np.diff(x)) if x.size > 1 else 1.0
    k = max(1, int(round(2.0 / step)))
    smooth = np.convolve(counts.astype(float), np.ones(k) / k, mode="same") if x.size > k else counts.astype(float)
    near = np.abs(x) < 5
    typical = median(smooth[near]) if np.any(near) else median(smooth)
    low = smooth < frac * typical
    i0 = int(np.argmin(np.abs(x)))
    left = np.nonzero(low[:i0])[0]
    right = np.nonzero(low[i0:])[0]
    a = int(left[-1]) + 1 if left.size else 0
    b = i0 + int(right[0]) if right.size else x.size
    return x[a:b], esf[a:b], counts[a:b]


def _line_fit(t: np.ndarray, y: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The least-squares straight line through ``(t, y)`` at ``at`` (``np.polyval(np.polyfit(t, y, 1), at)``
    to rounding: centred closed form, without the SVD)."""
    tm, ym = float(t.mean()), float(y.mean())
    dt = t - tm
    var = float(dt @ dt)
    slope = float(dt @ (y - ym)) / var if var > 0 else 0.0
    return ym + slope * (at - tm)


def flatten_rows(d, v, n_rows: int, x, esf, ok=None):
    """Remove illumination changes along the edge, line by line.

    Each line is regressed on the first-pass ESF, ``v = alpha_r + beta_r E(d)``; straight-line fits of
    ``alpha_r`` and ``beta_r`` over the lines map every line affinely onto the middle line's levels (a no-op
    on a uniformly lit edge, whatever its tails or the region's shape).  Only ``ok`` samples enter the fits.
    Returns (values, flags, the first-pass ESF at ``d``).
    """
    at = np.interp(d, x, esf)
    q = max(2, esf.size // 8)
    lo, hi = median(esf[:q]), median(esf[-q:])
    if not hi > lo:
        return v, [], at
    e = ((at - lo) / (hi - lo)).reshape(n_rows, -1)
    vv = v.reshape(n_rows, -1)
    if ok is None or ok.all():  # every sample in: the sums without the mask (x 1.0: the same values)
        n = np.full(n_rows, float(e.shape[1]))
        me, mv = e, vv
    else:
        m = ok.reshape(n_rows, -1).astype(float)
        n, me, mv = m.sum(axis=1), m * e, m * vv
    se, sv = me.sum(axis=1), mv.sum(axis=1)
    see, sev = (me * e).sum(axis=1), (me * vv).sum(axis=1)
    det = n * see - se * se
    ok = det > 1e-6 * np.maximum(n, 1) ** 2
    if np.count_nonzero(ok) < MIN_ROWS:
        return v, [], at
    beta = (n * sev - se * sv)[ok] / det[ok]
    alpha = (sv[ok] - beta * se[ok]) / n[ok]
    r = np.arange(n_rows, dtype=float)
    alpha_r, beta_r = _line_fit(r[ok], alpha, r), _line_fit(r[ok], beta, r)
    mid = n_rows // 2
    if np.any(beta_r <= 0.1 * beta_r[mid]):
        return v, [], at
    out = alpha_r[mid] + (vv - alpha_r[:, None]) * (beta_r[mid] / beta_r)[:, None]
    change = float(max(np.ptp(alpha_r), np.ptp(beta_r)) / beta_r[mid])
    flags = []
    if change > 0.02:
        flags.append(
            (
                "illumination_gradient",
                f"non-uniform illumination along the edge: levels change by {100 * change:.1f} % of the step "
                "over the lines (removed line by line)",
            )
        )
    return out.ravel(), flags, at
