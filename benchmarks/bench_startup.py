"""Start-up cost (issue 21, point 3): ``import satchain`` and ``satchain --help`` against a bare interpreter's
start, each the median of N fresh processes.

Usage: ``python benchmarks/bench_startup.py [--n 15]``
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time


def _median_s(argv: list[str], n: int) -> float:
    times = []
    for _ in range(n):
        t = time.perf_counter()
        subprocess.run(argv, check=True, capture_output=True)
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=15)
    n = ap.parse_args().n
    py = sys.executable
    bare = _median_s([py, "-c", "pass"], n)
    cases = {
        "import satchain": [py, "-c", "import satchain"],
        "import satchain; satchain.load_preset(...)": [py, "-c", "import satchain; satchain.load_preset('ankarasat3')"],
        "import numpy (reference)": [py, "-c", "import numpy"],
        "satchain --help": [py, "-m", "satchain.cli.main", "--help"],
        "satchain measure --help": [py, "-m", "satchain.cli.main", "measure", "--help"],
        "import typer, rich (reference)": [py, "-c", "import typer, rich.console"],
    }
    print(f"bare interpreter start: {bare * 1e3:.0f} ms (median of {n})")
    for name, argv in cases.items():
        t = _median_s(argv, n)
        print(f"{name:45s} {t * 1e3:7.0f} ms   beyond the bare start {(t - bare) * 1e3:6.0f} ms")


if __name__ == "__main__":
    main()
