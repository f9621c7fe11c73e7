"""What the Python API costs: ``satchain.run`` in memory vs the same run writing its run directory.

The run is ``satchain run``'s built-in default (the reference paper's camera and scene), or with ``--reduced`` the
end-to-end tests' reduced scene (tests/conftest.py ``REDUCED_SCENE_TOML``: edges, a star, bars and wedges on 170 m x
140 m, 7 cm ground-truth pixels). Printed: wall time of ``satchain.run(config)``
(budget, scene, simulation, measurement, prediction, comparison; nothing written), of
``satchain.run(config, out_dir=...)`` (the same plus figures, report.html, results.json, images), their
ratio, and the stage timings; best of ``--repeat`` runs (default 2).

Run:  PYTHONPATH=src python benchmarks/bench_run_api.py [--repeat N]
"""

from __future__ import annotations

import argparse
import re
import tempfile
import time
from pathlib import Path

import satchain

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--reduced", action="store_true", help="the tests' reduced scene instead of the default run")
    a = ap.parse_args()
    n = a.repeat
    text = (ROOT / "tests" / "conftest.py").read_text()
    scene = re.search(r'REDUCED_SCENE_TOML = """(.*?)"""', text, re.S).group(1)
    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "scene.toml").write_text(scene)
        config = {"scene": {"layout": str(Path(d) / "scene.toml"), "pixel_m": 0.07}, "simulation": {"seed": 11}}
        if not a.reduced:
            config = None
        mem, disk = [], []
        for i in range(n):
            t0 = time.perf_counter()
            r = satchain.run(config)
            mem.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            satchain.run(config, out_dir=Path(d) / f"out{i}")
            disk.append(time.perf_counter() - t0)
    print(f"satchain.run in memory:          {min(mem):6.2f} s   stages {dict(r.timings_s)}")
    print(f"satchain.run with out_dir:       {min(disk):6.2f} s")
    print(f"ratio (with report / in memory): {min(disk) / min(mem):6.2f}")
    print(f"checks: {r.comparison.n_checked} evaluated, {r.comparison.n_failed} failed, pass = {r.passed}")


if __name__ == "__main__":
    main()
