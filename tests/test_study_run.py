"""Run-depth studies (issue 31 points 1-3, 7): each case through the whole chain into its own folder, the table
against single runs of the same cases, resume, interruption, a killed worker, failed and errored cases, Dask."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

import satchain
from satchain.cli.main import app
from satchain.errors import ConfigError, SatchainIOError

WFE = "optics.wfe_rms_waves"


def _study(
    scene: str, tmp: Path, values=(0.0, 0.1), *, reports: str = "failed", repeats: int = 1, extra: str = ""
) -> Path:
    (tmp / "scene.toml").write_text(scene)
    (tmp / "run.toml").write_text(f'[system]\npreset = "ankarasat3"\n[scene]\nlayout = "scene.toml"\n{extra}')
    f = tmp / "study.toml"
    f.write_text(
        f'[base]\nfile = "run.toml"\n[[axes]]\nkey = "{WFE}"\nvalues = {list(values)}\n'
        f'[study]\ndepth = "run"\nreports = "{reports}"\nrepeats = {repeats}\n'
    )
    return f


def _rows(path: Path) -> list[dict[str, str]]:
    return list(csv.DictReader(path.open()))


def test_rows_equal_single_runs_of_the_same_cases_and_resume_keeps_them(tmp_path: Path, monkeypatch, tiny_scene_toml):
    f = _study(tiny_scene_toml, tmp_path)
    out = tmp_path / "out"
    r = satchain.study(f, out, workers=1)
    assert r.passed and r.n_cases == 2 and r.n_ok == 2 and r.resumed == 0
    rows = _rows(out / "study.csv")
    assert {row["case"] for row in rows} == {"c0001", "c0002"}
    for case in ("c0001", "c0002"):
        folder = out / "cases" / case
        assert {"results.json", "config.toml", "case.json", "summary.csv"} <= {p.name for p in folder.iterdir()}
        assert not (folder / "report.html").exists()  # reports = "failed": a passing case keeps none
        single = satchain.run(satchain.load_run_config(folder / "config.toml"))  # the case, run on its own
        mine = {row["figure"]: row for row in rows if row["case"] == case}
        assert len(mine) == len(single.comparison.rows)
        for check in single.comparison.rows:
            row = mine[check.figure]
            for col, value in (("measured", check.measured), ("predicted", check.predicted), ("error", check.error)):
                assert (row[col] == "") if value is None else float(row[col]) == value
            assert row["pass"] == ("" if check.passed is None else str(check.passed).lower())
        b = satchain.budget(single.system)  # the case's budget on every row
        assert {float(row["mtf_at_nyquist_act"]) for row in mine.values()} == {b.mtf_at_nyquist_act}
        assert {float(row["gsd_m"]) for row in mine.values()} == {b.gsd_m}
    # the case's wfe reached its system: more wavefront error, lower MTF at Nyquist
    mtf = {float(row[WFE]): float(row["mtf_at_nyquist_act"]) for row in rows}
    assert mtf[0.1] < mtf[0.0]
    before = {p: p.read_bytes() for p in out.glob("cases/*/results.json")}

    from satchain.studies import runner

    def never(*a, **k):
        raise AssertionError("a finished case was run again")

    monkeypatch.setattr(runner, "run_case", never)
    again = satchain.study(f, out, workers=1)  # resumed: nothing rerun, the same table
    assert again.resumed == 2 and again.passed
    assert {p: p.read_bytes() for p in out.glob("cases/*/results.json")} == before
    assert _rows(out / "study.csv") == rows


def test_failed_check_keeps_report_and_exit_1_error_case_recorded(tmp_path: Path, monkeypatch, tiny_scene_toml):
    no_measurement_is_that_close = "[tolerances]\nedge_mtf_at_nyquist = 1e-9\n"
    f = _study(tiny_scene_toml, tmp_path, extra=no_measurement_is_that_close)
    out = tmp_path / "out"
    from satchain import pipeline

    real = pipeline.run_in_memory

    def flaky(config, **kw):
        if config.system.inline and config.system.inline["optics"]["wfe_rms_waves"] == 0.1:
            raise ValueError("a case-specific failure\nover two lines")
        return real(config, **kw)

    monkeypatch.setattr(pipeline, "run_in_memory", flaky)
    res = CliRunner().invoke(app, ["study", str(f), "-o", str(out), "--workers", "1"])
    assert res.exit_code == 1, res.output
    rows = _rows(out / "study.csv")
    by_case = {row["case"]: row for row in rows}
    assert by_case["c0001"]["case_status"] == "failed" and (out / "cases/c0001/report.html").is_file()
    assert by_case["c0001"]["report"] == "cases/c0001/report.html"
    err = [row for row in rows if row["case"] == "c0002"]
    assert len(err) == 1 and err[0]["case_status"] == "error" and err[0]["figure"] == ""
    assert err[0]["message"] == "ValueError: a case-specific failure over two lines"
    assert "1 failed a check, 1 errored" in res.output
    rec = json.loads((out / "cases/c0002/case.json").read_text())
    assert rec["status"] == "error"
    assert (out / "study.html").is_file() and (out / "study.parquet").is_file()


def test_bad_output_folders_refused_nothing_changed(tmp_path: Path, tiny_scene_toml):
    f = _study(tiny_scene_toml, tmp_path)
    user = tmp_path / "mine"
    user.mkdir()
    (user / "notes.txt").write_text("keep me")
    res = CliRunner().invoke(app, ["study", str(f), "-o", str(user)])
    assert res.exit_code == 2 and "not a satchain study directory" in res.output
    assert sorted(p.name for p in user.iterdir()) == ["notes.txt"]
    budget = tmp_path / "b.toml"  # another study (budget depth) in a folder: a run-depth one is refused there
    budget.write_text(f'[base]\nfile = "run.toml"\n[[axes]]\nkey = "{WFE}"\nvalues = [0.0]\n')
    assert CliRunner().invoke(app, ["study", str(budget), "-o", str(tmp_path / "o")]).exit_code == 0
    listing = sorted(p.name for p in (tmp_path / "o").iterdir())
    res = CliRunner().invoke(app, ["study", str(f), "-o", str(tmp_path / "o")])
    assert res.exit_code == 2 and "holds another study" in res.output
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == listing
    with pytest.raises(SatchainIOError, match="holds another study"):
        satchain.study(f, tmp_path / "o")
    with pytest.raises(ConfigError, match="repeats = 2 with an axis 'simulation.seed'"):
        satchain.study(
            {"axes": [{"key": "simulation.seed", "values": [1, 2]}], "study": {"depth": "run", "repeats": 2}},
            tmp_path / "s",
        )
    assert not (tmp_path / "s").exists()


def test_repeats_have_their_own_seeds_and_folders(tmp_path: Path, tiny_scene_toml):
    f = _study(tiny_scene_toml, tmp_path, values=(0.0,), repeats=2)
    r = satchain.study(f, tmp_path / "out", workers=1)
    rows = _rows(tmp_path / "out" / "study.csv")
    assert {(row["repeat"], row["folder"]) for row in rows} == {("1", "cases/c0001-r1"), ("2", "cases/c0001-r2")}
    seeds = {row["repeat"]: int(row["seed"]) for row in rows}
    assert seeds["1"] != seeds["2"] and r.n_cases == 2
    for k in ("1", "2"):
        cfg = satchain.load_run_config(tmp_path / "out" / f"cases/c0001-r{k}" / "config.toml")
        assert cfg.simulation.seed == seeds[k]
    measured = {row["repeat"]: row["measured"] for row in rows if row["kind"] == "edge_mtf_at_nyquist"}
    assert measured["1"] != measured["2"]  # two noise realisations


def _satchain(*args: str, cwd: Path) -> subprocess.Popen:
    env = dict(os.environ, COLUMNS="200")
    return subprocess.Popen([sys.executable, "-m", "satchain", *args], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip


def _wait_for(pred, timeout: float = 120.0) -> None:
    t0 = time.monotonic()
    while not pred():
        if time.monotonic() - t0 > timeout:
            raise AssertionError("timed out")
        time.sleep(0.05)


def test_sigterm_keeps_finished_cases_then_rerun_finishes(tmp_path: Path, tiny_scene_toml):
    f = _study(tiny_scene_toml, tmp_path, values=(0.0, 0.02, 0.04, 0.06, 0.08, 0.1))
    out = tmp_path / "out"
    p = _satchain("study", str(f), "-o", str(out), "--workers", "2", cwd=tmp_path)
    _wait_for(lambda: any(out.glob("cases/c*/case.json")) or p.poll() is not None)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    if p.returncode == 0:
        pytest.skip("the study finished before the signal")  # never seen: six cases on two workers
    assert p.returncode == 128 + signal.SIGTERM, err
    assert "interrupted (SIGTERM)" in err and "rerun the same command" in err
    kept = {c.parent.name: c.parent.joinpath("results.json").read_bytes() for c in out.glob("cases/c*/case.json")}
    assert kept and len(kept) < 6
    assert not list(out.glob("cases/.*staging*"))  # the stopped workers' staging folders removed
    assert not (out / "study.csv").exists()
    r = _satchain("study", str(f), "-o", str(out), "--workers", "2", cwd=tmp_path)
    stdout, err = r.communicate(timeout=300)
    assert r.returncode == 0, err
    assert f"{len(kept)} kept from an earlier run" in stdout
    for name, data in kept.items():  # the finished cases were kept as they were
        assert (out / "cases" / name / "results.json").read_bytes() == data
    assert len({row["case"] for row in _rows(out / "study.csv")}) == 6


def test_a_killed_worker_is_retried(tmp_path: Path, tiny_scene_toml):
    f = _study(tiny_scene_toml, tmp_path, values=(0.0, 0.05, 0.1))
    out = tmp_path / "out"
    p = _satchain("study", str(f), "-o", str(out), "--workers", "2", cwd=tmp_path)
    owners: list[Path] = []

    def staging_owned() -> bool:
        owners[:] = [o for o in out.glob("cases/.*staging*/.satchain-owner.json") if o.stat().st_size]
        return bool(owners) or p.poll() is not None

    _wait_for(staging_owned)
    if owners:
        pid = json.loads(owners[0].read_text())["pid"]
        os.kill(pid, signal.SIGKILL)  # a worker dies mid-case (out of memory, killed)
    stdout, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    assert "3 ok" in stdout
    assert {row["case_status"] for row in _rows(out / "study.csv")} == {"ok"}
    assert not list(out.glob("cases/.*staging*"))


def test_dask_local_scheduler(tmp_path: Path, monkeypatch, tiny_scene_toml):
    pytest.importorskip("distributed")
    f = _study(tiny_scene_toml, tmp_path)
    res = CliRunner().invoke(app, ["study", str(f), "-o", str(tmp_path / "o"), "--scheduler", "local",
                                   "--workers", "2"])  # fmt: skip
    assert res.exit_code == 0, res.output
    local = satchain.study(f, tmp_path / "p", workers=1)  # the same cases, here: the same numbers
    assert _rows(tmp_path / "o" / "study.csv") == _rows(local.csv)
    from satchain.studies import runner

    monkeypatch.setattr(runner, "CONNECT_TIMEOUT_S", 2)
    bad = CliRunner().invoke(app, ["study", str(f), "-o", str(tmp_path / "q"), "--scheduler", "tcp://127.0.0.1:9"])
    assert bad.exit_code == 2 and "cannot reach the Dask scheduler" in bad.output


def test_example_and_study_file_one_not_both(tmp_path: Path, tiny_scene_toml):
    f = _study(tiny_scene_toml, tmp_path)
    both = CliRunner().invoke(app, ["study", str(f), "--example", "aperture-aberration", "-o", str(tmp_path / "o")])
    assert both.exit_code == 2 and "one, not both" in both.output
    unknown = CliRunner().invoke(app, ["study", "--example", "apertures", "-o", str(tmp_path / "o")])
    assert unknown.exit_code == 2 and "'apertures'" in unknown.output and "aperture-aberration" in unknown.output
    neither = CliRunner().invoke(app, ["study", "-o", str(tmp_path / "o")])
    assert neither.exit_code == 2
    assert not (tmp_path / "o").exists()


def test_seams_minimal_system_as_built_and_pushbroom_axes(
    tmp_path: Path, monkeypatch, minimal_system_toml, tiny_scene_toml
):
    """A minimal system file (only the required keys) as the base; the aperture (focal length held), the camera
    as built and the pushbroom line-rate error varied together (zip), at run depth."""
    import math

    (tmp_path / "minimal.toml").write_text(minimal_system_toml)
    (tmp_path / "scene.toml").write_text(tiny_scene_toml)
    spec = {
        "base": {"system": {"file": "minimal.toml"}, "scene": {"layout": "scene.toml"}},
        "axes": [
            {"key": "optics.aperture_diameter_m", "values": [0.4, 0.5]},
            {"key": "as_built.optics.wfe_rms_waves", "values": [0.0, 0.08]},
            {"key": "motion.line_rate_error", "values": [0.0, 0.05]},
        ],
        "study": {"depth": "run", "zip": True},
    }
    monkeypatch.chdir(tmp_path)  # a dict's relative paths are relative to the current folder
    r = satchain.study(spec, tmp_path / "out", workers=1)
    assert r.n_error == 0, r.errors
    assert any("optics.focal_length_m = 5 m" in line for line in r.held_fixed)
    for case, ap, wfe, rate in (("c0001", 0.4, 0.0, 0.0), ("c0002", 0.5, 0.08, 0.05)):
        cfg = satchain.load_run_config(tmp_path / "out" / "cases" / case / "config.toml")
        system = cfg.load_system()
        assert system.optics.aperture_diameter_m == ap and system.motion.line_rate_error == rate
        assert system.derived()["focal_length_m"] == pytest.approx(5.0, rel=1e-12)  # held: f_number followed
        res = json.loads((tmp_path / "out" / "cases" / case / "results.json").read_text())
        changed = {d["key"] if isinstance(d, dict) else d for d in res["as_built_differences"]}
        assert (wfe != 0.0) == any("wfe_rms_waves" in str(k) for k in changed)
        rows = [row for row in r.rows if row["case"] == case and row["kind"] == "edge_angle"]
        assert len(rows) == 1
        if rate:  # the pushbroom geometry maps the 6-degree edge: the predicted angle follows (1 + eps) tan 6
            assert "pushbroom image geometry" in rows[0]["figure"]
            assert rows[0]["predicted"] != pytest.approx(6.0, abs=0.05)
        else:
            assert rows[0]["predicted"] == pytest.approx(6.0, abs=1e-9)
        assert math.isfinite(rows[0]["measured"])
