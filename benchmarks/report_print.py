"""Print a run's report.html to A4 with headless Chromium and count pages and half-empty pages.

Usage: ``python benchmarks/report_print.py RUN_DIR`` (needs ``chromium`` and poppler's ``pdftoppm``; not a
test: neither is a project dependency). A page is half-empty when its content ends above half its height
(the last page excepted). Prints the page weight of report.html too.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image


def main(run_dir: str) -> None:
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
