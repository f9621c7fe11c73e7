"""The command line: budget text, JSON schema, output files, clear errors."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from satchain.cli import app

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
    assert {"budget.json", "mtf_alt.csv", "mtf_act.csv", "fig3a_mtf_budget.png", "fig3b_square_wave.png"} <= names
    assert not any(n.startswith(".") for n in names)  # no temp files left
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
        (["budget", "--freqs", "10,abc"], "--freqs = '10,abc': must be a comma-separated list"),
        (["budget", "--freqs", "-5"], "--freqs = '-5': must be one or more finite numbers >= 0"),
        (["budget", "--preset", "nosuch"], "preset = 'nosuch': must be one of"),
        (["budget", "--system", "/nonexistent/x.toml"], "not found"),
    ],
)
def test_budget_errors_are_clear(args, msg):
    r = runner.invoke(app, args)
    assert r.exit_code == 2
    assert msg in " ".join(r.stderr.split())
    assert "Traceback" not in r.output
