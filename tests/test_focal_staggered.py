"""`satchain run` with a staggered layout (issue 32 point 5): the two arrays imaged from the run's scene, combined on
the half-pitch grid and measured there -- each edge's MTF at the combined grid's Nyquist (1/p) and at one array's
(1/(2p)) against the system MTF times the combination's transfer function, each bar target's CTF against
Coltman's CTF of that MTF, the groups above one array's Nyquist resolved as predicted; the rows in the table,
results.json (schema), summary.csv and the report; the rasters under images/staggered/; a single-array system
unchanged; and point 8's refusal of a TDI count the arrays' separation cannot hold."""

from __future__ import annotations

import csv
import json
import math
import re
from types import SimpleNamespace

import jsonschema
import numpy as np
import pytest
import tomllib
from typer.testing import CliRunner

import satchain
from satchain.cli.main import app
from satchain.config.run import RunConfig
from satchain.errors import ConfigError
from satchain.focal import staggered
from satchain.io import read_image
from satchain.results import results_schema
from satchain.tf.budget import SystemOTF
from satchain.tf.ctf import coltman_ctf

#: Two slanted edges and two bar targets; at the minimal system's 0.5 m GSD the bars' periods are 3.2, 2.4, 1.8
#: and 1.6 px of one array: the last two above its Nyquist (below 2 px per period).
SCENE = """
[scene]
width_m = 80.0
height_m = 66.0
background = 0.2
pixel_m = 0.0625

[[items]]
kind = "slanted_edge"
id = "edge_act"
center_m = [16.0, 16.0]
size_m = 22.0
angle_deg = 5.0
measures = "act"

[[items]]
kind = "slanted_edge"
id = "edge_alt"
center_m = [16.0, 44.0]
size_m = 22.0
angle_deg = 5.0
measures = "alt"

[[items]]
kind = "bar_target"
id = "bars_act"
origin_m = [34.0, 4.0]
periods_m = [1.6, 1.2, 0.9, 0.8]
orientation = "act"
length_factor = 15.0

[[items]]
kind = "bar_target"
id = "bars_alt"
origin_m = [34.0, 34.0]
periods_m = [1.6, 1.2, 0.9, 0.8]
orientation = "alt"
length_factor = 15.0
"""
PITCH_M = 5e-6


def _staggered(toml: str, extra: str = "") -> str:
    return toml.replace("[detector]\n", f'[detector]\nlayout = "staggered"\n{extra}')


@pytest.fixture(scope="module")
def run(tmp_path_factory, minimal_system_toml):
    """One `satchain run` (in process) of the minimal system as a staggered layout on SCENE."""
    d = tmp_path_factory.mktemp("staggered")
    (d / "system.toml").write_text(_staggered(minimal_system_toml))
    (d / "scene.toml").write_text(SCENE)
    (d / "run.toml").write_text('[system]\nfile = "system.toml"\n[scene]\nlayout = "scene.toml"\npixel_m = 0.0625\n'
                                "[simulation]\nseed = 7\n")  # fmt: skip
    out = d / "out"
    res = CliRunner().invoke(app, ["run", "--config", str(d / "run.toml"), "-o", str(out)])
    system = satchain.ImagingSystem.from_dict(tomllib.loads(_staggered(minimal_system_toml)))
    return SimpleNamespace(res=res, out=out, data=json.loads((out / "results.json").read_text()), system=system)


def _combined_mtf(system, fx_mm, fy_mm) -> np.ndarray:
    """The combined grid's MTF, written here: |system OTF| x (1/2 + cos(pi p fx)/4 + cos(pi p fy)/4)."""
    p_mm = PITCH_M * 1e3
    h = 0.5 + 0.25 * np.cos(np.pi * p_mm * np.asarray(fx_mm)) + 0.25 * np.cos(np.pi * p_mm * np.asarray(fy_mm))
    return np.abs(np.asarray(SystemOTF(system)(fx_mm, fy_mm))) * h


def test_the_rows_join_the_run_and_pass(run):
    assert run.res.exit_code == 0, run.res.output
    rows = [r for r in run.data["summary"] if r["kind"].startswith("staggered_")]
    kinds = sorted((r["kind"], r["id"]) for r in rows)
    assert kinds == sorted([("staggered_edge_mtf_at_nyquist", e) for e in ("edge_act", "edge_alt")]
                           + [("staggered_edge_mtf_at_single_nyquist", e) for e in ("edge_act", "edge_alt")]
                           + [("staggered_bar_ctf", b) for b in ("bars_act", "bars_alt")])  # fmt: skip
    assert all(r["pass"] is True for r in rows)
    # the terminal table lists them (cells may wrap at the terminal's width: the start of the figure, and the count)
    assert "staggered edge" in run.res.output and "staggered bars" in run.res.output
    n = len(run.data["summary"])
    assert f"({n}/{n} pass)" in run.res.output
    with (run.out / "summary.csv").open() as fh:
        csv_rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    csv_kinds = {r["kind"] for r in csv_rows}
    assert all(r["unit"] and r["error_unit"] for r in csv_rows)  # every check's units stated
    assert {"staggered_edge_mtf_at_nyquist", "staggered_bar_ctf"} <= csv_kinds
    jsonschema.Draft202012Validator(results_schema()).validate(run.data)


def test_edges_against_the_closed_form_at_both_nyquists(run):
    """The prediction is |OTF| x H along the truth's normal, computed here; the reference-like optics (cutoff
    1/(lambda N) = 166.7 cy/mm below 1/p = 200) pass nothing at 1/p, so there the measured magnitude reads the
    noise's Rice mean; at one array's Nyquist the combination keeps 3/4 of the system MTF."""
    st = run.data["staggered"]
    assert st["nyquist_cy_per_mm"]["combined_axis"] == pytest.approx(200.0)
    assert st["nyquist_cy_per_mm"]["single_array"] == pytest.approx(100.0)
    assert st["combined_gsd_m"] == pytest.approx([0.25, 0.25])
    for e in st["edges"]:
        t = math.radians(5.0)
        n = (math.cos(t), math.sin(t)) if e["direction"] == "ACT" else (math.sin(t), math.cos(t))
        for key, f in (("combined_nyquist", 200.0), ("single_nyquist", 100.0)):
            at = e[key]
            model = at["model"] if at["model"] is not None else at["predicted"]
            assert abs(model) == pytest.approx(float(_combined_mtf(run.system, f * n[0], f * n[1])), abs=1e-6)
            assert abs(at["measured"] - at["predicted"]) <= 0.02
        assert e["combined_nyquist"]["model"] == pytest.approx(0.0, abs=1e-9)  # diffraction cut below 1/p
        assert e["single_nyquist"]["predicted"] > 0.1


def test_bars_above_one_arrays_nyquist_are_resolved_as_predicted(run):
    """Groups of 1.8 and 1.6 px (of one array) lie above its Nyquist: the main run (array A alone) cannot measure
    them, the combined grid does, with Coltman's CTF of the combined MTF (computed here)."""
    st = run.data["staggered"]
    for b in st["bars"]:
        beyond = [g for g in b["groups"] if g["beyond_single_nyquist"]]
        assert [round(g["period_single_px"], 3) for g in beyond] == [1.8, 1.6]
        for g in b["groups"]:
            f = 1 / (g["period_single_px"] * PITCH_M * 1e3)  # cy/mm on the focal plane

            def mtf(f_mm, axis=b["direction"]):
                f_mm = np.asarray(f_mm, float)
                return _combined_mtf(run.system, *((f_mm, 0 * f_mm) if axis == "ACT" else (0 * f_mm, f_mm)))

            assert g["ctf_predicted"] == pytest.approx(float(coltman_ctf(f, mtf)), abs=1e-6)
            assert g["compared"] and abs(g["ctf_measured"] - g["ctf_predicted"]) <= 0.02
            assert g["resolved_as_predicted"]
        assert all(0.04 < g["ctf_measured"] for g in beyond)  # modulation one array alone cannot sample
    single = {b["id"]: b for b in run.data["bar_targets"]}  # the main run: array A alone
    for b in single.values():
        assert all(f <= 0.5 for f in b["f_cy_per_px"])  # only the groups at >= 2 px per period


def test_rasters_round_trip_and_are_georeferenced(run):
    a, meta_a = read_image(run.out / "images" / "staggered" / "array_a.tif")
    b, meta_b = read_image(run.out / "images" / "staggered" / "array_b.tif")
    c, meta_c = read_image(run.out / "images" / "staggered" / "combined.tif")
    assert c.shape == (2 * a.shape[0], 2 * a.shape[1]) and b.shape == a.shape
    assert a.dtype == np.uint16 and c.dtype == np.float32  # 12-bit DN; the fill's means are not whole DN
    assert np.array_equal(c[0::2, 0::2], a) and np.array_equal(c[1::2, 1::2], b)
    inner = c[2:-2:2, 3:-2:2]  # A's rows, odd columns: the mean of the 4 neighbours (2 of A, 2 of B)
    expect = (c[2:-2:2, 2:-3:2] + c[2:-2:2, 4:-1:2] + c[1:-3:2, 3:-2:2] + c[3:-1:2, 3:-2:2]) / 4
    assert np.allclose(inner, expect, atol=1e-3)
    assert meta_a["pixel_m"] == pytest.approx(0.5) and meta_c["pixel_m"] == pytest.approx(0.25)
    assert meta_b["origin_m"] == pytest.approx([0.25, 0.25]) and meta_c["origin_m"] == pytest.approx([0.125, 0.125])


def test_report_section_with_the_figure(run):
    html = (run.out / "report.html").read_text()
    assert "Staggered arrays: the combined half-pitch grid" in html
    assert "The combined grid&#39;s MTF: predicted" in html  # the figure's caption (the image is inlined)
    assert "Bar groups on the combined grid" in html and "quincunx bilinear" in html
    assert (run.out / "figures" / "staggered_mtf.png").stat().st_size > 1000


def test_a_single_array_system_has_no_section(tiny_scene_toml, tmp_path):
    (tmp_path / "scene.toml").write_text(tiny_scene_toml)
    cfg = RunConfig.from_dict({"scene": {"layout": str(tmp_path / "scene.toml"), "pixel_m": 0.07}})
    budget = SimpleNamespace(system=satchain.load_preset("ankarasat3"))
    assert staggered.section(cfg, budget, None, lambda *a: None) is None
    res = satchain.run(cfg)
    assert "staggered" not in res.to_json_dict()
    assert not any(r.kind.startswith("staggered_") for r in res.comparison.rows)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ("tdi_stages = 8\nstagger_separation_px = 3.5\n",
         r"detector.stagger_separation_px = 3.5 cannot hold detector.tdi_stages = 8: .* >= 8.5 rows apart"),
        ("stagger_separation_px = 4.0\n", r"detector.stagger_separation_px = 4.0: must be a whole number of rows"),
    ],
)  # fmt: skip
def test_a_tdi_count_the_separation_cannot_hold_is_refused(minimal_system_toml, tmp_path, extra, message):
    """Two N-row TDI arrays half a line apart in phase sit (n + 1/2) rows apart with n >= N (they cannot
    overlap): a separation of 3.5 rows holds at most 3 stages."""
    f = tmp_path / "s.toml"
    f.write_text(_staggered(minimal_system_toml, extra))
    res = CliRunner().invoke(app, ["budget", "--system", str(f)])
    assert res.exit_code == 2 and len(res.output.strip().splitlines()) == 1
    assert re.search(message, res.output)
    fine = satchain.ImagingSystem.from_dict(tomllib.loads(_staggered(
        minimal_system_toml, "tdi_stages = 3\nstagger_separation_px = 3.5\n")))  # fmt: skip
    assert fine.detector.tdi_stages == 3
    with pytest.raises(ConfigError, match="needs detector.layout = 'staggered'"):
        satchain.ImagingSystem.from_dict(tomllib.loads(
            minimal_system_toml.replace("[detector]\n", "[detector]\nstagger_separation_px = 1.5\n")))  # fmt: skip


def test_a_group_at_the_noise_floor_is_listed_not_compared(run):
    """A group the bar measurement reads at its noise floor (its modulation not above 5 sigma of the noise: on
    the combined grid also the fill's own pattern) is neither compared nor counted resolved."""
    from satchain.focal._staggered_checks import bar_section, combined_mtf2d

    mtf2d = combined_mtf2d(SystemOTF(run.system), PITCH_M)
    cfg = RunConfig.from_dict({})
    entry = {
        "id": "b",
        "direction": "ALT",
        "f_cy_per_px": [0.2, 0.3],
        "ctf": [0.2, 0.4],
        "ctf_std": [0.01, 0.03],
        "groups": [{"group": 0}, {"group": 1}],
        "flags": ["group 1: at_noise_floor: modulation 0.1 +- 0.03"],
    }
    (row,), (b,) = bar_section([entry], mtf2d, cfg, pitch_m=PITCH_M)
    g0, g1 = b["groups"]
    assert g0["compared"] and not g1["compared"] and g1["at_noise_floor"] and "noise floor" in g1["not_compared"]
    assert not g1["resolved_measured"] and g1["beyond_single_nyquist"] and not g0["beyond_single_nyquist"]
    assert row.measured == pytest.approx(abs(0.2 - g0["ctf_predicted"]))  # group 1 (0.4 read) left out
