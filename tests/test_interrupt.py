"""Issue 18, point 8: an interrupted run (SIGTERM as SIGINT) removes its staging folder, keeps the previous
results and says so; staging folders of dead processes are removed by the next run into the same parent."""

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from satchain._safety import MARKER, OWNER, clean_stale

REPO = Path(__file__).resolve().parents[1]


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def _previous_results(out: Path) -> dict[str, bytes]:
    """A previous satchain run directory (marked), with content to compare afterwards."""
    out.mkdir()
    (out / MARKER).write_text(json.dumps({"tool": "satchain", "kind": "run", "format": 1}))
    (out / "results.json").write_text('{"pass": true, "previous": 1}')
    (out / "report.html").write_text("<html>previous</html>")
    return {p.name: p.read_bytes() for p in out.iterdir()}


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_signal_during_run_removes_staging_and_keeps_previous_results(tmp_path, reduced_scene_toml, sig):
    (tmp_path / "scene.toml").write_text(reduced_scene_toml)
    (tmp_path / "run.toml").write_text('[scene]\nlayout = "scene.toml"\npixel_m = 0.07\n')
    out = tmp_path / "res"
    before = _previous_results(out)
    env = {**os.environ, "PYTHONPATH": str(REPO / "src")}
    cmd = [sys.executable, "-m", "satchain.cli.main", "run", "--config", str(tmp_path / "run.toml"), "-o", str(out)]
    # SIGTERM's default action in the child, whatever the harness running the tests ignores (SIG_IGN is inherited)
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                         preexec_fn=lambda: signal.signal(signal.SIGTERM, signal.SIG_DFL))  # fmt: skip
    try:
        for _ in range(1200):  # the staging folder appears once the run has started writing
            staging = list(tmp_path.glob(".res.staging-*"))
            if staging and (staging[0] / OWNER).exists() or p.poll() is not None:
                break
            time.sleep(0.05)
        assert p.poll() is None, "the run ended before it could be interrupted: " + p.stderr.read()
        assert staging, "no staging folder appeared"
        p.send_signal(sig)
        stdout, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 128 + sig, (p.returncode, err[-800:], stdout[-800:])  # 143 for SIGTERM, 130 for SIGINT
    assert not list(tmp_path.glob(".res.*")), "staging folder left behind"
    assert {q.name: q.read_bytes() for q in out.iterdir()} == before
    assert f"interrupted ({signal.Signals(sig).name})" in err
    assert "previous results" in err and "were kept unchanged" in err and "Traceback" not in err


def test_interrupted_first_run_says_nothing_was_written(tmp_path, reduced_scene_toml):
    """The same in process: satchain.run raises the interruption (a KeyboardInterrupt) and leaves no folder."""
    import satchain
    from satchain._safety import Interrupted

    (tmp_path / "scene.toml").write_text(reduced_scene_toml)
    cfg = satchain.RunConfig.from_dict({"scene": {"layout": str(tmp_path / "scene.toml"), "pixel_m": 0.49}})

    def progress(stage, done, total):
        if stage == "scene":
            os.kill(os.getpid(), signal.SIGTERM)

    with pytest.raises(Interrupted) as info:
        satchain.run(cfg, out_dir=tmp_path / "res", progress=progress)
    assert info.value.signum == signal.SIGTERM and isinstance(info.value, KeyboardInterrupt)
    assert list(tmp_path.iterdir()) == [tmp_path / "scene.toml"]
    assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL  # the default action is restored


def test_stale_staging_with_a_dead_pid_is_removed_by_the_next_run_into_the_same_parent(tmp_path, reduced_scene_toml):
    """A killed run into parent/a left a staging folder (and a run into parent/b's orphaned old results); a
    run into parent/c removes the first, puts the second back, and keeps a live process's and unowned folders."""
    host = socket.gethostname()
    dead, live = _dead_pid(), os.getppid()
    folders = {}
    for name, pid in (("a.staging-x1", dead), ("b.old-x2", dead), ("d.staging-x3", live), ("e.staging-x4", None)):
        d = tmp_path / f".{name}"
        d.mkdir()
        (d / "partial.tif").write_text("x")
        if pid is not None:
            (d / OWNER).write_text(json.dumps({"pid": pid, "host": host, "time": 0}))
        folders[name] = d
    other_host = tmp_path / ".f.staging-x5"
    other_host.mkdir()
    (other_host / OWNER).write_text(json.dumps({"pid": dead, "host": host + "-elsewhere"}))

    (tmp_path / "scene.toml").write_text(reduced_scene_toml)
    import satchain

    cfg = satchain.RunConfig.from_dict({"scene": {"layout": str(tmp_path / "scene.toml"), "pixel_m": 0.49}})
    satchain.run(cfg, out_dir=tmp_path / "c")
    assert not folders["a.staging-x1"].exists()
    assert (tmp_path / "b" / "partial.tif").exists() and not (tmp_path / "b" / OWNER).exists()  # restored
    assert folders["d.staging-x3"].exists() and folders["e.staging-x4"].exists() and other_host.exists()
    assert (tmp_path / "c" / "results.json").is_file() and not (tmp_path / "c" / OWNER).exists()


def test_clean_stale_never_touches_a_live_or_foreign_folder(tmp_path):
    live = tmp_path / ".res.staging-live"
    live.mkdir()
    (live / OWNER).write_text(json.dumps({"pid": os.getpid(), "host": socket.gethostname()}))
    plain = tmp_path / ".notes.staging-draft"  # a user's folder that happens to match the pattern: no owner file
    plain.mkdir()
    assert clean_stale(tmp_path / "res") == []
    assert live.exists() and plain.exists()


def test_a_signal_whose_exception_library_code_swallows_still_stops_the_run(tmp_path, reduced_scene_toml):
    """Code between the handler and the run (a library's ``except BaseException: pass``, an ignored callback
    error) may swallow the Interrupted; the run checks for a received signal before it commits its results."""
    import satchain
    from satchain._safety import Interrupted

    (tmp_path / "scene.toml").write_text(reduced_scene_toml)
    cfg = satchain.RunConfig.from_dict({"scene": {"layout": str(tmp_path / "scene.toml"), "pixel_m": 0.49}})
    out = tmp_path / "res"
    before = _previous_results(out)
    swallowed = []

    def progress(stage, done, total):
        if stage == "scene" and not swallowed:
            try:
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(1.0)  # the handler runs here
            except BaseException as exc:  # what a careless library does
                swallowed.append(exc)

    with pytest.raises(Interrupted) as info:
        satchain.run(cfg, out_dir=out, progress=progress)
    assert swallowed and isinstance(swallowed[0], Interrupted)
    assert info.value.signum == signal.SIGTERM
    assert {q.name: q.read_bytes() for q in out.iterdir()} == before
    assert not list(tmp_path.glob(".res.*"))
    assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_signal_raised_where_python_ignores_exceptions_stops_the_run_quietly(tmp_path, reduced_scene_toml, capfd):
    """CI saw it: the SIGTERM handler ran inside an import lock's weakref callback, where Python prints
    "Exception ignored ... Traceback" and carries on. The run stops at its next progress step, and the
    interruption it recorded is not printed as an ignored exception."""
    import satchain
    from satchain._safety import Interrupted

    (tmp_path / "scene.toml").write_text(reduced_scene_toml)
    cfg = satchain.RunConfig.from_dict({"scene": {"layout": str(tmp_path / "scene.toml"), "pixel_m": 0.49}})
    stages = []

    class SignalsWhenCollected:
        def __del__(self):  # exceptions raised here are "ignored" by Python
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.5)  # the handler runs here

    def progress(stage, done, total):
        stages.append(stage)
        if stage == "scene" and stages.count("scene") == 1:
            SignalsWhenCollected()  # collected at once: its __del__ runs inside this call

    with pytest.raises(Interrupted):
        satchain.run(cfg, out_dir=tmp_path / "res", progress=progress)
    assert "simulate" not in stages  # stopped at the next step, not at the end
    err = capfd.readouterr().err
    assert "Exception ignored" not in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == [tmp_path / "scene.toml"]
