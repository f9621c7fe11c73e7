"""The NIIRS check: GIQE 5 from the measured edge RERs and image SNR vs the predicted GIQE 5."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from satchain.comparison._common import finite, within
from satchain.comparison.records import CheckRow, EdgeCheck, NiirsCheck
from satchain.comparison.sigma import SNR_REL_SIGMA, niirs_sigma, rer_sigma_bound
from satchain.prediction.core import Predictions

__all__ = ["niirs_check"]


def _mean_rer(edges: tuple[EdgeCheck, ...], direction: str) -> float | None:
    v = [e.rer_measured for e in edges if e.direction == direction and e.rer_measured is not None]
    return float(np.mean(v)) if v else None


def _mean_rer_sigma(edges: tuple[EdgeCheck, ...], direction: str) -> float | None:
    """1-sigma of the mean RER of the edges along ``direction`` (independent noise per edge)."""
    sig = [rer_sigma_bound(e.f_cy_per_px, e.mtf_sigma) for e in edges if e.direction == direction and e.rer_measured]
    known = [v for v in sig if v is not None]
    if not sig or len(known) < len(sig):
        return None
    return float(np.sqrt(np.sum(np.square(known))) / len(known))


def _niirs_sigma(r_act: float, r_alt: float, snr_m: float, snr_sigma: float | None, edges: tuple[EdgeCheck, ...],
                 gsd_in: float, elevation_deg: float) -> tuple[float | None, str | None]:  # fmt: skip
    s_act, s_alt = _mean_rer_sigma(edges, "ACT"), _mean_rer_sigma(edges, "ALT")
    if s_act is None or s_alt is None:
        return None, "an edge gave no MTF sigma, so the RER has none"
    sig = niirs_sigma(r_act, r_alt, snr_m, rer_act_sigma=s_act, rer_alt_sigma=s_alt, gsd_in=gsd_in,
                      elevation_deg=elevation_deg, snr_sigma=snr_sigma)  # fmt: skip
    return sig, None


def _snr_sigma(snr: Mapping[str, Any]) -> tuple[float | None, str | None]:
    """The measured SNR's own 1-sigma, or None and the row's note saying the fallback was used."""
    s = finite(snr.get("snr_sigma"))
    if s is not None and s >= 0:
        return s, None
    why = snr.get("snr_sigma_null_means") or "the SNR measurement reports none"
    return None, f"sigma takes the SNR's 1-sigma as an assumed {SNR_REL_SIGMA:.0%} of it, not measured ({why})"


def niirs_check(
    edges: tuple[EdgeCheck, ...], snr: Mapping[str, Any], pred: Predictions, tol: Any
) -> tuple[NiirsCheck, CheckRow]:
    """GIQE 5 from the measured edges' mean RER per axis and the image SNR vs the predicted GIQE 5; sigma
    the RER and SNR sigmas through GIQE 5 (the SNR's its measured ``snr_sigma``; without one, an assumed
    :data:`~satchain.comparison.sigma.SNR_REL_SIGMA` of it, and the row's ``note`` says so)."""
    from satchain import units
    from satchain.prediction.quality import giqe5, giqe5_rer

    r_act, r_alt = _mean_rer(edges, "ACT"), _mean_rer(edges, "ALT")
    snr_m = finite(snr.get("snr"))
    rer_m = giqe5_rer(r_act, r_alt) if r_act and r_alt else None
    snr_sig, note = _snr_sigma(snr)
    niirs_m, why = None, None
    sig: tuple[float | None, str | None] = (None, "no error (the check is n/a)")
    if rer_m is None:
        why = "needs a measured RER from both an ACT and an ALT edge"
    elif snr_m is None or snr_m <= 0:
        why = "no SNR measured on the image: " + str(snr.get("reason") or "missing")
    else:
        gsd_in = float(units.m_to_inches(pred.gsd_los_m))
        niirs_m = giqe5(gsd_in=gsd_in, rer=rer_m, snr=snr_m, elevation_deg=pred.elevation_deg)
        assert r_act is not None and r_alt is not None  # rer_m is made of both
        sig = _niirs_sigma(r_act, r_alt, snr_m, snr_sig, edges, gsd_in, pred.elevation_deg)
    pr = finite(pred.giqe5)
    err = None if niirs_m is None or pr is None else niirs_m - pr
    detail = {
        "giqe5_predicted": pr,
        "giqe5_measured": niirs_m,
        "rer_predicted": finite(pred.rer),
        "rer_measured": rer_m,
        "snr_predicted": finite(pred.snr),
        "snr_measured": snr_m,
        "snr_measured_sigma": snr_sig if snr_m is not None else None,
        "pass": within(err, tol.niirs),
        "reason": why,
        "giqe5_measured_sigma": sig[0] if err is not None else None,
    }
    sig = sig if err is not None else (None, "no error (the check is n/a)")
    row = CheckRow(
        "NIIRS (GIQE 5)",
        "niirs",
        None,
        niirs_m,
        pr,
        err,
        tol.niirs,
        f"±{tol.niirs}",
        within(err, tol.niirs),
        why,
        *sig,
        note=note if err is not None and sig[0] is not None else None,
    )
    return NiirsCheck.from_dict(detail), row
