"""The self-contained HTML report of a ``satchain run``: results first, the image shown, the comparison obvious.

Every figure and thumbnail is embedded as a PNG data URI and click-to-zoom is pure HTML/CSS (``<details>``),
so the page needs nothing outside itself. The report reads its inputs only through these attributes of
``ctx``: ``out``, ``system``, ``otf``, ``budget``, ``truth``, ``image``, ``focal_plane``, ``simulator``,
``measured``, ``comparison["results"]``, ``config`` (and ``timings_s`` / ``scene`` when present).
"""

from __future__ import annotations

import base64
from pathlib import Path

from jinja2 import Environment, PackageLoader, select_autoescape
from markupsafe import Markup

import satchain
from satchain import ctf as _ctf
from satchain.report import tables
from satchain.report._save import write_text
from satchain.report.budget import DirectionalMTF

__all__ = ["SECTIONS", "table1_rows", "write_report"]

#: The report's sections (anchor id, title), in order; the table of contents lists them.
SECTIONS = (
    ("summary", "Measured vs predicted: summary"),
    ("paper", "The reference paper and where the prediction comes from"),
    ("image", "The simulated image and every target"),
    ("edges", "Slanted edges: ESF, LSF and MTF"),
    ("star", "Siemens star: MTF per direction"),
    ("bars", "Bar targets: CTF"),
    ("wedges", "Hyperbolic wedges: resolution (Figure 4)"),
    ("niirs", "SNR and NIIRS"),
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
    resolution (integer-upscaled when small, pixels kept square)."""
    k = max(1, min(16, 900 // max(panel["width"], 1)))
    return Markup(
        '<details class="zoom"><summary title="click to zoom; click again to close">'
        '<img class="thumb" src="{}" alt="{}" width="{}" height="{}" style="--tw: {:.0f}px; --zw: {}px">'
        '</summary><p class="zoomnote">{} — {} × {} px of {} cm, shown ×{}; click the image to close</p></details>'
    ).format(
        Markup(_data_uri(panel["png"])),
        alt,
        panel["width"],
        panel["height"],
        display_w,
        panel["width"] * k,
        alt,
        panel["width"],
        panel["height"],
        f"{panel['pixel_m'] * 100:.3g}",
        k,
    )


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


def write_report(ctx, path: Path, *, curve_files: list[str] | None = None) -> None:
    """Render ``report.html`` from the run's figures (``ctx.out/figures``, ``ctx.out/budget``) and results."""
    from satchain.report.gallery import target_thumbnails

    out = ctx.out
    figs, budget_dir = out / "figures", out / "budget"
    res = ctx.comparison["results"]
    env = Environment(
        loader=PackageLoader("satchain.report", "templates"), autoescape=select_autoescape(["html", "j2"])
    )
    t1, is_paper = table1_rows(ctx)
    if curve_files is None:
        curve_files = sorted(p.name for p in (out / "curves").glob("*.csv"))
    timings = getattr(ctx, "timings_s", None) or {}
    html = env.get_template("report.html.j2").render(
        system=ctx.system,
        version=satchain.__version__,
        seed=ctx.config.simulation.seed,
        total_s=sum(timings.values()),
        sections=SECTIONS,
        verdict=tables.verdict(res),
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
        thumbs=target_thumbnails(ctx),
        table1=t1,
        table1_paper=is_paper,
        curve_files=curve_files,
        fig=lambda name, cap, cls="": _figure_html(figs / name, cap, cls=cls),
        bfig=lambda name, cap, cls="": _figure_html(budget_dir / name, cap, cls=cls),
        zoom=_zoom_img,
        fmt=tables.fmt,
    )
    write_text(path, html)
