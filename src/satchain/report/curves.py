"""Every measured and predicted curve of a run, as arrays (for the report's figures) and as CSV files.

:func:`build_curves` gathers, per target, the measured curve and the prediction evaluated the way the
measurement sees it (the same conventions as :mod:`satchain.comparison`); :func:`write_curves` writes
one CSV per curve family into ``curves/`` beside ``results.json``, with a header naming every column and its
unit. The edge ESF and LSF are not part of the measurement summary, so the edge is measured again here on
the same region of interest (identical numbers: the e-SFR is deterministic).

The predicted LSF along an edge normal ``n`` is the inverse Fourier transform of the (real, even) system
OTF along ``n``: ``LSF(x) = 2 * integral_0^fc OTF(f n) cos(2 pi f x) df`` (x, f in pixels and cycles per
pixel); the predicted ESF is its running integral, normalised from 0 (dark side) to 1 (bright side).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from satchain import units
from satchain.prediction.core import WIDE_COMPONENTS
from satchain.report._save import write_text
from satchain.report.kinds import BARS, EDGES, STARS, WEDGES
from satchain.tf import ctf as _ctf

__all__ = ["CSV_FAMILIES", "build_curves", "crossing", "edge_curves", "predicted_lsf", "write_curves"]

#: CSV file names (under ``curves/``), one per curve family.
CSV_FAMILIES = (
    "edges_esf_lsf.csv",
    "edges_mtf.csv",
    "star_mtf.csv",
    "bars_ctf.csv",
    "wedge_contrast.csv",
    "system_mtf_ctf.csv",
)

_DIRECTIONS = {
    "ACT": (1.0, 0.0),
    "ALT": (0.0, 1.0),
    "D45": (math.sqrt(0.5), math.sqrt(0.5)),
    "D135": (math.sqrt(0.5), -math.sqrt(0.5)),
}


def crossing(f, m, level: float) -> float | None:
    """First frequency where the curve ``m(f)`` falls to ``level`` (linear interpolation); None if never."""
    f, m = np.asarray(f, float), np.asarray(m, float)
    ok = np.isfinite(m)
    f, m = f[ok], m[ok]
    below = np.nonzero(m <= level)[0]
    if below.size == 0 or below[0] == 0:
        return None
    i = below[0]
    f0, f1, m0, m1 = f[i - 1], f[i], m[i - 1], m[i]
    return float(f0 + (level - m0) * (f1 - f0) / (m1 - m0)) if m1 != m0 else float(f1)


def _signed_axis_otf(otf, direction: tuple[float, float]):
    """Real part of the system OTF along a unit direction, as a function of cycles/pixel; its cut-off."""
    s = otf.system
    pitch_m = math.sqrt(s.detector.pitch_x_m * s.detector.pitch_y_m)
    n = math.hypot(*direction)
    ux, uy = direction[0] / n, direction[1] / n

    def along(f_cy_per_px):
        f_mm = units.cy_per_px_to_cy_per_mm(np.asarray(f_cy_per_px, float), pitch_m=pitch_m)
        return np.real(otf(f_mm * ux, f_mm * uy, exclude=local) if local else otf(f_mm * ux, f_mm * uy))

    local = tuple(c for c in WIDE_COMPONENTS if c in getattr(otf, "component_names", ()))  # as measured locally
    fc = float(units.cy_per_mm_to_cy_per_px(otf.cutoff_cy_per_mm, pitch_m=pitch_m))
    return along, fc


def predicted_lsf(otf, direction: tuple[float, float], x_px) -> tuple[np.ndarray, np.ndarray]:
    """Predicted LSF (1/px, unit area) and ESF (0..1) at distances ``x_px`` along ``direction``."""
    along, fc = _signed_axis_otf(otf, direction)
    f = np.linspace(0.0, min(fc, 4.0), 1601)
    w = np.full(f.size, f[1] - f[0])
    w[[0, -1]] *= 0.5
    x = np.asarray(x_px, float)
    lsf = 2.0 * (np.cos(2 * np.pi * np.outer(x, f)) @ (along(f) * w))
    esf = np.concatenate([[0.0], np.cumsum(0.5 * (lsf[1:] + lsf[:-1]) * np.diff(x))])
    esf = (esf - esf[0]) / (esf[-1] - esf[0]) if esf[-1] != esf[0] else esf
    return lsf, esf


def edge_curves(ctx) -> list[dict]:
    """The slanted edges' part of :func:`build_curves`: ``ctx.comparison["results"]`` needs only its edges."""
    return _edge_curves(ctx, ctx.comparison["results"])


def _edge_curves(ctx, res: dict) -> list[dict]:
    from satchain.measure import measure_edge

    truth = {it["id"]: it for it in ctx.truth["items"]}
    by_id = {e["id"]: e for e in (ctx.measured or {}).get(EDGES.key, [])}
    as_measured = getattr(ctx, "edge_results", None) or {}  # the run's own results: their ESF and LSF
    out = []
    for e in res.get(EDGES.key, []):
        m = by_id.get(e["id"], {})
        roi = m.get("roi_px")
        if roi is None:
            continue
        r = as_measured.get(e["id"])
        if r is None:  # a view without the measurement's objects: measured again on its ROI (the same curves)
            r = measure_edge(np.asarray(ctx.image, float), roi=roi, pixel_m=ctx.image_gsd_m)
        t = truth.get(e["id"], {})
        normal = t.get("normal_to_bright", (1.0, 0.0) if e["direction"] == "ACT" else (0.0, 1.0))
        x = np.asarray(r.esf_x_px, float)
        lsf_p, esf_p = predicted_lsf(ctx.otf, tuple(normal), x)
        esf_m = np.asarray(r.esf, float)
        if esf_m[-1] < esf_m[0]:  # the measured ESF falls: compare like with like
            esf_p, lsf_p = esf_p[::-1].copy(), lsf_p[::-1].copy()
        f = np.asarray(e["f_cy_per_px"], float)
        mm, mp = np.asarray(e["mtf_measured"], float), np.asarray(e["mtf_predicted"], float)
        sig = e.get("mtf_sigma") or [None] * f.size
        sig = np.array([np.nan if v is None else v for v in sig], float)
        out.append(
            {
                "id": e["id"],
                "direction": e["direction"],
                "angle_deg": e.get("angle_deg"),
                "x_px": x,
                "esf_measured": esf_m,
                "esf_predicted": esf_p,
                "lsf_measured": np.asarray(r.lsf, float),
                "lsf_predicted": lsf_p,
                "f_cy_per_px": f,
                "mtf_measured": mm,
                "mtf_predicted": mp,
                "mtf_sigma": sig if sig.size == f.size else np.full(f.size, np.nan),
                "mtf50": (crossing(f, mm, 0.5), crossing(f, mp, 0.5)),
                "mtf10": (crossing(f, mm, 0.1), crossing(f, mp, 0.1)),
                "nyquist": (e.get("mtf_at_nyquist_measured"), e.get("mtf_at_nyquist_predicted")),
                "sigma": e.get("mtf_at_nyquist_sigma", m.get("mtf_at_nyquist_sigma")),
                "passed": e.get("pass"),
                **_edge_as_built(e, f.size),
            }
        )
    return out


def _edge_as_built(e: dict, n: int) -> dict:
    """The prediction for the camera as built along the edge (a run with ``[as_built]``), else nothing."""
    ab = (e.get("as_built") or {}).get("mtf_predicted")
    if ab is None or len(ab) != n:
        return {}
    return {"mtf_predicted_as_built": np.array([np.nan if v is None else v for v in ab], float)}


def _wedge_curves(ctx, res: dict) -> list[dict]:
    from satchain.prediction.core import AxisMTF, system_mtf_cy_per_px

    by_id = {w["id"]: w for w in (ctx.measured or {}).get(WEDGES.key, [])}
    out = []
    for w in res.get(WEDGES.key, []):
        m = by_id.get(w["id"], {})
        lw = m.get("line_width_m")
        if lw is None or w.get("contrast") is None:
            continue
        lw = np.asarray(lw, float)
        gsd = float(w.get("gsd_m") or ctx.system.gsd_m)
        axis = _DIRECTIONS.get(str(w.get("axis", "ALT")).upper(), (0.0, 1.0))
        mtf = AxisMTF(system_mtf_cy_per_px(ctx.otf, local=True), axis)
        pred = np.asarray(_ctf.coltman_ctf(gsd / (2.0 * lw), mtf), float)
        out.append(
            {
                "id": w["id"],
                "axis": w.get("axis"),
                "line_width_m": lw,
                "position_m": np.asarray(w.get("position_m") or m.get("position_m_along_wedge") or lw * np.nan),
                "contrast_measured": np.asarray(w["contrast"], float),
                "contrast_predicted": np.asarray(
                    [np.nan if v is None else v for v in (w.get("contrast_predicted") or [None] * lw.size)], float
                ),
                "ctf_coltman_predicted": pred,
                "threshold": float(w.get("threshold") or 0.15),
                "resolution_m": w.get("resolution_m"),
                "resolution_predicted_m": w.get("resolution_predicted_m"),
                "gsd_m": gsd,
                "passed": w.get("pass"),
                **_wedge_as_built(w, lw.size),
            }
        )
    return out


def _wedge_as_built(w: dict, n: int) -> dict:
    """The wedge's scan and resolution predicted for the camera as built (a run with ``[as_built]``)."""
    ab = w.get("as_built") or {}
    c = ab.get("contrast_predicted")
    if c is None or len(c) != n:
        return {}
    return {
        "contrast_predicted_as_built": np.array([np.nan if v is None else v for v in c], float),
        "resolution_predicted_as_built_m": ab.get("resolution_predicted_m"),
    }


def build_curves(ctx, *, edges: list[dict] | None = None) -> dict[str, Any]:
    """Measured and predicted curves of every target of a run (arrays; see :func:`write_curves`); ``edges``:
    the edges' curves when already built (:func:`edge_curves`)."""
    res = ctx.comparison["results"]
    b = ctx.budget or {}
    return {
        "edges": _edge_curves(ctx, res) if edges is None else edges,
        "stars": list(res.get(STARS.key, [])),
        "bars": list(res.get(BARS.key, [])),
        "wedges": _wedge_curves(ctx, res),
        "system": {
            "f_cy_per_mm": b.get("frequencies_cy_per_mm"),
            "f_cy_per_px": b.get("frequencies_cy_per_px"),
            "mtf": b.get("mtf", {}),
            "ctf": b.get("ctf", {}),
        },
    }


def _csv(path: Path, header: list[str], columns: list[list], comment: str) -> None:
    lines = [f"# {comment}", ",".join(header)]
    for row in zip(*columns, strict=True):
        lines.append(",".join(_cell(v) for v in row))
    write_text(path, "\n".join(lines) + "\n")


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, str):
        return v
    v = float(v)
    return "" if not math.isfinite(v) else f"{v:.7g}"


def _rep(v, n: int) -> list:
    return [v] * n


def write_curves(curves: dict[str, Any], out_dir: str | Path) -> list[Path]:
    """One CSV per curve family (:data:`CSV_FAMILIES`) into ``out_dir``; returns the paths written.

    Empty cells are values that do not exist (NaN, or a measurement that was not made)."""
    d = Path(out_dir)
    cols: dict[str, tuple[list[str], list[list], str]] = {}
    e = curves["edges"]
    cols["edges_esf_lsf.csv"] = (
        [
            "edge_id",
            "direction",
            "x_px",
            "esf_measured",
            "esf_predicted",
            "lsf_measured_per_px",
            "lsf_predicted_per_px",
        ],
        _stack(e, ["id", "direction"], ["x_px", "esf_measured", "esf_predicted", "lsf_measured", "lsf_predicted"]),
        "slanted edges: ESF (normalised 0..1) and LSF (1/px) along the edge normal; x_px from the edge",
    )
    cols["edges_mtf.csv"] = (
        ["edge_id", "direction", "f_cy_per_px", "mtf_measured", "mtf_sigma_measured", "mtf_predicted"],
        _stack(e, ["id", "direction"], ["f_cy_per_px", "mtf_measured", "mtf_sigma", "mtf_predicted"]),
        "slanted edges: e-SFR (measured, with its 1-sigma noise) and system MTF along the edge normal (predicted); "
        "Nyquist = 0.5 cy/px",
    )
    cols["star_mtf.csv"] = _star_columns(curves["stars"])
    cols["bars_ctf.csv"] = _bars_columns(curves["bars"])
    cols["wedge_contrast.csv"] = (
        [
            "wedge_id",
            "axis",
            "position_m",
            "line_width_m",
            "contrast_measured",
            "contrast_predicted",
            "ctf_coltman_predicted",
        ],
        _stack(
            curves["wedges"],
            ["id", "axis"],
            ["position_m", "line_width_m", "contrast_measured", "contrast_predicted", "ctf_coltman_predicted"],
        ),
        "hyperbolic wedges: contrast across the stripes along the wedge, measured and predicted (the same scan on "
        "the wedge's noise-free predicted image), and Coltman's CTF of an infinite square wave for reference",
    )
    cols["system_mtf_ctf.csv"] = _system_columns(curves["system"])
    written = []
    for name in CSV_FAMILIES:
        header, columns, comment = cols[name]
        _csv(d / name, header, columns, comment)
        written.append(d / name)
    return written


def _star_columns(stars: list[dict]) -> tuple[list[str], list[list], str]:
    rows: list[list] = [[], [], [], [], []]
    for st in stars:
        f = list(st.get("f_cy_per_px", []))
        for dname, curve in (st.get("mtf_measured") or {}).items():
            pred = (st.get("directions") or {}).get(dname, {}).get("mtf_predicted", _rep(None, len(f)))
            for c, v in zip(
                rows, (_rep(st["id"], len(f)), _rep(dname, len(f)), f, list(curve), list(pred)), strict=True
            ):
                c.extend(v)
    return (
        ["star_id", "direction", "f_cy_per_px", "mtf_measured", "mtf_predicted"],
        rows,
        "Siemens star: MTF per direction (ACT, ALT, diagonals), measured and predicted",
    )


def _bars_columns(bars: list[dict]) -> tuple[list[str], list[list], str]:
    rows: list[list] = [[] for _ in range(14)]
    for br in bars:
        f = list(br.get("f_cy_per_px", []))
        lim = br.get("compared_up_to_cy_per_px", 0.2)
        n = len(f)
        given, flagged = br.get("group") or [], br.get("at_noise_floor") or []
        groups = given if len(given) == n else list(range(n))
        floor = flagged if len(flagged) == n else _rep(None, n)
        ab = (br.get("as_built") or {}).get("ctf_coltman_predicted")
        vals = (
            _rep(br["id"], n),
            _rep(br.get("direction"), n),
            [str(g) for g in groups],
            f,
            br.get("ctf_raw_measured") or _rep(None, n),
            br.get("ctf_measured", _rep(None, n)),
            br.get("ctf_std_measured") or _rep(None, n),
            br.get("ctf_correction") or _rep(None, n),
            br.get("ctf_coltman_predicted", _rep(None, n)),
            br.get("ctf_fourier_synthesis_predicted", _rep(None, n)),
            br.get("mtf_from_ctf_measured", _rep(None, n)),
            ["yes" if fi <= lim else "no" for fi in f],
            ["" if v is None else ("yes" if v else "no") for v in floor],
            ab if ab is not None and len(ab) == n else _rep(None, n),
        )
        for c, v in zip(rows, vals, strict=True):
            c.extend(v)
    return (
        [
            "bars_id",
            "direction",
            "group",
            "f_cy_per_px",
            "ctf_raw_measured",
            "ctf_measured",
            "ctf_std_measured",
            "ctf_correction_square_wave",
            "ctf_coltman_predicted",
            "ctf_paper_method_predicted",
            "mtf_from_ctf_measured",
            "compared",
            "at_noise_floor",
            "ctf_coltman_predicted_as_built",
        ],
        rows,
        "bar targets: CTF per bar group (group = its index in the target's design, as in results.json and the "
        "report); ctf_raw_measured = the group's fitted modulation, ctf_measured = raw + "
        "ctf_correction_square_wave (the model-corrected square-wave CTF that is compared); compared = whether "
        "the group enters the pass/fail check; at_noise_floor = its modulation is not above the noise (CTF ~0, "
        "measured); ctf_coltman_predicted_as_built = the prediction for the camera as built (a run with [as_built])",
    )


def _stack(items: list[dict], labels: list[str], arrays: list[str]) -> list[list]:
    out: list[list] = [[] for _ in range(len(labels) + len(arrays))]
    for it in items:
        n = len(it[arrays[0]])
        for i, k in enumerate(labels):
            out[i].extend(_rep(it.get(k), n))
        for j, k in enumerate(arrays):
            out[len(labels) + j].extend(list(np.asarray(it[k], float)))
    return out


def _system_columns(sysc: dict) -> tuple[list[str], list[list], str]:
    f_mm = list(np.asarray(sysc.get("f_cy_per_mm") if sysc.get("f_cy_per_mm") is not None else [], float))
    n = len(f_mm)
    header, columns = ["f_cy_per_mm"], [f_mm]
    f_px = sysc.get("f_cy_per_px") or {}
    for d in ("alt", "act"):
        if isinstance(f_px, dict) and f_px.get(d) is not None and len(f_px[d]) == n:
            header.append(f"f_cy_per_px_{d}")
            columns.append(list(f_px[d]))
    for d in ("alt", "act"):
        for comp, vals in (sysc.get("mtf") or {}).get(d, {}).items():
            if np.ndim(vals) == 1 and len(vals) == n:
                header.append(f"mtf_{comp}_{d}")
                columns.append(list(vals))
        for kind, vals in (sysc.get("ctf") or {}).get(d, {}).items():
            if np.ndim(vals) == 1 and len(vals) == n:
                header.append(f"ctf_{kind}_{d}")
                columns.append(list(vals))
    return header, columns, "MTF budget: every component and the system, ALT and ACT, and the system CTF"
