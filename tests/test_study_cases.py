"""satchain study, budget depth (issue 31 points 1, 2 and 7): the study file, its cases (product and zip, linspace
and step values, seeds), every case validated before anything is written, and study.csv's rows against
satchain.budget() of the same systems built by hand."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from satchain.cli.main import app
from satchain.config.study import Axis, StudyFile, load_study
from satchain.config.system import load_preset
from satchain.errors import ConfigError
from satchain.prediction.budget import budget
from satchain.studies.cases import expand_cases
from satchain.studies.tables import FIGURES

AP = "optics.aperture_diameter_m"
WFE = "optics.wfe_rms_waves"


def _study(axes, **study) -> StudyFile:
    return StudyFile.from_dict({"axes": axes, "study": {"depth": "budget", **study}})


def test_product_and_zip_counts():
    axes = [{"key": AP, "values": [0.35, 0.5, 0.7]}, {"key": WFE, "values": [0.0, 0.05, 0.1]}]
    assert len(expand_cases(_study(axes))) == 9
    cases = expand_cases(_study(axes, zip=True))
    assert len(cases) == 3 and [c.values for c in cases][1] == {AP: 0.5, WFE: 0.05}
    assert [c.case_id for c in cases] == ["c0001", "c0002", "c0003"]


def test_linspace_and_step_values_exact():
    assert Axis(key=AP, start=0.3, stop=0.7, num=5).expanded() == (0.3, 0.4, 0.5, 0.6, 0.7)
    assert Axis(key=WFE, start=0.0, stop=0.1, step=0.05).expanded() == (0.0, 0.05, 0.1)
    assert Axis(key=WFE, start=0.1, stop=0.0, step=-0.025).expanded() == (0.1, 0.075, 0.05, 0.025, 0.0)
    assert Axis(key="detector.tdi_stages", start=1, stop=10, step=4).expanded() == (1.0, 5.0, 9.0)


def test_seeds_distinct_and_reproducible():
    s = _study([{"key": AP, "values": [0.35, 0.5, 0.7]}], repeats=3)
    a, b = expand_cases(s), expand_cases(s)
    seeds = [x for c in a for x in c.seeds]
    assert len(seeds) == 9 and len(set(seeds)) == 9
    assert seeds == [x for c in b for x in c.seeds]


@pytest.mark.parametrize(
    ("axes", "study", "named"),
    [
        (
            [{"key": AP, "values": [0.3, 0.5]}, {"key": WFE, "values": [0.0]}],
            {"zip": True},
            [AP, "2 values", WFE, "has 1"],
        ),
        ([{"key": AP, "values": []}], {}, [AP, "at least one value"]),
        ([{"key": "optics.nope", "values": [1.0]}], {}, ["optics.nope"]),
        ([{"key": WFE, "values": [0.0, 5.0]}], {}, ["c0002", WFE, "5", "0.25"]),
        (
            [{"key": AP, "start": 0.3, "stop": 0.7, "num": 101}, {"key": WFE, "start": 0, "stop": 0.1, "num": 100}],
            {},
            ["10100 cases", "10000", "--max-cases"],
        ),
        ([{"key": "scene.pixel_m", "values": [0.035]}], {}, ["scene.pixel_m", "depth = 'run'"]),
        ([{"key": AP, "values": [0.3], "start": 0.1}], {}, [AP, "both given"]),
        ([{"key": AP, "values": [float("nan")]}], {}, ["axes[0].values", "finite"]),
    ],
)
def test_bad_input_refused_naming_key_and_value(tmp_path: Path, axes, study, named):
    with pytest.raises(ConfigError) as err:
        expand_cases(_study(axes, **study))
    for n in named:
        assert n in str(err.value), str(err.value)
    # the CLI: one line, exit 2, nothing written under -o
    lines = ["[study]", 'depth = "budget"'] + [f"{k} = {str(v).lower()}" for k, v in study.items()]
    for a in axes:
        lines += ["[[axes]]"] + [f"{k} = {_toml(v)}" for k, v in a.items()]
    f = tmp_path / "study.toml"
    f.write_text("\n".join(lines) + "\n")
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["study", str(f), "-o", str(out)])
    assert res.exit_code == 2, res.output
    assert named[0] in res.stderr and not out.exists()


def _toml(v) -> str:
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    if isinstance(v, float) and math.isnan(v):
        return "nan"
    return repr(v)


def test_max_cases_allows_more():
    axes = [{"key": AP, "start": 0.3, "stop": 0.7, "num": 101}, {"key": WFE, "start": 0, "stop": 0.1, "num": 100}]
    with pytest.raises(ConfigError, match="more than 10000"):
        expand_cases(_study(axes), max_cases=None)
    with pytest.raises(ConfigError, match="10100 cases, more than 50"):
        expand_cases(_study(axes), max_cases=50)


def test_budget_rows_equal_budget_of_systems_built_by_hand(tmp_path: Path):
    f = tmp_path / "study.toml"
    (tmp_path / "run.toml").write_text('[system]\npreset = "ankarasat3"\n[simulation]\nseed = 11\n')
    f.write_text(
        '[base]\nfile = "run.toml"\n[[axes]]\nkey = "optics.aperture_diameter_m"\nvalues = [0.35, 0.5, 0.7]\n'
        '[[axes]]\nkey = "optics.wfe_rms_waves"\nvalues = [0.0, 0.05]\n[study]\ndepth = "budget"\n'
    )
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["study", str(f), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "focal_length_m" in res.stdout and "f_number follows" in res.stdout
    rows = list(csv.DictReader((out / "study.csv").open()))
    assert len(rows) == 6 * len(FIGURES)
    base = load_preset("ankarasat3")
    focal = base.derived()["focal_length_m"]
    seen = set()
    for r in rows:
        ap, wfe = float(r[AP]), float(r[WFE])
        d = base.to_dict()
        d["optics"].pop("f_number", None)
        d["optics"].update(aperture_diameter_m=ap, focal_length_m=focal, wfe_rms_waves=wfe)
        b = budget(type(base).from_dict(d))
        assert float(r["predicted"]) == pytest.approx(getattr(b, FIGURES[r["figure"]]), rel=1e-12, abs=1e-15)
        for k in ("gsd_m", "q", "mtf_at_nyquist_act", "mtf_at_nyquist_alt", "snr", "niirs"):
            assert float(r[k]) == pytest.approx(getattr(b, k), rel=1e-12, abs=1e-15)
        assert r["measured"] == r["error"] == r["sigma"] == r["z"] == r["pass"] == r["folder"] == ""
        assert r["case_status"] == "ok" and r["kind"] == "budget" and r["repeat"] == "1"
        seen.add((r["case"], r["seed"]))
    assert len(seen) == 6 and len({s for _, s in seen}) == 6
    table = pq.read_table(out / "study.parquet")  # the same table, typed
    assert table.column_names == list(rows[0])
    assert str(table.schema.field("case").type) == "string" and str(table.schema.field("seed").type) == "int64"
    assert str(table.schema.field("pass").type) == "bool" and str(table.schema.field("predicted").type) == "double"
    for r, p in zip(rows, table.to_pylist(), strict=True):
        assert p["case"] == r["case"] and p["figure"] == r["figure"] and p["seed"] == int(r["seed"])
        assert p["predicted"] == float(r["predicted"]) and p[AP] == float(r[AP]) and p["niirs"] == float(r["niirs"])
        assert p["measured"] is None and p["pass"] is None
    gsd = {float(r["gsd_m"]) for r in rows}
    assert max(gsd) - min(gsd) < 1e-12  # the focal length is held: the GSD stays
    q = {float(r[AP]): float(r["q"]) for r in rows}
    assert q[0.35] * 0.35 == pytest.approx(q[0.7] * 0.7, rel=1e-9)  # Q ~ 1/aperture
    # rerun into the same study folder: allowed; into a user's folder: refused
    assert CliRunner().invoke(app, ["study", str(f), "-o", str(out)]).exit_code == 0
    res = CliRunner().invoke(app, ["study", str(f), "-o", str(tmp_path)])
    assert res.exit_code == 2 and not (tmp_path / "study.csv").exists()


def test_study_file_inline_base_and_run_depth(tmp_path: Path):
    f = tmp_path / "s.toml"
    f.write_text(
        '[base.system]\npreset = "ankarasat3"\n[[axes]]\nkey = "detector.tdi_stages"\nstart = 8\nstop = 32\nstep = 8\n'
    )
    assert load_study(f).study.depth == "budget"  # the default: predictions only
    f.write_text(f.read_text() + '[study]\ndepth = "run"\n')
    s = load_study(f)
    assert (
        s.study.depth == "run"
        and s.study.reports == "failed"
        and s.axis_values()["detector.tdi_stages"] == (8.0, 16.0, 24.0, 32.0)
    )
    assert [c.system.detector.tdi_stages for c in expand_cases(s)] == [8, 16, 24, 32]
    f.write_text('[base]\nfile = "run.toml"\nsystem = {}\n[[axes]]\nkey = "optics.wfe_rms_waves"\nvalues = [0.0]\n')
    with pytest.raises(ConfigError, match="file and system are both given"):
        load_study(f)
    f.write_text('[[axes]]\nkey = "optics.wfe_rms_waves"\nvalues = [0.0]\n[study]\nrepeats = 0\n')
    with pytest.raises(ConfigError, match=r"study.repeats = 0"):
        load_study(f)


def test_run_depth_cases_carry_their_run_configuration():
    axes = [
        {"key": "scene.pixel_m", "values": [0.035, 0.05]},
        {"key": "as_built.optics.wfe_rms_waves", "values": [0.0, 0.1]},
        {"key": "simulation.seed", "values": [3.0, 4.0]},
    ]
    cases = expand_cases(StudyFile.from_dict({"axes": axes, "study": {"depth": "run", "zip": True}}))
    c = cases[1].config
    assert c is not None and c.scene.pixel_m == 0.05 and c.simulation.seed == 4
    built = c.load_as_built_system()
    assert built is not None and built.optics.wfe_rms_waves == 0.1
    bad = [{"key": "as_built.optics.wfe_rms_waves", "values": [0.0, 9.0]}]
    with pytest.raises(ConfigError, match=r"case c0002 \(as_built.optics.wfe_rms_waves = 9\).*wfe_rms_waves"):
        expand_cases(StudyFile.from_dict({"axes": bad, "study": {"depth": "run"}}))
    with pytest.raises(ConfigError, match=r"case c0001 \(scene.pixel_m = -1\).*scene.pixel_m"):
        pixel = [{"key": "scene.pixel_m", "values": [-1.0]}]
        expand_cases(StudyFile.from_dict({"axes": pixel, "study": {"depth": "run"}}))
