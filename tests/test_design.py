"""satchain design: the inverse question by the budget (issue 31 point 4) -- the found interval's ends against a
dense grid of the same margins, the binding margin ~0 at an end, unreachable targets, bad input (exit 2)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from satchain.cli.main import app
from satchain.config.system import load_preset
from satchain.errors import ConfigError
from satchain.studies.design import design, design_figures, parse_target, parse_vary, vary_system

KEY = "optics.aperture_diameter_m"
TARGETS = ["niirs>=5.2", "mtf_nyquist_alt>=0.10", "snr>=60"]


@pytest.fixture(scope="module")
def system():
    return load_preset("ankarasat3")


@pytest.fixture(scope="module")
def result(system):
    return design(system, KEY, 0.2, 1.5, [parse_target(t) for t in TARGETS])


def test_ends_agree_with_a_dense_grid(system, result):
    targets = [parse_target(t) for t in TARGETS]
    # a dense grid (step 1.3/2000) around each end of the found interval, plus a coarser one over the whole range
    step = 1.3 / 2000
    assert len(result.intervals) == 1
    iv = result.intervals[0]
    grid = np.concatenate(
        [
            0.2 + step * np.arange(2001)[abs(0.2 + step * np.arange(2001) - iv["lo"]) < 20 * step],
            np.linspace(0.2, 1.5, 131),
        ]
    )
    grid = np.unique(grid)
    ok = np.array([all(t.margin(design_figures(vary_system(system, KEY, x))) >= 0 for t in targets) for x in grid])
    feasible = grid[ok]
    assert feasible.min() == pytest.approx(iv["lo"], abs=step)
    assert feasible.max() == pytest.approx(iv["hi"], abs=1e-12)  # the range's end
    assert iv["hi"] == 1.5 and iv["hi_binding"] is None


def test_binding_margin_is_zero_at_the_end(result):
    iv = result.intervals[0]
    assert iv["lo_binding"] == "snr>=60"
    assert abs(iv["margins_lo"]["snr>=60"]) < 1e-6
    assert all(m > 0 for k, m in iv["margins_lo"].items() if k != "snr>=60")
    # at fixed focal length the f-number follows the aperture: said in the result
    assert result.follows == "optics.f_number" and "focal_length_m" in result.held_fixed


def test_q_target_end_matches_the_closed_form(system):
    """Q grows as the aperture shrinks at fixed focal length: Q >= 1.5 holds below an aperture Q * D / 1.5."""
    r = design(system, KEY, 0.2, 1.5, [parse_target("q>=1.5")])
    (iv,) = r.intervals
    assert iv["lo"] == 0.2 and iv["hi_binding"] == "q>=1.5"
    assert abs(iv["margins_hi"]["q>=1.5"]) < 1e-9
    # Q = lambda N / p at N = f / D: the closed form of the end
    d = system.derived()
    q07 = d["q_effective"] * 0.7  # Q * D is constant at fixed focal length
    assert iv["hi"] == pytest.approx(q07 / 1.5, rel=1e-6)


def test_cli_text_and_json():
    runner = CliRunner()
    args = ["design", "--preset", "ankarasat3", "--vary", f"{KEY}=0.2:1.5"] + sum(
        (["--target", t] for t in TARGETS), []
    )
    res = runner.invoke(app, [*args, "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["feasible"] and d["follows"] == "optics.f_number"
    assert d["intervals"][0]["lo_binding"] == "snr>=60"
    res = runner.invoke(app, args)
    assert res.exit_code == 0 and "feasible:" in res.stdout and "f_number follows" in res.stdout


def test_unreachable_target_names_itself_and_the_best_value():
    res = CliRunner().invoke(app, ["design", "--vary", f"{KEY}=0.2:1.5", "--target", "niirs>=7", "--target", "snr>=60"])
    assert res.exit_code == 1
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "niirs>=7" in lines[0] and "best niirs found is 5.27" in lines[0]


@pytest.mark.parametrize(
    ("vary", "target", "named"),
    [
        ("optics.nope=0.2:1.5", "niirs>=5", "optics.nope"),
        (f"{KEY}=-1:1.5", "niirs>=5", "aperture_diameter_m = -1"),
        (f"{KEY}=1.5:0.2", "niirs>=5", "1.5:0.2"),
        (f"{KEY}=a:b", "niirs>=5", "'a'"),
        (f"{KEY}=0.2:1.5", "foo>=5", "'foo'"),
        (f"{KEY}=0.2:1.5", "niirs=>5", "niirs=>5"),
        (f"{KEY}=0.2:1.5", "niirs>=x", "'x'"),
    ],
)
def test_bad_input_exits_2_naming_it(vary, target, named):
    res = CliRunner().invoke(app, ["design", "--vary", vary, "--target", target])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and named in lines[0]


def test_parsers():
    assert parse_vary(f"{KEY}=0.2:1.5") == (KEY, 0.2, 1.5)
    with pytest.raises(ConfigError, match="unknown quantity"):
        parse_target("bogus<1")


def test_two_keys_feasibility_map_agrees_with_the_one_key_answer(system, tmp_path):
    """Each row of the map (one TDI count) is feasible exactly from the one-key answer's lower end up; the CLI writes
    feasibility.csv (one row per cell) and feasibility.png."""
    from satchain.studies.design_map import feasibility_map

    targets = [parse_target(t) for t in TARGETS]
    fmap = feasibility_map(system, [(KEY, 0.4, 1.2), ("detector.tdi_stages", 8, 32)], targets, n=5)
    assert fmap.x2.tolist() == [8, 14, 20, 26, 32]
    for i2, tdi in enumerate(fmap.x2):
        one = design(vary_system(system, "detector.tdi_stages", tdi), KEY, 0.4, 1.2, targets)
        lo = one.intervals[0]["lo"] if one.intervals else np.inf
        assert fmap.feasible[i2].tolist() == (fmap.x1 >= lo).tolist(), tdi
    out = tmp_path / "map"
    args = ["design", "--vary", f"{KEY}=0.4:1.2", "--vary", "detector.tdi_stages=8:32", "--grid", "4", "-o", str(out)]
    res = CliRunner().invoke(app, args + sum((["--target", t] for t in TARGETS), []))
    assert res.exit_code == 0, res.output
    rows = (out / "feasibility.csv").read_text().splitlines()
    assert len(rows) == 1 + 16 and rows[0].startswith(f"{KEY},detector.tdi_stages,")
    assert (out / "feasibility.png").stat().st_size > 0
    assert json.loads((out / "design.json").read_text())["cells"] == 16


def test_python_entry_point_gives_the_cli_answer(system, result):
    import satchain

    r = satchain.design("ankarasat3", {KEY: (0.2, 1.5)}, TARGETS)  # a preset name, target strings
    assert r.intervals == result.intervals and r.held_fixed == result.held_fixed
    m = satchain.design(system, {KEY: (0.5, 1.0), "detector.tdi_stages": (8, 32)}, ["snr>=60"], grid=5)
    assert m.feasible.shape == (5, 5)
    # feasibility on the map's grid is the budget's SNR against the threshold, point by point
    for i2, tdi in enumerate(m.x2):
        for i1, ap in enumerate(m.x1):
            s = vary_system(vary_system(system, KEY, float(ap)), "detector.tdi_stages", float(tdi))
            assert m.feasible[i2, i1] == (design_figures(s)["snr"] >= 60)
    with pytest.raises(ConfigError, match="must map one or two keys"):
        satchain.design(system, {}, TARGETS)
    with pytest.raises(ConfigError, match="lo must be below hi"):
        satchain.design(system, {KEY: (1.0, 0.5)}, TARGETS)
    with pytest.raises(ConfigError, match="unknown quantity 'nirs'"):
        satchain.design(system, {KEY: (0.5, 1.0)}, ["nirs>=5"])
