"""ACT and ALT MTF of an image with no truth file: every usable slanted edge found, measured and combined.

:func:`measure_found_edges` runs :func:`~satchain.measure.find.find_edges`, measures each candidate with
:func:`~satchain.measure.edge.measure_edge` (refusals are kept, with their reason), and combines the edges of
each direction into one MTF curve:

* per-edge uncertainty ``sigma_i(f)``: the edge module's own propagated noise curve where it provides one
  (``mtf_sigma``/``mtf_std``), else its noise at Nyquist scaled by the transfer of the ESF derivative,
  ``sigma_i(f) = sigma_i(Nyq) sin(2 pi f w) / sin(pi w)`` (``w`` = 1/4 px bins; 0 at f = 0, where the MTF is 1
  by normalisation), floored at :data:`SIGMA_FLOOR` (so noise-free edges agree within their sigma);
* combined curve: the inverse-variance weighted mean; its sigma ``1 / sqrt(sum 1/sigma_i^2)`` is inflated by
  the Birge ratio ``sqrt(chi2 / (n - 1))`` where the edges scatter more than their sigmas allow (PDG practice),
  and the result is flagged when that happens at Nyquist beyond the 1 % chi-square quantile; then the
  method's systematic :data:`SIGMA_FLOOR` and the tilt systematic (below) are added in quadrature;
* ``scatter_at_nyquist``: the plain standard deviation of the per-edge values (a consistency check).

The edges are tilted a few degrees, so each measures the MTF along its normal, roughly
``MTF_dir^(cos^2 t) MTF_other^(sin^2 t)``; where both directions are measured, ``mean(sin^2 t) |MTF_ACT -
MTF_ALT|`` is added to the sigma as a systematic (it is not corrected, as MTF Mapper does not).

CEOS-style table: the MTF at normalised frequencies f / f_s = 0, 0.02, ..., 0.5 (Nyquist), with the row at 0.25
(half Nyquist) that CEOS reports, and each row's ground frequency (cy/m) where the pixel size is known.  The slanted
edge also measures the pre-sampling MTF beyond Nyquist (to 1.0 cy/px), but there the image itself is aliased and
the noise grows; ``f_max`` = 1.0 extends the table where wanted.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.stats import chi2 as chi2_dist

from satchain._validate import check_range
from satchain.errors import InputError
from satchain.measure._common import ResultMixin, first_crossing, unmask, valid_mask
from satchain.measure._zero_fill import zero_fill_mask
from satchain.measure.edge import EdgeResult, measure_edge
from satchain.measure.edge._axis import check_axis
from satchain.measure.find import EdgeCandidate, EdgeSearch, Rejection, find_edges

__all__ = ["CombinedMTF", "FindResult", "FoundEdge", "SIGMA_FLOOR", "ceos_csv", "ceos_table", "measure_found_edges"]

#: Systematic 1-sigma of the slanted-edge MTF (the method's accuracy on exact, noise-free edges), added in
#: quadrature to the combined sigma (it is common to all edges, so averaging does not shrink it).
SIGMA_FLOOR = 0.003
MTF_VALID_MAX = 1.2  # a measured MTF above this is not printed as a result
_BIN_PX = 0.25


@dataclass(frozen=True)
class FoundEdge(ResultMixin):
    """One measured edge: the candidate found and the summary of its slanted-edge measurement.

    ``mtf_at_nyquist_sigma`` = the edge's noise sigma and :data:`SIGMA_FLOOR` in quadrature; ``warnings`` and
    ``flags`` are those of the edge measurement (``flags`` empty where the edge module has none).
    Two collinear halves of one target edge (a checkerboard's cross: opposite polarities, the junction
    between them) are joined: ``angle_deg`` is then the angle of the one line fitted to both (a longer
    baseline), ``own_angle_deg`` the half's own and ``joined_with`` the other half's index in ``edges``; each
    half's ESF is then projected on that joint line (``own_mtf_at_nyquist``: the half measured on its own line).
    ``mtf50_cy_per_m_ground`` is MTF50 on the ground (with a pixel size); ``frequency_scale`` = f_row / f_normal
    of this edge (``cos`` of its tilt; 1 on the normal axis).
    """

    candidate: EdgeCandidate
    direction: str
    angle_deg: float
    mtf_at_nyquist: float
    mtf_at_nyquist_sigma: float
    mtf50_cy_per_px: float | None
    rer: float
    noise_sigma: float
    warnings: tuple[str, ...]
    flags: tuple[str, ...] = ()
    own_angle_deg: float | None = None
    joined_with: int | None = None
    own_mtf_at_nyquist: float | None = None
    mtf50_cy_per_m_ground: float | None = None
    frequency_scale: float = 1.0


@dataclass(frozen=True)
class CombinedMTF(ResultMixin):
    """Combined MTF of one direction (ACT or ALT); ``sigma`` is the 1-sigma uncertainty of ``mtf``; with a
    ground pixel size, ``f_cy_per_m_ground`` = ``f_cy_per_px / pixel_m`` and MTF50 in cy/m."""

    direction: str
    f_cy_per_px: np.ndarray
    mtf: np.ndarray
    sigma: np.ndarray
    n_edges: int
    mtf_at_nyquist: float
    mtf_at_nyquist_sigma: float
    mtf50_cy_per_px: float | None
    scatter_at_nyquist: float | None
    chi2_reduced_at_nyquist: float | None
    flags: tuple[str, ...]
    f_cy_per_m_ground: np.ndarray | None = None
    mtf50_cy_per_m_ground: float | None = None


@dataclass(frozen=True)
class FindResult(ResultMixin):
    """Result of :func:`measure_found_edges`: per-edge results, combined ACT/ALT curves, what was rejected;
    ``pixel_m`` the ground pixel size (m) or None, ``frequency_axis`` the axis of every frequency."""

    edges: tuple[FoundEdge, ...]
    combined: dict
    rejected: tuple[Rejection, ...]
    noise_sigma: float
    shape: tuple[int, int]
    flags: tuple[str, ...]
    results: tuple = ()  # the full EdgeResult of each edge (not serialised)
    pixel_m: float | None = None
    frequency_axis: str = "normal"

    def to_dict(self) -> dict:
        return {
            "shape": list(self.shape),
            "pixel_m": self.pixel_m,
            "frequency_axis": self.frequency_axis,
            "noise_sigma": self.noise_sigma,
            "flags": list(self.flags),
            "combined": {k: v.to_dict() for k, v in self.combined.items()},
            "edges": [{**e.to_dict(), "candidate": e.candidate.to_dict()} for e in self.edges],
            "rejected": [r.to_dict() for r in self.rejected],
            "rejection_counts": rejection_counts(self.rejected),
        }


def rejection_counts(rejected) -> dict[str, int]:
    out: dict[str, int] = {}
    for r in rejected:
        out[r.reason] = out.get(r.reason, 0) + 1
    return out


def _nyquist_sigma(r: EdgeResult) -> float:
    """The edge's statistical 1-sigma at Nyquist."""
    return float(r.mtf_at_nyquist_sigma)


def _edge_sigma_curve(r: EdgeResult) -> np.ndarray:
    """Per-frequency 1-sigma of an edge's MTF (see the module docstring)."""
    f = np.asarray(r.f_cy_per_px, dtype=float)
    s = getattr(r, "mtf_sigma", None)
    if s is not None and np.shape(s) == f.shape and np.all(np.isfinite(s)):
        return np.maximum(np.asarray(s, dtype=float), SIGMA_FLOOR)
    w = float(getattr(r, "bin_width_px", _BIN_PX) or _BIN_PX)
    shape = np.abs(np.sin(2 * np.pi * f * w)) / np.sin(np.pi * w)
    shape = np.where(f > 0.5, np.maximum(shape, 1.0) * f / 0.5, shape)  # keep growing past Nyquist
    return np.maximum(_nyquist_sigma(r) * shape, SIGMA_FLOOR)


def _measure_one(image, c: EdgeCandidate, opts: dict, ok=None, edge_line=None):
    """(EdgeResult, None) or (None, reason detail); ``opts`` are :func:`measure_edge`'s keywords."""
    try:
        x0, y0, x1, y1 = c.roi  # crop first: measure_edge would convert the whole image to float64 per call
        v = None if ok is None else ok[y0:y1, x0:x1]
        line = None if edge_line is None else (edge_line[0] - x0, edge_line[1] - y0, edge_line[2])
        r = measure_edge(np.asarray(image)[y0:y1, x0:x1], valid=v, edge_line=line, **opts)
    except InputError as exc:
        return None, str(exc)
    if r.direction != c.direction:
        return None, f"measure_edge saw an {r.direction} edge where an {c.direction} edge was found"
    if abs(r.angle_deg - c.angle_deg) > 1.0:
        return None, f"angle {r.angle_deg:.2f} deg measured vs {c.angle_deg:.2f} deg found"
    if r.edge_point_xy is not None:  # in the image, not the crop
        r = dataclasses.replace(r, edge_point_xy=(r.edge_point_xy[0] + x0, r.edge_point_xy[1] + y0))
    m = np.asarray(r.mtf)
    if not np.all(np.isfinite(m)) or m.min() < 0 or r.mtf_at_nyquist > MTF_VALID_MAX:
        return None, "MTF outside [0, 1.2]"
    return r, None


def _found(c: EdgeCandidate, r: EdgeResult, pixel_m: float | None) -> FoundEdge:
    """The summary of one measured edge."""
    m50 = r.mtf50_cy_per_px
    return FoundEdge(
        c,
        r.direction,
        r.angle_deg,
        r.mtf_at_nyquist,
        float(np.hypot(_nyquist_sigma(r), SIGMA_FLOOR)),
        m50,
        r.rer,
        r.noise_sigma,
        tuple(r.warnings),
        tuple(str(x) for x in getattr(r, "flags", ()) or ()),
        mtf50_cy_per_m_ground=None if (m50 is None or pixel_m is None) else m50 / pixel_m,
        frequency_scale=float(getattr(r, "frequency_scale", 1.0)),
    )


def _on_joint_lines(image, edges, results, lines: dict, opts: dict, ok):
    """Measure each joined half again with its ESF projected on the joint line (a baseline twice as long fixes
    the slope better than the half's own fit); a half the joint line does not suit keeps its own measurement,
    with a warning."""
    edges, results = list(edges), list(results)
    for k, line in lines.items():
        e = edges[k]
        r, why = _measure_one(image, e.candidate, opts, ok, edge_line=line)
        if r is None:
            w = f"measured on its own line: the joint line with edge {e.joined_with} was refused ({why})"
            edges[k] = dataclasses.replace(e, warnings=(*e.warnings, w))
            continue
        joint = _found(e.candidate, r, opts["pixel_m"])
        edges[k] = dataclasses.replace(
            joint, angle_deg=e.angle_deg, own_angle_deg=e.own_angle_deg, joined_with=e.joined_with,
            own_mtf_at_nyquist=e.mtf_at_nyquist,
        )  # fmt: skip
        results[k] = r
    return edges, results


def _line(r: EdgeResult):
    """(a, c, slope dc/da) of a measured edge: a along it (y for ACT, x for ALT), c across it."""
    assert r.edge_point_xy is not None  # every measured edge has one (set by measure_edge)
    x, y = r.edge_point_xy
    t = np.deg2rad(r.angle_deg)
    if r.direction == "ACT":
        return y, x, float(np.tan(t))
    return x, y, float(np.cos(t) / np.sin(t))


def _join_collinear(edges: list[FoundEdge], results: list[EdgeResult]):
    """Join pairs of collinear edges (same direction, angles within 1 deg, each centre within 1.5 px of the
    other's line): one straight line ``c = c0 + s a`` fitted by least squares to both halves' centre
    positions (variance ``sigma^2 / n``) and slopes (variance ``12 sigma^2 / n^3``), ``n`` lines each.
    Returns (edges, {index: the joint line (x, y, angle_deg) at that half's centre}); halves fitted with a
    curved (degree > 1) edge are not joined."""
    out = list(edges)
    lines: dict[int, tuple[float, float, float]] = {}
    used: set[int] = set()
    for i, j in itertools.combinations(range(len(edges)), 2):
        ri, rj = results[i], results[j]
        if i in used or j in used or ri.direction != rj.direction or ri.edge_point_xy is None:
            continue
        if max(getattr(ri, "fit_degree", 1), getattr(rj, "fit_degree", 1)) > 1:
            continue
        if abs(ri.angle_deg - rj.angle_deg) > 1.0:
            continue
        (ai, ci, si), (aj, cj, sj) = _line(ri), _line(rj)
        if abs(cj - ci - si * (aj - ai)) > 1.5 or abs(ci - cj - sj * (ai - aj)) > 1.5 or abs(aj - ai) < 10:
            continue
        ni, nj = float(ri.n_lines), float(rj.n_lines)
        a0 = 0.5 * (ai + aj)
        # rows: [1, a - a0] for positions (weight n), [0, 1] for slopes (weight n^3 / 12)
        design = np.array([[1.0, ai - a0], [1.0, aj - a0], [0.0, 1.0], [0.0, 1.0]])
        obs = np.array([ci, cj, si, sj])
        w = np.array([ni, nj, ni**3 / 12.0, nj**3 / 12.0])
        sol = np.linalg.solve(design.T @ (w[:, None] * design), design.T @ (w * obs))
        s = float(sol[1])
        ang = float(np.degrees(np.arctan(s))) if ri.direction == "ACT" else float(np.degrees(np.arctan2(1.0, s)))
        if ang > 90.0:
            ang -= 180.0
        for k, other, ak in ((i, j, ai), (j, i, aj)):
            out[k] = dataclasses.replace(out[k], angle_deg=ang, own_angle_deg=out[k].angle_deg, joined_with=other)
            ck = float(sol[0] + s * (ak - a0))
            lines[k] = (ck, ak, ang) if ri.direction == "ACT" else (ak, ck, ang)
        used |= {i, j}
    return out, lines


def _combine(direction: str, results: list[EdgeResult], pixel_m: float | None = None) -> CombinedMTF:
    """Inverse-variance weighted mean of the edges' MTF curves, Birge-inflated sigma, consistency flags; on the
    frequencies every edge reaches (the shortest band: a band-limited edge, or the row axis of the most tilted
    one)."""
    f = np.asarray(min((r.f_cy_per_px for r in results), key=lambda a: a[-1]), dtype=float)
    m = np.array([np.interp(f, r.f_cy_per_px, r.mtf) for r in results])
    s = np.array([np.interp(f, r.f_cy_per_px, _edge_sigma_curve(r)) for r in results])
    s[:, 0] = np.maximum(s[:, 0], 1e-9)
    w = 1.0 / s**2
    mean = (w * m).sum(axis=0) / w.sum(axis=0)
    sig = 1.0 / np.sqrt(w.sum(axis=0))
    n = len(results)
    i_nyq = int(np.argmin(np.abs(f - 0.5)))
    flags = []
    chi2r = scatter = None
    if n > 1:
        chi2 = (w * (m - mean) ** 2).sum(axis=0) / (n - 1)
        sig = sig * np.sqrt(np.maximum(chi2, 1.0))
        chi2r = float(chi2[i_nyq])
        scatter = float(np.std(m[:, i_nyq], ddof=1))
        if chi2r * (n - 1) > chi2_dist.ppf(0.99, n - 1):
            flags.append(
                f"{direction} edges disagree beyond their uncertainties at Nyquist (reduced chi2 {chi2r:.1f}); "
                "sigma inflated by the Birge ratio"
            )
    else:
        flags.append(f"{direction}: a single edge; no cross-check between edges")
    sig = np.sqrt(sig**2 + SIGMA_FLOOR**2)
    sig[0] = 0.0  # MTF(0) = 1 by normalisation
    if mean[i_nyq] < 3 * sig[i_nyq]:
        flags.append(
            f"{direction}: MTF at Nyquist {mean[i_nyq]:.3f} is within 3 sigma of 0; the noise biases a modulus "
            "upwards there, so read it as an upper bound"
        )
    if np.any(mean > MTF_VALID_MAX):
        flags.append(f"{direction}: combined MTF exceeds {MTF_VALID_MAX} somewhere; those values are withheld")
    m50 = first_crossing(f, mean, 0.5)
    return CombinedMTF(
        direction=direction,
        f_cy_per_px=f,
        mtf=mean,
        sigma=sig,
        n_edges=n,
        mtf_at_nyquist=float(mean[i_nyq]),
        mtf_at_nyquist_sigma=float(sig[i_nyq]),
        mtf50_cy_per_px=m50,
        scatter_at_nyquist=scatter,
        chi2_reduced_at_nyquist=chi2r,
        flags=tuple(flags),
        f_cy_per_m_ground=None if pixel_m is None else f / pixel_m,
        mtf50_cy_per_m_ground=None if (pixel_m is None or m50 is None) else m50 / pixel_m,
    )


def _add_tilt_systematic(combined: dict, edges: list[FoundEdge]) -> dict:
    """Add the tilt systematic in quadrature: an edge tilted by t measures the MTF along its normal, about
    ``MTF_dir^(cos^2 t) MTF_other^(sin^2 t)``, i.e. off the axis cut by ~ ``sin^2 t |MTF_ACT - MTF_ALT|``."""
    if len(combined) < 2:
        return combined
    diff = np.abs(combined["ACT"].mtf - combined["ALT"].mtf)
    out = {}
    for d, c in combined.items():
        s2 = float(np.mean([np.sin(np.deg2rad(e.candidate.tilt_deg)) ** 2 for e in edges if e.direction == d]))
        sig = np.sqrt(c.sigma**2 + (s2 * diff) ** 2)
        sig[0] = 0.0  # MTF(0) = 1 by normalisation
        i_nyq = int(np.argmin(np.abs(c.f_cy_per_px - 0.5)))
        out[d] = dataclasses.replace(c, sigma=sig, mtf_at_nyquist_sigma=float(sig[i_nyq]))
    return out


def _refusal(search: EdgeSearch, rejected: list[Rejection]) -> InputError:
    counts = rejection_counts(rejected)
    if not counts:
        why = "no straight high-contrast edge segment at all (blank, noise-only or smooth image)"
    else:
        ranked = sorted(counts.items(), key=lambda kv: -kv[1])
        why = ", ".join(f"{k}: {v}" for k, v in ranked)
        example = next(r.detail for r in rejected if r.reason == ranked[0][0])
        why = f"{sum(counts.values())} segment(s) rejected ({why}); e.g. {ranked[0][0]}: {example}"
    return InputError(f"image: no usable slanted edge found; {why}")


def measure_found_edges(
    image,
    *,
    pixel_m: float | None = None,
    min_length_px: float = 25.0,
    max_edges: int | None = None,
    min_cnr: float = 10.0,
    search: EdgeSearch | None = None,
    full_scale: float | None = None,
    valid=None,
    nodata: float | None = None,
    frequency_axis: str = "normal",
) -> FindResult:
    """Find every usable slanted edge of ``image``, measure each, and combine them into ACT and ALT MTFs.

    Parameters
    ----------
    image : array_like, 2-D
        The image (no truth file needed); a numpy masked array's masked pixels are excluded as ``valid =
        False`` ones are.
    pixel_m : float, optional
        Ground sample distance (m): adds ground frequencies (cy/m) to every edge, the combined curves and
        the CEOS table.
    min_length_px, max_edges, min_cnr
        Passed to :func:`~satchain.measure.find.find_edges`.
    search : EdgeSearch, optional
        A previous :func:`find_edges` result to measure instead of searching again.
    full_scale : float, optional
        The sensor's full scale in the image's units, passed to the edge measurement (an edge with more than
        1 % of its pixels there is refused as clipped); integer images default to their dtype maximum.
    valid : array_like of bool, optional
        Pixels to use (True), e.g. the area-of-interest mask; excluded pixels are left out of the search,
        the noise and every edge's ESF, and are never clipping.
    nodata : float, optional
        Pixels equal to this value are excluded as well (0 for the zero-filled crops cal/val tools write).
        Without ``valid`` and ``nodata``, the zeros of an integer image are excluded where they are evidently a
        fill (:func:`~satchain.measure._zero_fill.zero_fill_mask`, noisy or not; flagged, as is a fill that
        the evidence cannot tell from a clipped dark area and that stays data).
    frequency_axis : {"normal", "row"}
        ``"normal"`` (default): every edge's MTF along its normal.  ``"row"``: along the image row (ACT) or
        column (ALT), as MTF_Estimator reports it: each edge's normal axis scaled by the cosine of its tilt
        (``MTF_row(f) = MTF_normal(f / cos t)``, see :func:`~satchain.measure.edge.measure_edge`), before
        the edges are combined.

    Returns
    -------
    FindResult
        ``combined`` maps "ACT"/"ALT" to a :class:`CombinedMTF` for each direction with at least one edge.

    Raises
    ------
    InputError
        No usable edge (the message counts the rejected segments by reason).

    Examples
    --------
    >>> y, x = np.mgrid[0:160, 0:160]
    >>> t = np.deg2rad(6.0)
    >>> img = 0.2 + 0.6 / (1 + np.exp(-((x - 80.3) * np.cos(t) - (y - 80) * np.sin(t)) / 0.5))
    >>> res = measure_found_edges(img)
    >>> sorted(res.combined), res.edges[0].direction
    (['ACT'], 'ACT')
    """
    image, valid = unmask(image, valid)
    ok, fill_note = valid_mask(image, valid, nodata), None
    if ok is None and valid is None and nodata is None:
        ok, fill_note = zero_fill_mask(image)
    if search is None:
        search = find_edges(image, min_length_px=min_length_px, max_edges=max_edges, min_cnr=min_cnr, valid=ok)
    opts: dict[str, Any] = {"pixel_m": pixel_m, "full_scale": full_scale, "frequency_axis": check_axis(frequency_axis)}
    rejected = list(search.rejected)
    edges, results = [], []
    for c in search.candidates:
        r, why = _measure_one(image, c, opts, ok)
        if r is None:
            rejected.append(Rejection(c.center_xy, c.angle_deg, c.length_px, "measurement refused", why))
            continue
        edges.append(_found(c, r, pixel_m))
        results.append(r)
    if not edges:
        raise _refusal(search, rejected)
    edges, lines = _join_collinear(edges, results)
    edges, results = _on_joint_lines(image, edges, results, lines, opts, ok)
    combined = {}
    for d in ("ACT", "ALT"):
        rs = [r for r in results if r.direction == d]
        if rs:
            combined[d] = _combine(d, rs, pixel_m)
    combined = _add_tilt_systematic(combined, edges)
    flags = list(search.warnings) + ([fill_note] if fill_note else [])
    for d in ("ACT", "ALT"):
        if d not in combined:
            flags.append(f"no usable {d} edge: only the {'ALT' if d == 'ACT' else 'ACT'} MTF is measured")
    rows, cols = np.shape(image)
    shape = (int(rows), int(cols))
    return FindResult(
        tuple(edges), combined, tuple(rejected), search.noise_sigma, shape, tuple(flags), tuple(results),
        pixel_m=pixel_m, frequency_axis=opts["frequency_axis"],
    )  # fmt: skip


def ceos_table(
    result: FindResult, *, step: float = 0.02, f_max: float = 0.5, pixel_m: float | None = None
) -> dict[str, np.ndarray]:
    """MTF at normalised frequencies f / f_s = 0, step, ..., f_max and 0.25 (half Nyquist): columns
    ``f_over_fs``, ``mtf_act``, ``mtf_act_sigma``, ``mtf_alt``, ``mtf_alt_sigma`` (NaN where a direction is
    missing or a value is outside [0, 1.2]); with a ground pixel size (``pixel_m``, else the result's) also
    ``f_cy_per_m_ground`` = (f / f_s) / pixel_m, the ground frequency of each row.

    ``f_s`` is the sampling frequency (1 cy/px), so 0.5 is Nyquist; ``f_max`` in (0, 1].  The frequencies are
    on the result's ``frequency_axis`` (along the edge normal, or the image row / column).
    """
    check_range("step", step, 0.0, 0.5, lo_open=True)
    check_range("f_max", f_max, 0.0, 1.0, lo_open=True)
    p = pixel_m if pixel_m is not None else getattr(result, "pixel_m", None)
    fn = np.round(np.arange(0.0, f_max + step / 2, step), 10)
    fn = np.union1d(fn, [0.25]) if f_max >= 0.25 else fn  # the CEOS row at half Nyquist, whatever the step
    out = {"f_over_fs": fn, **({"f_cy_per_m_ground": fn / p} if p else {})}
    for d in ("ACT", "ALT"):
        c = result.combined.get(d)
        if c is None:
            m = s = np.full(fn.size, np.nan)
        else:
            m = np.interp(fn, c.f_cy_per_px, c.mtf, right=np.nan)
            s = np.interp(fn, c.f_cy_per_px, c.sigma, right=np.nan)
            bad = ~((m >= 0) & (m <= MTF_VALID_MAX))
            m, s = np.where(bad, np.nan, m), np.where(bad, np.nan, s)
        out[f"mtf_{d.lower()}"] = m
        out[f"mtf_{d.lower()}_sigma"] = s
    return out


def ceos_csv(result: FindResult, *, step: float = 0.02, f_max: float = 0.5, pixel_m: float | None = None) -> str:
    """The :func:`ceos_table` as CSV text (empty cells where a value is not available).

    With a ground pixel size (``pixel_m``, else the result's) a column ``f_cy_per_m_ground`` = (f / f_s) /
    pixel_m is added.
    """
    t = ceos_table(result, step=step, f_max=f_max, pixel_m=pixel_m)
    cols: list[str] = [k for k in ("f_over_fs", "f_cy_per_m_ground") if k in t]
    cols += ["mtf_act", "mtf_act_sigma", "mtf_alt", "mtf_alt_sigma"]
    lines = [",".join(cols)]
    for i in range(t["f_over_fs"].size):
        cells = []
        for k in cols:
            v = float(t[k][i])
            cells.append("" if not np.isfinite(v) else (f"{v:.2f}" if k == "f_over_fs" else f"{v:.6g}"))
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"
