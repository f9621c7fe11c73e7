"""What the Python API costs: ``satchain.run`` in memory vs the same run writing its run directory.

The run is ``satchain run``'s built-in default (the reference paper's camera and scene), or with ``--reduced`` the
end-to-end tests' reduced scene (tests/conftest.py ``REDUCED_SCENE_TOML``: edges, a star, bars and wedges on 170 m x
140 m, 7 cm ground-truth pixels). Printed: wall time of ``satchain.run(config)``
(budget, scene, simulation, measurement, prediction, comparison; nothing written), of
``satchain.run(config, out_dir=...)`` (the same plus figures, report.html, results.json, images), their
ratio, and the stage timings; best of ``--repeat`` runs (default 2). Also the CPU time of each (this process and
the figure helpers it started) and the wall time that CPU time needs at the least on this machine's CPUs: the
run folder cannot come in under that however its work is scheduled, so the printed "CPU floor" ratio is what
scheduling alone could reach.

Run:  PYTHONPATH=src python benchmarks/bench_run_api.py [--repeat N]
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import tempfile
import time
from pathlib import Path

import satchain

ROOT = Path(__file__).resolve().parents[1]


def _cpu() -> tuple[float, float]:
    """CPU seconds (user + system) of this process and of its children that have ended."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime, kids.ru_utime + kids.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--reduced", action="store_true", help="the tests' reduced scene instead of the default run")
    a = ap.parse_args()
    if a.repeat < 1:
        ap.error(f"--repeat = {a.repeat}: must be a whole number >= 1")
    n = a.repeat
    text = (ROOT / "tests" / "conftest.py").read_text()
    scene = re.search(r'REDUCED_SCENE_TOML = """(.*?)"""', text, re.S).group(1)
    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "scene.toml").write_text(scene)
        config = {"scene": {"layout": str(Path(d) / "scene.toml"), "pixel_m": 0.07}, "simulation": {"seed": 11}}
        if not a.reduced:
            config = None
        mem, disk, mem_cpu, disk_cpu = [], [], [], []
        for i in range(n):
            c0, t0 = _cpu(), time.perf_counter()
            r = satchain.run(config)
            mem.append(time.perf_counter() - t0)
            mem_cpu.append(_cpu()[0] - c0[0])
            c0, t0 = _cpu(), time.perf_counter()
            satchain.run(config, out_dir=Path(d) / f"out{i}")
            disk.append(time.perf_counter() - t0)
            c1 = _cpu()
            disk_cpu.append((c1[0] - c0[0], c1[1] - c0[1]))
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    own, helpers = min(c[0] for c in disk_cpu), min(c[1] for c in disk_cpu)
    print(f"satchain.run in memory:          {min(mem):6.2f} s   stages {dict(r.timings_s)}")
    print(f"satchain.run with out_dir:       {min(disk):6.2f} s")
    print(f"ratio (with report / in memory): {min(disk) / min(mem):6.2f}")
    floor = max(min(mem), (own + helpers) / cpus)
    print(
        f"CPU time: in memory {min(mem_cpu):.2f} s; with out_dir {own + helpers:.2f} s ({own:.2f} s in this process, "
        f"{helpers:.2f} s in the figure helpers); on {cpus} CPUs that needs >= {floor:.2f} s of wall time: "
        f"CPU floor ratio {floor / min(mem):.2f}"
    )
    print(f"checks: {r.comparison.n_checked} evaluated, {r.comparison.n_failed} failed, pass = {r.passed}")


if __name__ == "__main__":
    main()
