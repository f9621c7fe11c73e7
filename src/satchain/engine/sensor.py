"""Detector signal chain after the optics: electrons, noise, full-well clipping and quantisation.

The optical simulation produces the footprint-averaged input quantity (reflectance, say) for every output
pixel; the sensor turns it into electrons by a linear radiometric gain, adds noise (shot, dark current,
read noise, optional PRNU/DSNU), clips at the full well and quantises to DN.

Noise is reproducible and independent of tiling and of the number of workers: it is drawn block by block
on a fixed grid of ``block_px`` x ``block_px`` output blocks, each from its own generator seeded by
``(seed, stream, block_row, block_col)``; the fixed-pattern noise (PRNU, DSNU) uses its own stream, so it
is the same pattern for every exposure with the same seed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from satchain._validate import check_choice, check_range
from satchain.errors import ConfigError

__all__ = ["OUTPUT_UNITS", "SensorModel", "block_generator", "sensor_from_system"]

OUTPUT_UNITS = ("dn", "electrons", "radiance", "reflectance")
_SHOT, _FIXED_PATTERN, _READ = 0, 1, 2


def block_generator(seed: int, stream: int, block_row: int, block_col: int) -> np.random.Generator:
    """The generator of one noise block: a pure function of (seed, stream, block row, block column)."""
    return np.random.default_rng([int(seed), int(stream), int(block_row), int(block_col)])


@dataclass(frozen=True)
class SensorModel:
    """Linear radiometric gain plus the detector noise budget (all per output pixel, TDI included).

    Parameters
    ----------
    electrons_per_unit : float
        Signal electrons per unit of the simulated input quantity (e.g. per unit reflectance).
    offset_e : float
        Signal electrons at input 0 (path radiance), added before noise.
    radiance_per_unit, radiance_offset : float
        TOA radiance (W m^-2 sr^-1, in band) per unit input and at input 0, for ``units="radiance"``.
    dark_e : float
        Mean dark electrons (dark current x integration time x stages).
    read_noise_e : float
        Total read noise, rms electrons (already accumulated over TDI stages).
    full_well_e : float
        Saturation level; electrons are clipped to it.
    bit_depth : int
        ADC bits; the ADC range spans the full well: ``full_well_e / 2**bit_depth`` electrons per DN (as
        :func:`satchain.radiometry.noise_budget` assumes for the quantisation noise).
    prnu : float
        Photo-response non-uniformity, rms fraction of the signal (fixed pattern).
    dsnu_e : float
        Dark-signal non-uniformity, rms electrons (fixed pattern).
    """

    electrons_per_unit: float = 1.0
    offset_e: float = 0.0
    radiance_per_unit: float = 1.0
    radiance_offset: float = 0.0
    dark_e: float = 0.0
    read_noise_e: float = 0.0
    full_well_e: float = math.inf
    bit_depth: int = 12
    prnu: float = 0.0
    dsnu_e: float = 0.0

    def __post_init__(self) -> None:
        check_range("electrons_per_unit", self.electrons_per_unit, 0, None, lo_open=True)
        for name in ("offset_e", "dark_e", "read_noise_e", "prnu", "dsnu_e"):
            check_range(name, getattr(self, name), 0, None)
        if not (self.full_well_e > 0):
            raise ConfigError(f"full_well_e = {self.full_well_e!r}: must be > 0")
        if not 1 <= int(self.bit_depth) <= 32:
            raise ConfigError(f"bit_depth = {self.bit_depth!r}: must be in [1, 32]")

    @property
    def gain_e_per_dn(self) -> float:
        if math.isinf(self.full_well_e):
            raise ConfigError("full_well_e = inf: DN output needs a finite full well")
        return self.full_well_e / 2 ** int(self.bit_depth)

    def full_scale(self, units: str = "dn", *, noise: bool = True) -> float | None:
        """The value at which :meth:`convert` clips, in ``units`` (the sensor's full scale): ``2**bit_depth - 1``
        DN, the full well in electrons, or the full well's reflectance/radiance (dark and offset removed).
        None where the output is never clipped: an infinite full well, or noise-free reflectance/radiance.

        Examples
        --------
        >>> s = SensorModel(electrons_per_unit=50000.0, offset_e=1000.0, full_well_e=41000.0, bit_depth=12)
        >>> s.full_scale("dn"), s.full_scale("electrons"), s.full_scale("reflectance")
        (4095.0, 41000.0, 0.8)
        """
        check_choice("units", units, OUTPUT_UNITS)
        if units == "dn":
            return float(2 ** int(self.bit_depth) - 1)
        if math.isinf(self.full_well_e) or (not noise and units != "electrons"):
            return None
        if units == "electrons":
            return float(self.full_well_e)
        unit = (self.full_well_e - self.dark_e - self.offset_e) / self.electrons_per_unit
        return unit if units == "reflectance" else self.radiance_offset + self.radiance_per_unit * unit

    def convert(
        self,
        values: np.ndarray,
        *,
        origin: tuple[int, int],
        units: str = "dn",
        noise: bool = True,
        seed: int = 0,
        block_px: int = 64,
    ) -> np.ndarray:
        """Turn the optical output of one tile into ``units``; ``origin`` is the tile's (row, col) in the
        output image and must lie on the noise-block grid."""
        check_choice("units", units, OUTPUT_UNITS)
        if origin[0] % block_px or origin[1] % block_px:
            raise ConfigError(f"origin = {origin!r}: must be a multiple of block_px = {block_px}")
        if not noise and units == "reflectance":
            return values
        if not noise and units == "radiance":
            return self.radiance_offset + self.radiance_per_unit * values
        e = self.offset_e + self.electrons_per_unit * values
        if noise:
            e = self._noisy(e, origin=origin, seed=seed, block_px=block_px)
        else:
            e = e + self.dark_e
        e = np.minimum(e, self.full_well_e)
        if units == "electrons":
            return e
        if units == "dn":
            return np.clip(np.floor(e / self.gain_e_per_dn), 0, 2 ** int(self.bit_depth) - 1)
        # back to the input quantity, noise included, dark level removed
        unit = (e - self.dark_e - self.offset_e) / self.electrons_per_unit
        return unit if units == "reflectance" else self.radiance_offset + self.radiance_per_unit * unit

    def _noisy(self, e: np.ndarray, *, origin, seed: int, block_px: int) -> np.ndarray:
        out = np.empty_like(e, dtype=np.float64)
        h, w = e.shape
        for r in range(0, h, block_px):
            for c in range(0, w, block_px):
                br, bc = (origin[0] + r) // block_px, (origin[1] + c) // block_px
                sig = np.clip(e[r : r + block_px, c : c + block_px], 0, None)
                bh, bw = sig.shape
                fpn = block_generator(seed, _FIXED_PATTERN, br, bc)
                gain = 1.0 + self.prnu * fpn.standard_normal((block_px, block_px))[:bh, :bw]
                dark = self.dark_e + self.dsnu_e * fpn.standard_normal((block_px, block_px))[:bh, :bw]
                mean = np.clip(sig * gain + dark, 0, None)
                # inverse-CDF Poisson from one uniform per pixel: a pixel's draw depends only on its own mean
                # and its place in the block, never on its neighbours' values or the image extent
                u = block_generator(seed, _SHOT, br, bc).random((block_px, block_px))[:bh, :bw]
                pois = _poisson_ppf(u, mean)
                read = (
                    self.read_noise_e
                    * block_generator(seed, _READ, br, bc).standard_normal((block_px, block_px))[:bh, :bw]
                )
                out[r : r + bh, c : c + bw] = pois + read
        return out


#: Above this mean the Poisson quantile is taken from its Cornish-Fisher expansion (CDF error ~1e-4 at 200
#: electrons and falling as mean^-3/2); below it scipy's exact inverse CDF is used.
_POISSON_EXACT_BELOW = 200.0


def _poisson_ppf(u: np.ndarray, mean: np.ndarray) -> np.ndarray:
    """Poisson variates from uniforms ``u`` by the quantile function, one uniform per pixel (so a pixel's draw
    depends only on its own mean and uniform).

    Examples
    --------
    >>> u = np.random.default_rng(0).random(200_000)
    >>> x = _poisson_ppf(u, np.full(u.shape, 1000.0))
    >>> round(float(x.mean()), -0), round(float(x.var()), -1)
    (1000.0, 1000.0)
    """
    from scipy.special import ndtri

    mean = np.broadcast_to(mean, u.shape)
    z = ndtri(np.clip(u, 1e-300, 1 - 1e-16))
    sq = np.sqrt(mean)
    # Cornish-Fisher: quantile of Poisson(m) ~ m + sqrt(m) z + (z^2 - 1)/6 + (z^3 - 7 z)/(72 sqrt(m)) (cont. corr.)
    cf = np.floor(mean + sq * z + (z * z - 1.0) / 6.0 + (z**3 - 7.0 * z) / (72.0 * np.maximum(sq, 1e-12)) + 0.5)
    out = np.maximum(cf, 0.0)
    low = mean < _POISSON_EXACT_BELOW
    if np.any(low):
        out = out.copy() if not out.flags.writeable else out
        out[low] = _poisson_ppf_exact(u[low], mean[low])
    return np.where(mean > 0, out, 0.0)


def _poisson_ppf_exact(q: np.ndarray, mean: np.ndarray) -> np.ndarray:
    """``scipy.stats.poisson.ppf(q, mean)`` for ``0 < q < 1`` and ``mean >= 0``, by the same special functions
    (the smallest k with CDF(k) >= q), without importing :mod:`scipy.stats` (about 1 s of start-up)."""
    from scipy import special

    with np.errstate(invalid="ignore"):
        k = np.ceil(special.pdtrik(q, mean))
        below = np.maximum(k - 1, 0)
        return np.where(special.pdtr(below, mean) >= q, below, k)


def sensor_from_system(system) -> SensorModel:
    """The SensorModel of an ImagingSystem, from its radiometric budget (:mod:`satchain.radiometry`).

    The signal is linear in surface reflectance, ``N(rho) = rho N_1 + N_path`` electrons (all TDI stages);
    dark electrons are ``dark_current x integration time x stages``; read noise accumulates once for CCD-style
    (charge-domain) TDI and ``sqrt(stages)`` times for CMOS-style (digital) TDI. A detector without a stated
    ``full_well_e`` saturates at the signal of reflectance 1 (plus dark), so its ADC range spans reflectance 0..1.

    Examples
    --------
    >>> from satchain import load_preset
    >>> from satchain.radiometry import signal_electrons
    >>> s = load_preset("ankarasat3")
    >>> m = sensor_from_system(s)
    >>> bool(np.isclose(m.offset_e + 0.2 * m.electrons_per_unit, signal_electrons(s, 0.2)))
    True
    """
    from satchain import radiometry

    det = system.detector
    n0, n1 = (float(v) for v in np.asarray(radiometry.signal_electrons(system, [0.0, 1.0])))
    l0, l1 = (radiometry.radiometric_budget(system, reflectance=r).radiance_toa_band_w_per_m2_sr for r in (0.0, 1.0))
    stages = det.tdi_stages
    read = det.read_noise_e * (math.sqrt(stages) if det.readout == "cmos" else 1.0)
    return SensorModel(
        electrons_per_unit=n1 - n0,
        offset_e=n0,
        radiance_per_unit=l1 - l0,
        radiance_offset=l0,
        dark_e=det.dark_current_e_per_s * system.integration_time_s * stages,
        read_noise_e=read,
        # no stated full well (a system without radiometric detail): the ADC range spans reflectance 0..1
        full_well_e=n1 + det.dark_current_e_per_s * system.integration_time_s * stages
        if det.full_well_e is None
        else det.full_well_e,
        bit_depth=det.bit_depth or 12,
        prnu=det.prnu,
        dsnu_e=det.dsnu_e,
    )
