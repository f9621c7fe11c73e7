"""The packaged example studies (``satchain study --example NAME -o DIR``) and what their tables show.

``aperture-aberration`` is the reference paper's future work, run: "effects of optical degradations (smaller
aperture optics and/or various aberrations) on spatial resolution". The paper's camera (ankarasat3, GSD
0.49 m) with apertures 0.35-0.70 m at its focal length and pixel (the GSD stays, the f-number and
Q = lambda N / p grow as the aperture shrinks) x wavefront errors of 0, 0.05 and 0.10 waves rms, the whole
chain per case. :func:`aperture_findings` turns its table into the paper's claim, quantified: the aperture
(and Q) below which the hyperbolic wedge's resolution departs from the GSD by more than 10 %.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from importlib import resources
from pathlib import Path
from typing import Any

from satchain.errors import ConfigError

__all__ = [
    "APERTURE_KEY",
    "DEPARTURE",
    "EXAMPLES",
    "WFE_KEY",
    "aperture_findings",
    "example_path",
]

#: the packaged example studies: name -> study file in satchain/data/studies/
EXAMPLES: dict[str, str] = {"aperture-aberration": "aperture_aberration.toml"}

#: the axes :func:`aperture_findings` reads
APERTURE_KEY = "optics.aperture_diameter_m"
WFE_KEY = "optics.wfe_rms_waves"
#: the departure from the GSD that counts: |resolution / GSD - 1| > DEPARTURE
DEPARTURE = 0.10
_PCT = f"{DEPARTURE * 100:g} %"


def example_path(name: str) -> Path:
    """The packaged study file of the example ``name`` (its scene file lies beside it).

    Raises
    ------
    ConfigError
        An unknown name (the message names it and the allowed ones).

    Examples
    --------
    >>> example_path("aperture-aberration").name
    'aperture_aberration.toml'
    """
    if not isinstance(name, str) or name not in EXAMPLES:
        raise ConfigError(f"example = {name!r}: unknown example study; must be one of {', '.join(EXAMPLES)}")
    return Path(str(resources.files("satchain") / "data" / "studies" / EXAMPLES[name]))


def _number(v: Any) -> float | None:
    """``v`` as a finite float, or None (empty, missing, NaN, not a number)."""
    if v is None or isinstance(v, bool) or v == "":
        return None
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


_DIRECTION = re.compile(r"\b(ACT|ALT)\b", re.IGNORECASE)


def _direction(row: Mapping[str, Any]) -> str | None:
    """The wedge's direction (ACT or ALT): the last one the row's figure names (``... resolution (m, ALT)``),
    else the one its check id names."""
    for key in ("figure", "check_id"):
        found = _DIRECTION.findall(str(row.get(key) or "").replace("_", " "))
        if found:
            return str(found[-1]).upper()
    return None


def _wedge_points(rows: Sequence[Mapping[str, Any]]) -> dict[tuple[float, str, str], dict[float, list[tuple]]]:
    """(wfe, direction, source) -> aperture -> [(resolution / GSD, Q), ...] from the wedge rows of cases that
    ran (a case that errored has no figures); source is 'measured' or 'predicted'."""
    out: dict[tuple[float, str, str], dict[float, list[tuple]]] = {}
    for row in rows:
        if row.get("kind") != "wedge_resolution" or str(row.get("case_status") or "").lower().startswith("error"):
            continue
        d, a, w = _direction(row), _number(row.get(APERTURE_KEY)), _number(row.get(WFE_KEY))
        gsd, q = _number(row.get("gsd_m")), _number(row.get("q"))
        if d is None or a is None or w is None or gsd is None or gsd <= 0 or q is None:
            continue
        for source in ("measured", "predicted"):
            res = _number(row.get(source))
            if res is not None:
                out.setdefault((w, d, source), {}).setdefault(a, []).append((res / gsd, q))
    return out


def _departure(points: dict[float, list[tuple]], unit: str) -> str:
    """Where, from the largest aperture down, ``|resolution / GSD - 1|`` first exceeds :data:`DEPARTURE`:
    the aperture and Q there, linearly interpolated between the axis' values (one sentence)."""
    apertures = sorted(points, reverse=True)
    ratio = {a: sum(p[0] for p in points[a]) / len(points[a]) for a in apertures}
    q = {a: sum(p[1] for p in points[a]) / len(points[a]) for a in apertures}
    top = apertures[0]
    if abs(ratio[top] - 1) > DEPARTURE:
        return f"departs by more than {_PCT} already at {top:.2f}{unit} (Q = {q[top]:.2f})"
    for big, small in zip(apertures, apertures[1:], strict=False):
        if abs(ratio[small] - 1) > DEPARTURE:
            target = 1 + math.copysign(DEPARTURE, ratio[small] - 1)
            t = (target - ratio[big]) / (ratio[small] - ratio[big])  # 0 at the larger aperture, 1 at the smaller
            a_x, q_x = big + t * (small - big), q[big] + t * (q[small] - q[big])
            return f"departs by more than {_PCT} below {a_x:.2f}{unit} (Q = {q_x:.2f})"
    return f"stays within {_PCT} down to {apertures[-1]:.2f}{unit}"


def aperture_findings(
    rows: Sequence[Mapping[str, Any]], axes: Mapping[str, Any] | Sequence[str]
) -> list[tuple[str, str]]:
    """The aperture-aberration study's findings: where the wedge resolution leaves the GSD.

    For each wavefront error and each wedge direction (ACT, ALT): the aperture below which the hyperbolic
    wedge's resolution departs from the GSD by more than 10 % (``|resolution / GSD - 1| > 0.10``), and Q
    there, both linearly interpolated between the axis' values, from the measured resolutions and from the
    predicted ones (the same contrast scan on the noise-free predicted image); or that it departs already at
    the largest aperture, or stays within 10 % down to the smallest. Several rows of one case and direction
    (repeats, several wedges) are averaged. The first pair states the resolution at the largest aperture and
    smallest wavefront error (the paper's "detector limited" camera).

    Parameters
    ----------
    rows : sequence of mappings
        The study table's rows: the axes' keys, ``kind`` (rows of kind ``wedge_resolution`` are read),
        ``figure`` (naming ACT or ALT; else ``check_id``), ``measured``, ``predicted`` (m), ``gsd_m``, ``q``
        and ``case_status`` (a case whose status starts with "error" is left out).
    axes : mapping or sequence of str
        The study's axes (key -> values, or the keys): findings need both ``optics.aperture_diameter_m``
        and ``optics.wfe_rms_waves``; without them the answer is ``[]``.

    Returns
    -------
    list of (title, sentence)

    Examples
    --------
    >>> rows = [{"optics.aperture_diameter_m": a, "optics.wfe_rms_waves": 0.0, "kind": "wedge_resolution",
    ...          "figure": "wedge w resolution (m, ALT)", "measured": r, "predicted": r, "gsd_m": 0.5,
    ...          "q": 0.7 / a, "case_status": "ok", "check_id": "w"} for a, r in [(0.4, 0.6), (0.7, 0.5)]]
    >>> title, sentence = aperture_findings(rows, ["optics.aperture_diameter_m", "optics.wfe_rms_waves"])[1]
    >>> title, sentence.split("; ")[0]
    ('ALT wedge resolution vs GSD, WFE 0 waves rms', 'measured: departs by more than 10 % below 0.55 m (Q = 1.38)')
    """
    keys = list(axes)
    if APERTURE_KEY not in keys or WFE_KEY not in keys:
        return []
    points = _wedge_points(rows)
    if not points:
        return []
    unit = " m" if APERTURE_KEY.endswith("_m") else ""
    out = [_detector_limited(points, unit)]
    for wfe in sorted({k[0] for k in points}):
        for d in ("ACT", "ALT"):
            parts = [
                f"{s}: {_departure(points[(wfe, d, s)], unit)}"
                for s in ("measured", "predicted")
                if (wfe, d, s) in points
            ]
            if parts:
                out.append((f"{d} wedge resolution vs GSD, WFE {wfe:g} waves rms", "; ".join(parts)))
    return out


def _detector_limited(points: dict[tuple[float, str, str], dict[float, list[tuple]]], unit: str) -> tuple[str, str]:
    """The resolution over the GSD at the largest aperture and smallest WFE, per direction and source."""
    wfe = min(k[0] for k in points)
    a_top = max(a for k, v in points.items() if k[0] == wfe for a in v)
    said, q_top = [], None
    for d in ("ACT", "ALT"):
        vals = []
        for s in ("measured", "predicted"):
            p = points.get((wfe, d, s), {}).get(a_top)
            if p:
                r = sum(x[0] for x in p) / len(p)
                q_top = p[0][1]
                vals.append(f"{(r - 1) * 100:+.0f} % {s}")
        if vals:
            said.append(f"{d} {' / '.join(vals)}")
    where = f"at {a_top:.2f}{unit}" + (f" (Q = {q_top:.2f})" if q_top is not None else "") + f" and WFE {wfe:g}"
    return (
        "the reference camera (detector limited?)",
        f"{where} the wedge resolution is off the GSD by " + ", ".join(said),
    )
