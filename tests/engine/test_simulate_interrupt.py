"""Issue 29 item 10: a single-file `satchain simulate` stopped by SIGTERM (or Ctrl-C) behaves as `satchain run`:
exit 128 + signal, one line saying so, and nothing left behind (no staging folder, no output)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import rasterio
from rasterio import Affine

REPO = Path(__file__).resolve().parents[2]

#: runs the command line with the band's formation preceded by a signal to the process itself (so the signal
#: arrives while the staging folder exists, every time)
_CHILD = """
import os, signal, sys
import satchain.engine.georaster as g
sig, form = int(sys.argv[1]), g._form_band
def _form_band(*a, **k):
    os.kill(os.getpid(), sig)
    return form(*a, **k)
g._form_band = _form_band
from satchain.cli.main import app
app(sys.argv[2:], prog_name="satchain")
"""


def _raster(path: Path) -> Path:
    x = np.arange(200)[None, :] + np.zeros((200, 1))
    a = np.where(x < 100, 0.2, 0.6).astype(np.float32)
    with rasterio.open(path, "w", driver="GTiff", width=200, height=200, count=1, dtype="float32",
                       crs="EPSG:32636", transform=Affine(0.07, 0, 5e5, 0, -0.07, 4.4e6)) as d:  # fmt: skip
        d.write(a, 1)
    return path


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_during_simulate_exits_128_plus_signal_and_leaves_nothing(tmp_path, sig):
    src = _raster(tmp_path / "in.tif")
    out = tmp_path / "out" / "OUT.tif"
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    cmd = [sys.executable, "-c", _CHILD, str(int(sig)), "simulate", str(src), "--preset", "ankarasat3", "-o", str(out)]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120,
                       preexec_fn=lambda: signal.signal(signal.SIGTERM, signal.SIG_DFL))  # fmt: skip
    assert p.returncode == 128 + sig, (p.returncode, p.stderr[-800:])
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and f"interrupted ({signal.Signals(sig).name})" in lines[0], p.stderr
    assert "nothing was written" in lines[0] and "Traceback" not in p.stderr
    assert sorted(q.name for q in out.parent.iterdir()) == [], "a staging folder or an output was left behind"
