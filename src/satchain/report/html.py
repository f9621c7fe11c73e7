"""The self-contained HTML report of a ``satchain run`` (every figure embedded as a data URI)."""

from __future__ import annotations

import base64
import math
from pathlib import Path

import numpy as np
from jinja2 import Environment, PackageLoader, select_autoescape
from markupsafe import Markup

import satchain
from satchain import ctf as _ctf
from satchain.report._save import write_text
from satchain.report.budget import DirectionalMTF

__all__ = ["table1_rows", "write_report"]


def _fmt(v) -> str:
    if v is None:
        return "–"
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, (float, np.floating)):
        return "–" if not math.isfinite(v) else f"{v:.4g}"
    if isinstance(v, (list, tuple)):
        return ", ".join(_fmt(x) for x in v)
    return str(v)


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


def write_report(ctx, path: Path) -> None:
    figs = ctx.out / "figures"

    def img(name: str, caption: str) -> Markup:
        p = (figs / name).resolve()
        if not p.exists():
            return Markup("")
        data = base64.b64encode(p.read_bytes()).decode("ascii")
        return Markup(
            '<figure><img src="data:image/png;base64,{}" alt="{}"><figcaption>{}</figcaption></figure>'
        ).format(Markup(data), caption, caption)

    env = Environment(
        loader=PackageLoader("satchain.report", "templates"), autoescape=select_autoescape(["html", "j2"])
    )
    res = ctx.comparison["results"]
    rows = res["summary"]
    plots = [
        (n, c)
        for n, c in (
            ("edges_mtf.png", "Slanted edges: measured e-SFR vs the predicted MTF along each edge normal."),
            ("star_mtf.png", "Siemens star: MTF per direction, measured vs predicted."),
            (
                "bars_ctf.png",
                "Bar targets: measured CTF vs Coltman's predicted CTF (and the paper's method).",
            ),
            (
                "wedge_contrast.png",
                "Hyperbolic wedges: contrast across the stripes along the wedge (the paper's scan).",
            ),
        )
    ]
    chains = [
        (p.name, p.stem.replace("_", " "))
        for p in sorted(figs.glob("fig4_wedge_*.png")) + sorted(figs.glob("target_*.png"))
    ]
    t1, is_paper = table1_rows(ctx)
    html = env.get_template("report.html.j2").render(
        system=ctx.system,
        version=satchain.__version__,
        seed=ctx.config.simulation.seed,
        total_s=sum(ctx.timings_s.values()),
        rows=rows,
        n_pass=sum(r["pass"] is True for r in rows),
        n_checked=sum(r["pass"] is not None for r in rows),
        derived=ctx.budget["derived"],
        results=res,
        radiometry=ctx.budget["radiometry"],
        table1=t1,
        table1_paper=is_paper,
        plots=plots,
        chains=chains,
        img=img,
        fmt=_fmt,
    )
    write_text(path, html)
