"""Time and peak memory of `satchain simulate` formed in time (an ACT oscillation) against the static path, on the
same tiled uint16 GeoTIFF, each run in its own child process (its own peak RSS from ``os.wait4``): issue 20,
point 6 ("its memory at 8192^2 and on a streamed gigapixel scene").

Usage: ``python benchmarks/bench_pushbroom_memory.py [--n 8192] [--pixel-m 0.07] [--keep DIR]``
(``--n 32768 --pixel-m 0.098`` for a gigapixel scene, which streams).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from importlib import resources
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_georaster import run_child  # noqa: E402  (the benchmarks folder is not a package)

YAW = "\n[orbit]\nlatitude_deg = 0.0\ninclination_deg = 97.6\nearth_rotation = true\nyaw_steering = true\n"
OSCILLATION = '\n[[motion.oscillation]]\naxis = "act"\namplitude_px = 0.5\nfrequency_hz = 4465.0\nphase_deg = 30.0\n'


def _with_orbit(preset: str, keys: str) -> str:
    """The preset with the Earth-rotation keys added to its own [orbit] table."""
    head, sep, tail = preset.partition("[orbit]\n")
    return head + sep + keys.split("[orbit]\n", 1)[1] + tail if sep else preset + keys


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=8192)
    ap.add_argument("--pixel-m", type=float, default=0.07)
    ap.add_argument("--keep", type=Path, default=None)
    a = ap.parse_args()
    d = a.keep or Path(tempfile.mkdtemp(prefix="bench_pushbroom_memory_"))
    d.mkdir(parents=True, exist_ok=True)
    src = d / f"in{a.n}_{a.pixel_m:g}.tif"
    if not src.exists():
        here = Path(__file__).resolve().parent / "bench_georaster.py"
        cmd = [sys.executable, str(here), "--n", str(a.n), "--pixel-m", str(a.pixel_m), "--write-only", str(src)]
        subprocess.run(cmd, check=True)
    preset = resources.files("satchain.presets").joinpath("ankarasat3.toml").read_text()
    systems = {"static": d / "static.toml", "in time": d / "oscillation.toml"}
    systems["static"].write_text(preset)
    systems["in time"].write_text(preset + OSCILLATION)
    systems["yaw steering"] = d / "yaw.toml"  # the frame rotated (engine.yaw), then rows in time
    systems["yaw steering"].write_text(_with_orbit(preset, YAW))
    rows = {}
    for name, sysf in systems.items():
        out = d / f"out_{name.replace(' ', '_')}.tif"
        out.unlink(missing_ok=True)
        t = time.perf_counter()
        cmd = [sys.executable, "-m", "satchain", "simulate", str(src), "--system", str(sysf), "-o", str(out)]
        code, stdout, stderr, rss = run_child(cmd)
        if code != 0:
            sys.exit(f"{name}: simulate failed: {stderr.strip()}")
        rows[name] = (time.perf_counter() - t, rss, "streamed" in stdout)
    for name, (wall, rss, streamed) in rows.items():
        print(f"{a.n}^2 uint16 at {a.pixel_m:g} m, {name:8s}: {wall:7.1f} s, {a.n * a.n / wall / 1e6:6.1f} Mpx/s, "
              f"peak RSS {rss:.2f} GB{' (streamed)' if streamed else ''}")  # fmt: skip
    for name in ("in time", "yaw steering"):
        print(f"{name} / static: {rows[name][0] / rows['static'][0]:.2f} x the time, "
              f"{rows[name][1] / rows['static'][1]:.2f} x the memory")  # fmt: skip


if __name__ == "__main__":
    main()
