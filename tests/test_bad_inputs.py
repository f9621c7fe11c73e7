"""Issue 11: bad and hostile inputs across every command -> exit status 2 and exactly one line on stderr
(``error: ...``), never a traceback, and no file of the user's changed."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import tifffile
from typer.testing import CliRunner

from satchain.cli.main import app

PRESET = Path(__file__).resolve().parents[1] / "src" / "satchain" / "presets" / "ankarasat3.toml"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("bad")
    rng = np.random.default_rng(0)
    f = {"dir": d / "adir"}
    f["dir"].mkdir()
    f["img"] = d / "img.tif"
    tifffile.imwrite(f["img"], rng.random((64, 64)).astype(np.float32), description='{"satchain": {"pixel_m": 0.5}}')
    f["flat"] = d / "flat.tif"
    tifffile.imwrite(f["flat"], np.full((64, 64), 0.3, np.float32), description='{"satchain": {"pixel_m": 0.5}}')
    f["corrupt"] = d / "corrupt.tif"
    f["corrupt"].write_bytes(b"II*\x00" + os.urandom(200))
    f["empty"] = d / "empty.tif"
    f["empty"].write_bytes(b"")
    f["text_png"] = d / "text.png"
    f["text_png"].write_text("not a png")
    f["cube"] = d / "cube.npy"
    np.save(f["cube"], np.zeros((4, 4, 4)))
    f["nan"] = d / "nan.npy"
    np.save(f["nan"], np.full((300, 300), np.nan))
    f["bare"] = d / "bare.npy"
    np.save(f["bare"], np.full((300, 300), 0.5))
    for key, value in (("meta_text", "abc"), ("meta_huge", 1e308), ("meta_list", [1, 2])):
        f[key] = d / f"{key}.tif"
        tifffile.imwrite(
            f[key], np.full((64, 64), 9, np.uint8), description=json.dumps({"satchain": {"pixel_m": value}})
        )
    f["complex"] = d / "complex.npy"
    np.save(f["complex"], np.ones((64, 64), np.complex64))
    f["objects"] = d / "objects.npy"
    np.save(f["objects"], np.array([[None, 1]], dtype=object), allow_pickle=True)
    f["bad_toml"] = d / "bad.toml"
    f["bad_toml"].write_text("name = \n[optics")
    f["unknown_key"] = d / "unknown.toml"
    f["unknown_key"].write_text(PRESET.read_text().replace("[optics]", "[optics]\nbanana = 3"))
    f["neg_fnum"] = d / "neg.toml"
    f["neg_fnum"].write_text(PRESET.read_text().replace("f_number = 9.72", "f_number = -9.72"))
    f["no_well"] = d / "no_well.toml"
    f["no_well"].write_text(PRESET.read_text().replace("full_well_e = 60000.0", ""))
    f["bad_scene"] = d / "scene.toml"
    f["bad_scene"].write_text('[scene]\nwidth_m = -5\n[[items]]\nkind = "unicorn"\n')
    f["cfg_unknown"] = d / "cfg_unknown.toml"
    f["cfg_unknown"].write_text("[simulation]\nsed = 3\n")
    f["cfg_seed"] = d / "cfg_seed.toml"
    f["cfg_seed"].write_text("[simulation]\nseed = -1\n")
    f["cfg_both"] = d / "cfg_both.toml"
    f["cfg_both"].write_text('[system]\npreset = "ankarasat3"\nfile = "x.toml"\n')
    f["cfg_bad"] = d / "cfg_bad.toml"
    f["cfg_bad"].write_text("[simulation\n")
    f["cfg_relfile"] = d / "cfg_relfile.toml"
    f["cfg_relfile"].write_text('[system]\nfile = "nowhere/cam.toml"\n')
    f["truth_garbage"] = d / "garbage.json"
    f["truth_garbage"].write_text("{not json")
    f["truth_list"] = d / "list.json"
    f["truth_list"].write_text(json.dumps([1, 2, 3]))
    f["web"] = d / "webapp"
    f["web"].mkdir()
    (f["web"] / "manifest.json").write_text("{}")
    (f["web"] / "index.html").write_text("<html/>")
    f["afile"] = d / "afile.txt"
    f["afile"].write_text("keep me")
    f["out"] = d / "out.tif"
    f["mdir"] = d / "mdir"
    f["mdir"].mkdir()
    f["mtruth"] = f["mdir"] / "auto.json"
    f["mtruth"].write_text(json.dumps({"format": "satchain-scene-truth/1", "items": []}))
    return f


def _cases(f):
    out, img, d = str(f["out"]), str(f["img"]), f["dir"]
    return {
        # budget
        "budget unknown preset": ["budget", "--preset", "nosuch"],
        "budget missing system": ["budget", "--system", "missing.toml"],
        "budget system is a directory": ["budget", "--system", str(d)],
        "budget invalid TOML": ["budget", "--system", str(f["bad_toml"])],
        "budget unknown key": ["budget", "--system", str(f["unknown_key"])],
        "budget system is a device": ["budget", "--system", os.devnull.replace("null", "zero")],
        "budget negative f-number": ["budget", "--system", str(f["neg_fnum"])],
        "budget freqs not numbers": ["budget", "--freqs", "ten,[dask]"],
        "budget negative freq": ["budget", "--freqs", "-5"],
        "budget preset and system": ["budget", "--preset", "ankarasat3", "--system", str(f["unknown_key"])],
        "budget -o is a file": ["budget", "-o", str(f["afile"])],
        "budget -o holds --system": ["budget", "--system", str(f["mtruth"]), "-o", str(f["mdir"])],
        # scene
        "scene missing layout": ["scene", "--layout", "nosuch.toml", "-o", out],
        "scene layout is a directory": ["scene", "--layout", str(d), "-o", out],
        "scene invalid layout": ["scene", "--layout", str(f["bad_scene"]), "-o", out],
        "scene negative pixel": ["scene", "--pixel-m", "-1", "-o", out],
        "scene zero pixel": ["scene", "--pixel-m", "0", "-o", out],
        "scene window of 3": ["scene", "--window", "1,2,3", "-o", out],
        "scene window words": ["scene", "--window", "a,b,c,d", "-o", out],
        "scene window outside": ["scene", "--pixel-m", "1", "--window", "100000,0,10,10", "-o", out],
        "scene window negative": ["scene", "--pixel-m", "1", "--window", "-5,0,10,10", "-o", out],
        "scene micrometre pixels": ["scene", "--pixel-m", "1e-6", "-o", out],
        "scene -o a directory": ["scene", "--pixel-m", "2", "-o", str(d)],
        "scene -o over layout": ["scene", "--layout", str(f["bad_scene"]), "-o", str(f["bad_scene"])],
        # simulate
        "simulate missing input": ["simulate", "nosuch.tif", "-o", out],
        "simulate input directory": ["simulate", str(d), "-o", out],
        "simulate corrupt TIFF": ["simulate", str(f["corrupt"]), "-o", out],
        "simulate empty TIFF": ["simulate", str(f["empty"]), "-o", out],
        "simulate text as PNG": ["simulate", str(f["text_png"]), "--scene-pixel-m", "0.5", "-o", out],
        "simulate 3-D array": ["simulate", str(f["cube"]), "--scene-pixel-m", "0.5", "-o", out],
        "simulate NaN image": ["simulate", str(f["nan"]), "--scene-pixel-m", "0.2", "-o", out],
        "simulate no pixel size": ["simulate", str(f["bare"]), "-o", out],
        "simulate metadata pixel text": ["simulate", str(f["meta_text"]), "-o", out],
        "simulate metadata pixel 1e308": ["simulate", str(f["meta_huge"]), "-o", out],
        "simulate metadata pixel list": ["simulate", str(f["meta_list"]), "-o", out],
        "simulate pixel 1e308": ["simulate", img, "--scene-pixel-m", "1e308", "-o", out],
        "edge metadata pixel text": ["measure", "edge", str(f["meta_text"])],
        "simulate complex image": ["simulate", str(f["complex"]), "--scene-pixel-m", "0.5", "-o", out],
        "simulate pickled objects": ["simulate", str(f["objects"]), "--scene-pixel-m", "0.5", "-o", out],
        "edge complex image": ["measure", "edge", str(f["complex"]), "--pixel-m", "0.5"],
        "simulate a one-pixel truth": ["simulate", "paper", "--scene-pixel-m", "1000", "-o", out],
        "simulate truth at a millimetre": ["simulate", "paper", "--scene-pixel-m", "1e-3", "-o", out],
        "simulate negative pixel": ["simulate", img, "--scene-pixel-m", "-1", "-o", out],
        "simulate bad units": ["simulate", img, "--units", "furlongs", "-o", out],
        "simulate negative seed": ["simulate", img, "--seed", "-1", "-o", out],
        "simulate -o is input": ["simulate", img, "-o", img],
        "simulate fp is -o": ["simulate", img, "--focal-plane", out, "-o", out],
        "simulate bad fp grid": ["simulate", img, "--focal-plane-grid", "fine", "--focal-plane", "fp.tif", "-o", out],
        "simulate negative input scale": ["simulate", img, "--input-scale", "-2", "-o", out],
        "simulate input scale on a scene": ["simulate", "paper", "--input-scale", "0.5", "-o", out],
        "simulate bits without full well": ["simulate", img, "--system", str(f["no_well"]), "-o", out],
        "simulate -o a directory": ["simulate", img, "-o", str(d)],
        "simulate unknown scheduler": ["simulate", img, "--scheduler", "tcp://[::1", "-o", out],
        # run
        "run missing config": ["run", "--config", "missing.toml", "-o", str(f["dir"] / "r")],
        "run config is a device": ["run", "--config", os.devnull.replace("null", "zero"), "-o", str(f["dir"] / "r")],
        "run invalid config": ["run", "--config", str(f["cfg_bad"]), "-o", str(f["dir"] / "r")],
        "run unknown key": ["run", "--config", str(f["cfg_unknown"]), "-o", str(f["dir"] / "r")],
        "run negative seed": ["run", "--config", str(f["cfg_seed"]), "-o", str(f["dir"] / "r")],
        "run preset and file": ["run", "--config", str(f["cfg_both"]), "-o", str(f["dir"] / "r")],
        "run missing system file": ["run", "--config", str(f["cfg_relfile"]), "-o", str(f["dir"] / "r")],
        "run -o a web app": ["run", "-o", str(f["web"])],
        "run -o a file": ["run", "-o", str(f["afile"])],
        "run unknown preset": ["run", "--preset", "nosuch", "-o", str(f["dir"] / "r")],
        # measure
        "edge missing image": ["measure", "edge", "nosuch.tif"],
        "edge directory": ["measure", "edge", str(d)],
        "edge corrupt": ["measure", "edge", str(f["corrupt"])],
        "edge flat image": ["measure", "edge", str(f["flat"])],
        "edge roi of 3": ["measure", "edge", img, "--roi", "1,2,3"],
        "edge zero pixel": ["measure", "edge", img, "--pixel-m", "0"],
        "edge 3-D": ["measure", "edge", str(f["cube"])],
        "star too few cycles": ["measure", "star", img, "--cycles", "2"],
        "star radius 1e9": ["measure", "star", img, "--cycles", "16", "--radius", "1e9"],
        "star negative radius": ["measure", "star", img, "--cycles", "16", "--radius", "-3"],
        "star flat": ["measure", "star", str(f["flat"]), "--cycles", "16"],
        "bars negative pixel": ["measure", "bars", img, "--periods-px", "8,12", "--pixel-m", "-1"],
        "bars corrupt": ["measure", "bars", str(f["corrupt"]), "--periods-px", "8,12"],
        "wedge missing truth": ["measure", "wedge", img, "--truth", "missing.json"],
        "wedge garbage truth": ["measure", "wedge", img, "--truth", str(f["truth_garbage"])],
        "auto garbage truth": ["measure", "auto", img, "--truth", str(f["truth_garbage"])],
        "auto list truth": ["measure", "auto", img, "--truth", str(f["truth_list"])],
        "auto truth is a directory": ["measure", "auto", img, "--truth", str(d)],
        "auto -o over its truth": ["measure", "auto", img, "--truth", str(f["mtruth"]), "-o", str(f["mdir"])],
    }


def _snapshot(root: Path) -> dict:
    return {p: p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def test_bad_inputs_sweep(files, monkeypatch):
    monkeypatch.setenv("SATCHAIN_MEMORY_LIMIT", "2G")
    root = files["img"].parent
    before = _snapshot(root)
    cases = _cases(files)
    assert len(cases) >= 40
    commands = {c[0] if c[0] != "measure" else c[1] for c in cases.values()}
    assert commands >= {"budget", "scene", "simulate", "run", "edge", "star", "bars", "wedge", "auto"}
    monkeypatch.chdir(root)
    runner = CliRunner()
    bad = []
    for name, args in cases.items():
        r = runner.invoke(app, args)
        lines = r.stderr.strip().splitlines()
        ok = r.exit_code == 2 and len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in r.output
        if not ok:
            bad.append((name, r.exit_code, r.stderr[-300:], repr(r.exception)))
    assert not bad, "\n".join(map(str, bad))
    assert _snapshot(root) == before  # nothing of the user's changed
    assert not files["out"].exists() and not (files["dir"] / "r").exists()


@pytest.mark.parametrize(
    "args",
    [
        ["budget", "--system", "{dir}"],
        ["simulate", "{corrupt}", "-o", "{out}"],
        ["measure", "star", "{img}", "--cycles", "16", "--radius", "1e9"],
    ],
)
def test_bad_inputs_in_a_real_process(files, args):
    """The installed entry point (a real process, a real terminal-less stderr): one line, exit 2."""
    argv = [a.format(**{k: str(v) for k, v in files.items()}) for a in args]
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "src"), "SATCHAIN_MEMORY_LIMIT": "2G"}
    p = subprocess.run([sys.executable, "-m", "satchain.cli.main", *argv], capture_output=True, text=True, env=env)
    assert p.returncode == 2, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and p.stderr.startswith("error: ")


# ------------------------------------------------------------------------------- issue 18: the CLI hostile test
@pytest.fixture(scope="module")
def hostile(tmp_path_factory, reduced_scene_toml):
    """A small rendered scene (image + truth) and the hostile files of issue 18."""
    d = tmp_path_factory.mktemp("hostile")
    (d / "scene.toml").write_text(reduced_scene_toml)
    args = ["scene", "--layout", str(d / "scene.toml"), "--pixel-m", "0.5", "-o", str(d / "sc.tif")]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    image = tifffile.imread(d / "sc.tif")
    f = {"dir": d, "image": d / "sc.tif", "truth": d / "sc.truth.json"}
    f["nan_image"] = d / "nan.tif"
    nan = np.full(image.shape, np.nan, np.float32)
    tifffile.imwrite(f["nan_image"], nan, description='{"satchain": {"pixel_m": 0.5}}')
    f["wrong_pixel"] = d / "wrong_pixel.tif"
    tifffile.imwrite(f["wrong_pixel"], image, description='{"satchain": {"pixel_m": 5.0}}')
    f["other_truth"] = d / "other.truth.json"
    f["other_truth"].write_text(json.dumps({"format": "satchain-scene-truth/1", "items": []}))
    text = PRESET.read_text()
    for key, value in (("alt_true", "true"), ("alt_nan", "nan"), ("alt_text", '"500000"')):
        f[key] = d / f"{key}.toml"
        f[key].write_text(text.replace("altitude_m = 567000.0", f"altitude_m = {value}"))
        assert f[key].read_text() != text
    f["latin1"] = d / "latin1.toml"
    f["latin1"].write_bytes(text.replace('name = "', 'name = "Ankara Üniversitesi ', 1).encode("latin-1"))
    f["cfg_seed"] = d / "cfg_seed.toml"
    f["cfg_seed"].write_text("[simulation]\nseed = true\n")
    f["cfg_overview"] = d / "cfg_overview.toml"
    f["cfg_overview"].write_text("[scene]\noverview_pixel_m = 1e-4\n")
    f["user_dir"] = d / "mybudget"
    f["user_dir"].mkdir()
    (f["user_dir"] / "budget.json").write_text('{"my": "own budget"}')
    return f


HOSTILE_CLI = {
    # bools, strings and NaN are never numbers (altitude_m = true was taken as 1 m: NIIRS -71.9, exit 0)
    "altitude_m = true": (["budget", "--system", "{alt_true}"], "orbit.altitude_m = True: must be a number"),
    "altitude_m = nan": (["budget", "--system", "{alt_nan}"], "orbit.altitude_m = nan: not a finite number"),
    "altitude_m = '500000'": (["budget", "--system", "{alt_text}"], "not a string"),
    "run seed = true": (["run", "--config", "{cfg_seed}", "-o", "{dir}/r"], "simulation.seed = True"),
    "edge --pixel-m nan": (["measure", "edge", "{image}", "--pixel-m", "nan"], "--pixel-m = nan: not a finite"),
    # a Latin-1 system file: named, with the byte offset (was 'unexpected UnicodeDecodeError')
    "Latin-1 system file": (["budget", "--system", "{latin1}"], "not UTF-8 text (byte 0xdc at offset"),
    # impossible work refused up front with its memory (was a generic out-of-memory after 109 s)
    "overview_pixel_m = 1e-4": (["run", "--config", "{cfg_overview}", "-o", "{dir}/r"], "GiB of memory; must be >="),
    # measure auto measured nothing (was exit 0)
    "auto on an all-NaN image": (["measure", "auto", "{nan_image}", "--truth", "{truth}"], "every pixel is NaN"),
    "auto at a wrong pixel size": (
        ["measure", "auto", "{wrong_pixel}", "--truth", "{truth}"],
        "nothing was measured: all 4 targets",
    ),
    "auto with a truth of no targets": (["measure", "auto", "{image}", "--truth", "{other_truth}"], "no target"),
    # budget -o over a user's folder (was: their budget.json overwritten)
    "budget -o a user's folder": (["budget", "-o", "{user_dir}"], "not a satchain budget directory"),
}


@pytest.mark.parametrize("name", list(HOSTILE_CLI))
def test_issue18_hostile_cli_inputs_exit_2_with_one_line(hostile, name, monkeypatch):
    monkeypatch.setenv("SATCHAIN_MEMORY_LIMIT", "2G")
    args, expected = HOSTILE_CLI[name]
    before = _snapshot(hostile["dir"])
    r = CliRunner().invoke(app, [a.format(**{k: str(v) for k, v in hostile.items()}) for a in args])
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2, (r.exit_code, r.output)
    assert lines[-1].startswith("error: ") and expected in lines[-1], r.stderr
    assert "unexpected" not in r.stderr and "Traceback" not in r.output
    assert _snapshot(hostile["dir"]) == before  # nothing of the user's changed
    assert not (hostile["dir"] / "r").exists()


def test_issue18_auto_with_its_own_truth_and_pixel_still_measures(hostile):
    """The control for the refusals above: the same image, its truth and pixel size, measure and exit 0."""
    r = CliRunner().invoke(app, ["measure", "auto", str(hostile["image"]), "--truth", str(hostile["truth"]), "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert len(out["slanted_edges"]) == 2 and len(out["siemens_star"]) == 1


def test_issue18_budget_writes_again_into_its_own_directory(tmp_path):
    out = tmp_path / "b"
    for _ in range(2):  # a new directory, then the same one (marked as satchain's budget output)
        r = CliRunner().invoke(app, ["budget", "-o", str(out)])
        assert r.exit_code == 0, r.output
    assert json.loads((out / ".satchain-run.json").read_text())["kind"] == "budget"
    r = CliRunner().invoke(app, ["run", "-o", str(out)])  # a run does not replace a budget directory
    assert r.exit_code == 2 and "not a satchain run directory" in r.stderr
