"""Data safety (issue 11): never destroy a user's file, refuse impossible work up front, clean what a killed
run left behind, integer inputs scaled to reflectance, DN written at the camera's bit depth, reproducible runs."""

import json
import os
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
import tifffile
from typer.testing import CliRunner

from satchain._safety import MARKER, OWNER, check_distinct_paths, check_run_dir, clean_stale
from satchain.cli.main import app
from satchain.errors import ConfigError, SatchainIOError
from satchain.io import images as io

runner = CliRunner()
PRESET = Path(__file__).resolve().parents[1] / "src" / "satchain" / "presets" / "ankarasat3.toml"


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def _tif(path, array, pixel_m=0.2, **kw):
    tifffile.imwrite(path, array, description=json.dumps({"satchain": {"pixel_m": pixel_m}}), **kw)
    return path


# ------------------------------------------------------------------------------------- 1. run directories
def test_run_refuses_a_folder_with_a_manifest_but_no_marker_and_leaves_it_untouched(tmp_path):
    web = tmp_path / "webapp"
    web.mkdir()
    (web / "manifest.json").write_text('{"name": "my web app"}')
    (web / "index.html").write_text("<html></html>")
    before = {p.name: p.read_bytes() for p in web.iterdir()}
    r = runner.invoke(app, ["run", "-o", str(web)])
    assert r.exit_code == 2
    assert "index.html" in r.stderr and "manifest.json" in r.stderr and MARKER in r.stderr
    assert {p.name: p.read_bytes() for p in web.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["webapp"]  # no staging folder left either


def test_check_run_dir_allows_only_missing_empty_or_marked(tmp_path):
    check_run_dir(tmp_path / "new")
    (tmp_path / "empty").mkdir()
    check_run_dir(tmp_path / "empty")
    marked = tmp_path / "marked"
    marked.mkdir()
    (marked / "results.json").write_text("{}")
    with pytest.raises(SatchainIOError, match="results.json"):
        check_run_dir(marked)
    (marked / MARKER).write_text(json.dumps({"tool": "satchain", "kind": "run", "format": 1}))
    check_run_dir(marked)
    (marked / MARKER).write_text(json.dumps({"tool": "other", "kind": "run"}))  # someone else's marker
    with pytest.raises(SatchainIOError):
        check_run_dir(marked)
    (tmp_path / "file").write_text("x")
    with pytest.raises(SatchainIOError, match="not a directory"):
        check_run_dir(tmp_path / "file")


# ------------------------------------------------------------------------------------- 2. distinct paths
def test_simulate_refuses_to_overwrite_its_input_and_focal_plane_equal_to_out(tmp_path):
    src = _tif(tmp_path / "s.tif", np.full((64, 64), 100, np.uint8))
    before = src.read_bytes()
    r = runner.invoke(app, ["simulate", str(src), "-o", str(src)])
    assert r.exit_code == 2 and "INPUT" in r.stderr
    o = str(tmp_path / "o.tif")
    r = runner.invoke(app, ["simulate", str(src), "-o", o, "--focal-plane", o])
    assert r.exit_code == 2 and "--focal-plane" in r.stderr
    assert src.read_bytes() == before and not (tmp_path / "o.tif").exists()


def test_same_file_through_links_and_relative_paths(tmp_path, monkeypatch):
    a = tmp_path / "a.tif"
    a.write_bytes(b"data")
    os.link(a, tmp_path / "hard.tif")
    os.symlink(a, tmp_path / "soft.tif")
    monkeypatch.chdir(tmp_path)
    for alias in ("hard.tif", "soft.tif", "./a.tif", str(tmp_path / "x" / ".." / "a.tif")):
        with pytest.raises(ConfigError, match="same file"):
            check_distinct_paths({"-o": alias}, {"IMAGE": "a.tif"})
    check_distinct_paths({"-o": "b.tif", "--focal-plane": "c.tif"}, {"IMAGE": "a.tif"})


def test_every_writing_command_refuses_an_input_as_output(tmp_path):
    img = _tif(tmp_path / "img.tif", np.full((64, 64), 0.5, np.float32))
    scene = tmp_path / "layout.toml"
    scene.write_text("[scene]\nwidth_m = 20.0\nheight_m = 20.0\npixel_m = 0.5\n")
    truth = tmp_path / "auto.json"
    truth.write_text("{}")
    system = tmp_path / "budget.json"
    system.write_text(PRESET.read_text())
    cfg = tmp_path / "run" / "run.toml"
    cfg.parent.mkdir()
    cfg.write_text("[simulation]\nseed = 1\n")
    kept = {p: p.read_bytes() for p in (img, scene, truth, system, cfg)}
    cases = [
        ["scene", "--layout", str(scene), "-o", str(scene)],
        ["budget", "--system", str(system), "-o", str(tmp_path)],  # would write budget.json over --system
        ["run", "--config", str(cfg), "-o", str(cfg.parent)],  # -o holds --config
        ["simulate", str(img), "--focal-plane", str(img), "-o", str(tmp_path / "o.tif")],
    ]
    for c in cases:
        r = runner.invoke(app, c)
        assert r.exit_code == 2 and "overwrit" in r.stderr or "replace" in r.stderr, (c, r.output)
    assert {p: p.read_bytes() for p in kept} == kept


# ------------------------------------------------------------------------------------- 3. resources
def test_huge_simulation_is_refused_before_allocating_with_its_memory(tmp_path, monkeypatch):
    from satchain.engine import simulate as sim_mod

    monkeypatch.setenv("SATCHAIN_MEMORY_LIMIT", "4G")
    monkeypatch.setattr(sim_mod.Simulator, "decimate", lambda *a, **k: pytest.fail("decimated before the check"))
    img = _tif(tmp_path / "big.tif", np.zeros((2000, 2000), np.uint8), tile=(256, 256))
    r = runner.invoke(app, ["simulate", str(img), "--scene-pixel-m", "5", "-o", str(tmp_path / "o.tif")])
    assert r.exit_code == 2 and "GiB" in r.stderr and "Gpx" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o.tif").exists()


def test_scene_at_a_micrometre_and_star_radius_1e9_are_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("SATCHAIN_MEMORY_LIMIT", "2G")
    r = runner.invoke(app, ["scene", "--pixel-m", "1e-6", "-o", str(tmp_path / "s.tif")])
    assert r.exit_code == 2 and "GiB" in r.stderr and not list(tmp_path.iterdir())
    img = _tif(tmp_path / "star.tif", np.full((64, 64), 0.5, np.float32), pixel_m=0.5)
    r = runner.invoke(app, ["measure", "star", str(img), "--cycles", "16", "--radius", "1e9"])
    line = " ".join(r.stderr.split())  # outside the image, named with its extent (not a memory problem)
    assert r.exit_code == 2 and "--radius = 1e+09: outside the image (64 x 64 px" in line and "GiB" not in line


def test_tiled_tiff_is_read_by_window_never_whole(tmp_path):
    """A 6000 x 6000 tiled TIFF: a window read decodes only its tiles and allocates far less than the image."""
    from satchain.scene import ImageScene

    rng = np.random.default_rng(1)
    a = rng.integers(0, 256, size=(6000, 6000), dtype=np.uint8)
    path = _tif(tmp_path / "big.tif", a, tile=(256, 256), compression="zlib", compressionargs={"level": 1})
    tracemalloc.start()
    s = ImageScene(path)
    block = s.render((3000, 2900, 300, 300))
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert s.shape_px() == (6000, 6000) and s._reader.segments_read == 4  # rows 11..12 x cols 11..12
    np.testing.assert_allclose(block, a[3000:3300, 2900:3200] / 255.0, rtol=1e-6)
    assert peak < a.nbytes / 20  # the image as uint8 is 36 MB, as float32 144 MB


def test_simulation_from_a_windowed_tiff_equals_the_in_memory_one(tmp_path):
    """The engine reads the file window by window (spy: no read is the whole image) and gets the same answer."""
    from satchain import load_preset
    from satchain.engine.simulate import SimParams, Simulator
    from satchain.engine.sources import ArraySource, SceneSource
    from satchain.scene import ImageScene

    rng = np.random.default_rng(2)
    a = rng.integers(0, 65536, size=(700, 900), dtype=np.uint16)
    path = _tif(tmp_path / "g.tif", a, pixel_m=0.07, tile=(128, 128), compression="zlib")
    scene = ImageScene(path)
    reads = []
    orig = scene._reader.read
    scene._reader.read = lambda *w: reads.append(w[2] * w[3]) or orig(*w)
    src = SceneSource(scene)
    params = SimParams(max_tile_bytes=8 * 2**20)
    sim = Simulator(load_preset("ankarasat3"), input_pixel_m=0.07, input_shape=a.shape, params=params)
    got = sim.form_image(sim.decimate(src))
    ref = sim.form_image(sim.decimate(ArraySource(a / 65535.0, pixel_m=0.07)))
    assert len(reads) > 1 and max(reads) < a.size
    np.testing.assert_allclose(got, ref, atol=1e-6)


# ------------------------------------------------------------------------------------- 4. integer inputs
@pytest.mark.parametrize(("dtype", "top"), [(np.uint8, 255), (np.uint16, 65535)])
def test_integer_inputs_are_scaled_to_reflectance(tmp_path, dtype, top):
    """8- and 16-bit full scale is reflectance 1: a uniform half-scale image simulates to the DN of reflectance
    0.5 (not saturated), the same as a float image of 0.5, and --input-scale overrides the rule."""
    from satchain import load_preset, radiometry

    half = np.full((300, 300), top // 2, dtype)
    i = _tif(tmp_path / "i.tif", half)
    f = _tif(tmp_path / "f.tif", np.full((300, 300), (top // 2) / top, np.float32))
    outs = {}
    for name, src, extra in [("i", i, []), ("f", f, []), ("s", i, ["--input-scale", str(0.25 / (top // 2))])]:
        r = runner.invoke(app, ["simulate", str(src), "--no-noise", "-o", str(tmp_path / f"{name}_o.tif"), *extra])
        assert r.exit_code == 0, r.output
        outs[name] = tifffile.imread(tmp_path / f"{name}_o.tif").astype(float)
    s = load_preset("ankarasat3")
    gain = 60000.0 / 2**12  # the preset's full well over its 12-bit range
    for name, rho in (("i", (top // 2) / top), ("s", 0.25)):
        expected = np.floor(float(radiometry.signal_electrons(s, rho)) / gain)
        assert abs(np.median(outs[name]) - expected) <= 1, name
    np.testing.assert_array_equal(outs["i"], outs["f"])
    assert outs["i"].max() < 4095


# ------------------------------------------------------------------------------------- 5, 6. error text
def test_unexpected_errors_are_one_line_and_debug_shows_the_traceback(tmp_path):
    import typer

    from satchain.cli._common import handle_errors, set_debug

    errors = {
        "dir": IsADirectoryError(21, "Is a directory", str(tmp_path)),
        "key": KeyError("alt"),
        "mem": MemoryError(),
        "perm": PermissionError(13, "Permission denied", "/root/x.tif"),
    }
    mini = typer.Typer()

    @mini.command()
    @handle_errors
    def boom(kind: str):
        raise errors[kind]

    for kind in errors:
        r = CliRunner().invoke(mini, [kind])
        assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1 and r.stderr.startswith("error: ")
        assert "Traceback" not in r.output, kind
    set_debug(True)
    try:
        assert isinstance(CliRunner().invoke(mini, ["key"]).exception, KeyError)
    finally:
        set_debug(False)
    # the real app: --debug lets the error propagate; without it, one line
    r = runner.invoke(app, ["--debug", "budget", "--system", str(tmp_path)])
    assert isinstance(r.exception, SatchainIOError)
    r = runner.invoke(app, ["budget", "--system", str(tmp_path)])
    assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1 and "directory" in r.stderr
    r = runner.invoke(app, ["budget", "--no-such-option"])  # typer's own usage error stays exit 2
    assert r.exit_code == 2


def test_brackets_survive_the_terminal_library():
    from satchain.cli._common import handle_errors

    @handle_errors
    def boom():
        raise ConfigError("install satchain[dask]; scene [scene] must be in [min, max]")

    runner_app = __import__("typer").Typer()
    runner_app.command()(boom)
    r = CliRunner().invoke(runner_app, [])
    assert r.exit_code == 2
    assert r.stderr.strip() == "error: install satchain[dask]; scene [scene] must be in [min, max]"


# ------------------------------------------------------------------------------------- 9. bit depth
def test_simulate_writes_dn_at_the_camera_bit_depth(tmp_path):
    """A 24-bit camera's DN are 2**12 times its 12-bit twin's (same full well): nothing is cut at 16 bits."""
    sys24 = tmp_path / "cam24.toml"
    sys24.write_text(PRESET.read_text().replace("bit_depth = 12", "bit_depth = 24"))
    imgs = {}
    for bits, extra in ((12, ["--preset", "ankarasat3"]), (24, ["--system", str(sys24)])):
        out = tmp_path / f"o{bits}.tif"
        r = runner.invoke(app, ["simulate", "paper", "--scene-pixel-m", "0.25", "--no-noise", "-o", str(out), *extra])
        assert r.exit_code == 0, r.output
        imgs[bits], meta = io.read_image(out)
        assert meta["bit_depth"] == bits
    assert imgs[12].dtype == np.uint16 and imgs[24].dtype == np.uint32
    assert imgs[24].max() > 65535
    d = imgs[24].astype(np.int64) - imgs[12].astype(np.int64) * 2**12
    assert d.min() >= -1 and d.max() < 2**12 + 1  # floor(x 2^12) vs 2^12 floor(x)


def test_write_simulated_keeps_82600():
    import tempfile

    p = Path(tempfile.mkdtemp()) / "s.tif"
    io.write_simulated(p, np.array([[82600.0, 0.0]]), units="dn", bit_depth=24, pixel_m=0.5)
    a, meta = io.read_image(p)
    assert a.dtype == np.uint32 and a[0, 0] == 82600 and meta["bit_depth"] == 24


# ------------------------------------------------------------------------------------- 10. stale leftovers
def test_stale_staging_and_temp_files_of_dead_processes_are_cleaned(tmp_path):
    out = tmp_path / "res"
    dead, live = _dead_pid(), os.getppid()
    folders = {}
    for kind, pid in (("staging-dead", dead), ("old-dead", dead), ("staging-live", live)):
        d = tmp_path / f".res.{kind.split('-')[0]}-{kind.split('-')[1]}x"
        d.mkdir()
        (d / OWNER).write_text(json.dumps({"pid": pid, "host": __import__("socket").gethostname()}))
        folders[kind] = d
    foreign = tmp_path / ".other.staging-1"  # another output's folder: not ours to clean
    foreign.mkdir()
    removed = clean_stale(out)
    assert set(removed) == {folders["staging-dead"], folders["old-dead"]}
    assert folders["staging-live"].exists() and foreign.exists()
    # temporary files of atomic writes: the dead process's is removed by the next write, a live one's kept
    t_dead = tmp_path / f".x.tif.{dead}.abc.tmp"
    t_live = tmp_path / f".x.tif.{live}.abc.tmp"
    t_dead.write_text("partial")
    t_live.write_text("partial")
    io.write_tiff(tmp_path / "x.tif", np.zeros((4, 4), np.float32))
    assert not t_dead.exists() and t_live.exists()


def test_killed_run_leftovers_are_removed_by_the_next_run(tmp_path):
    """A process that made a staging folder the way run does and was killed (-9): the next run removes it."""
    code = (
        "import sys, tempfile, os; from pathlib import Path; from satchain._safety import claim; "
        f"d = tempfile.mkdtemp(prefix='.res.staging-', dir={str(tmp_path)!r}); claim(d); "
        "Path(d, 'partial.tif').write_text('x'); print(d, flush=True); os.kill(os.getpid(), 9)"
    )
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "src")}
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    staging = Path(p.stdout.strip())
    assert p.returncode == -9 and staging.is_dir()
    from satchain.pipeline import _check_out_dir

    _check_out_dir(tmp_path / "res")  # the first thing run_pipeline does
    assert not staging.exists()


def test_warnings_and_written_paths_keep_their_brackets(tmp_path):
    from satchain.cli._common import print_warning

    runner_app = __import__("typer").Typer()
    runner_app.command()(lambda: print_warning("pip install satchain[dask] for [scene] in [min, max]"))
    r = CliRunner().invoke(runner_app, [])
    assert r.stderr.strip() == "warning: pip install satchain[dask] for [scene] in [min, max]"
    out = tmp_path / "run[1]" / "s[bold].tif"
    r = runner.invoke(app, ["scene", "--pixel-m", "2", "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert f"wrote tiff: {out}" in " ".join(r.stdout.split())


@pytest.mark.parametrize(
    "layout",
    [
        {"tile": (32, 48), "compression": "zlib"},
        {"tile": (32, 32), "bigtiff": True},
        {"rowsperstrip": 7, "compression": "zlib"},
        {},  # contiguous, uncompressed: memory-mapped
        "npy",
    ],
)
def test_window_reads_equal_the_array_for_every_layout(tmp_path, layout):
    rng = np.random.default_rng(3)
    a = rng.integers(0, 65536, size=(101, 157), dtype=np.uint16)
    if layout == "npy":
        path = tmp_path / "a.npy"
        np.save(path, a)
    else:
        path = _tif(tmp_path / "a.tif", a, **layout)
    with io.open_image(path) as r:
        assert r.shape == a.shape and r.dtype == a.dtype
        for _ in range(25):
            r0, c0 = rng.integers(0, 101), rng.integers(0, 157)
            h, w = rng.integers(1, 102 - r0), rng.integers(1, 158 - c0)
            np.testing.assert_array_equal(r.read(r0, c0, h, w), a[r0 : r0 + h, c0 : c0 + w])
        with pytest.raises(Exception, match="outside the image"):
            r.read(100, 0, 2, 1)


def test_sidecar_files_replace_only_what_satchain_wrote(tmp_path):
    """`simulate -o x.tif` also writes x.png: a user's own x.png is refused and kept; satchain's own is replaced
    (a re-run); the same for scene's preview and truth file."""
    from PIL import Image

    Image.fromarray(np.zeros((4, 4), np.uint8)).save(tmp_path / "x.png")  # the user's, no satchain chunk
    mine = (tmp_path / "x.png").read_bytes()
    args = ["simulate", "paper", "--scene-pixel-m", "0.5", "--no-noise", "-o", str(tmp_path / "x.tif")]
    r = runner.invoke(app, args)
    assert r.exit_code == 2 and "x.png" in r.stderr and (tmp_path / "x.png").read_bytes() == mine
    assert not (tmp_path / "x.tif").exists()
    (tmp_path / "x.png").unlink()
    assert runner.invoke(app, args).exit_code == 0
    assert runner.invoke(app, args).exit_code == 0  # its own preview: replaced
    (tmp_path / "s.truth.json").write_text('{"my": "notes"}')
    r = runner.invoke(app, ["scene", "--pixel-m", "2", "-o", str(tmp_path / "s.tif")])
    assert r.exit_code == 2 and "s.truth.json" in r.stderr
    assert (tmp_path / "s.truth.json").read_text() == '{"my": "notes"}'


def test_float_image_in_0_255_is_refused_not_saturated(tmp_path):
    """A float image holding 8-bit values (0..255) is not reflectance: refused with the fix, not a saturated
    image; with --input-scale 1/255 it simulates to the DN of its reflectance."""
    a = np.full((300, 300), 51.0, np.float32)  # 51/255 = reflectance 0.2
    src = _tif(tmp_path / "f255.tif", a)
    r = runner.invoke(app, ["simulate", str(src), "--no-noise", "-o", str(tmp_path / "o.tif")])
    assert r.exit_code == 2 and "--input-scale" in r.stderr and not (tmp_path / "o.tif").exists()
    r = runner.invoke(
        app, ["simulate", str(src), "--no-noise", "--input-scale", str(1 / 255), "-o", str(tmp_path / "o.tif")]
    )
    assert r.exit_code == 0, r.output
    ref = _tif(tmp_path / "f02.tif", np.full((300, 300), 0.2, np.float32))
    assert runner.invoke(app, ["simulate", str(ref), "--no-noise", "-o", str(tmp_path / "r.tif")]).exit_code == 0
    np.testing.assert_array_equal(tifffile.imread(tmp_path / "o.tif"), tifffile.imread(tmp_path / "r.tif"))


# ------------------------------------------------------------ issue 18: inputs not used as they stand
def _read_warns(path, match):
    from satchain.errors import SatchainWarning

    with pytest.warns(SatchainWarning, match=match):
        return io.read_image(path)


def test_rgb_and_palette_images_are_converted_to_grey_with_a_warning(tmp_path):
    from PIL import Image

    rng = np.random.default_rng(3)
    rgb = rng.integers(0, 256, (20, 30, 3), dtype=np.uint8)
    luma = rgb.astype(float) @ [0.299, 0.587, 0.114]  # ITU-R BT.601, computed here
    tifffile.imwrite(tmp_path / "rgb.tif", rgb, photometric="rgb")
    img, _ = _read_warns(tmp_path / "rgb.tif", r"RGB image \(3 samples per pixel\) converted to grey by luma")
    assert img.shape == (20, 30) and np.max(np.abs(img - luma)) <= 0.5
    Image.fromarray(rgb).save(tmp_path / "rgb.png")
    img, meta = _read_warns(tmp_path / "rgb.png", "RGB image converted to grey by luma")
    assert img.shape == (20, 30) and np.max(np.abs(img - luma)) <= 1.0 and meta["converted_from"] == "RGB"
    grey = rng.integers(0, 256, (20, 30), dtype=np.uint8)
    Image.fromarray(grey).convert("P").save(tmp_path / "pal.png")  # a grey palette: the values come back
    img, _ = _read_warns(tmp_path / "pal.png", "palette image: its colours converted to grey")
    assert np.array_equal(img, grey)
    bands = rng.random((4, 20, 30)).astype(np.float32)  # a 4-band image that is not RGB: band 1, said so
    tifffile.imwrite(tmp_path / "ms.tif", bands, planarconfig="separate", photometric="minisblack")
    img, _ = _read_warns(tmp_path / "ms.tif", r"4 samples \(bands\) per pixel: band 1 is used")
    assert np.array_equal(img, bands[0])


def test_multi_page_tiff_warns_that_page_1_is_used(tmp_path):
    a, b = np.full((16, 16), 0.25, np.float32), np.full((16, 16), 0.75, np.float32)
    with tifffile.TiffWriter(tmp_path / "two.tif") as w:
        w.write(a, description=json.dumps({"satchain": {"pixel_m": 0.5}}))
        w.write(b)
    img, meta = _read_warns(tmp_path / "two.tif", r"holds 2 images \(pages\); page 1 is used")
    assert np.array_equal(img, a) and meta["pixel_m"] == 0.5
    from satchain.errors import SatchainWarning

    with pytest.warns(SatchainWarning, match="page 1 is used"), io.open_image(tmp_path / "two.tif") as r:
        assert np.array_equal(r.read(0, 0, 16, 16), a)


def test_implausible_pixel_sizes_and_resolution_tags_warn(tmp_path):
    from PIL import Image

    from satchain.errors import SatchainWarning

    img = np.zeros((8, 8), np.uint8)
    _tif(tmp_path / "tiny.tif", img, pixel_m=1e-7)
    _, meta = _read_warns(tmp_path / "tiny.tif", r"pixel size 1e-07 m is implausible for a ground pixel")
    assert meta["pixel_m"] == 1e-7  # used as stated (in range), but said
    Image.fromarray(img).save(tmp_path / "print.png", dpi=(72, 72))  # a print resolution, not the ground
    _, meta = _read_warns(tmp_path / "print.png", r"72(\.\d+)? dpi \(0.353 mm per pixel\) is a print resolution")
    assert "pixel_m" not in meta
    Image.fromarray(img).save(tmp_path / "ground.png", dpi=(0.0254 / 0.5, 0.0254 / 0.5))  # pHYs of 2 px/m
    with warnings_as_errors():
        _, meta = io.read_image(tmp_path / "ground.png")
    assert meta["pixel_m"] == pytest.approx(0.5, rel=1e-3)
    tifffile.imwrite(tmp_path / "res.tif", img, description=json.dumps({"satchain": {"pixel_m": 0.5}}),
                     resolution=(1 / 200.0, 1 / 200.0), resolutionunit="CENTIMETER")  # fmt: skip  # 2 m per pixel
    _, meta = _read_warns(tmp_path / "res.tif", r"resolution tags say 2 m per pixel, its pixel size 0.5 m")
    assert meta["pixel_m"] == 0.5
    # satchain's own files (pixel size, tags and GeoTIFF keys agree) read without any warning
    io.write_tiff(tmp_path / "own.tif", img.astype(np.float32), pixel_m=0.5)
    with warnings_as_errors():
        assert io.read_image(tmp_path / "own.tif")[1]["pixel_m"] == 0.5
    with pytest.warns(SatchainWarning):  # and the warnings are SatchainWarnings, not errors
        io.read_image(tmp_path / "tiny.tif")


def test_geographic_pixel_scale_is_not_taken_for_metres(tmp_path):
    """A GeoTIFF in latitude/longitude (GTModelTypeGeoKey = 2) states its pixel size in degrees."""
    keys = (1, 1, 0, 2, 1024, 0, 1, 2, 1025, 0, 1, 1)  # ModelType = geographic, RasterType = PixelIsArea
    tags = [(33550, "d", 3, (1e-5, 1e-5, 0.0), False), (34735, "H", len(keys), keys, False)]
    tifffile.imwrite(tmp_path / "geo.tif", np.zeros((8, 8), np.float32), extratags=tags)
    _, meta = io.read_image(tmp_path / "geo.tif")
    assert "pixel_m" not in meta and "degrees" in meta["invalid_pixel_m"]
    r = runner.invoke(app, ["measure", "edge", str(tmp_path / "geo.tif")])
    assert r.exit_code == 2 and "degrees" in r.stderr and "--pixel-m" in r.stderr


def test_cli_prints_each_input_warning_once_as_one_line(tmp_path):
    y, x = np.mgrid[0:96, 0:96]
    edge = (0.2 + 0.5 * (x - 48 > 0.1 * (y - 48))).astype(np.float32)
    with tifffile.TiffWriter(tmp_path / "two.tif") as w:
        w.write(edge, description=json.dumps({"satchain": {"pixel_m": 0.5}}))
        w.write(edge)
    r = runner.invoke(app, ["measure", "edge", str(tmp_path / "two.tif")])
    assert r.exit_code == 0, r.output
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("warning: ")]
    assert lines == [f"warning: image = {str(tmp_path / 'two.tif')!r}: the TIFF holds 2 images (pages); page 1 is "
                     "used, the others ignored"]  # fmt: skip


class warnings_as_errors:  # noqa: N801
    """``with warnings_as_errors():`` -- any warning inside fails the test."""

    def __enter__(self):
        import warnings

        self._ctx = warnings.catch_warnings()
        self._ctx.__enter__()
        warnings.simplefilter("error")

    def __exit__(self, *exc):
        return self._ctx.__exit__(*exc)


def test_a_folder_marked_for_another_kind_is_refused_by_what_its_marker_says(tmp_path):
    """`budget -o` into a run's folder: the marker is there, so the message must not say it is missing."""
    from satchain._safety import MARKER, check_run_dir, write_run_marker
    from satchain.errors import SatchainIOError

    d = tmp_path / "r7a"
    d.mkdir()
    write_run_marker(d, kind="run")
    (d / "report.html").write_text("x")
    with pytest.raises(SatchainIOError) as e:
        check_run_dir(d, kind="budget")
    text = str(e.value)
    assert "not a satchain budget directory" in text and f"no {MARKER}" not in text
    assert "'run'" in text and MARKER in text
