"""Parameter sweeps over real imagery (``satchain simulate IN... --sweep KEY=V1,V2 -o DIR``, satchain.engine.sweep):
parsing and up-front refusal, the cartesian product, the manifest, reproducible seeds, a failed case, and the
physics (a longer along-track smear blurs an edge across rows more, and leaves one across columns alone)."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from satchain import io, load_preset
from satchain.cli.main import app
from satchain.engine import files
from satchain.engine.files import simulate_file
from satchain.engine.sweep import case_seed, parse_sweep, plan_sweep, read_manifest, simulate_sweep
from satchain.errors import ConfigError

SYSTEM = load_preset("ankarasat3")
PIXEL_M = SYSTEM.gsd_act_m / 4  # 4 input pixels per output pixel
runner = CliRunner()


def _edge(shape=(128, 128), position=61.3, along="y", lo=0.1, hi=0.6) -> np.ndarray:
    """A straight edge integrated exactly over the pixels: bright beyond ``position`` (px) along ``along``."""
    i = np.arange(shape[0] if along == "y" else shape[1], dtype=float)
    cover = np.clip(i + 1 - position, 0.0, 1.0)  # the bright part of pixel [i, i+1)
    prof = lo + (hi - lo) * cover
    img = np.repeat(prof[:, None], shape[1], axis=1) if along == "y" else np.repeat(prof[None, :], shape[0], axis=0)
    return img.astype(np.float32)


@pytest.fixture()
def inputs(tmp_path):
    d = tmp_path / "in"
    d.mkdir()
    rows, cols = d / "rows.tif", d / "cols.tif"  # the edge across rows (ALT) / across columns (ACT)
    io.write_tiff(rows, _edge(along="y"), pixel_m=PIXEL_M)
    io.write_tiff(cols, _edge(along="x"), pixel_m=PIXEL_M)
    return rows, cols


def _cli(*args):
    return runner.invoke(app, ["simulate", *map(str, args)])


# ------------------------------------------------------------------------------------------------ parsing


def test_values_are_typed_as_the_key_needs_them():
    got = parse_sweep(["motion.smear_px=0.5, 1,2e0", "detector.readout=ccd,cmos", "atmosphere.turbulence=true,False"])
    assert got == {"motion.smear_px": [0.5, 1, 2.0], "detector.readout": ["ccd", "cmos"],
                   "atmosphere.turbulence": [True, False]}  # fmt: skip
    assert parse_sweep(["radiometry.integration_time_s=none,0.001"]) == {"radiometry.integration_time_s": [None, 0.001]}


@settings(max_examples=60, deadline=None)
@given(st.floats(min_value=0, max_value=100, allow_nan=False))
def test_a_value_written_in_a_name_reads_back_as_the_same_value(value):
    (case,), _ = plan_sweep(["a.tif"], SYSTEM, "out", sweep={"motion.smear_px": [value]})
    text = case.id.split("=", 1)[1]
    assert parse_sweep([f"motion.smear_px={text}"])["motion.smear_px"] == [value]


BAD = [
    (["--sweep", "motion.bogus=1"], "motion has no field 'bogus'"),
    (["--sweep", "smear=1"], "parameter 'smear'"),
    (["--sweep", "motion.smear_px=0.5,abc"], "motion.smear_px=abc: not a finite number"),
    (["--sweep", "motion.smear_px=nan"], "not a finite number"),
    (["--sweep", "motion.smear_px="], "needs one or more comma-separated values"),
    (["--sweep", "motion.smear_px=1,,2"], "none empty"),
    (["--sweep", "motion.smear_px"], "must be KEY=V1,V2"),
    (["--sweep", "motion.smear_px=1,1.0"], "the value 1 is given twice"),
    (["--sweep", "motion.smear_px=1", "--sweep", "motion.smear_px=2"], "given twice"),
    (["--sweep", "motion.smear_px=0.5,500"], "motion.smear_px = 500"),
    (["--sweep", "detector.readout=ccd,foo"], "'ccd' or 'cmos'"),
    (["--sweep", "atmosphere.turbulence=yes"], "takes true or false"),
    (["--sweep", "optics.wavelengths_m=5e-7"], "not one value per case"),
    (["--sweep", "motion.smear_px=1", "--focal-plane", "f.tif"], "--focal-plane"),
    (["--sweep", "motion.smear_px=1", "--seed", "-1"], "--seed -1"),
    (["--sweep", "motion.smear_px=1", "--units", "kelvin"], "--units"),
    (["{missing}", "--sweep", "motion.smear_px=1"], "no such file"),
    (["{rows}"], "would both write 'rows.tif'"),  # the same input twice
]


@pytest.mark.parametrize(("args", "message"), BAD, ids=[" ".join(a) for a, _ in BAD])
def test_a_bad_sweep_is_one_line_exit_2_and_nothing_written(tmp_path, inputs, args, message):
    rows, _ = inputs
    args = [a.format(missing=tmp_path / "missing.tif", rows=rows) for a in args]
    r = _cli(rows, *args, "-o", tmp_path / "out")
    assert r.exit_code == 2, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0], r.stderr
    assert not (tmp_path / "out").exists()


def test_a_sweep_wants_a_directory_of_its_own(tmp_path, inputs):
    rows, _ = inputs
    r = _cli(rows, "--sweep", "motion.smear_px=1", "-o", tmp_path / "out.tif")
    assert r.exit_code == 2 and "-o is a directory" in r.stderr and not (tmp_path / "out.tif").exists()
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    r = _cli(rows, "--sweep", "motion.smear_px=1", "-o", mine)
    assert r.exit_code == 2 and "not a satchain simulate directory" in r.stderr
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]


def test_every_combination_is_validated_before_any_work(tmp_path):
    # each value alone is valid; one combination is not (the obscuration is checked per system): nothing runs
    with pytest.raises(ConfigError, match="optics.obscuration_ratio"):
        simulate_sweep(["paper"], SYSTEM, tmp_path / "o", sweep={"optics.obscuration_ratio": [0.3, 1.0]})
    assert not (tmp_path / "o").exists()


# ------------------------------------------------------------------------------------------------ the product


def test_the_cartesian_product_one_image_per_case_and_the_manifest(tmp_path, inputs):
    rows, cols = inputs
    out = tmp_path / "out"
    r = _cli(rows, cols, "--sweep", "motion.smear_px=0.5,1,2", "--sweep", "optics.obscuration_ratio=0.2,0.3",
             "-o", out)  # fmt: skip
    assert r.exit_code == 0, r.output
    assert "simulated 12 of 12 cases" in r.stdout
    data = json.loads((out / "manifest.json").read_text())
    assert data["format"] == "satchain-sweep/1" and data["seed"] == 0
    assert data["sweep"] == {"motion.smear_px": [0.5, 1, 2], "optics.obscuration_ratio": [0.2, 0.3]}
    cases = data["cases"]
    expected = [(i, s, o) for i in ("rows.tif", "cols.tif") for s in (0.5, 1, 2) for o in (0.2, 0.3)]
    assert [(c["input"].rsplit("/", 1)[-1], *c["parameters"].values()) for c in cases] == expected
    assert [c["case"] for c in cases] == list(range(1, 13))
    assert cases[0]["id"] == "rows__motion.smear_px=0.5__optics.obscuration_ratio=0.2"
    assert {c["status"] for c in cases} == {"written"} and {tuple(c["shape_px"]) for c in cases} == {(32, 32)}
    assert len({c["image"] for c in cases}) == len({c["seed"] for c in cases}) == 12
    images = [io.read_image(out / c["image"])[0] for c in cases]
    assert all((out / c["preview"]).is_file() for c in cases)
    assert len({a.tobytes() for a in images}) == 12  # every case its own image (and its own noise)
    with open(out / "manifest.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert [(int(t["case"]), t["id"], int(t["seed"]), t["status"], t["image"]) for t in table] == [
        (c["case"], c["id"], c["seed"], c["status"], c["image"]) for c in cases
    ]
    assert [float(t["motion.smear_px"]) for t in table[:6]] == [0.5, 0.5, 1, 1, 2, 2]
    assert read_manifest(out)[3].image == out / cases[3]["image"]
    # the directory is the sweep's: a second sweep may write into it again
    assert _cli(rows, "--sweep", "motion.smear_px=4", "-o", out).exit_code == 0


def test_several_inputs_without_a_sweep_one_image_each(tmp_path, inputs):
    rows, cols = inputs
    r = _cli(rows, cols, "-o", tmp_path / "out")
    assert r.exit_code == 0, r.output
    assert [(c.id, c.parameters) for c in read_manifest(tmp_path / "out")] == [("rows", {}), ("cols", {})]


# ------------------------------------------------------------------------------------------------ seeds


def test_a_case_alone_with_its_seed_reproduces_its_image_bit_for_bit(tmp_path, inputs):
    rows, cols = inputs
    out = tmp_path / "all"
    r = _cli(rows, cols, "--sweep", "motion.smear_px=0.5,2", "--seed", "11", "-o", out)  # DN, with noise
    assert r.exit_code == 0, r.output
    case = read_manifest(out)[3]  # cols, smear 2
    assert case.seed == case_seed(11, cols, {"motion.smear_px": 2})
    image = io.read_image(case.image)[0]
    # the same case alone: in a sweep of one ...
    r = _cli(cols, "--sweep", "motion.smear_px=2", "--seed", "11", "-o", tmp_path / "one")
    assert r.exit_code == 0, r.output
    (alone,) = read_manifest(tmp_path / "one")
    assert alone.seed == case.seed
    np.testing.assert_array_equal(io.read_image(alone.image)[0], image)
    # ... and by simulate_file with the manifest's seed
    again = simulate_file(cols, tmp_path / "again.tif", SYSTEM.replace(case.parameters), seed=case.seed)
    np.testing.assert_array_equal(io.read_image(again.path)[0], image)
    # the noise differs between cases (their own seeds), and so with another sweep seed
    other = read_manifest(out)[2]  # cols, smear 0.5
    assert other.seed != case.seed
    r = _cli(cols, "--sweep", "motion.smear_px=2", "--seed", "12", "-o", tmp_path / "seed12")
    assert not np.array_equal(io.read_image(read_manifest(tmp_path / "seed12")[0].image)[0], image)


def test_one_input_without_a_sweep_is_the_single_file_command(tmp_path, inputs):
    rows, _ = inputs
    r = _cli(rows, "--seed", "5", "-o", tmp_path / "one.tif")
    assert r.exit_code == 0, r.output
    assert not (tmp_path / "manifest.json").exists()
    ref = simulate_file(rows, tmp_path / "ref.tif", SYSTEM, seed=5)
    np.testing.assert_array_equal(io.read_image(tmp_path / "one.tif")[0], io.read_image(ref.path)[0])


# ------------------------------------------------------------------------------------------------ physics


def _edge_sharpness(image: np.ndarray, axis: int) -> float:
    """The largest step between neighbouring pixels across the edge, over the whole step (1: a perfect edge)."""
    prof = image[8:-8].mean(axis=0) if axis == 1 else image[:, 8:-8].mean(axis=1)
    step = prof[-4:].mean() - prof[:4].mean()
    return float(np.max(np.diff(prof)) / step)


def test_a_longer_smear_blurs_an_edge_across_rows_more_and_leaves_columns_alone(tmp_path, inputs):
    smears = [0.0, 0.5, 1.0, 2.0, 3.0, 4.0]
    cases = simulate_sweep(inputs, SYSTEM, tmp_path / "out", sweep={"motion.smear_px": smears},
                           units="reflectance", noise=False)  # fmt: skip
    images = [io.read_image(c.image)[0].astype(float) for c in cases]
    rows = [_edge_sharpness(a, axis=0) for a in images[: len(smears)]]
    cols = [_edge_sharpness(a, axis=1) for a in images[len(smears) :]]
    assert all(a > b for a, b in zip(rows, rows[1:], strict=False)), rows  # ALT: blurs more and more
    assert rows[-1] < 0.6 * rows[0]
    np.testing.assert_allclose(cols, cols[0], rtol=1e-6)  # ACT: the along-track smear does not touch it
    assert cols[0] == pytest.approx(rows[0], rel=0.05)  # the same edge, the same blur without smear
    # closed form: a linear smear of 3 px is the 1 px smear shifted by -1, 0 and +1 px and averaged
    one, three = images[smears.index(1.0)], images[smears.index(3.0)]
    np.testing.assert_allclose(three[4:-4], (one[3:-5] + one[4:-4] + one[5:-3]) / 3, atol=1e-6)


# ------------------------------------------------------------------------------------------------ a failed case


@pytest.fixture()
def failing_third_case(monkeypatch):
    real, calls = files.simulate_file, []

    def fake(input_, out, system, **kw):
        calls.append(out)
        if len(calls) == 3:
            out.write_bytes(b"half a TIFF")  # a case that dies while writing
            raise MemoryError("out of memory in case 3")
        return real(input_, out, system, **kw)

    monkeypatch.setattr(files, "simulate_file", fake)
    return calls


def test_a_failed_case_leaves_no_file_and_the_manifest_says_what_was_written(tmp_path, inputs, failing_third_case):
    rows, _ = inputs
    out = tmp_path / "out"
    r = _cli(rows, "--sweep", "motion.smear_px=0.5,1,2,4", "-o", out)
    assert r.exit_code == 2
    assert "simulated 2 of 4 cases" in r.stdout and "(case 3, rows__motion.smear_px=2, failed; 1 not run)" in r.stdout
    assert r.stderr.strip().splitlines() == ["error: out of memory: reduce the image or scene size (or the window), "
                                             "or use a machine with more memory"]  # fmt: skip
    cases = read_manifest(out)
    assert [c.status for c in cases] == ["written", "written", "failed", "not run"]
    assert cases[2].error == "MemoryError: out of memory in case 3"
    assert [c.image.exists() for c in cases] == [True, True, False, False]
    assert not [p for p in out.iterdir() if p.name.startswith(".") and p.name != ".satchain-run.json"]
    with open(out / "manifest.csv", newline="") as f:
        assert [row["status"] for row in csv.DictReader(f)] == ["written", "written", "failed", "not run"]


def test_an_interrupted_sweep_records_it_and_exits_130(tmp_path, inputs, monkeypatch):
    rows, _ = inputs
    real = files.simulate_file

    def fake(input_, out, system, **kw):
        if "smear_px=1" in out.name:
            raise KeyboardInterrupt
        return real(input_, out, system, **kw)

    monkeypatch.setattr(files, "simulate_file", fake)
    with pytest.raises(KeyboardInterrupt):
        simulate_sweep([rows], SYSTEM, tmp_path / "py", sweep={"motion.smear_px": [0.5, 1, 2]})
    assert [c.status for c in read_manifest(tmp_path / "py")] == ["written", "interrupted", "not run"]
    r = _cli(rows, "--sweep", "motion.smear_px=0.5,1,2", "-o", tmp_path / "cli")
    assert r.exit_code == 130 and "interrupted (SIGINT)" in r.stderr


# issue 29 follow-up: a rerun replaces the sweep folder as `run` replaces its own
@pytest.mark.parametrize("listed", [True, False])  # False: a manifest written before it listed its files
def test_a_rerun_replaces_the_earlier_sweeps_cases_and_keeps_the_users_files(tmp_path, inputs, listed):
    rows, _ = inputs
    out = tmp_path / "sw"
    assert _cli(rows, "--sweep", "motion.smear_px=0.5,2", "-o", out).exit_code == 0
    (out / "mynotes.txt").write_text("mine")
    if not listed:
        m = json.loads((out / "manifest.json").read_text())
        m.pop("files", None)
        (out / "manifest.json").write_text(json.dumps(m))
    r = _cli(rows, "--sweep", "motion.smear_px=0.7", "-o", out)
    assert r.exit_code == 0, r.output
    assert f"kept 1 file satchain did not write in {str(out)!r}: mynotes.txt" in " ".join(r.output.split())
    cases = read_manifest(out)
    assert [c.parameters for c in cases] == [{"motion.smear_px": 0.7}]
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [
            ".satchain-run.json",
            "manifest.csv",
            "manifest.json",
            "mynotes.txt",
            cases[0].image.name,
            cases[0].preview.name,
        ]  # fmt: skip
    )
    assert (out / "mynotes.txt").read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in", "sw"]  # no staging folder left beside it


def test_a_users_file_where_the_rerun_writes_is_refused_before_any_work(tmp_path, inputs):
    rows, _ = inputs
    out = tmp_path / "sw"
    assert _cli(rows, "--sweep", "motion.smear_px=0.5", "-o", out).exit_code == 0
    (out / "rows__motion.smear_px=0.7.png").write_bytes(b"my drawing")
    before = sorted(p.name for p in out.iterdir())
    r = _cli(rows, "--sweep", "motion.smear_px=0.7", "-o", out)
    assert r.exit_code == 2 and "not listed in its manifest.json" in " ".join(r.output.split()), r.output
    assert sorted(p.name for p in out.iterdir()) == before
    assert (out / "rows__motion.smear_px=0.7.png").read_bytes() == b"my drawing"
