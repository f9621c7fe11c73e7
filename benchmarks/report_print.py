"""Print a run's report.html to A4 with headless Chromium and count pages and half-empty pages.

Usage: ``python benchmarks/report_print.py RUN_DIR`` (needs ``chromium`` and poppler's ``pdftoppm``; not a
test: neither is a project dependency). A page is half-empty when its content ends above half its height
(the last page excepted). Prints the page weight of report.html, how many of results.json's flags the page
shows, and the sigma of every summary row too.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from markupsafe import escape
from PIL import Image


def flags_and_sigma(run_dir: Path) -> None:
    res = json.loads((run_dir / "results.json").read_text())
    page = (run_dir / "report.html").read_text()
    keys = ("slanted_edges", "siemens_star", "bar_targets", "hyperbolic_wedge")
    flags = [str(f) for k in keys for x in res.get(k, []) for f in x.get("flags") or []]
    flags += [str(w) for w in res.get("warnings") or []]
    shown = sum(str(escape(f)) in page for f in flags)  # as jinja2 escapes it
    print(f"flags in results.json: {len(flags)}; shown in report.html: {shown}")
    for r in res["summary"]:
        err, sig, z = (r.get(k) for k in ("error", "sigma", "z"))
        err = "-" if err is None else format(err, "+.4g")
        sig = "-" if sig is None else format(sig, ".2g")
        z = "-" if z is None else format(z, "+.2f")
        print(f"  {r['figure']:48s} error {err:>10}  sigma {sig:>7}  z {z:>6}  {r.get('sigma_null_means') or ''}")


def main(run_dir: str) -> None:
    flags_and_sigma(Path(run_dir).resolve())
    html = Path(run_dir).resolve() / "report.html"
    with tempfile.TemporaryDirectory() as tmp:
        pdf = Path(tmp) / "r.pdf"
        subprocess.run(
            ["chromium", "--headless", "--no-sandbox", "--disable-gpu", f"--print-to-pdf={pdf}", html.as_uri()],
            check=True,
            capture_output=True,
        )
        subprocess.run(["pdftoppm", "-r", "30", "-png", str(pdf), str(Path(tmp) / "p")], check=True)
        pages = sorted(Path(tmp).glob("p-*.png"))
        ends = []
        for p in pages:
            a = np.asarray(Image.open(p).convert("L"), float)
            h = a.shape[0]
            body = a[int(0.04 * h) : int(0.95 * h)]  # without the browser's header and footer lines
            rows = np.flatnonzero((body < 235).any(axis=1))
            ends.append(0.0 if rows.size == 0 else (rows[-1] + 1) / body.shape[0])
    half = [i + 1 for i, e in enumerate(ends[:-1]) if e < 0.5]
    print(f"report.html: {html.stat().st_size / 1e6:.2f} MB; A4 pages: {len(pages)}; half-empty pages: {half}")
    print("content ends at (fraction of page):", " ".join(f"{e:.2f}" for e in ends))


if __name__ == "__main__":
    main(sys.argv[1])
