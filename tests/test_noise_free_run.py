"""A run whose image cannot support a check says n/a with the reason (issue 29, item 7): a noise-free image has no
noise, so its "SNR" (the scatter of the background, the scene's and the optics' own) is not a measurement, and
the NIIRS from it is not either. They were compared as measured: SNR 2820 against 48.9, NIIRS pass at z +786."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from satchain.cli.main import app


def strict_loads(text: str):
    """json.loads that refuses NaN / Infinity (results.json is strict JSON)."""

    def reject(name):
        raise ValueError(f"results.json holds {name}: not strict JSON")

    return json.loads(text, parse_constant=reject)


#: An ACT and an ALT edge (the NIIRS needs both RERs). Noise-free, the background still scatters by ~1e-4 of its
#: level (the optics' tails, rounding): that is not noise.
TWO_EDGES = """
[scene]
width_m = 120.0
height_m = 140.0
background = 0.2

[[items]]
kind = "slanted_edge"
id = "edge_act"
center_m = [35.0, 35.0]
angle_deg = 6.0
measures = "act"

[[items]]
kind = "slanted_edge"
id = "edge_alt"
center_m = [35.0, 102.0]
angle_deg = 7.0
measures = "alt"
"""


@pytest.fixture(scope="module")
def noise_free_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("noisefree")
    (d / "scene.toml").write_text(TWO_EDGES)
    (d / "run.toml").write_text(
        '[scene]\nlayout = "scene.toml"\npixel_m = 0.07\n[simulation]\nunits = "reflectance"\nnoise = false\n'
    )
    r = CliRunner().invoke(app, ["run", "--config", str(d / "run.toml"), "-o", str(d / "o")])
    return r, d / "o"


def test_noise_free_image_gives_no_snr_and_niirs_is_na_with_reason(noise_free_run):
    r, out = noise_free_run
    assert r.exit_code == 0, r.output
    res = strict_loads((out / "results.json").read_text())
    (niirs,) = [row for row in res["summary"] if row["kind"] == "niirs"]
    assert niirs["pass"] is None and niirs["measured"] is None and niirs["z"] is None
    assert "noise-free" in niirs["reason"]
    assert res["niirs"]["snr_measured"] is None and res["snr_measurement"]["snr"] is None
    assert "noise-free" in res["snr_measurement"]["reason"]
    # the edges need no noise: they are still compared, and the count says how many were not
    edges = [row for row in res["summary"] if row["kind"] == "edge_mtf_at_nyquist"]
    assert len(edges) == 2 and all(row["pass"] is True for row in edges)
    n = len(res["summary"])
    assert res["n_checked"] == n - 1 and res["pass"] is True
    assert f"({n - 1}/{n - 1} pass, 1 n/a)" in r.stdout
    assert "n/a: NIIRS (GIQE 5): no SNR measured on the image: the image is noise-free" in r.stderr
    html = (out / "report.html").read_text()
    assert "the image is noise-free" in html and "1 not comparable" in html
    # the NIIRS section does not describe a sigma for a NIIRS that was not measured: it says n/a and why
    niirs = html[html.index('<h2 id="niirs">') : html.index('<h2 id="image">')]
    assert "assumed 5 %" not in niirs and "propagates" not in niirs
    assert "measured NIIRS is n/a" in niirs and "the image is noise-free" in niirs
