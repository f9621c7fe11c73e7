"""``satchain measure edge``: refusals (exit 2, one line), --fit-degree, flags and sigma shown and in --json."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _render_edge import render_iso_edge, truth_mtf
from typer.testing import CliRunner

from satchain.cli.measure import measure_app

runner = CliRunner()


def _save(tmp_path, name, img):
    p = tmp_path / f"{name}.npy"
    np.save(p, img)
    return str(p)


def test_stripe_and_corner_exit_2_with_one_line(tmp_path):
    a = render_iso_edge((80, 80), 5.0, q=None, blur_px=0.6, offset_px=-6.0)
    b = render_iso_edge((80, 80), 5.0, q=None, blur_px=0.6, offset_px=6.0)
    c = render_iso_edge((80, 80), 95.0, q=None, blur_px=0.6, offset_px=0.0)
    for img in (0.1 + a - b, 0.1 + a * c):
        r = runner.invoke(measure_app, ["edge", _save(tmp_path, "bad", img)])
        assert r.exit_code == 2
        err = r.stderr.strip()
        assert err.startswith("error:") and "edge" in err and "\n" not in err
        assert "Traceback" not in r.output and "MTF at Nyquist" not in r.stdout


def test_curved_edge_auto_degree_and_flags_in_json(tmp_path):
    img = 0.1 + 0.8 * render_iso_edge((200, 200), 5.0, q=None, blur_px=0.571, radius_px=2000.0)
    path = _save(tmp_path, "curved", img)
    truth = float(truth_mtf(0.5, q=None, blur_px=0.571))
    d = json.loads(runner.invoke(measure_app, ["edge", path, "--json"]).stdout)
    assert abs(d["mtf_at_nyquist"] - truth) < 0.01
    assert d["fit_degree"] == 2 and "curved_edge" in d["flags"]
    assert len(d["mtf_sigma"]) == len(d["mtf"]) and len(d["warnings"]) == len(d["flags"])
    d1 = json.loads(runner.invoke(measure_app, ["edge", path, "--json", "--fit-degree", "1"]).stdout)
    assert d1["fit_degree"] == 1 and d1["mtf_at_nyquist"] < truth - 0.05
    r = runner.invoke(measure_app, ["edge", path])
    assert r.exit_code == 0
    assert "curved_edge" in r.stdout and "+-" in r.stdout and "1 sigma" in r.stdout


@pytest.mark.parametrize("bad", ["4", "quadratic", "0"])
def test_bad_fit_degree_exit_2(tmp_path, bad):
    path = _save(tmp_path, "e", render_iso_edge((60, 60), 6.0))
    r = runner.invoke(measure_app, ["edge", path, "--fit-degree", bad])
    assert r.exit_code == 2 and "--fit-degree" in r.stderr
