"""Measured vs predicted: the one place where measurement meets prediction, as a pure function.

:func:`compare` takes the measurements (:func:`satchain.measure.auto.measure_auto`'s result, plus the SNR of
:func:`satchain.measure.snr.measure_snr`), the predictions (:func:`satchain.prediction.core.predict`) and the
tolerances, and returns a :class:`Comparison`: one :class:`CheckRow` per check, and the per-target detail
the report plots. No I/O, no system object. The checks, one registry entry per target kind (:data:`CHECKS`),
each in its own module:

* slanted edge (:mod:`.edge`) -- MTF at Nyquist (0.5 cy/px along the edge normal, the e-SFR's axis):
  ``|measured - predicted| <= edge_mtf_at_nyquist``; and the edge angle: ``|measured - truth| <= edge_angle_deg``;
* Siemens star (:mod:`.star`) -- the largest ``measured - predicted`` MTF (signed) over the sector directions
  (ACT, ALT, diagonals) and 0.05..0.5 cy/px, the prediction being the same measurement on the star's
  noise-free predicted image (:mod:`satchain.prediction.star`), the system MTF beside it:
  ``|error| <= star_mtf``;
* bar target (:mod:`.bars`) -- the largest ``|measured - Coltman|`` CTF along the bars' modulation axis, for
  groups with at least 2.5 px per period (:data:`BAR_COMPARE_MAX_CY_PER_PX`): ``<= bar_ctf``;
* hyperbolic wedge (:mod:`.wedge`) -- resolvable line width: ``|measured / predicted - 1| <=
  wedge_resolution_rel``, the prediction being the same 15 % crossing measured on the wedge's noise-free
  predicted image;
* NIIRS (:mod:`.niirs`) -- GIQE 5 from the measured edge RERs and image SNR vs the predicted GIQE 5: ``<= niirs``.

Every limit is inclusive. A check whose measurement is missing (the target could not be measured -- it is
in the measurement's ``skipped`` list -- or nothing lies in the compared range) is **n/a** (``passed =
None``, with ``reason``), never a failure.

Every row carries ``sigma``, the 1-sigma of its ``error``, or ``sigma_null_means`` saying why not. The
prediction is exact for the simulated system model, so sigma is the measurement's: the edge's
``mtf_at_nyquist_sigma`` and the angle's from its per-line position noise; the star's, that of the largest of
its compared errors from their measured 1-sigma (:func:`~satchain.comparison.star.max_error_sigma`); the bars'
``ctf_std`` at the group of the largest error; the NIIRS's RER (bounded from each edge's MTF 1-sigma) and SNR
(its measured ``snr_sigma``; :data:`SNR_REL_SIGMA` of it only when it has none, and the row's ``note`` says
so) sigmas through GIQE 5 (the formulas in :mod:`satchain.comparison.sigma`).
``z = error / sigma``; a row whose tolerance is below :data:`NOISE_SIGMAS` sigma and whose ``|z|`` is below
:data:`REAL_DIFFERENCE_Z` is ``tolerance_inside_noise`` (it can fail on noise alone; a larger ``|z|`` is a real
difference). For bars the error is a maximum over many points, so its z is biased high (a
maximum of noise); the star's sigma is that of its maximum.
"""

from __future__ import annotations

from satchain.comparison._common import PREDICTION_SIGMA_NOTE
from satchain.comparison.bars import BAR_COMPARE_MAX_CY_PER_PX
from satchain.comparison.core import CHECKS, TargetChecks, compare
from satchain.comparison.records import (
    NOISE_SIGMAS,
    REAL_DIFFERENCE_Z,
    BarCheck,
    CheckRow,
    Comparison,
    EdgeCheck,
    NiirsCheck,
    StarCheck,
    WedgeCheck,
    row_texts,
    signed_text,
)
from satchain.comparison.sigma import SNR_REL_SIGMA, edge_angle_sigma_deg
from satchain.comparison.star import STAR_F_MIN_CY_PER_PX, max_error_sigma

__all__ = [
    "BAR_COMPARE_MAX_CY_PER_PX",
    "CHECKS",
    "NOISE_SIGMAS",
    "PREDICTION_SIGMA_NOTE",
    "REAL_DIFFERENCE_Z",
    "SNR_REL_SIGMA",
    "STAR_F_MIN_CY_PER_PX",
    "BarCheck",
    "CheckRow",
    "Comparison",
    "EdgeCheck",
    "NiirsCheck",
    "StarCheck",
    "TargetChecks",
    "WedgeCheck",
    "compare",
    "edge_angle_sigma_deg",
    "max_error_sigma",
    "row_texts",
    "signed_text",
]
