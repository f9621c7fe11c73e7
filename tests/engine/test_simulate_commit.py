"""Issue 29 follow-up of item 10: the outputs of one `satchain simulate` (image, PNG preview, focal plane) are
committed together, and the message says truthfully what happened, wherever the signal arrives: before the
commit nothing is replaced (the previous set stays whole), during the renames the signal waits until all are in
(and the message says they were written). Each signal is sent by the process to itself at a fixed step."""

from __future__ import annotations

import hashlib
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

#: the command line with ``module:attr[@text]`` (argv 2) wrapped so that its first call (with an argument that
#: ends with ``text``) signals the process first
_CHILD = """
import importlib, os, sys
sig, target = int(sys.argv[1]), sys.argv[2]
target, _, text = target.partition("@")
mod, attr = target.split(":")
owner = importlib.import_module(mod)
*path, leaf = attr.split(".")
for p in path:
    owner = getattr(owner, p)
orig, fired = getattr(owner, leaf), []
def hooked(*a, **k):
    if not fired and (not text or any(str(x).endswith(text) for x in a)):
        fired.append(1)
        os.kill(os.getpid(), sig)
    return orig(*a, **k)
setattr(owner, leaf, hooked)
from satchain.cli.main import app
app(sys.argv[3:], prog_name="satchain")
"""


def _raster(path: Path, level: float) -> Path:
    x = np.arange(160)[None, :] + np.zeros((160, 1))
    a = np.where(x < 80, 0.2, level).astype(np.float32)
    with rasterio.open(path, "w", driver="GTiff", width=160, height=160, count=1, dtype="float32",
                       crs="EPSG:32636", transform=Affine(0.07, 0, 5e5, 0, -0.07, 4.4e6)) as d:  # fmt: skip
        d.write(a, 1)
    return path


def _run(tmp_path, src, target, sig=signal.SIGTERM):
    out, fp = tmp_path / "o" / "OUT.tif", tmp_path / "o" / "FP.tif"
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    cmd = [sys.executable, "-c", _CHILD, str(int(sig)), target, "simulate", str(src), "--preset", "ankarasat3",
           "--no-noise", "--focal-plane", str(fp), "-o", str(out)]  # fmt: skip
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120,
                       preexec_fn=lambda: signal.signal(signal.SIGTERM, signal.SIG_DFL))  # fmt: skip
    return p, [out, out.with_suffix(".png"), fp]


def _digest(paths):
    return [hashlib.sha256(p.read_bytes()).hexdigest() if p.exists() else None for p in paths]


# the band's formation (before any output is staged), the focal plane's writing (image and preview staged)
@pytest.mark.parametrize("target", ["satchain.engine.georaster:_form_band",
                                    "satchain.engine.georaster:_FocalPlane.write"])  # fmt: skip
@pytest.mark.parametrize("earlier", [False, True])
def test_a_signal_before_the_commit_replaces_none_of_the_outputs(tmp_path, target, earlier):
    src = _raster(tmp_path / "in.tif", 0.7)
    outs = [tmp_path / "o" / n for n in ("OUT.tif", "OUT.png", "FP.tif")]
    (tmp_path / "o").mkdir()
    if earlier:
        env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
        first = subprocess.run([sys.executable, "-m", "satchain", "simulate", str(_raster(tmp_path / "old.tif", 0.5)),
                                "--preset", "ankarasat3", "--no-noise", "--focal-plane", str(outs[2]), "-o",
                                str(outs[0])], capture_output=True, text=True, env=env, timeout=120)  # fmt: skip
        assert first.returncode == 0, first.stderr
    before = _digest(outs)
    p, _ = _run(tmp_path, src, target)
    assert p.returncode == 128 + signal.SIGTERM, (p.returncode, p.stderr[-800:])
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "interrupted (SIGTERM)" in lines[0] and "nothing was written" in lines[0], p.stderr
    assert ("unchanged" in lines[0]) == earlier
    assert _digest(outs) == before, "an output was replaced although the message says none was"
    assert sorted(q.name for q in (tmp_path / "o").iterdir()) == sorted(o.name for o in outs if earlier)


def test_a_signal_during_the_renames_waits_until_every_output_is_in(tmp_path):
    (tmp_path / "o").mkdir()
    src = _raster(tmp_path / "in.tif", 0.7)
    p, outs = _run(tmp_path, src, "satchain.io._commit:os.replace@OUT.tif")  # the commit's rename
    assert p.returncode == 128 + signal.SIGTERM, (p.returncode, p.stderr[-800:])
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "had finished" in lines[0] and "were written" in lines[0], p.stderr
    assert all(o.exists() for o in outs)
    assert sorted(q.name for q in (tmp_path / "o").iterdir()) == sorted(o.name for o in outs)
    with rasterio.open(outs[0]) as a, rasterio.open(outs[2]) as f:
        assert a.crs.to_epsg() == 32636 and f.crs.to_epsg() == 32636
        assert np.nanmax(f.read(1)) > 0.6  # this run's scene (0.7), not an earlier one


def test_a_signal_while_the_command_line_starts_is_answered_in_one_line(tmp_path):
    """SIGTERM before simulate's own handler (here: while the system is loaded) says nothing was written, as
    the console script ``satchain`` runs it (the handler is installed at the command line's first import)."""
    script = tmp_path / "satchain"  # the console script's name: the start-up handler is the entry point's only
    script.write_text(_CHILD)
    (tmp_path / "o").mkdir()
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    cmd = [
        sys.executable,
        str(script),
        str(int(signal.SIGTERM)),
        "satchain.cli.simulate:system_from_options",
        "simulate",
        str(_raster(tmp_path / "in.tif", 0.7)),
        "--preset",
        "ankarasat3",
        "-o",
        str(tmp_path / "o" / "OUT.tif"),
    ]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120,
                       preexec_fn=lambda: signal.signal(signal.SIGTERM, signal.SIG_DFL))  # fmt: skip
    assert p.returncode == 128 + signal.SIGTERM, (p.returncode, p.stderr[-800:])
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "interrupted (SIGTERM)" in lines[0] and "nothing was written" in lines[0], p.stderr
    assert list((tmp_path / "o").iterdir()) == []


def test_importing_the_command_line_leaves_sigterm_alone_in_another_program():
    import satchain.cli.main  # noqa: F401

    assert signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None) or "satchain" not in str(
        getattr(signal.getsignal(signal.SIGTERM), "__module__", "")
    )
