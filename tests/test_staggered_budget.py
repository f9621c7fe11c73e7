"""The budget of a staggered layout (issue 32 point 5): closed forms at the single array's and the combined grid's
Nyquist, its validation, and `satchain budget` (text and JSON) with and without it."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import satchain
from satchain.cli.main import app
from satchain.errors import ConfigError
from satchain.tf.budget import SystemOTF


def _system(**detector) -> satchain.ImagingSystem:
    return satchain.ImagingSystem.from_dict(
        {"name": "m", "orbit": {"altitude_m": 500e3}, "optics": {"aperture_diameter_m": 0.5, "f_number": 4.0,
         "wavelengths_m": [6e-7]}, "detector": {"pitch_m": 5e-6, **detector}}  # fmt: skip
    )


def test_closed_forms_at_both_nyquists():
    s = _system(layout="staggered", fill_factor=0.49)  # a 3.5 um photosite: its sinc is not 0 at 1/p
    st = satchain.budget(s).to_dict()["staggered"]
    p_mm = 5e-3
    assert st["nyquist_cy_per_mm"]["axis"] == pytest.approx(1 / p_mm)
    assert st["nyquist_cy_per_mm"]["single_array"] == pytest.approx(1 / (2 * p_mm))
    assert st["nyquist_cy_per_mm"]["diagonal"] == pytest.approx(1 / (np.sqrt(2) * p_mm))
    assert st["combined_pitch_m"] == pytest.approx(2.5e-6)
    assert st["combined_gsd_m"]["act"] == pytest.approx(s.derived()["gsd_act_m"] / 2)
    otf = SystemOTF(s)
    for d, (fx, fy) in {"act": (1.0, 0.0), "alt": (0.0, 1.0)}.items():
        # the combination's transfer function: 1/2 + cos(pi p fx)/4 + cos(pi p fy)/4 -> 1/2 at 1/p, 3/4 at 1/(2p)
        full = abs(complex(np.asarray(otf(fx / p_mm, fy / p_mm))))
        half = abs(complex(np.asarray(otf(fx / (2 * p_mm), fy / (2 * p_mm)))))
        assert full > 0.01  # the smaller photosite passes the combined Nyquist
        assert st["mtf_at_combined_nyquist"][d] == pytest.approx(0.5 * full, rel=1e-9)
        assert st["mtf_at_single_nyquist"][d] == pytest.approx(0.75 * half, rel=1e-9)
    # a full (100 %) photosite: its sinc is 0 at 1/p, so nothing passes the combined Nyquist itself
    full_fill = satchain.budget(_system(layout="staggered")).to_dict()["staggered"]
    assert full_fill["mtf_at_combined_nyquist"]["act"] == pytest.approx(0.0, abs=1e-12)


def test_single_layout_budget_unchanged_and_refusals():
    assert "staggered" not in satchain.budget(_system()).to_dict()
    with pytest.raises(ConfigError, match="layout = 'staggered': needs square pixels"):
        satchain.ImagingSystem.from_dict(
            {"orbit": {"altitude_m": 5e5}, "optics": {"aperture_diameter_m": 0.5, "f_number": 4.0},
             "detector": {"pitch_x_m": 5e-6, "pitch_y_m": 6e-6, "layout": "staggered"}}  # fmt: skip
        )
    with pytest.raises(ConfigError, match="detector.layout"):
        _system(layout="interleaved")
    with pytest.raises(ConfigError, match="and no cfa"):
        _system(layout="staggered", cfa="RGGB")


def test_cli_budget_text_and_json(tmp_path, minimal_system_toml):
    f = tmp_path / "s.toml"
    f.write_text(minimal_system_toml.replace("[detector]\n", '[detector]\nlayout = "staggered"\n'))
    text = CliRunner().invoke(app, ["budget", "--system", str(f)])
    assert text.exit_code == 0 and "staggered: two arrays combined onto 2.5 um" in text.output
    data = json.loads(CliRunner().invoke(app, ["budget", "--system", str(f), "--json"]).stdout)
    assert data["staggered"]["nyquist_cy_per_mm"]["axis"] == pytest.approx(200.0)
    bad = tmp_path / "b.toml"
    bad.write_text(minimal_system_toml.replace("[detector]\n", '[detector]\nlayout = "interleaved"\n'))
    res = CliRunner().invoke(app, ["budget", "--system", str(bad)])
    assert res.exit_code == 2 and "detector.layout" in res.output
