"""The diffraction OTF and PSF of a sampled pupil by FFT: central obscuration, spider vanes, Zernike wavefront.

:class:`PupilOTF` / :func:`pupil_otf` compute the autocorrelation of the sampled pupil function by FFT, i.e.
the Fourier transform of the PSF of the reference paper's eq. 1, ``PSF = |FT{p}|^2 / ((lambda f)^2 * integral
p)``; :func:`pupil_psf` samples that PSF. The pupil is sampled by exact area coverage (annulus minus vanes) and
carries ``exp(+2 pi i W)`` with ``W`` in waves (:mod:`satchain.tf.zernike`) and is transformed with the kernel
``exp(-2 pi i u.x / (lambda f))``: a positive Noll Z2 (Z3) moves the PSF by ``4 c lambda F#`` towards +x (+y).
Zemax OpticStudio and GalSim use the kernel of the other sign (``W -> -W``: the PSF rotated by 180 degrees), which
:class:`satchain.config.system.Optics` accepts as ``zernike_sign = "zemax"``. Accuracy and memory knobs travel
in :class:`PupilParams`. Part of :mod:`satchain.tf.optics`, which re-exports every public name.

Examples
--------
>>> otf = pupil_otf([0.0, 100.0], 0.0, wavelength_m=500e-9, f_number=10.0, aperture_diameter_m=0.1)
>>> np.round(otf.real, 3).tolist()  # the clear circular pupil at v = 0 and 0.5
[1.0, 0.391]
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from satchain._validate import as_float_array, check_positive, check_range
from satchain.errors import ConfigError, InputError, ResourceLimitError
from satchain.tf.annular import _oneill, optical_cutoff_cy_per_mm
from satchain.tf.zernike import noll_to_nm, zernike_noll

__all__ = ["PupilOTF", "PupilPSF", "PupilParams", "pupil_otf", "pupil_psf"]


@dataclass(frozen=True)
class PupilParams:
    """Accuracy and resource knobs of the pupil-FFT OTF and PSF (passed explicitly, as GalSim's GSParams).

    Parameters
    ----------
    samples_across_pupil : int
        Pupil samples across the aperture diameter, ``N``. The OTF is computed on a lag grid of spacing
        ``cutoff / N``. For a clear or obscured pupil the FFT OTF differs from the closed form by at most
        about ``0.1 / (N (1 - eps))`` (largest at the first lag): 2e-4 (eps = 0) to 4e-4 (eps = 0.5) with
        the default 512, whose FFT takes about 0.1 s; ``eps`` above 0.8 needs a larger N for 1e-3.
    max_fft_bytes : int
        Work whose FFT arrays would need more memory is refused with ResourceLimitError.
    """

    samples_across_pupil: int = 512
    max_fft_bytes: int = 2 * 1024**3

    def __post_init__(self) -> None:
        n = self.samples_across_pupil
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 16 <= n <= 65536:
            raise ConfigError(f"PupilParams.samples_across_pupil = {n!r}: must be an integer in [16, 65536]")
        check_positive("PupilParams.max_fft_bytes", self.max_fft_bytes)


# ----------------------------------------------------------------------------------------- pupil sampling
def _halfplane_coverage(d, nx, ny):
    """Exact fraction of a unit pixel lying in the half-plane ``{n . (x - centre) < d}`` (unit normal n).

    The projection of a uniform unit square on ``n`` is the convolution of two boxes of widths ``|nx|``
    and ``|ny|``; its CDF at ``d`` is the piecewise-quadratic expression below. Exact for straight edges,
    and within ``~1 / (12 R)`` pixel area per edge pixel for a circle of radius R pixels.
    """
    a = np.maximum(np.abs(nx), 1e-6)
    b = np.maximum(np.abs(ny), 1e-6)
    p, q = (a + b) / 2.0, (a - b) / 2.0

    def r2(z):
        return np.square(np.maximum(z, 0.0)) / 2.0

    return np.clip((r2(d + p) - r2(d + q) - r2(d - q) + r2(d - p)) / (a * b), 0.0, 1.0)


def _pupil_transmission(n: int, eps: float, spiders, dx_m: float):
    """Area-coverage transmission of the annulus minus spider vanes on an ``n x n`` grid [y, x].

    Pixel centres sit at ``(i - (n - 1) / 2)`` pixels, so the aperture of diameter ``n`` pixels fills the grid
    exactly. Also returns normalised pupil radius ``rho`` and angle ``theta`` at the pixel centres.
    """
    c = np.arange(n) - (n - 1) / 2.0
    y, x = c[:, None], c[None, :]
    r = np.hypot(x, y)
    rs = np.where(r > 0, r, 1.0)
    nx, ny = x / rs, y / rs
    radius = n / 2.0
    t = _halfplane_coverage(radius - r, nx, ny)
    if eps > 0:
        t = t - _halfplane_coverage(eps * radius - r, nx, ny)
    if spiders is not None and spiders.count > 0:
        w = spiders.width_m / dx_m
        for k in range(spiders.count):
            ang = math.radians(spiders.angle_deg + 360.0 * k / spiders.count)
            ex, ey = math.cos(ang), math.sin(ang)
            along, across = ex * x + ey * y, -ey * x + ex * y
            strip = _halfplane_coverage(w / 2 - across, -ey, ex) - _halfplane_coverage(-w / 2 - across, -ey, ex)
            t = t * (1.0 - strip * _halfplane_coverage(along, ex, ey))
    return np.clip(t, 0.0, 1.0), r / radius, np.arctan2(y, x)


def _pupil_function(n: int, *, eps: float, spiders, zernikes: Mapping[int, float], dx_m: float):
    """Sampled pupil ``T exp(2 pi i W)`` (real when there is no wavefront)."""
    t, rho, theta = _pupil_transmission(n, eps, spiders, dx_m)
    terms = [(j, c) for j, c in zernikes.items() if c != 0]
    if not terms:
        return t
    w = sum(c * zernike_noll(j, rho, theta) for j, c in terms)
    return t * np.exp(2j * np.pi * w)


def _check_fft_memory(m: int, params: PupilParams, what: str) -> None:
    need = 6 * 16 * m * m  # a few complex m x m work arrays
    if need > params.max_fft_bytes:
        raise ResourceLimitError(
            f"{what}: an FFT grid of {m} x {m} needs about {need / 1024**3:.2f} GiB, more than "
            f"PupilParams.max_fft_bytes = {params.max_fft_bytes / 1024**3:.2f} GiB; lower "
            f"PupilParams.samples_across_pupil (= {params.samples_across_pupil}) or raise the limit"
        )


def _check_pupil(wavelength_m, f_number, aperture_diameter_m, obscuration_ratio, spiders, zernikes):
    lam = check_positive("wavelength_m", wavelength_m)
    fno = check_positive("f_number", f_number)
    d = check_positive("aperture_diameter_m", aperture_diameter_m)
    eps = check_range("obscuration_ratio", obscuration_ratio, 0.0, 1.0, hi_open=True)
    if spiders is not None and spiders.count > 0 and spiders.width_m >= d:
        raise ConfigError(f"spiders.width_m = {spiders.width_m!r}: must be < aperture_diameter_m ({d!r})")
    z = {}
    for j, c in dict(zernikes or {}).items():
        noll_to_nm(j)
        z[int(j)] = check_range(f"zernike_rms_waves[{j}]", c)
    return lam, fno, d, eps, z


def _broadcast_freqs(fx_cy_per_mm, fy_cy_per_mm):
    fx = as_float_array("fx_cy_per_mm", fx_cy_per_mm)
    fy = as_float_array("fy_cy_per_mm", fy_cy_per_mm)
    try:
        return np.broadcast_arrays(fx, fy)
    except ValueError:
        raise InputError(
            f"fx_cy_per_mm (shape {fx.shape}) and fy_cy_per_mm (shape {fy.shape}): must broadcast together"
        ) from None


class PupilOTF:
    """Diffraction OTF of a sampled pupil, precomputed on a grid once and callable at any (fx, fy).

    The OTF is the normalised autocorrelation of the pupil function ``p``, computed as the FFT of
    ``|FT{p}|^2`` -- the Fourier transform of the PSF of the reference paper's eq. 1 (Goodman,
    *Introduction to Fourier Optics*: the incoherent OTF is the normalised pupil autocorrelation). With
    ``N`` samples across the aperture the OTF is known on a lag grid of spacing ``cutoff / N``. Between
    lags it is interpolated with the closed form as a control variate: the grid stores
    ``OTF - annular_mtf`` (small and smooth: the annulus's cusp at f = 0 and its behaviour at the cutoff
    cancel), interpolated bilinearly in real and imaginary parts, and the exact :func:`annular_mtf` of the
    same obscuration is added back. It is exactly 0 at and beyond the cutoff.

    Parameters
    ----------
    wavelength_m, f_number, aperture_diameter_m : float
        Wavelength, working F-number and aperture diameter (m); ``focal_length = F# * D``.
    obscuration_ratio : float
        Central obscuration diameter ratio in [0, 1).
    spiders : satchain.config.system.Spiders, optional
        ``count`` radial vanes of ``width_m`` from the centre outwards, equally spaced by ``360 / count``
        degrees, the first at ``angle_deg`` from +x (ACT).
    zernike_rms_waves : mapping of int to float, optional
        Wavefront as Noll index -> rms coefficient in waves at ``wavelength_m`` (4 = defocus).
    params : PupilParams

    Examples
    --------
    >>> otf = PupilOTF(wavelength_m=500e-9, f_number=10.0, aperture_diameter_m=0.1,
    ...                params=PupilParams(samples_across_pupil=128))
    >>> round(abs(complex(otf(0.0, 0.0))), 6), round(abs(complex(otf(250.0, 0.0))), 6)
    (1.0, 0.0)
    """

    __slots__ = (
        "_delta",
        "_n",
        "cutoff_cy_per_mm",
        "is_real",
        "lag_step_cy_per_mm",
        "obscuration_ratio",
        "wavelength_m",
    )

    def __init__(
        self,
        *,
        wavelength_m: float,
        f_number: float,
        aperture_diameter_m: float,
        obscuration_ratio: float = 0.0,
        spiders=None,
        zernike_rms_waves: Mapping[int, float] | None = None,
        params: PupilParams = PupilParams(),  # noqa: B008 (frozen, immutable)
    ) -> None:
        lam, fno, d, eps, z = _check_pupil(
            wavelength_m, f_number, aperture_diameter_m, obscuration_ratio, spiders, zernike_rms_waves
        )
        n = params.samples_across_pupil
        m = 2 * n  # autocorrelation support is 2N - 1 lags: no wrap-around
        _check_fft_memory(m, params, "PupilOTF")
        p = _pupil_function(n, eps=eps, spiders=spiders, zernikes=z, dx_m=d / n)
        delta = _autocorrelation(p, m)  # [lag_y, lag_x], lags -n .. n (index n is lag 0)
        delta -= _oneill(self._lag_radius(n), eps)
        delta.flags.writeable = False
        self._delta, self._n = delta, n
        self.is_real = not np.iscomplexobj(p)
        self.wavelength_m, self.obscuration_ratio = lam, eps
        self.cutoff_cy_per_mm = optical_cutoff_cy_per_mm(lam, fno)
        self.lag_step_cy_per_mm = self.cutoff_cy_per_mm / n

    @staticmethod
    def _lag_radius(n: int) -> np.ndarray:
        k = np.arange(-n, n + 1) / n
        return np.hypot(k[:, None], k[None, :])

    @property
    def grid(self) -> np.ndarray:
        """The FFT OTF at its lags ``[ky, kx]``, ``f = (k - N) * lag_step_cy_per_mm`` (a new array)."""
        return self._delta + _oneill(self._lag_radius(self._n), self.obscuration_ratio)

    def __call__(self, fx_cy_per_mm, fy_cy_per_mm) -> np.ndarray:
        """Complex OTF at focal-plane frequencies (cy/mm), broadcast shape of the inputs."""
        fx, fy = _broadcast_freqs(fx_cy_per_mm, fy_cy_per_mm)
        fr = np.hypot(fx, fy)
        inside = fr < self.cutoff_cy_per_mm
        out = np.zeros(fx.shape, dtype=np.complex128)
        ix = fx[inside] / self.lag_step_cy_per_mm + self._n
        iy = fy[inside] / self.lag_step_cy_per_mm + self._n
        out[inside] = _bilinear(self._delta, iy, ix) + _oneill(
            fr[inside] / self.cutoff_cy_per_mm, self.obscuration_ratio
        )
        return out


def _autocorrelation(p: np.ndarray, m: int) -> np.ndarray:
    """Autocorrelation ``sum_u p(u) conj(p(u + k)) / sum |p|`` for lags ``-n..n`` [y, x], lag 0 set to 1.

    Dividing by the aperture area ``sum |p|`` (not by ``sum |p|^2``) makes the lags k != 0 of area-coverage
    samples match the continuous autocorrelation to O(1/N^2) away from f = 0: in 1-D the discrete sum is
    exact at every nonzero integer lag, only the lag-0 value ``sum t^2`` falls short of the area.
    """
    from scipy.fft import fft2, irfft2, rfft2  # (here: importing scipy.fft costs 0.2 s, most callers never need it)

    n = p.shape[0]
    area = np.sum(np.abs(p))
    if np.iscomplexobj(p):
        g = fft2(p, s=(m, m))
        acf = fft2(np.abs(g) ** 2) / (m * m * area)  # forward FFT of the PSF = conj(ifft)
    else:
        g = rfft2(p, s=(m, m))
        acf = irfft2(np.abs(g) ** 2, s=(m, m)) / area
    acf[0, 0] = 1.0
    acf = np.fft.fftshift(acf)  # lag 0 at index m // 2 = n
    out = np.zeros((2 * n + 1, 2 * n + 1), dtype=acf.dtype)
    out[1:-1, 1:-1] = acf[1:, 1:]  # lags -n and n (= cutoff) stay 0
    return out


def _bilinear(grid: np.ndarray, iy: np.ndarray, ix: np.ndarray) -> np.ndarray:
    """Bilinear interpolation of ``grid`` at fractional indices (inside the grid)."""
    last = grid.shape[0] - 2
    y0 = np.clip(np.floor(iy).astype(np.intp), 0, last)
    x0 = np.clip(np.floor(ix).astype(np.intp), 0, last)
    ty, tx = iy - y0, ix - x0
    top = grid[y0, x0] * (1 - tx) + grid[y0, x0 + 1] * tx
    bot = grid[y0 + 1, x0] * (1 - tx) + grid[y0 + 1, x0 + 1] * tx
    return top * (1 - ty) + bot * ty


def pupil_otf(
    fx_cy_per_mm,
    fy_cy_per_mm,
    *,
    wavelength_m: float,
    f_number: float,
    aperture_diameter_m: float,
    obscuration_ratio: float = 0.0,
    spiders=None,
    zernike_rms_waves: Mapping[int, float] | None = None,
    params: PupilParams = PupilParams(),  # noqa: B008
) -> np.ndarray:
    """Complex diffraction OTF from the pupil function by FFT, at focal-plane frequencies (cy/mm).

    A one-shot :class:`PupilOTF`; build that object instead to evaluate many frequency grids.

    Examples
    --------
    >>> otf = pupil_otf([0.0, 100.0], 0.0, wavelength_m=500e-9, f_number=10.0, aperture_diameter_m=0.1)
    >>> from satchain.tf.annular import annular_mtf
    >>> ref = annular_mtf([0.0, 100.0], wavelength_m=500e-9, f_number=10.0)
    >>> bool(np.allclose(otf, ref, atol=1e-3))
    True
    """
    otf = PupilOTF(
        wavelength_m=wavelength_m,
        f_number=f_number,
        aperture_diameter_m=aperture_diameter_m,
        obscuration_ratio=obscuration_ratio,
        spiders=spiders,
        zernike_rms_waves=zernike_rms_waves,
        params=params,
    )
    return otf(fx_cy_per_mm, fy_cy_per_mm)


@dataclass(frozen=True)
class PupilPSF:
    """A focal-plane PSF sampled on a square grid ``[y, x]`` with the centre (x = y = 0) at ``[c, c]``.

    ``psf_per_m2 * spacing_m**2`` sums to slightly less than 1 (0.990 for a clear pupil with N = 64 samples
    across, 0.995 for N = 128): the energy beyond the field is missing and area-averaged pupil samples taper
    the PSF towards the field edge.
    """

    psf_per_m2: np.ndarray
    spacing_m: float
    centre_index: int

    @property
    def x_m(self) -> np.ndarray:
        """Sample positions along either axis (m)."""
        return (np.arange(self.psf_per_m2.shape[0]) - self.centre_index) * self.spacing_m


def pupil_psf(
    *,
    wavelength_m: float,
    f_number: float,
    aperture_diameter_m: float,
    obscuration_ratio: float = 0.0,
    spiders=None,
    zernike_rms_waves: Mapping[int, float] | None = None,
    samples_per_lambda_f_number: int = 2,
    params: PupilParams = PupilParams(),  # noqa: B008
) -> PupilPSF:
    """PSF of the reference paper's eq. 1, ``|FT{p}|^2 / ((lambda f)^2 int p)``, sampled by FFT (1/m^2).

    ``int p`` is the aperture area (of ``|p|`` when there is a wavefront), so an unaberrated PSF peaks at
    ``area / (lambda f)^2`` and integrates to 1 over the whole plane. The sample spacing is
    ``lambda F# / samples_per_lambda_f_number``; the field is ``N lambda F#`` wide
    (N = ``params.samples_across_pupil``) and periodic; area-averaged pupil samples taper the PSF towards
    the field edge (by the squared sinc of one pupil sample) instead of aliasing the far wings back.

    Examples
    --------
    >>> psf = pupil_psf(wavelength_m=500e-9, f_number=10.0, aperture_diameter_m=0.1,
    ...                 params=PupilParams(samples_across_pupil=64))
    >>> c, peak_per_m2 = psf.centre_index, np.pi / (4 * (500e-9 * 10.0) ** 2)  # area / (lambda f)^2
    >>> round(psf.spacing_m * 1e6, 3), round(float(psf.psf_per_m2[c, c] / peak_per_m2), 3)
    (2.5, 1.0)
    """
    lam, fno, d, eps, z = _check_pupil(
        wavelength_m, f_number, aperture_diameter_m, obscuration_ratio, spiders, zernike_rms_waves
    )
    from scipy.fft import fft2, next_fast_len

    q = samples_per_lambda_f_number
    if isinstance(q, bool) or not isinstance(q, (int, np.integer)) or not 1 <= q <= 64:
        raise ConfigError(f"samples_per_lambda_f_number = {q!r}: must be an integer in [1, 64]")
    n = params.samples_across_pupil
    m = next_fast_len(q * n)
    _check_fft_memory(m, params, "pupil_psf")
    dx = d / n
    p = _pupil_function(n, eps=eps, spiders=spiders, zernikes=z, dx_m=dx)
    g = np.fft.fftshift(fft2(p, s=(m, m)))
    focal = fno * d
    spacing = lam * focal / (m * dx)
    psf = np.abs(g) ** 2 * dx**4 / ((lam * focal) ** 2 * np.sum(np.abs(p)) * dx**2)
    return PupilPSF(psf_per_m2=psf, spacing_m=spacing, centre_index=m // 2)
