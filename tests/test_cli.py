"""The command line: budget text, JSON schema, output files, clear errors."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from satchain.cli.main import app

runner = CliRunner()


def test_budget_json_schema_and_values(ankarasat3):
    r = runner.invoke(app, ["budget", "--preset", "ankarasat3", "--freqs", "10,42.5,85.034", "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["derived"]["gsd_act_m"] == pytest.approx(0.49) and d["derived"]["gsd_alt_m"] == pytest.approx(0.49)
    assert d["derived"]["nyquist_cy_per_mm"] == pytest.approx(85.034, abs=1e-3)
    assert d["frequencies_cy_per_mm"] == [10.0, 42.5, 85.034]
    for direction in ("alt", "act"):
        assert {"diffraction", "detector", "system"} <= set(d["mtf"][direction])
        assert set(d["ctf"][direction]) == {"coltman", "fourier_synthesis"}
        assert len(d["mtf"][direction]["system"]) == 3
    assert d["mtf"]["alt"]["system"][2] == pytest.approx(d["mtf_at_nyquist"]["alt"], abs=1e-4)
    prod = np.prod([d["mtf"]["alt"][k] for k in d["mtf"]["alt"] if k != "system"], axis=0)
    np.testing.assert_allclose(d["mtf"]["alt"]["system"], prod, atol=1e-12)


def test_budget_text_and_outputs(tmp_path):
    r = runner.invoke(app, ["budget", "-o", str(tmp_path / "out")])
    assert r.exit_code == 0, r.output
    assert "MTF at Nyquist: ALT 0.12" in r.stdout
    names = {p.name for p in (tmp_path / "out").iterdir()}
    assert {
        "budget.json",
        "mtf_alt.csv",
        "mtf_act.csv",
        "fig3a_mtf_budget.png",
        "fig3b_square_wave.png",
    } <= names
    assert not any(n.startswith(".") for n in names - {".satchain-run.json"})  # no temp files left (the marker)
    png = (tmp_path / "out" / "fig3a_mtf_budget.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000
    rows = (tmp_path / "out" / "mtf_alt.csv").read_text().splitlines()
    assert rows[0].startswith("f_cy_per_mm,f_cy_per_px,f_cy_per_m_ground,mtf_diffraction")


def test_budget_from_system_file(tmp_path):
    p = tmp_path / "cam.toml"
    p.write_text(
        "[orbit]\naltitude_m = 500e3\n[optics]\naperture_diameter_m = 0.5\nf_number = 10\nwavelengths_m = [6e-7]\n"
        "[detector]\npitch_m = 5e-6\n"
    )
    r = runner.invoke(app, ["budget", "--system", str(p), "--json", "--freqs", "100"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["derived"]["gsd_alt_m"] == pytest.approx(0.5)
    assert d["derived"]["nyquist_cy_per_mm"] == pytest.approx(100.0)


@pytest.mark.parametrize(
    ("args", "msg"),
    [
        (["budget", "--freqs", "10,abc"], "--freqs = '10,abc': must be comma-separated numbers"),
        (["budget", "--freqs", "-5"], "--freqs = '-5': must be comma-separated numbers >= 0"),
        (["budget", "--preset", "nosuch"], "preset = 'nosuch': must be one of"),
        (["budget", "--system", "/nonexistent/x.toml"], "not found"),
    ],
)
def test_budget_errors_are_clear(args, msg):
    r = runner.invoke(app, args)
    assert r.exit_code == 2
    assert msg in " ".join(r.stderr.split())
    assert "Traceback" not in r.output


def test_budget_includes_radiometry_and_quality():
    r = runner.invoke(app, ["budget", "--json", "--freqs", "85.034"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    q = d["quality"]
    assert {"rer_act", "rer_alt", "overshoot", "giqe4", "giqe5", "snr"} <= set(q)
    assert 0 < q["rer_alt"] < q["rer_act"] < 1  # ALT has the smear
    assert d["radiometry"]["snr"] > 0 and d["radiometry"]["signal_e"] > 0
    assert d["mtfa"]["alt"] < d["mtfa"]["act"]


def test_scene_then_simulate_through_cli(tmp_path):
    import tifffile

    from satchain import load_preset
    from satchain.io.images import read_image

    r = runner.invoke(
        app, ["scene", "--pixel-m", "0.245", "--window", "0,0,400,300", "-o", str(tmp_path / "s" / "sc.tif")]
    )
    assert r.exit_code == 0, r.output
    for name in ("sc.tif", "sc.png", "sc.truth.json"):
        assert (tmp_path / "s" / name).exists()
    img, meta = read_image(tmp_path / "s" / "sc.tif")
    assert img.shape == (300, 400) and meta["pixel_m"] == pytest.approx(0.245)
    out = tmp_path / "sim.tif"
    r = runner.invoke(
        app,
        [
            "simulate",
            str(tmp_path / "s" / "sc.tif"),
            "--units",
            "reflectance",
            "--no-noise",
            "--focal-plane",
            str(tmp_path / "fp.tif"),
            "-o",
            str(out),
        ],
    )
    assert r.exit_code == 0, r.output
    sim, meta = read_image(out)
    s = load_preset("ankarasat3")
    assert sim.shape == (
        int(300 * 0.245 / s.gsd_alt_m + 1e-9),
        int(400 * 0.245 / s.gsd_act_m + 1e-9),
    )  # k = 2
    assert meta["pixel_m"] == pytest.approx(s.gsd_act_m)
    # reflectance units, no noise: the filtered values stay within the scene's reflectance range
    assert img.min() - 0.02 <= sim.min() and sim.max() <= img.max() + 0.1
    assert sim.mean() == pytest.approx(img[: sim.shape[0] * 2, : sim.shape[1] * 2].mean(), abs=0.01)
    assert tifffile.imread(tmp_path / "fp.tif").ndim == 2
    # DN with noise: integer, within the ADC range, reproducible from the seed
    a, b = tmp_path / "a.tif", tmp_path / "b.tif"
    for p in (a, b):
        assert (
            runner.invoke(app, ["simulate", str(tmp_path / "s" / "sc.tif"), "--seed", "7", "-o", str(p)]).exit_code == 0
        )
    da, db = tifffile.imread(a), tifffile.imread(b)
    assert da.dtype == np.uint16 and da.max() < 2**12
    np.testing.assert_array_equal(da, db)


def test_simulate_errors(tmp_path):
    r = runner.invoke(app, ["simulate", "paper", "--units", "kelvin", "-o", str(tmp_path / "x.tif")])
    assert r.exit_code == 2 and "--units = 'kelvin'" in r.stderr
    r = runner.invoke(app, ["simulate", str(tmp_path / "missing.tif"), "-o", str(tmp_path / "x.tif")])
    assert r.exit_code == 2 and "missing.tif" in r.stderr
    assert not (tmp_path / "x.tif").exists()


def test_simulate_on_a_local_dask_cluster_equals_in_process(tmp_path):
    pytest.importorskip("distributed")
    import tifffile

    a, b = tmp_path / "dask.tif", tmp_path / "local.tif"
    common = ["paper", "--scene-pixel-m", "0.245", "--units", "reflectance", "--no-noise"]
    assert runner.invoke(app, ["simulate", *common, "--scheduler", "local", "-o", str(a)]).exit_code == 0
    assert runner.invoke(app, ["simulate", *common, "-o", str(b)]).exit_code == 0
    np.testing.assert_array_equal(tifffile.imread(a), tifffile.imread(b))


def test_simulate_sets_up_its_own_process_allocator(tmp_path, monkeypatch):
    """`satchain simulate` runs in a process satchain owns: it keeps freed tile buffers (satchain.engine._malloc),
    which the library never does in a caller's process (nor `satchain run`, whose memory it would only raise)."""
    import satchain.engine._malloc as memory

    calls = []
    monkeypatch.setattr(memory, "keep_freed_memory", lambda: calls.append(1))
    runner.invoke(app, ["simulate", "paper", "--units", "kelvin", "-o", str(tmp_path / "x.tif")])
    assert len(calls) == 1
    runner.invoke(app, ["run", "--print-config"])
    assert len(calls) == 1
