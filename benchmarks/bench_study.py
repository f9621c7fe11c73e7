"""What a design study costs against doing its work by hand (issue 31 point 6).

1. Budget depth: ``satchain.study`` of 1,000 cases (40 apertures x 25 wavefront errors; every case validated,
   budgeted, written to study.csv / study.parquet and drawn on study.html) against the same 1,000 systems built
   and budgeted in one loop (``vary_system`` then ``satchain.budget``). Target: ratio < 2.
2. Run depth: 16 cases of a small scene (the tests' reduced scene: two edges, a star, a wedge) through the whole
   chain with 2 local workers against 1 worker (in this process). Target: throughput ratio >= 1.5 (on a machine
   with at least 2 free cores). Printed too: the peak resident memory of each worker (from each case's record),
   which bounds a worker's memory whatever the number of cases.

Run:  python benchmarks/bench_study.py [--budget-only] [--cases 16]
"""

from __future__ import annotations

import argparse
import re
import tempfile
import time
from pathlib import Path

import numpy as np

import satchain

ROOT = Path(__file__).resolve().parents[1]
AP, WFE = "optics.aperture_diameter_m", "optics.wfe_rms_waves"


def bench_budget() -> None:
    from satchain.studies.design import vary_system

    aps = [float(x) for x in np.round(np.linspace(0.3, 1.0, 40), 6)]
    wfes = [float(x) for x in np.round(np.linspace(0.0, 0.12, 25), 6)]
    base = satchain.load_preset("ankarasat3")
    t0 = time.perf_counter()
    for a in aps:
        for w in wfes:
            satchain.budget(vary_system(vary_system(base, AP, a), WFE, w))
    by_hand = time.perf_counter() - t0
    spec = {"base": {"system": {"preset": "ankarasat3"}}, "axes": [{"key": AP, "values": aps}, {"key": WFE,
            "values": wfes}]}  # fmt: skip
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        r = satchain.study(spec, Path(d) / "out")
        study = time.perf_counter() - t0
        size = sum(p.stat().st_size for p in (Path(d) / "out").iterdir()) / 2**20
    print(f"budget depth, {r.n_cases} cases: study {study:.2f} s (tables, page {size:.1f} MB included); "
          f"1000 budgets by hand {by_hand:.2f} s; ratio {study / by_hand:.2f} (target < 2)")  # fmt: skip


def bench_run(n_cases: int) -> None:
    text = (ROOT / "tests" / "conftest.py").read_text()
    m = re.search(r'REDUCED_SCENE_TOML = """(.*?)"""', text, re.S)
    assert m is not None
    wfes = [round(0.1 * i / (n_cases - 1), 6) for i in range(n_cases)]
    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "scene.toml").write_text(m.group(1))
        (Path(d) / "run.toml").write_text('[system]\npreset = "ankarasat3"\n[scene]\nlayout = "scene.toml"\n')
        f = Path(d) / "study.toml"
        f.write_text(f'[base]\nfile = "run.toml"\n[[axes]]\nkey = "{WFE}"\nvalues = {wfes}\n[study]\ndepth = "run"\n')
        satchain.run(str(Path(d) / "run.toml"))  # warm: imports and caches, so both sides start equal
        times = {}
        rss = {}
        for workers in (1, 2):
            t0 = time.perf_counter()
            r = satchain.study(f, Path(d) / f"w{workers}", workers=workers)
            times[workers] = time.perf_counter() - t0
            rss[workers] = r.peak_rss_mb
            assert r.n_ok + r.n_failed == n_cases, r.errors
    ratio = times[1] / times[2]
    print(f"run depth, {n_cases} cases: 1 worker {times[1]:.1f} s ({n_cases / times[1]:.2f} cases/s), 2 workers "
          f"{times[2]:.1f} s ({n_cases / times[2]:.2f} cases/s); throughput ratio {ratio:.2f} (target >= 1.5)")
    print(f"peak RSS per worker: {rss[2]:.0f} MB with 2 workers (this process, 1 worker: {rss[1]:.0f} MB)")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--budget-only", action="store_true")
    ap.add_argument("--cases", type=int, default=16)
    a = ap.parse_args()
    if a.cases < 2:
        ap.error(f"--cases = {a.cases}: must be at least 2")
    bench_budget()
    if not a.budget_only:
        bench_run(a.cases)


if __name__ == "__main__":
    main()
