"""Tables of the HTML report in words and units: key figures, the measured-vs-predicted summary, camera
inputs, derived quantities, radiometry, the paper's results beside satchain's, and the not-measured list
grouped by reason. Everything is read defensively (``.get``) from ``results.json`` and the budget, so keys
added later (a format version, an overall pass flag, ``"n/a"`` statuses, ``*_sigma`` fields) are tolerated.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from typing import Any

import numpy as np

from satchain.report.kinds import BARS, EDGES, STARS, WEDGES, measured_entries

__all__ = [
    "PAPER",
    "PAPER_CITATION",
    "camera_rows",
    "derived_rows",
    "failed_checks",
    "fmt",
    "key_figures",
    "measurement_flags",
    "paper_rows",
    "radiometry_rows",
    "sigma_text",
    "skipped_groups",
    "summary_rows",
    "verdict",
]

PAPER_CITATION = (
    "“Spatial resolution and modulation transfer function analyses for satellite imaging” "
    "(AnkaraSat-3 image-chain study; text in shared/reference/paper.txt)"
)
#: The paper's own results that satchain reproduces (values as printed in the paper).
PAPER = {"mtf_at_nyquist_alt": 0.1228, "wedge_resolution_m": 0.525, "gsd_m": 0.49}
_DIR_WORDS = {"ACT": "across-track", "ALT": "along-track", "D45": "diagonal 45°", "D135": "diagonal 135°"}


def fmt(v, digits: int = 3, *, unit: str = "", signed: bool = False) -> str:
    """A number with fixed decimals (no exponent for ordinary magnitudes), or an en dash when missing. A
    nonzero value that would round to zero gets the decimals of its first significant digit, so a signed
    error keeps its sign ("-0.004", never "+0.000" or "-0.000")."""
    if v is None or isinstance(v, str):
        return "–" if v is None else v
    try:
        x = float(v)
    except (TypeError, ValueError):
        return str(v)
    if not math.isfinite(x):
        return "–"
    if x == 0:
        x, signed = 0.0, False  # no "-0.00", no "+0.00"
    elif round(x, digits) == 0:  # keep the sign and one significant digit: -0.0039 -> "-0.004", not "+0.00"
        digits = max(digits, -math.floor(math.log10(abs(x))))
    s = f"{x:+.{digits}f}" if signed else f"{x:.{digits}f}"
    return f"{s} {unit}".rstrip()


def _status(p) -> str:
    """'pass', 'fail' or 'n/a' from a pass field (True/False/None/'n/a')."""
    if p is True:
        return "pass"
    if p is False:
        return "fail"
    return "n/a"


def _num(v) -> float | None:
    """A finite float, or None for anything else (None, NaN, "n/a", ...)."""
    if isinstance(v, bool):
        return None
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def _diff(m, p) -> float | None:
    m, p = _num(m), _num(p)
    return None if m is None or p is None else m - p


def _mean(vals) -> float | None:
    v = [x for x in (_num(x) for x in vals) if x is not None]
    return float(np.mean(v)) if v else None


def verdict(res: dict) -> dict[str, Any]:
    """Overall result: results' own ``passed`` when present, else all compared checks passed."""
    st = [_status(r.get("pass")) for r in res.get("summary", [])]
    n_pass, n_fail = st.count("pass"), st.count("fail")
    passed = res.get("passed")
    if not isinstance(passed, bool):
        passed = n_fail == 0 and n_pass > 0
    return {"passed": passed, "n_pass": n_pass, "n_fail": n_fail, "n_na": st.count("n/a"), "n": len(st)}


def key_figures(res: dict, budget: dict) -> list[dict]:
    """GSD, MTF at Nyquist (ACT/ALT, predicted and measured), SNR and NIIRS, as label/predicted/measured."""
    edges = res.get(EDGES.key, [])
    mtf_n = res.get("mtf_at_nyquist") or {}
    niirs = res.get("niirs") or {}
    rad = res.get("radiometry") or {}

    def edge_mean(d):
        return _edge_mean_text(edges, d)

    return [
        {"label": "GSD", "predicted": fmt(res.get("gsd_m"), 3, unit="m"), "measured": "(geometry)"},
        {
            "label": "MTF at Nyquist, across-track",
            "predicted": fmt(mtf_n.get("act")),
            "measured": edge_mean("ACT"),
        },
        {"label": "MTF at Nyquist, along-track", "predicted": fmt(mtf_n.get("alt")), "measured": edge_mean("ALT")},
        {"label": "scene SNR (albedo 0.2)", "predicted": fmt(rad.get("snr"), 1), "measured": "–"},
        {
            "label": "contrast SNR (GIQE)",
            "predicted": fmt(niirs.get("snr_predicted"), 1),
            "measured": fmt(niirs.get("snr_measured"), 1)
            + (f" ± {fmt(niirs['snr_measured_sigma'], 2)}" if niirs.get("snr_measured_sigma") is not None else ""),
        },
        {
            "label": "NIIRS (GIQE 5)",
            "predicted": fmt(niirs.get("giqe5_predicted"), 2),
            "measured": fmt(niirs.get("giqe5_measured"), 2),
        },
    ]


def _edge_mean_text(edges: list, direction: str) -> str:
    """The measured MTF at Nyquist along ``direction``: one edge's value with its id, or the mean of several
    labelled as such, each edge's value beside it."""
    vals = [(e.get("id"), _num(e.get("mtf_at_nyquist_measured"))) for e in edges if e.get("direction") == direction]
    vals = [(i, v) for i, v in vals if v is not None]
    if not vals:
        return "–"
    if len(vals) == 1:
        return f"{fmt(vals[0][1])} (edge {vals[0][0]})"
    each = ", ".join(f"{i} {fmt(v)}" for i, v in vals)
    return f"{fmt(float(np.mean([v for _, v in vals])))} (mean of {len(vals)} edges: {each})"


def failed_checks(res: dict) -> list[dict]:
    """The failed checks, for the page's first screen: the row's figure, its z (and z against the camera as built
    when the run has one) and the section that shows it."""
    out = []
    for s in res.get("summary", []):
        if s.get("pass") is not False:
            continue
        z, zb = _num(s.get("z")), _num(s.get("z_as_built"))
        detail = [f"z {fmt(z, 1, signed=True)}"] if z is not None else []
        if zb is not None:
            detail.append(f"z as built {fmt(zb, 1, signed=True)}")
        out.append({"figure": str(s.get("figure")), "detail": ", ".join(detail),
                    "anchor": _ANCHORS.get(str(s.get("kind")), "summary")})  # fmt: skip
    return out


def _row(quantity, target, meas, pred, diff, tol, p, digits=3, unit="", signed=True):
    return {
        "quantity": quantity,
        "target": target,
        "measured": fmt(meas, digits, unit=unit),
        "predicted": fmt(pred, digits, unit=unit),
        "difference": fmt(diff, digits, unit=unit, signed=signed),
        "tolerance": tol,
        "status": _status(p),
        "sigma": "–",
        "z": "–",
        "noise": False,
        "sigma_note": "",
        "note": "",
        "anchor": "",
        "n_flags": 0,
        "ab_predicted": "–",
        "ab_difference": "–",
        "ab_z": "–",
        "ab_status": "n/a",
    }


#: The report section that shows each summary-row kind (the flags sit there, beside the measurement).
_ANCHORS = {
    "edge_mtf_at_nyquist": "edges",
    "edge_angle": "edges",
    "star_mtf": "star",
    "bar_ctf": "bars",
    "wedge_resolution": "wedges",
    "niirs": "niirs",
}


def sigma_text(s: dict) -> str:
    """A summary row's 1-sigma in the unit of its error (the wedge's error is relative: in %)."""
    sig = _num(s.get("sigma"))
    if sig is None:
        return "–"
    if s.get("kind") == "wedge_resolution":
        return fmt(100 * sig, 1, unit="%")
    if s.get("kind") == "edge_angle":
        return fmt(sig, 4, unit="°")
    return fmt(sig, 2 if s.get("kind") == "niirs" else 4)


def _with_sigma(row: dict, s: dict | None, flags: dict) -> dict:
    """``row`` with the sigma, z and "tolerance inside noise" of its results.json summary row ``s``, the
    section that shows it and how many flags its measurement carries."""
    if not s:
        return row
    z = _num(s.get("z"))
    row.update(
        sigma=sigma_text(s),
        z=fmt(z, 1, signed=True) if z is not None else "–",
        noise=s.get("tolerance_inside_noise") is True,
        sigma_note="" if _num(s.get("sigma")) is not None else str(s.get("sigma_null_means") or ""),
        note=str(s.get("note") or ""),
        anchor=_ANCHORS.get(str(s.get("kind")), ""),
        n_flags=len(flags.get(s.get("id"), ())) if s.get("kind") != "edge_angle" else 0,
        **_as_built_cells(s),
    )
    if s.get("pass") is None and s.get("reason"):  # n/a: why the image does not support the check
        row["target"] += f" (n/a: {s['reason']})"
    return row


def _as_built_cells(s: dict) -> dict:
    """The row's check against the camera as built (results.json's ``*_as_built``), in the row's own units: the
    prediction, the difference (for bars the largest |difference|, for the wedge measured - predicted in cm) and
    z; nothing for a run simulated as designed."""
    if "predicted_as_built" not in s:
        return {}
    kind = str(s.get("kind"))
    units = {"wedge_resolution": (100, 1, "cm"), "edge_angle": (1, 3, "°"), "niirs": (1, 2, "")}
    scale, digits, unit = units.get(kind, (1, 3, ""))
    p, err, z = _num(s.get("predicted_as_built")), _num(s.get("error_as_built")), _num(s.get("z_as_built"))
    if kind == "wedge_resolution":  # its error is relative: the difference in cm, as the design's column
        m = _num(s.get("measured"))
        err = None if m is None or p is None else m - p
    return {
        "ab_predicted": "–" if kind == "bar_ctf" else fmt(None if p is None else p * scale, digits, unit=unit),
        "ab_difference": fmt(None if err is None else err * scale, digits, unit=unit, signed=kind != "bar_ctf"),
        "ab_z": fmt(z, 1, signed=True) if z is not None else "–",
        "ab_status": _status(s.get("pass_as_built")),
    }


def _mtf_rows(res: dict, tol: dict) -> list[dict]:
    """Rows of the edges, stars and bars."""
    rows = []
    for e in res.get(EDGES.key, []):
        m, p = e.get("mtf_at_nyquist_measured"), e.get("mtf_at_nyquist_predicted")
        d = _diff(m, p)
        rows.append(
            _row(
                f"MTF at Nyquist, {_DIR_WORDS.get(e.get('direction'), e.get('direction'))}",
                f"slanted edge {e['id']}",
                m,
                p,
                d,
                f"± {fmt(tol.get('edge_mtf_at_nyquist'), 3)}",
                e.get("pass"),
            )
            | {"_key": ("edge_mtf_at_nyquist", e.get("id"))}
        )
    for st in res.get(STARS.key, []):
        signed = st.get("error") is not None  # the MTF at the largest difference, measured and predicted
        rows.append(
            _row(
                "largest MTF difference up to Nyquist, all directions",
                f"Siemens star {st['id']}",
                st.get("measured_at_worst"),
                st.get("predicted_at_worst"),
                st.get("error") if signed else st.get("max_abs_error_to_nyquist"),
                f"≤ {fmt(tol.get('star_mtf'), 3)}",
                st.get("pass"),
                signed=signed,
            )
            | {"_key": ("star_mtf", st.get("id"))}
        )
    for b in res.get(BARS.key, []):
        lim = b.get("compared_up_to_cy_per_px")
        q = "largest CTF difference to Coltman's CTF" + (f" (groups ≤ {lim:g} cy/px)" if lim else "")
        rows.append(
            _row(
                q,
                f"bar target {b['id']}",
                None,
                None,
                b.get("max_abs_error"),
                f"≤ {fmt(tol.get('bar_ctf'), 3)}",
                b.get("pass"),
                signed=False,
            )
            | {"_key": ("bar_ctf", b.get("id"))}
        )
    return rows


def _resolution_rows(res: dict, tol: dict) -> list[dict]:
    """Rows of the wedges and NIIRS."""
    rows = []
    for w in res.get(WEDGES.key, []):
        m, p = _num(w.get("resolution_m")), _num(w.get("resolution_predicted_m"))
        m_cm = None if m is None else 100 * m
        p_cm = None if p is None else 100 * p
        d = _diff(m_cm, p_cm)
        rt = tol.get("wedge_resolution_rel")
        rows.append(
            _row(
                f"resolution (line width at 15 % contrast), {_DIR_WORDS.get(w.get('axis'), w.get('axis'))}",
                f"hyperbolic wedge {w['id']}",
                m_cm,
                p_cm,
                d,
                "–" if rt is None else f"± {rt:.0%}",
                w.get("pass"),
                1,
                "cm",
            )
            | {"_key": ("wedge_resolution", w.get("id"))}
        )
    n = res.get("niirs") or {}
    if n:
        m, p = n.get("giqe5_measured"), n.get("giqe5_predicted")
        d = _diff(m, p)
        rows.append(
            _row(
                "NIIRS (GIQE 5)",
                "image (edges' RER, measured SNR)",
                m,
                p,
                d,
                f"± {fmt(tol.get('niirs'), 2)}",
                n.get("pass"),
                2,
            )
            | {"_key": ("niirs", None)}
        )
    return rows


def summary_rows(res: dict) -> list[dict]:
    """Measured vs predicted in words: one row per check, a signed difference, fixed precision, the error's
    1-sigma and z = error / sigma, "tolerance inside noise" and the number of flags of the measurement."""
    tol = res.get("tolerances") or {}
    rows = _mtf_rows(res, tol) + _angle_rows(res) + _resolution_rows(res, tol)
    summary = {(s.get("kind"), s.get("id")): s for s in res.get("summary", [])}
    flags = measurement_flags(res)
    rows = [_with_sigma(r, summary.get(r.pop("_key")), flags) for r in rows] + _not_measured_rows(res)
    return rows + _focal_rows(res, flags)


#: Summary-row kinds of the focal plane as flown (satchain.focal: bands, colour planes, staggered arrays)
FOCAL_KIND_PREFIXES = ("band_", "cfa_", "staggered_")


def _focal_rows(res: dict, flags: dict) -> list[dict]:
    """The focal-plane sections' checks (their figure in words, as the terminal prints it), in their order."""
    out = []
    for r in res.get("summary", []):
        if not str(r.get("kind", "")).startswith(FOCAL_KIND_PREFIXES):
            continue
        m, p, e = _num(r.get("measured")), _num(r.get("predicted")), _num(r.get("error"))
        row = _row(r.get("figure"), r.get("id") or "", m, p, e, r.get("tolerance"), r.get("pass"), 4)
        row = _with_sigma(row, r, flags)
        row["anchor"] = "focal-plane"
        out.append(row)
    return out


def measurement_flags(res: dict) -> dict[str | None, list[str]]:
    """Every flag results.json holds, by target id: the edges', star's, bars' and wedges' ``flags`` (None: the
    run's ``warnings``)."""
    out: dict[str | None, list[str]] = {}
    for _, x in measured_entries(res):
        out.setdefault(x.get("id"), []).extend(str(f) for f in x.get("flags") or [])
    out[None] = [str(w) for w in res.get("warnings") or []]
    return out


#: Summary-row kinds in words: (quantity, target).
_KIND_WORDS = {
    "edge_mtf_at_nyquist": ("MTF at Nyquist", "slanted edge"),
    "star_mtf": ("largest MTF difference up to Nyquist, all directions", "Siemens star"),
    "bar_ctf": ("largest CTF difference to Coltman's CTF", "bar target"),
    "wedge_resolution": ("resolution (line width at 15 % contrast)", "hyperbolic wedge"),
}


def _angle_rows(res: dict) -> list[dict]:
    """The edge-angle checks (measured vs true tilt of each slanted edge), from the summary rows."""
    rows = []
    for r in res.get("summary", []):
        if r.get("kind") != "edge_angle":
            continue
        m, p = _num(r.get("measured")), _num(r.get("predicted"))
        tol = f"± {fmt(r.get('tolerance_value'), 1)} °"
        row = _row("edge angle", f"slanted edge {r.get('id')}", m, p, _diff(m, p), tol, r.get("pass"), 3, "°")
        rows.append(row | {"_key": ("edge_angle", r.get("id"))})
    return rows


def _not_measured_rows(res: dict) -> list[dict]:
    """The checks of targets the measurement had to skip: n/a, with the reason as the target's note."""
    shown = {x.get("id") for _, x in measured_entries(res)}
    rows = []
    for r in res.get("summary", []):
        if r.get("pass") is not None or r.get("kind") not in _KIND_WORDS or r.get("id") in shown:
            continue
        q, t = _KIND_WORDS[r["kind"]]
        row = _row(q, f"{t} {r.get('id')}", None, None, None, r.get("tolerance", "–"), None)
        row["target"] += f" ({r.get('reason') or 'not measured'})"
        rows.append(row)
    return rows


def camera_rows(system) -> list[tuple[str, str]]:
    """The camera's inputs, named and with units."""
    o, d, m, orb = system.optics, system.detector, system.motion, system.orbit
    qe = d.qe if isinstance(d.qe, (int, float)) else f"table of {len(d.qe)} values"
    wl = ", ".join(f"{w * 1e9:.1f}" for w in o.wavelengths_m)
    return [
        ("orbit altitude", fmt(orb.altitude_m / 1e3, 1, unit="km")),
        ("off-nadir look angle", fmt(orb.off_nadir_deg, 1, unit="°")),
        ("aperture diameter", fmt(o.aperture_diameter_m, 3, unit="m")),
        ("focal length", fmt(system.focal_length_m, 3, unit="m")),
        ("f-number", fmt(system.f_number, 2)),
        ("central obscuration (diameter ratio)", fmt(o.obscuration_ratio, 4)),
        ("wavelength(s) of the diffraction MTF", f"{wl} nm"),
        ("pixel pitch", f"{d.pitch_x_m * 1e6:.2f} × {d.pitch_y_m * 1e6:.2f} µm"),
        ("quantum efficiency", qe if isinstance(qe, str) else fmt(qe, 2)),
        ("read noise", fmt(d.read_noise_e, 1, unit="e⁻ rms")),
        ("full well", "–" if d.full_well_e is None else f"{d.full_well_e:,.0f} e⁻"),
        ("dark current", f"{d.dark_current_e_per_s:,.0f} e⁻/s"),
        ("ADC bit depth", "–" if d.bit_depth is None else f"{d.bit_depth} bit"),
        ("TDI stages", f"{d.tdi_stages} ({d.readout.upper()} accumulation)"),
        ("along-track smear", fmt(m.smear_px, 4, unit="px")),
        ("jitter", fmt(m.jitter_rms_px, 3, unit="px rms")),
    ]


_DERIVED = [
    ("focal_length_m", "focal length", 1, 3, "m"),
    ("gsd_act_m", "GSD across-track", 100, 1, "cm"),
    ("gsd_alt_m", "GSD along-track", 100, 1, "cm"),
    ("ifov_act_urad", "IFOV across-track", 1, 4, "µrad"),
    ("range_m", "slant range", 1e-3, 1, "km"),
    ("nyquist_cy_per_mm", "Nyquist frequency (focal plane)", 1, 2, "cy/mm"),
    ("nyquist_act_cy_per_m_ground", "Nyquist frequency (ground)", 1, 3, "cy/m"),
    ("effective_wavelength_m", "effective wavelength", 1e9, 1, "nm"),
    ("q_effective", "Q = λ F# / pitch", 1, 3, ""),
    ("limited_by", "resolution limited by", None, 0, ""),
    ("ground_speed_m_per_s", "ground speed", 1e-3, 3, "km/s"),
]


def derived_rows(derived: dict) -> list[tuple[str, str]]:
    """Derived geometry in words and units (only the keys present)."""
    out = []
    for key, label, scale, digits, unit in _DERIVED:
        if key not in derived:
            continue
        v = derived[key]
        if isinstance(v, (list, tuple)):
            v = v[0] if v else None
        out.append(
            (label, str(v) if scale is None else fmt(None if v is None else float(v) * scale, digits, unit=unit))
        )
    return out


_RADIOMETRY = [
    ("reflectance", "scene reflectance (albedo)", 1, 2, ""),
    ("sun_zenith_deg", "sun zenith angle", 1, 1, "°"),
    ("atmosphere_transmission_down", "atmospheric transmission, down", 1, 2, ""),
    ("atmosphere_transmission_up", "atmospheric transmission, up", 1, 2, ""),
    ("radiance_toa_band_w_per_m2_sr", "in-band radiance at the top of the atmosphere", 1, 2, "W m⁻² sr⁻¹"),
    ("focal_plane_irradiance_band_w_per_m2", "in-band focal-plane irradiance", 1, 4, "W m⁻²"),
    ("integration_time_s", "integration time per TDI stage", 1e6, 2, "µs"),
    ("signal_e", "signal (all TDI stages)", 1, 0, "e⁻"),
    ("well_fill", "full-well fill", 100, 1, "%"),
    ("snr", "scene SNR at this albedo", 1, 1, ""),
    ("signal_7pct_e", "signal at 7 % reflectance", 1, 0, "e⁻"),
    ("signal_15pct_e", "signal at 15 % reflectance", 1, 0, "e⁻"),
    ("contrast_snr", "contrast SNR (GIQE: 15 % vs 7 % reflectance)", 1, 1, ""),
]


def radiometry_rows(rad: dict) -> list[tuple[str, str]]:
    out = []
    for key, label, scale, digits, unit in _RADIOMETRY:
        v = rad.get(key)
        if v is None or isinstance(v, (dict, list)):
            continue
        out.append((label, fmt(float(v) * scale, digits, unit=unit)))
    return out


def paper_rows(res: dict) -> list[dict]:
    """The paper's own results beside satchain's prediction and measurement."""
    mtf_n = _num((res.get("mtf_at_nyquist") or {}).get("alt"))
    alt_edges = _mean(e.get("mtf_at_nyquist_measured") for e in res.get(EDGES.key, []) if e.get("direction") == "ALT")
    wedges = [w for w in res.get(WEDGES.key, []) if w.get("axis") == "ALT"] or res.get(WEDGES.key, [])
    w = wedges[0] if wedges else {}
    wm, wp = _num(w.get("resolution_m")), _num(w.get("resolution_predicted_m"))
    return [
        {
            "quantity": "system MTF at Nyquist, along-track",
            "paper": "12.28 %",
            "predicted": fmt(None if mtf_n is None else 100 * mtf_n, 2, unit="%"),
            "measured": fmt(None if alt_edges is None else 100 * alt_edges, 2, unit="%"),
        },
        {
            "quantity": "hyperbolic-wedge resolution" + (f" ({w.get('id')})" if w else ""),
            "paper": "52.5 cm",
            "predicted": fmt(None if wp is None else 100 * wp, 1, unit="cm"),
            "measured": fmt(None if wm is None else 100 * wm, 1, unit="cm"),
        },
        {
            "quantity": "GSD",
            "paper": "49 cm",
            "predicted": fmt(100 * res["gsd_m"], 1, unit="cm") if res.get("gsd_m") else "–",
            "measured": "–",
        },
    ]


def skipped_groups(skipped: list[dict]) -> list[dict]:
    """Not-measured items grouped by kind and reason: kind, reason, count, ids."""
    groups: OrderedDict[tuple[str, str], list[str]] = OrderedDict()
    for s in skipped:
        groups.setdefault((str(s.get("kind", "")), str(s.get("reason", ""))), []).append(str(s.get("id", "")))
    return [
        {"kind": k.replace("_", " "), "reason": r, "count": len(ids), "ids": ", ".join(ids)}
        for (k, r), ids in groups.items()
    ]
