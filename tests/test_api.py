"""The public Python API: what ``import satchain`` offers, the rectangle type, the typed truth reader, and no
matplotlib backend switch anywhere."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import tomllib
from typer.testing import CliRunner

import satchain
from satchain.errors import InputError
from satchain.geometry import Rect, as_rect
from satchain.measure._common import crop_roi
from satchain.scene.truth import BarTargetTruth, EdgeTruth, ObjectTruth, StarTruth, WedgeTruth, read_truth

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"


def test_documented_names_resolve_to_their_objects():
    from satchain import api, comparison, measure, prediction
    from satchain.config import run as runconfig
    from satchain.engine import simulate as engine_simulate
    from satchain.tf import budget as tf_budget

    expected = {
        "run": api.run,
        "RunResult": api.RunResult,
        "RunConfig": runconfig.RunConfig,
        "compare": comparison.compare,
        "predict": prediction.predict,
        "simulate": engine_simulate.simulate,
        "SystemOTF": tf_budget.SystemOTF,
        "measure_edge": measure.measure_edge,
        "measure_star": measure.measure_star,
        "measure_bars": measure.measure_bars,
        "measure_wedge": measure.measure_wedge,
    }
    for name, obj in expected.items():
        public = getattr(satchain, name)  # the entry points are their functions behind a type check
        assert public is obj or public.__wrapped__ is obj, name
        assert name in satchain.__all__
    for name in satchain.__all__:
        assert getattr(satchain, name) is not None, name
    assert {"ImagingSystem", "load_preset", "coltman_ctf", "measure_auto", "InputError"} <= set(dir(satchain))
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        satchain.nope  # noqa: B018


def test_py_typed_is_shipped():
    assert (SRC / "satchain" / "py.typed").is_file()
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["satchain"]
    assert "py.typed" in data


def _run(code: str, **env) -> str:
    import os

    r = subprocess.run(
        [sys.executable, "-c", code],
        env={**os.environ, "PYTHONPATH": str(SRC), **env},
        capture_output=True,
        text=True,
        check=True,
    )
    return r.stdout.strip()


def test_import_is_light_and_never_switches_the_matplotlib_backend():
    code = "import sys, satchain; print('matplotlib' in sys.modules, 'scipy' in sys.modules)"
    assert _run(code) == "False False"
    code = (
        "import matplotlib, satchain, satchain.report.run_figures, satchain.report.figures, "
        "satchain.report.measure_plots, satchain.report.radiometry_plot, satchain.report.html, satchain.pipeline; "
        "import sys; print(matplotlib.get_backend(), 'matplotlib.pyplot' in sys.modules)"
    )
    assert _run(code, MPLBACKEND="svg") == "svg False"


def test_plots_render_headless_through_the_object_oriented_api(tmp_path):
    from matplotlib.figure import Figure

    from satchain.report._save import save_figure

    fig = Figure(figsize=(2, 2))
    ax = fig.subplots()
    ax.plot([0, 1], [0, 1])
    save_figure(fig, tmp_path / "f.png")
    assert (tmp_path / "f.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# ------------------------------------------------------------------------------------------------ Rect


def test_rect_round_trips_and_slices():
    r = Rect.from_roi((5, 2, 25, 12))
    assert (r.row0, r.col0, r.row1, r.col1) == (2, 5, 12, 25)
    assert Rect.from_window(r.to_window()) == r and Rect.from_roi(r.to_roi()) == r
    img = np.arange(20 * 30).reshape(20, 30).astype(float)
    assert np.array_equal(img[r.slices], img[2:12, 5:25])
    assert np.array_equal(crop_roi(img, r), crop_roi(img, (5, 2, 25, 12)))
    assert as_rect((2, 5, 10, 20), kind="window") == r and as_rect(r) is r
    assert r.inside(img.shape) and not Rect(0, 0, 21, 5).inside(img.shape)


@pytest.mark.parametrize("bad", [(0, 0, 0, 5), (3, 0, 2, 5), (0.5, 0, 2, 2)])
def test_rect_refuses_empty_inverted_or_fractional(bad):
    with pytest.raises(InputError, match="Rect|must be"):
        Rect(*bad)


# ------------------------------------------------------------------------------------------------ truth


@pytest.fixture(scope="module")
def truth_file(tmp_path_factory):
    d = tmp_path_factory.mktemp("truth")
    r = CliRunner().invoke(satchain_cli(), ["scene", "--layout", "paper", "--pixel-m", "2.0", "-o", str(d / "p.tif")])
    assert r.exit_code == 0, r.output
    return d / "p.truth.json"


def satchain_cli():
    from satchain.cli.main import app

    return app


def test_truth_written_by_the_scene_command_round_trips_losslessly(truth_file):
    raw = json.loads(truth_file.read_text())
    t = read_truth(truth_file)
    assert t.to_dict() == raw
    assert read_truth(raw) == t
    assert json.loads(json.dumps(t.to_dict())) == raw
    kinds = {type(it) for it in t.items}
    assert {EdgeTruth, StarTruth, BarTargetTruth, WedgeTruth, ObjectTruth} <= kinds
    assert t.pixel_m == 2.0 and t.window == Rect(0, 0, *raw["shape_px"])


def test_truth_items_are_typed_with_their_geometry(truth_file):
    raw = {it["id"]: it for it in json.loads(truth_file.read_text())["items"]}
    t = read_truth(truth_file)
    e = t["edge_act_5deg"]
    assert isinstance(e, EdgeTruth) and e.measures == "act" and e.angle_deg == 5.0
    assert np.hypot(*e.normal_to_bright) == pytest.approx(1.0) and e.bright > e.dark
    assert e.bbox_px == Rect.from_window(raw["edge_act_5deg"]["bbox_px"])
    (star,) = t.stars
    assert star.cycles == 32 and star.center_m == tuple(raw[star.id]["center_m"])
    bars = t.bar_targets[0]
    assert [g.period_m for g in bars.groups] == raw[bars.id]["periods_m"]
    assert all(len(g.bars_m) == bars.n_bars for g in bars.groups)
    assert {w.orientation for w in t.wedges} >= {"horizontal", "vertical"}
    assert all(o.kind in ("road", "car", "railway", "wagon", "house") for o in t.objects)


def test_truth_reader_refuses_other_files(tmp_path):
    p = tmp_path / "x.json"
    p.write_text(json.dumps({"format": "something-else", "items": []}))
    with pytest.raises(InputError, match="truth format"):
        read_truth(p)
    with pytest.raises(OSError, match="not found"):
        read_truth(tmp_path / "missing.json")
