"""Square-wave (bar target) response <-> MTF.

Two definitions of the *contrast transfer function* (CTF) live here, both labelled, never mixed:

* **Coltman's CTF** (:func:`coltman_ctf`, inverse :func:`mtf_from_ctf`): the modulation, at the bar
  centres, of the image of an *ideal* (infinite-series) 0/1 square wave of frequency ``f``,

  ``CTF(f) = (4/pi) * sum_{k>=0} (-1)^k M((2k+1) f) / (2k+1)``

  (J. W. Coltman, "The specification of imaging properties by response to a sine wave input",
  JOSA 44, 468 (1954); G. D. Boreman, *Modulation Transfer Function in Optical and
  Electro-Optical Systems*, SPIE 2001, bar-target section). It is the physical response of a bar
  target: it tends to 1 at low frequency and to ``(4/pi) M(f) ~ 1.273 M(f)`` above a third of the
  cutoff, where only the fundamental passes.

* **The reference paper's Fourier-synthesis CTF** (:func:`ctf_fourier_synthesis`): a square wave
  represented by a *truncated* Fourier series (10 odd harmonics by default), each coefficient
  multiplied by the MTF, and "the degraded square wave modulation divided by the input square wave
  modulation" (paper, Figure 3(b) and Table 1). The truncated input overshoots (Gibbs), so the
  division rescales the result by about ``1/1.179``: ``~0.85`` at low frequency (where Coltman
  gives ~0.98) and ``~1.08 M(f)`` near the cutoff. The paper's remark that "CTF and MTF get almost
  the same value at low transfer values" is this artefact, not a property of bar targets.

Frequencies are unit-agnostic: pass ``f`` and the MTF's argument in the same unit (cy/mm, cy/px, ...).
An MTF is any vectorised callable ``mtf(f) -> array``; if it has an attribute ``cutoff`` it is
taken as exactly zero beyond it (see :func:`band_limited` and :func:`tabulated_mtf`), which makes
both Coltman series finite sums.

Examples
--------
>>> tri = band_limited(lambda f: 1.0 - f, cutoff=1.0)  # a triangular MTF with cutoff 1
>>> round(float(coltman_ctf(0.5, tri)), 6)  # only the fundamental passes: (4/pi) * 0.5
0.63662
>>> ctf = band_limited(lambda g: coltman_ctf(g, tri), cutoff=1.0)
>>> round(float(mtf_from_ctf(0.2, ctf)), 12)  # Coltman's inverse series gives M back
0.8
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from satchain._validate import as_float_array, check_positive, check_range
from satchain.errors import ConfigError, InputError

__all__ = [
    "BandLimited",
    "TabulatedMTF",
    "band_limited",
    "coltman_ctf",
    "ctf_fourier_synthesis",
    "mtf_from_ctf",
    "square_wave_series",
    "tabulated_mtf",
    "wedge_resolution_m",
]

# Largest number of (frequency, harmonic) pairs evaluated at once; bounds memory, not results.
_MAX_BLOCK = 1 << 22
_FIRST_CHUNK = 64


# --------------------------------------------------------------------------------------------------
# Callables with a cutoff
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class BandLimited:
    """A transfer function ``func`` forced to zero above ``cutoff`` (see :func:`band_limited`)."""

    func: Callable
    cutoff: float

    def __call__(self, f):
        f = np.asarray(f, dtype=np.float64)
        out = np.zeros(f.shape)
        inside = f <= self.cutoff
        if np.any(inside):
            out[inside] = np.asarray(self.func(f[inside]), dtype=np.float64)
        return out


@dataclass(frozen=True, eq=False)
class TabulatedMTF:
    """Piecewise-linear MTF through ``(f_grid, mtf_values)``, zero beyond the last grid point.

    Build it with :func:`tabulated_mtf`, which validates the table.
    """

    f_grid: np.ndarray = field(repr=False)
    mtf_values: np.ndarray = field(repr=False)

    @property
    def cutoff(self) -> float:
        """The last grid frequency: the MTF is zero above it."""
        return float(self.f_grid[-1])

    def __call__(self, f):
        f = np.asarray(f, dtype=np.float64)
        return np.interp(f, self.f_grid, self.mtf_values, right=0.0)


def band_limited(func: Callable, cutoff: float) -> BandLimited:
    """Wrap ``func`` so that it is zero above ``cutoff`` and advertises ``cutoff``.

    ``func`` is only called on frequencies ``<= cutoff`` (so closed forms undefined beyond their
    cutoff, such as ``acos(f / f_c)``, are safe). The Coltman series of a band-limited MTF are finite
    sums, evaluated exactly by :func:`coltman_ctf` and :func:`mtf_from_ctf`.

    Parameters
    ----------
    func : callable
        Vectorised ``func(f) -> array``.
    cutoff : float
        Frequency (same unit as ``f``) above which the result is zero; finite and > 0.

    Examples
    --------
    >>> m = band_limited(lambda f: 1.0 - f, cutoff=1.0)
    >>> m([0.25, 1.0, 2.0]).tolist()
    [0.75, 0.0, 0.0]
    """
    if not callable(func):
        raise ConfigError(f"func = {func!r}: must be callable")
    return BandLimited(func, check_positive("cutoff", cutoff))


def tabulated_mtf(f_grid, mtf_values) -> TabulatedMTF:
    """A callable MTF interpolating a table linearly, zero beyond the last grid frequency.

    If the first grid frequency is above zero, the point ``(0, 1)`` is prepended (an MTF is
    normalised to 1 at zero frequency), so frequencies below the table interpolate towards 1.
    A table that starts at ``f = 0`` is used as given.

    Parameters
    ----------
    f_grid : array_like, 1-D
        Strictly increasing, finite, non-negative frequencies (any unit, used consistently).
    mtf_values : array_like, 1-D
        MTF at ``f_grid``: finite and ``>= 0``, same length.

    Returns
    -------
    TabulatedMTF
        Callable ``mtf(f)``, with attribute ``cutoff`` = the last grid frequency.

    Examples
    --------
    >>> m = tabulated_mtf([10.0, 20.0], [0.5, 0.0])
    >>> m([0.0, 5.0, 15.0, 30.0]).tolist()
    [1.0, 0.75, 0.25, 0.0]
    >>> m.cutoff
    20.0
    """
    f_grid = as_float_array("f_grid", f_grid, ndim=1)
    values = as_float_array("mtf_values", mtf_values, ndim=1)
    if f_grid.size < 1:
        raise InputError("f_grid: must hold at least one frequency")
    if values.shape != f_grid.shape:
        raise InputError(f"mtf_values: shape {values.shape} must match f_grid's shape {f_grid.shape}")
    if f_grid[0] < 0:
        raise InputError(f"f_grid[0] = {f_grid[0]!r}: frequencies must be >= 0")
    if np.any(np.diff(f_grid) <= 0):
        raise InputError("f_grid: must be strictly increasing")
    if np.any(values < 0):
        raise InputError(f"mtf_values: min = {values.min()!r}; must be >= 0")
    if f_grid[0] > 0:
        f_grid = np.concatenate(([0.0], f_grid))
        values = np.concatenate(([1.0], values))
    f_grid.setflags(write=False)
    values.setflags(write=False)
    return TabulatedMTF(f_grid, values)


# --------------------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------------------


def _check_int(name: str, value, lo: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < lo:
        raise ConfigError(f"{name} = {value!r}: must be an integer >= {lo}")
    return int(value)


def _check_frequencies(f) -> np.ndarray:
    f = as_float_array("f", f)
    if f.size and np.min(f) < 0:
        raise InputError(f"f: min = {float(np.min(f))!r}; frequencies must be >= 0")
    return f


def _cutoff_of(tf, name: str) -> float | None:
    """The callable's ``cutoff`` attribute, validated; ``None`` when absent or infinite."""
    if not callable(tf):
        raise ConfigError(f"{name} = {tf!r}: must be a callable {name}(f) -> array")
    cutoff = getattr(tf, "cutoff", None)
    if cutoff is None or (isinstance(cutoff, numbers.Real) and math.isinf(cutoff) and float(cutoff) > 0):
        return None
    return check_positive(f"{name}.cutoff", cutoff)


def _evaluate(tf, g: np.ndarray, cutoff: float | None, name: str) -> np.ndarray:
    """``tf(g)`` as a float array of g's shape, zero above ``cutoff``; refuses complex/NaN output."""
    out = np.zeros(g.shape)
    inside = np.ones(g.shape, dtype=bool) if cutoff is None else g <= cutoff
    if not np.any(inside):
        return out
    vals = np.asarray(tf(g[inside]))
    if np.iscomplexobj(vals):
        raise InputError(f"{name}: returned complex values; pass a real transfer function (e.g. |OTF|)")
    n = int(np.count_nonzero(inside))
    if vals.shape not in ((), (n,)):
        raise InputError(f"{name}: returned shape {vals.shape} for {n} frequencies; must be vectorised")
    vals = np.broadcast_to(vals.astype(np.float64, copy=False), (n,))
    if not np.all(np.isfinite(vals)):
        n_bad = int(np.count_nonzero(~np.isfinite(vals)))
        raise InputError(f"{name}: returned NaN/inf at {n_bad} of {n} frequencies")
    out[inside] = vals
    return out


def _coltman_signs(j: np.ndarray) -> np.ndarray:
    """``(-1)^k`` for ``j = 2k + 1``."""
    return np.where(((j - 1) // 2) % 2 == 0, 1.0, -1.0)


def _inverse_coefficients(j: np.ndarray) -> np.ndarray:
    """``B_j = mu(j) * (-1)^((j-1)/2)`` for odd ``j`` (mu: Moebius function).

    ``B_j = (-1)^m (-1)^((j-1)/2)`` when ``j`` is a product of ``m`` distinct primes, 0 when ``j``
    has a square factor (Coltman 1954). These are the Dirichlet inverse of the Coltman signs, which
    makes :func:`mtf_from_ctf` the exact inverse of :func:`coltman_ctf`.
    """
    n = int(j.max())
    mu = np.ones(n + 1, dtype=np.int8)
    is_prime = np.ones(n + 1, dtype=bool)
    is_prime[:2] = False
    for p in range(2, math.isqrt(n) + 1):
        if is_prime[p]:
            is_prime[p * p :: p] = False
    for q in np.flatnonzero(is_prime[3:]) + 3:  # j is odd: the prime 2 never divides it
        mu[q::q] *= -1
        mu[q * q :: q * q] = 0
    return mu[j].astype(np.float64) * _coltman_signs(j)


def _odd_series(f, tf, coefficients, *, name: str, rtol: float, max_terms: int) -> np.ndarray:
    """``sum_{j odd} coefficients(j) * tf(j f) / j`` for each ``f > 0`` (1-D array).

    With a cutoff the sum runs over every ``j f <= cutoff`` (exact); without one, it runs in chunks
    until a whole chunk has ``|tf(j f)| / j <= rtol``.
    """
    cutoff = _cutoff_of(tf, name)
    if cutoff is not None:
        n_needed = np.where(f <= cutoff, np.floor((cutoff / f - 1.0) / 2.0) + 1.0, 0.0)
        if f.size and n_needed.max() > max_terms:
            i = int(np.argmax(n_needed))
            raise ConfigError(
                f"max_terms = {max_terms}: f = {f[i]:g} needs {int(n_needed[i])} terms below "
                f"{name}.cutoff = {cutoff:g}; raise max_terms (or drop such low frequencies)"
            )
    total = np.zeros(f.shape)
    active = np.arange(f.size)
    k0, chunk = 0, _FIRST_CHUNK
    while active.size:
        if k0 >= max_terms:
            raise ConfigError(
                f"max_terms = {max_terms}: the series for {name} did not reach rtol = {rtol:g} at "
                f"{active.size} frequencies (min f = {f[active].min():g}); raise max_terms or rtol, "
                f"or give {name} a cutoff (satchain.tf.ctf.band_limited)"
            )
        k1 = min(k0 + chunk, max_terms)
        j = 2 * np.arange(k0, k1) + 1
        fa = f[active]
        vals = _evaluate(tf, fa[:, None] * j[None, :], cutoff, name) / j
        total[active] += vals @ coefficients(j)
        if cutoff is not None:
            done = (2 * k1 + 1) * fa > cutoff
        else:
            done = np.all(np.abs(vals) <= rtol, axis=1)
        active = active[~done]
        k0 = k1
        chunk = max(_FIRST_CHUNK, min(2 * chunk, _MAX_BLOCK // max(active.size, 1)))
    return total


def _series_transform(f, tf, coefficients, scale, *, name, rtol, max_terms):
    f = _check_frequencies(f)
    rtol = check_range("rtol", rtol, 0.0, 1.0, lo_open=True)
    max_terms = _check_int("max_terms", max_terms, 1)
    _cutoff_of(tf, name)
    flat = f.ravel()
    out = np.empty(flat.shape)
    zero = flat == 0
    if np.any(zero):  # the series' limit f -> 0 is tf(0) (for a tf continuous at 0)
        out[zero] = _evaluate(tf, np.zeros(1), None, name)[0]
    pos = ~zero
    out[pos] = scale * _odd_series(flat[pos], tf, coefficients, name=name, rtol=rtol, max_terms=max_terms)
    out = out.reshape(f.shape)
    return out[()] if out.ndim == 0 else out


# --------------------------------------------------------------------------------------------------
# Coltman's series, both ways
# --------------------------------------------------------------------------------------------------


def coltman_ctf(f, mtf, *, rtol: float = 1e-12, max_terms: int = 100_000):
    """Coltman's square-wave response (CTF) from the MTF.

    ``CTF(f) = (4/pi) * sum_{k>=0} (-1)^k M((2k+1) f) / (2k+1)``  (Coltman 1954, JOSA 44, 468;
    Boreman 2001): the modulation at the bar centres of the image of an ideal 0/1 square
    wave (50 % duty) of frequency ``f``. This is the physical bar-target response, unlike
    :func:`ctf_fourier_synthesis` (the paper's method, see there).

    Parameters
    ----------
    f : array_like
        Square-wave frequencies (``>= 0``), in the unit ``mtf`` takes.
    mtf : callable
        Vectorised ``mtf(f) -> array`` (real; a signed OTF is allowed). If it has an attribute
        ``cutoff``, it is taken as zero above it and the series is summed exactly over every
        harmonic ``(2k+1) f <= cutoff``. Otherwise harmonics are added in chunks (64, 128, ...)
        until a whole chunk has ``|M((2k+1) f)| / (2k+1) <= rtol``: such an MTF must decay.
    rtol : float, optional
        Term tolerance, relative to the unit zero-frequency response; only used without a cutoff.
    max_terms : int, optional
        Most harmonics per frequency; exceeding it raises :class:`~satchain.errors.ConfigError`.

    Returns
    -------
    ndarray or float
        CTF at ``f``, same shape. At ``f = 0`` it is the series' limit ``M(0)`` (1 for a normalised MTF).

    Examples
    --------
    >>> perfect = band_limited(lambda f: np.ones_like(f), cutoff=1e4)
    >>> round(float(coltman_ctf(1.0, perfect)), 4)  # (4/pi)(1 - 1/3 + ... - 1/9999) = 1 - 6e-5
    0.9999
    >>> gauss = lambda f: np.exp(-(f**2))
    >>> round(float(coltman_ctf(1.0, gauss)), 6)  # (4/pi)(e^-1 - e^-9 / 3 + ...)
    0.468346
    """
    return _series_transform(f, mtf, _coltman_signs, 4.0 / math.pi, name="mtf", rtol=rtol, max_terms=max_terms)


def mtf_from_ctf(f, ctf, *, rtol: float = 1e-12, max_terms: int = 100_000):
    """MTF from Coltman's square-wave response by Coltman's inverse series.

    ``M(f) = (pi/4) * sum_{k odd} B_k C(k f) / k`` with ``B_k = (-1)^m (-1)^((k-1)/2)`` when ``k`` is a
    product of ``m`` distinct primes and ``B_k = 0`` when ``k`` has a square factor:
    ``M = (pi/4)[C(f) + C(3f)/3 - C(5f)/5 + C(7f)/7 + C(11f)/11 - C(13f)/13 - C(15f)/15 + ...]``
    (Coltman 1954; Boreman 2001). ``B_k = mu(k) chi(k)`` (Moebius function times the
    character mod 4), the Dirichlet inverse of the forward signs, so the round trip with
    :func:`coltman_ctf` is exact up to rounding when both series are finite.

    The series needs ``C`` at every odd multiple of ``f``: give ``ctf`` a ``cutoff`` (the MTF's
    cutoff: above it the square-wave response is zero too), e.g. with :func:`band_limited` or
    :func:`tabulated_mtf`. Without one, terms are added until a chunk is below ``rtol`` (see
    :func:`coltman_ctf`). This inverse applies to Coltman's CTF only, not to
    :func:`ctf_fourier_synthesis`.

    Parameters
    ----------
    f : array_like
        Frequencies (``>= 0``), in the unit ``ctf`` takes.
    ctf : callable
        Vectorised ``ctf(f) -> array``, optionally with attribute ``cutoff``.
    rtol, max_terms
        As in :func:`coltman_ctf`.

    Returns
    -------
    ndarray or float
        MTF at ``f``, same shape; ``C(0)`` at ``f = 0``.

    Examples
    --------
    >>> mtf = band_limited(lambda f: 1.0 - f, cutoff=1.0)
    >>> ctf = band_limited(lambda g: coltman_ctf(g, mtf), cutoff=1.0)
    >>> np.round(mtf_from_ctf([0.1, 0.3, 0.7], ctf), 12).tolist()
    [0.9, 0.7, 0.3]
    """
    return _series_transform(f, ctf, _inverse_coefficients, math.pi / 4.0, name="ctf", rtol=rtol, max_terms=max_terms)


# --------------------------------------------------------------------------------------------------
# The reference paper's Fourier-synthesis method
# --------------------------------------------------------------------------------------------------


def _sine_sum(phase_cycles: np.ndarray, coef: np.ndarray, j: np.ndarray) -> np.ndarray:
    """``sum_i coef[..., i] * sin(2 pi j_i t)`` for t in ``phase_cycles`` (1-D), blockwise."""
    out = np.empty(coef.shape[:-1] + phase_cycles.shape)
    step = max(1, _MAX_BLOCK // max(j.size, 1))
    for s in range(0, phase_cycles.size, step):
        t = phase_cycles[s : s + step]
        out[..., s : s + step] = coef @ np.sin(2.0 * np.pi * np.outer(j, t))
    return out


def square_wave_series(x, period: float, *, n_harmonics: int = 10, mtf=None, f_unit_scale: float = 1.0):
    """Truncated Fourier series of a 0/1 square wave, optionally degraded by an MTF.

    ``s(x) = 0.5 + (2/pi) * sum_{k<n} M_k sin(2 pi (2k+1) x / period) / (2k+1)``, with ``M_k = 1``
    (input) or ``M_k = mtf((2k+1) / period * f_unit_scale)`` (degraded). The bar (value 1) spans
    ``0 < x < period/2`` of each period. This is what the reference paper's Figure 3(b) plots (16 m
    ground period, black: input, blue: degraded).

    Parameters
    ----------
    x : array_like
        Positions, in the unit of ``period`` (e.g. ground metres).
    period : float
        Square-wave period (one bar + one gap), > 0.
    n_harmonics : int, optional
        Number of odd harmonics kept (1, 3, 5, ...), >= 1.
    mtf : callable, optional
        Vectorised ``mtf(f) -> array``; ``None`` gives the undegraded input series. Zero above its
        ``cutoff`` attribute, if any.
    f_unit_scale : float, optional
        Multiplies the harmonic frequencies ``(2k+1)/period`` before calling ``mtf``, so that ``x``
        can be in ground metres while the MTF takes focal-plane cy/mm: then ``f_unit_scale`` is the
        focal frequency of 1 cy/m on the ground, ``satchain.units.ground_to_focal_cy_per_mm(1.0, ...)``.

    Returns
    -------
    ndarray
        The series at ``x``, same shape.

    Examples
    --------
    >>> s = square_wave_series([0.25, 0.75], 1.0, n_harmonics=1)  # 0.5 +/- 2/pi
    >>> np.round(s, 6).tolist()
    [1.13662, -0.13662]
    """
    x = as_float_array("x", x)
    period = check_positive("period", period)
    n = _check_int("n_harmonics", n_harmonics, 1)
    scale = check_positive("f_unit_scale", f_unit_scale)
    j = 2 * np.arange(n) + 1
    coef = (2.0 / np.pi) / j
    if mtf is not None:
        coef = coef * _evaluate(mtf, j / period * scale, _cutoff_of(mtf, "mtf"), "mtf")
    t = np.mod(x.ravel() / period, 1.0)
    return (0.5 + _sine_sum(t, coef, j)).reshape(x.shape)


def _modulation(series: np.ndarray) -> np.ndarray:
    hi, lo = series.max(axis=-1), series.min(axis=-1)
    return (hi - lo) / (hi + lo)


def ctf_fourier_synthesis(f, mtf, *, n_harmonics: int = 10, samples_per_period: int = 2048):
    """The reference paper's CTF: degraded truncated square-wave modulation / input modulation.

    A 0/1 square wave of frequency ``f`` is represented by its Fourier series truncated to
    ``n_harmonics`` odd harmonics, ``0.5 + (2/pi) sum sin(2 pi (2k+1) f x) / (2k+1)``; each
    coefficient is multiplied by ``M((2k+1) f)``; the result is the modulation
    ``(max - min) / (max + min)`` of the degraded series divided by that of the input series, both
    sampled at ``samples_per_period`` points over one period (paper, Figure 3(b) and Table 1). With
    the default 10 harmonics this reproduces the paper's Table 1 CTF column from its MTF column.

    **Why it differs from Coltman's CTF** (:func:`coltman_ctf`). The truncated input series is not a
    square wave: it overshoots at every edge (Gibbs phenomenon), so its modulation is not 1 but
    ``~1.18`` (-> ``(2/pi) Si(pi) = 1.178979...`` as ``n_harmonics`` grows; 1.1798 for 10
    harmonics sampled at 2048 points). Dividing by it rescales everything by ``~1/1.18``:

    * near the cutoff, where only the fundamental passes, Coltman gives ``CTF = (4/pi) M ~ 1.273 M``
      (the true square-wave response at the bar centres) while this method gives
      ``(4/pi) M / 1.179 ~ 1.08 M``;
    * at low frequency, once the blurred series has lost its overshoot (its upper harmonics, up to
      ``(2 n_harmonics - 1) f``, attenuated) while the input keeps it, the method gives about
      Coltman's CTF / 1.18: ~0.85 where Coltman gives ~0.98 on the paper's system at 2 cy/mm. Only
      as ``f -> 0``, where every kept harmonic passes unattenuated, does it return to 1.

    The paper's observation that CTF ~ MTF at low transfer values is this truncation artefact.
    satchain reports both, labelled: use :func:`coltman_ctf` for a physical bar-target prediction
    and this function to reproduce the paper.

    Parameters
    ----------
    f : array_like
        Square-wave frequencies (``>= 0``), in the unit ``mtf`` takes.
    mtf : callable
        Vectorised ``mtf(f) -> array``; zero above its ``cutoff`` attribute, if any.
    n_harmonics : int, optional
        Odd harmonics kept, >= 1. The default 10 reproduces Table 1 (to 0.0015 with the paper's MTF);
        more harmonics move the low-frequency values by up to 0.01.
    samples_per_period : int, optional
        Samples over one period used for max/min; must resolve the highest harmonic
        (``> 2 (2 n_harmonics - 1)``).

    Returns
    -------
    ndarray or float
        The paper's CTF at ``f``, same shape.

    Examples
    --------
    >>> m = band_limited(lambda f: 1.0 - f, cutoff=1.0)
    >>> round(float(ctf_fourier_synthesis(0.5, m)), 4)  # (4/pi)(0.5) / 1.1798
    0.5396
    >>> round(float(coltman_ctf(0.5, m)), 4)
    0.6366
    """
    f = _check_frequencies(f)
    n = _check_int("n_harmonics", n_harmonics, 1)
    n_samples = _check_int("samples_per_period", samples_per_period, 2 * (2 * n - 1) + 1)
    cutoff = _cutoff_of(mtf, "mtf")
    j = 2 * np.arange(n) + 1
    coef = (2.0 / np.pi) / j
    t = np.arange(n_samples) / n_samples
    input_modulation = _modulation(0.5 + _sine_sum(t, coef, j))
    flat = f.ravel()
    out = np.empty(flat.shape)
    step = max(1, _MAX_BLOCK // (n_samples + n))
    for s in range(0, flat.size, step):
        m = _evaluate(mtf, flat[s : s + step, None] * j[None, :], cutoff, "mtf")
        out[s : s + step] = _modulation(0.5 + _sine_sum(t, m * coef, j)) / input_modulation
    out = out.reshape(f.shape)
    return out[()] if out.ndim == 0 else out


# --------------------------------------------------------------------------------------------------
# Resolution of a hyperbolic wedge (prediction)
# --------------------------------------------------------------------------------------------------


def wedge_resolution_m(mtf, *, gsd_m: float, threshold: float, sampling_limit_m: float | None = None) -> float:
    """Predicted resolvable line width (ground m) of stripes across which ``mtf`` (cy/px) acts.

    The width ``w`` at which Coltman's CTF at ``f = gsd_m / (2 w)`` cy/px falls to ``threshold``, but never finer
    than ``sampling_limit_m`` (default ``gsd_m``): a line pair narrower than two samples aliases (the paper's
    detector-limited argument: resolution = GSD when Q < 2; along a diagonal of a square grid pass
    ``gsd_m / sqrt(2)``, whose Nyquist frequency is ``sqrt(2) / (2 GSD)``). NaN when even ``20 gsd_m`` wide
    stripes stay below the threshold.

    Examples
    --------
    >>> tri = band_limited(lambda f: 1.0 - f, cutoff=1.0)  # (4/pi)(1 - f) = 0.15 at f = 0.882 cy/px
    >>> round(wedge_resolution_m(tri, gsd_m=1.0, threshold=0.15, sampling_limit_m=0.1), 4)
    0.5668
    """
    from scipy.optimize import brentq

    gsd_m = check_positive("gsd_m", gsd_m)
    threshold = check_range("threshold", threshold, 0.0, 1.0)
    limit = gsd_m if sampling_limit_m is None else check_positive("sampling_limit_m", sampling_limit_m)

    def ctf_minus(w_m: float) -> float:  # ground line width -> cycles per pixel across the stripes
        return float(coltman_ctf(np.atleast_1d(gsd_m / (2.0 * w_m)), mtf)[0]) - threshold

    lo, hi = 0.05 * gsd_m, 20.0 * gsd_m
    if ctf_minus(hi) < 0:
        return float("nan")
    w = lo if ctf_minus(lo) > 0 else float(brentq(ctf_minus, lo, hi, xtol=1e-9 * gsd_m))
    return max(w, limit)
