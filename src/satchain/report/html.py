"""The self-contained HTML report of a ``satchain run``: results first, the image shown, the comparison obvious.

Every figure and thumbnail is embedded as a PNG data URI and click-to-zoom is pure HTML/CSS (``<details>``),
so the page needs nothing outside itself. The report reads its inputs only through these attributes of
``ctx``: ``out``, ``system``, ``otf``, ``budget``, ``truth``, ``image``, ``focal_plane``, ``simulator``,
``measured``, ``comparison["results"]``, ``config`` (and ``timings_s`` / ``scene`` when present).
"""

from __future__ import annotations

import base64
import functools
import re
from pathlib import Path

from jinja2 import Environment, PackageLoader, select_autoescape
from markupsafe import Markup

import satchain
from satchain.report import tables
from satchain.report._save import write_text
from satchain.report.budget import DirectionalMTF
from satchain.report.focal_plane import focal_parts
from satchain.report.kinds import BARS, WEDGES, measured_entries
from satchain.tf import ctf as _ctf

__all__ = ["SECTIONS", "table1_rows", "write_report"]

#: The report's sections (anchor id, title), in order; the table of contents lists them.
SECTIONS = (
    ("summary", "Measured vs predicted: summary"),
    ("edges", "Slanted edges: ESF, LSF and MTF"),
    ("star", "Siemens star: MTF per direction"),
    ("bars", "Bar targets: CTF"),
    ("wedges", "Hyperbolic wedges: resolution (Figure 4)"),
    ("niirs", "SNR and NIIRS"),
    ("focal-plane", "The focal plane as flown: bands, colour planes, staggered arrays"),
    ("image", "The simulated image and every target"),
    ("paper", "The reference paper and where the prediction comes from"),
    ("camera", "Camera, geometry and radiometry (Figure 2)"),
    ("budget", "MTF budget and Table 1 (Figure 3)"),
    ("scene", "Synthetic ground truth (Figure 1)"),
    ("not-measured", "Not measured"),
    ("files", "Files and reproduction"),
)


def table1_rows(ctx) -> tuple[list[dict], bool]:
    """The paper's Table 1 at its focal-plane frequencies (cy/mm) for this system; the paper's own columns
    beside it when the system is the paper's."""
    from satchain.presets.paper import read_table1

    t, s = read_table1(), ctx.system
    m = DirectionalMTF(ctx.otf, "alt")
    f = t.f_cy_per_mm
    col = _ctf.coltman_ctf(f, m)
    paper = _ctf.ctf_fourier_synthesis(f, m)
    g = f / s.focal_cy_per_mm_per_ground_cy_per_m("alt")
    is_paper = s.name == "ankarasat3"
    rows = [
        {
            "f": float(f[i]),
            "period": float(1 / g[i]),
            "mtf": float(m(f[i])),
            "coltman": float(col[i]),
            "paper_method": float(paper[i]),
            "paper_mtf": float(t.system_mtf[i]),
            "paper_ctf": float(t.ctf[i]),
        }
        for i in range(f.size)
    ]
    return rows, is_paper


def micro_sign(text) -> str:
    """Write micrometres as "µm" (system descriptions are free text and may say "5.88 um")."""
    return _UM.sub(r"\1µm", str(text or ""))


_UM = re.compile(r"(\d\s?)um\b")


def _data_uri(png: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def _figure_html(path: Path, caption: str, *, cls: str = "") -> Markup:
    """A figure file as an embedded <figure> (nothing when the file is missing); a click opens it at its
    native size (for phones, where the page shrinks it)."""
    if not path.exists():
        return Markup("")
    png = path.read_bytes()
    width = int.from_bytes(png[16:20], "big") if png[:8] == b"\x89PNG\r\n\x1a\n" else 0
    return Markup(
        '<figure class="{}"><details class="zoom fig"><summary title="click to enlarge; click again to close">'
        '<img src="{}" alt="{}" style="--zw: {}px"></summary></details><figcaption>{}</figcaption></figure>'
    ).format(cls, Markup(_data_uri(png)), caption, width or 1000, caption)


def _zoom_img(panel: dict, alt: str, display_w: float) -> Markup:
    """A thumbnail ``display_w`` CSS px wide (at most) that opens, on click, as an overlay at native
    resolution (integer-upscaled when small, pixels kept square); the target's region overlay on top."""
    k = max(1, min(16, 900 // max(panel["width"], 1)))
    return Markup(
        '<details class="zoom"><summary title="click to zoom; click again to close"><span class="ovwrap">'
        '<img class="thumb" src="{}" alt="{}" width="{}" height="{}" style="--tw: {:.0f}px; --zw: {}px">{}'
        '</span></summary><p class="zoomnote">{} — {} × {} px of {} cm, shown ×{}; click the image to close</p>'
        "</details>"
    ).format(
        Markup(_data_uri(panel["png"])),
        alt,
        panel["width"],
        panel["height"],
        display_w,
        panel["width"] * k,
        Markup(panel.get("overlay", "")),
        alt,
        panel["width"],
        panel["height"],
        f"{panel['pixel_m'] * 100:.3g}",
        k,
    )


def _thumbs_with_overlays(ctx, thumbs: list[dict], lim: float) -> list[dict]:
    """The gallery's targets with their display width (CSS px) and each panel's region overlay."""
    from satchain.report.gallery import mapped_box, panel_maps
    from satchain.report.kinds import overlay_svg

    items = {it["id"]: it for it in ctx.truth["items"]}
    meas = ctx.measured or {}
    by_id = {m["id"]: m for _, m in measured_entries(meas)}
    origin = tuple(meas.get("origin_m") or (0.0, 0.0))
    geo = getattr(ctx, "image_affine", None)  # a pushbroom image's map from truth metres to its pixels
    maps = panel_maps(ctx)
    for t in thumbs:
        w, h = t["box_m"][2] - t["box_m"][0], t["box_m"][3] - t["box_m"][1]
        t["wide"] = w > 2.5 * h
        t["tw"] = min(1100 if t["wide"] else 360, 420 * w / h)
        for p in t["panels"]:  # each panel's overlay in its own coordinates (the detector's: the image's pixels)
            pm = maps.get(p.get("title"))
            p["overlay"] = overlay_svg(items.get(t["id"], {}), by_id.get(t["id"]), mapped_box(pm, t["box_m"]),
                                       gsd_m=float(ctx.image_gsd_m), origin_m=origin, compared_up_to_cy_per_px=lim,
                                       display_px=t["tw"], to_image=geo, panel=pm)  # fmt: skip
    return thumbs


def _bar_rows(b: dict) -> list[dict]:
    """A bar target's groups: raw and corrected CTF, correction, 1-sigma, Coltman, difference, z, flags."""
    f = b.get("f_cy_per_px") or []
    lim = b.get("compared_up_to_cy_per_px") or 0.4
    n = len(f)

    def col(key):
        v = b.get(key) or []
        return v if len(v) == n else [None] * n

    raw, meas, corr, std, pred = (col(k) for k in ("ctf_raw_measured", "ctf_measured", "ctf_correction",
                                                     "ctf_std_measured", "ctf_coltman_predicted"))  # fmt: skip
    given = b.get("group") or []
    groups = given if len(given) == n else list(range(n))  # the design's numbers
    floor = col("at_noise_floor")
    ab = (b.get("as_built") or {}).get("ctf_coltman_predicted") or []
    ab = ab if len(ab) == n else [None] * n
    rows = []
    for j in range(n):
        d = tables._diff(meas[j], pred[j])
        s = tables._num(std[j])
        rows.append({
            "f": tables.fmt(f[j], 3), "period": tables.fmt(1 / f[j] if f[j] else None, 2),
            "raw": tables.fmt(raw[j]), "corr": tables.fmt(corr[j], 3, signed=True), "ctf": tables.fmt(meas[j]),
            "std": tables.fmt(s, 3), "pred": tables.fmt(pred[j]), "diff": tables.fmt(d, 3, signed=True),
            "z": tables.fmt(d / s, 1, signed=True) if d is not None and s else "–",
            "compared": f[j] <= lim + 1e-12,
            "flags": [x for x in b.get("flags") or [] if x.startswith(f"group {groups[j]}:")],
            "group": groups[j], "floor": floor[j] is True,
            "ab": tables.fmt(None if tables._num(ab[j]) is None else round(float(ab[j]), 6)),  # a null: 0, not 7e-17
        })  # fmt: skip
    return rows


def _correction_range(b: dict) -> tuple[float, float] | None:
    c = [v for v in (tables._num(x) for x in b.get("ctf_correction") or []) if v is not None and v != 0]
    return (min(c), max(c)) if c else None


def _all_flags(ctx, res: dict) -> dict:
    """The flags results.json holds per target, plus the measurement's own flags of targets whose
    results.json entry carries none (the wedges')."""
    out = tables.measurement_flags(res)
    for m in (ctx.measured or {}).get(WEDGES.key, []):
        if not out.get(m.get("id")):
            out[m.get("id")] = [str(f) for f in m.get("flags") or []]
    return out


def _bar_limit(res: dict) -> float:
    from satchain.comparison import BAR_COMPARE_MAX_CY_PER_PX

    bars = res.get(BARS.key) or []
    return float(bars[0].get("compared_up_to_cy_per_px") or BAR_COMPARE_MAX_CY_PER_PX) if bars else 0.4


def _snr_rel_sigma() -> float:
    """The SNR's 1-sigma (relative) the NIIRS check assumes when the SNR measurement gives none."""
    from satchain.comparison.sigma import SNR_REL_SIGMA

    return float(SNR_REL_SIGMA)


def _fit_rows(system) -> list[dict]:
    prov = getattr(system, "provenance", None) or {}
    names = prov.get("fitted_parameters") or []
    vals = prov.get("fitted_values") or []
    errs = prov.get("fitted_stderr") or [None] * len(names)
    out = []
    for n, v, e in zip(names, vals, errs, strict=False):
        scale, unit, dig = (1e9, "nm", 2) if n.endswith("wavelength_m") else (1, "px" if "px" in n else "", 4)
        out.append(
            {
                "name": n,
                "value": tables.fmt(v * scale, dig, unit=unit),
                "sigma": tables.fmt(None if e is None else e * scale, dig, unit=unit),
            }
        )
    return out


@functools.lru_cache(maxsize=1)
def _environment() -> Environment:
    """The report's Jinja environment, made once per process: it keeps the compiled template (compiling it costs
    about 60 ms, more than rendering it), and reloads it if the file changes."""
    env = Environment(
        loader=PackageLoader("satchain.report", "templates"), autoescape=select_autoescape(["html", "j2"])
    )
    env.tests["group_flag"] = lambda f: str(f).startswith("group ")
    env.filters["micro"] = micro_sign
    return env


def write_report(
    ctx, path: Path, *, curve_files: list[str] | None = None, thumbnails: list[dict] | None = None
) -> None:
    """Render ``report.html`` from the run's figures (``ctx.out/figures``, ``ctx.out/budget``) and results."""
    from satchain.report.gallery import target_thumbnails

    out = ctx.out
    figs, budget_dir = out / "figures", out / "budget"
    res = ctx.comparison["results"]
    env = _environment()
    t1, is_paper = table1_rows(ctx)
    if curve_files is None:
        curve_files = sorted(p.name for p in (out / "curves").glob("*.csv"))
    timings = getattr(ctx, "timings_s", None) or {}
    focal = focal_parts(res, figs)  # bands, colour planes, staggered arrays (their figures drawn here)
    html = env.get_template("report.html.j2").render(
        system=ctx.system,
        version=satchain.__version__,
        seed=ctx.config.simulation.seed,
        total_s=sum(timings.values()),
        sections=[s for s in SECTIONS if s[0] != "focal-plane" or focal],
        focal=focal,
        verdict=tables.verdict(res),
        failed=tables.failed_checks(res),
        snr_rel_sigma=_snr_rel_sigma(),
        key=tables.key_figures(res, ctx.budget),
        rows=tables.summary_rows(res),
        paper=tables.paper_rows(res),
        fit=_fit_rows(ctx.system),
        provenance=getattr(ctx.system, "provenance", None) or {},
        citation=tables.PAPER_CITATION,
        camera=tables.camera_rows(ctx.system),
        derived=tables.derived_rows(ctx.budget["derived"]),
        radiometry=tables.radiometry_rows(ctx.budget["radiometry"]),
        skipped=tables.skipped_groups(res.get("skipped", [])),
        n_skipped=len(res.get("skipped", [])),
        results=res,
        as_built=res.get("as_built_differences") or [],
        tol=res.get("tolerances") or {},
        thumbs=_thumbs_with_overlays(
            ctx, target_thumbnails(ctx) if thumbnails is None else thumbnails, _bar_limit(res)
        ),
        flags=_all_flags(ctx, res),
        bar_rows=_bar_rows,
        correction_range=_correction_range,
        sigma_text=tables.sigma_text,
        table1=t1,
        table1_paper=is_paper,
        curve_files=curve_files,
        fig=lambda name, cap, cls="": _figure_html(figs / name, cap, cls=cls),
        bfig=lambda name, cap, cls="": _figure_html(budget_dir / name, cap, cls=cls),
        zoom=_zoom_img,
        fmt=tables.fmt,
    )
    write_text(path, html)
