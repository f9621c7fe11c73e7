"""The noise budget of a TDI pixel: shot, dark, read, quantisation and PRNU, CCD- or CMOS-style.

Part of :mod:`satchain.radiometry`, which re-exports every public name. References: G. C. Holst and
T. S. Lomheim, *CMOS/CCD Sensors and Camera Systems*, 2nd ed., SPIE 2011, ch. 6; R. D. Fiete, *Modeling the
Imaging Chain of Digital Cameras*, SPIE 2010, ch. 6.

Examples
--------
>>> noise_budget(400.0).total_e  # shot noise alone: sqrt(400)
20.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from satchain._validate import check_choice, check_positive, check_range
from satchain.errors import ConfigError, InputError

__all__ = ["NoiseBudget", "noise_budget"]


@dataclass(frozen=True)
class NoiseBudget:
    """Noise terms in electrons rms at one signal level, after TDI accumulation; ``total_e`` is their
    quadrature sum."""

    signal_e: float
    shot_e: float
    dark_e: float
    read_e: float
    quantisation_e: float
    prnu_e: float
    total_e: float

    @property
    def snr(self) -> float:
        return self.signal_e / self.total_e if self.total_e > 0 else math.inf

    def to_dict(self) -> dict[str, float]:
        return {
            "signal_e": self.signal_e,
            "shot_noise_e": self.shot_e,
            "dark_noise_e": self.dark_e,
            "read_noise_e": self.read_e,
            "quantisation_noise_e": self.quantisation_e,
            "prnu_noise_e": self.prnu_e,
            "total_noise_e": self.total_e,
            "snr": self.snr,
        }


def noise_budget(
    signal_e: float,
    *,
    stages: int = 1,
    integration_time_s: float = 0.0,
    read_noise_e: float = 0.0,
    dark_current_e_per_s: float = 0.0,
    readout: str = "ccd",
    full_well_e: float | None = None,
    bit_depth: int | None = None,
    prnu: float = 0.0,
) -> NoiseBudget:
    """Temporal noise of a TDI pixel whose accumulated signal is ``signal_e`` electrons.

    * shot: ``sqrt(signal)`` (Poisson);
    * dark: ``sqrt(i_dark t N)``, the shot noise of the dark charge over ``N`` stages;
    * read: ``sigma_read`` for ``readout="ccd"`` (charge summed in the charge domain, read once) or
      ``sqrt(N) sigma_read`` for ``"cmos"`` (digital TDI: every stage is read and the reads are summed;
      Holst & Lomheim 2011 sec. 6.7);
    * quantisation: ``q / sqrt(12)`` with ``q = full_well / 2^bits`` electrons per DN (the ADC range spans
      the full well), once for CCD, ``sqrt(N)`` times for CMOS digital TDI (every stage is digitised);
    * PRNU: ``prnu signal / sqrt(N)`` -- a gain spread between pixels, averaged over the ``N`` pixels a TDI
      column sums (0 unless given; it is fixed-pattern and removed by flat-fielding).

    The total is the quadrature sum (independent terms).

    Examples
    --------
    >>> nb = noise_budget(10000.0, stages=4, read_noise_e=30.0, readout="cmos")
    >>> nb.shot_e, nb.read_e, round(nb.total_e, 3)
    (100.0, 60.0, 116.619)
    """
    s = check_range("signal_e", signal_e, 0.0, None, error=InputError)
    n = int(check_range("detector.tdi_stages", stages, 1, None))
    t = check_range("integration_time_s", integration_time_s, 0.0, None)
    check_choice("detector.readout", readout, ("ccd", "cmos"))
    accum = math.sqrt(n) if readout == "cmos" else 1.0
    shot = math.sqrt(s)
    dark = math.sqrt(check_range("detector.dark_current_e_per_s", dark_current_e_per_s, 0.0, None) * t * n)
    read = check_range("detector.read_noise_e", read_noise_e, 0.0, None) * accum
    quant = 0.0
    if bit_depth is not None:
        if full_well_e is None:
            raise ConfigError(f"detector.bit_depth = {bit_depth!r} needs detector.full_well_e (e- per DN)")
        bits = int(check_range("detector.bit_depth", bit_depth, 1, 32))
        quant = check_positive("detector.full_well_e", full_well_e) / 2.0**bits / math.sqrt(12.0) * accum
    prnu_e = check_range("detector.prnu", prnu, 0.0, 1.0) * s / math.sqrt(n)
    total = math.sqrt(shot**2 + dark**2 + read**2 + quant**2 + prnu_e**2)
    return NoiseBudget(s, shot, dark, read, quant, prnu_e, total)
