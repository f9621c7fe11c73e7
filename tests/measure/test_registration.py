"""Band-to-band registration (issue 32, points 6-7): ``measure_registration`` and ``satchain measure registration``.

Every image is rendered here, independently of the code under test, at exactly known subpixel offsets: a
band-limited texture (a sum of random sinusoids through a Gaussian optics MTF, integrated over each pixel --
evaluated analytically at shifted coordinates, so the shift carries no interpolation error), and target scenes
(a tilted square: slanted edges at two orientations; ACT and ALT bar groups) integrated over each pixel by
6 x 6 sub-samples of their analytic form. The sign convention: ``image(y, x) = reference(y - dy, x - dx)``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import ndtr
from typer.testing import CliRunner

from satchain.errors import InputError
from satchain.measure.registration import FLOOR_PX, measure_registration

N = 96

# ------------------------------------------------------------------------------------------------ the renders


def _texture(shape, dy=0.0, dx=0.0, *, seed=0, blur=0.6, k=60, pixel=1.0, origin=0.0, fmax=0.5):
    """A band-limited random texture: ``k`` sinusoids (frequencies uniform to ``fmax`` cy/px per axis) through a
    Gaussian MTF of ``blur`` px, each integrated over a square pixel of side ``pixel`` (sinc), with the
    content displaced by (dy, dx) px; pixel (i, j) is centred at ``origin + pixel * (i, j) + (pixel - 1) / 2``
    (fine-grid coordinates: a coarse pixel of side 4 covers 4 x 4 fine ones). Unit rms at ``pixel = 1``."""
    g = np.random.default_rng(seed)
    f = g.uniform(-fmax, fmax, (k, 2))
    phase = g.uniform(0, 2 * np.pi, k)
    amp = np.exp(-2 * np.pi**2 * blur**2 * (f**2).sum(axis=1))
    ny, nx = shape
    yc = origin + pixel * np.arange(ny)[:, None] + (pixel - 1) / 2 - dy
    xc = origin + pixel * np.arange(nx)[None, :] + (pixel - 1) / 2 - dx
    out = np.zeros(shape)
    for (fy, fx), p, a in zip(f, phase, amp, strict=True):
        out += a * np.sinc(fy * pixel) * np.sinc(fx * pixel) * np.cos(2 * np.pi * (fy * yc + fx * xc) + p)
    rms = np.sqrt(0.5 * np.sum((amp * np.sinc(f[:, 0]) * np.sinc(f[:, 1])) ** 2))
    return out / rms


def _pixelated(fun, shape, dy=0.0, dx=0.0, ss=6):
    """``fun(y, x)`` integrated over each pixel by ss x ss sub-samples, the content displaced by (dy, dx)."""
    o = (np.arange(ss) + 0.5) / ss - 0.5
    y, x = np.mgrid[0 : shape[0], 0 : shape[1]].astype(float)
    return sum(fun(y + a - dy, x + b - dx) for a in o for b in o) / ss**2


def _square(angle_deg, blur=0.6, half=22.0):
    """A bright square tilted by ``angle_deg`` on a dark ground: four slanted edges (two orientations)."""
    t = np.deg2rad(angle_deg)

    def fun(y, x):
        u = (x - N / 2) * np.cos(t) + (y - N / 2) * np.sin(t)
        v = -(x - N / 2) * np.sin(t) + (y - N / 2) * np.cos(t)
        return 0.2 + 0.6 * ndtr((half - np.abs(u)) / blur) * ndtr((half - np.abs(v)) / blur)

    return fun


def _bars(y, x, period=6.0, blur=0.5):
    """Five ACT bars (varying along x) and five ALT bars (varying along y), each bar half a period wide."""
    out = np.full_like(x, 0.2)
    for k in range(5):
        x0, y0 = 10 + k * period, 50 + k * period
        out = out + 0.5 * (ndtr((x - x0) / blur) - ndtr((x - x0 - period / 2) / blur)) * (
            ndtr((y - 10) / blur) - ndtr((y - 80) / blur)
        )
        out = out + 0.5 * (ndtr((y - y0) / blur) - ndtr((y - y0 - period / 2) / blur)) * (
            ndtr((x - 50) / blur) - ndtr((x - 88) / blur)
        )
    return out


def _edge(angle_deg, blur=0.6):
    t = np.deg2rad(angle_deg)
    return lambda y, x: 0.2 + 0.6 * ndtr(((x - N / 2) * np.cos(t) - (y - N / 2) * np.sin(t)) / blur)


SCENES = {
    "texture": lambda dy, dx: _texture((N, N), dy, dx),
    "square 3 deg": lambda dy, dx: _pixelated(_square(3.0), (N, N), dy, dx),
    "square 10 deg": lambda dy, dx: _pixelated(_square(10.0), (N, N), dy, dx),
    "square 27 deg": lambda dy, dx: _pixelated(_square(27.0), (N, N), dy, dx),
    "square 40 deg": lambda dy, dx: _pixelated(_square(40.0), (N, N), dy, dx),
    "bars": lambda dy, dx: _pixelated(_bars, (N, N), dy, dx),
}
_REF_CACHE: dict[str, np.ndarray] = {}


def _ref(name: str) -> np.ndarray:
    if name not in _REF_CACHE:
        _REF_CACHE[name] = SCENES[name](0.0, 0.0)
    return _REF_CACHE[name]


# ----------------------------------------------------------------------------------------------- the sign


@pytest.mark.parametrize(("dy", "dx"), [(0.0, 1.0), (1.0, 0.0), (0.0, -1.0)])
def test_a_feature_moved_by_plus_one_px_along_x_gives_plus_one(dy, dx):
    """The square (a feature) drawn 1 px further along x (larger column) in ``image``: offset_px = (0, +1); and
    shifting ``image`` back by -offset maps it onto the reference (the documented convention)."""
    ref = _ref("square 10 deg")
    sy, sx = int(dy), int(dx)
    img = np.roll(ref, (sy, sx), axis=(0, 1))  # content moved by whole pixels: no interpolation at all
    r = measure_registration(ref, img)
    assert r.offset_px == pytest.approx((dy, dx), abs=1e-3)
    assert np.allclose(np.roll(img, (-sy, -sx), axis=(0, 1)), ref)


# ------------------------------------------------------------------------------------------------ accuracy


@settings(max_examples=25, deadline=None, derandomize=True)
@given(dy=st.floats(-2.0, 2.0), dx=st.floats(-2.0, 2.0))
def test_texture_offsets_recovered_noise_free(dy, dx):
    r = measure_registration(_ref("texture"), SCENES["texture"](dy, dx))
    err = np.subtract(r.offset_px, (dy, dx))
    assert np.all(np.abs(err) < 0.02), (dy, dx, err)
    assert np.all(np.abs(err) <= 3 * np.asarray(r.sigma_px)), (err, r.sigma_px)  # the stated floor is honest
    assert r.correlation > 0.999 and r.gain == pytest.approx(1.0, abs=1e-3) and r.flags == ()


@pytest.mark.parametrize("scene", [s for s in SCENES if s != "texture"])
@pytest.mark.parametrize(("dy", "dx"), [(0.0, 0.30), (0.30, 0.0), (-1.37, 1.81), (0.5, -0.5)])
def test_target_scenes_offsets_recovered_noise_free(scene, dy, dx):
    r = measure_registration(_ref(scene), SCENES[scene](dy, dx))
    err = np.subtract(r.offset_px, (dy, dx))
    assert np.all(np.abs(err) < 0.02), (scene, err)
    assert np.all(np.abs(err) <= 3 * np.asarray(r.sigma_px)), (scene, err, r.sigma_px)


@pytest.mark.parametrize("scene", list(SCENES))
def test_the_issue_acceptance_a_030_px_band_offset_within_002_px(scene):
    for offset in [(0.0, 0.30), (0.30, 0.0), (0.30, -0.30)]:
        r = measure_registration(_ref(scene), SCENES[scene](*offset))
        assert np.all(np.abs(np.subtract(r.offset_px, offset)) < 0.02), (scene, offset, r.offset_px)


@settings(max_examples=20, deadline=None, derandomize=True)
@given(
    scene=st.sampled_from(["texture", "square 10 deg", "bars"]),
    dy=st.floats(-2.0, 2.0),
    dx=st.floats(-2.0, 2.0),
    seed=st.integers(0, 2**16),
)
def test_noisy_offsets_within_three_sigma(scene, dy, dx, seed):
    """White noise at SNR 50 (the scene's standard deviation over the noise's) in both images, independently."""
    ref, img = _ref(scene), SCENES[scene](dy, dx)
    g = np.random.default_rng(seed)
    noise = float(np.std(ref)) / 50
    r = measure_registration(ref + g.normal(0, noise, ref.shape), img + g.normal(0, noise, ref.shape))
    err = np.subtract(r.offset_px, (dy, dx))
    assert np.all(np.abs(err) <= 3 * np.asarray(r.sigma_px)), (scene, err, r.sigma_px)
    assert r.noise_rms == pytest.approx(noise * np.sqrt(2), rel=0.15)  # reference + image noise, per pixel


@pytest.mark.parametrize("scene", ["texture", "square 10 deg", "bars"])
def test_sigma_matches_the_spread_over_noise_realisations(scene):
    """Monte Carlo: the standard deviation of the offsets over 80 noise realisations (SNR 30) is within 30 % of
    the mean reported noise sigma (the sample's own scatter is ~8 %)."""
    ref, img = _ref(scene), SCENES[scene](0.3, -0.7)
    g = np.random.default_rng(7)
    noise = float(np.std(ref)) / 30
    runs = [measure_registration(ref + g.normal(0, noise, ref.shape), img + g.normal(0, noise, ref.shape))
            for _ in range(80)]  # fmt: skip
    spread = np.std([r.offset_px for r in runs], axis=0, ddof=1)
    sigma = np.mean([r.sigma_noise_px for r in runs], axis=0)
    assert np.all(np.abs(spread / sigma - 1) < 0.30), (scene, spread, sigma)
    assert np.all(np.abs(np.mean([r.offset_px for r in runs], axis=0) - (0.3, -0.7)) < 3 * sigma / np.sqrt(80) + 2e-3)


def test_sigma_grows_as_the_noise():
    ref, img = _ref("texture"), SCENES["texture"](0.2, 0.4)
    g = np.random.default_rng(3)
    sig = []
    for noise in (0.01, 0.04):
        r = measure_registration(ref + g.normal(0, noise, ref.shape), img + g.normal(0, noise, ref.shape))
        sig.append(np.asarray(r.sigma_noise_px))
    assert np.allclose(sig[1] / sig[0], 4.0, rtol=0.15)


# --------------------------------------------------------------------------------- radiometry, grids, masks


def test_different_radiometry_and_inverted_contrast_register():
    """Two bands see the ground with different gains and offsets; vegetation inverts the contrast between red and
    NIR: the least squares' gain absorbs both (negative gain: flagged)."""
    ref = 1000 + 300 * _ref("texture")
    img = 200 - 80 * SCENES["texture"](0.3, -0.45)
    r = measure_registration(ref, img)
    assert r.offset_px == pytest.approx((0.3, -0.45), abs=0.005)
    assert r.gain == pytest.approx(-300 / 80, rel=1e-3) and "inverted_contrast" in r.flags
    assert r.correlation < -0.999


@pytest.mark.parametrize(("dy", "dx"), [(0.30, 0.0), (0.0, -0.30), (0.25, 0.6)])
def test_an_ms_band_at_four_times_the_pitch(dy, dx):
    """PAN (fine) and an MS band whose pixel covers 4 x 4 PAN pixels (rendered directly at its own pixel, not by
    averaging), its content displaced by (dy, dx) MS pixels: the offset comes back in MS pixels. The texture stops
    at the MS band's Nyquist frequency (0.125 cy per PAN pixel): content above it would alias in the MS band,
    where it does not move with the offset."""
    pan = _texture((4 * 48, 4 * 48), blur=1.0, fmax=0.125)
    ms = _texture((48, 48), 4 * dy, 4 * dx, blur=1.0, pixel=4.0, fmax=0.125)
    r = measure_registration(pan, ms, scale=4)
    assert r.scale == 4 and np.all(np.abs(np.subtract(r.offset_px, (dy, dx))) < 0.02), r.offset_px


def test_masked_nodata_is_left_out_and_nan_outside_a_mask_refused():
    ref, img = _ref("texture").copy(), SCENES["texture"](0.3, 0.3)
    img[60:80, 10:40] = np.nan  # nodata in the image
    mask = np.isfinite(img)
    r = measure_registration(ref, img, mask=mask)
    assert r.offset_px == pytest.approx((0.3, 0.3), abs=0.005) and "masked" in r.flags
    assert r.usable_fraction < 0.75
    masked = measure_registration(ref, np.ma.masked_invalid(img))
    assert masked.offset_px == pytest.approx(r.offset_px, abs=1e-9)
    with pytest.raises(InputError, match=r"NaN/inf value\(s\) outside the mask"):
        measure_registration(ref, img)


def test_roi_measures_the_region():
    ref = _texture((N, 2 * N))
    img = _texture((N, 2 * N), 0.3, 0.2)
    img[:, N:] = _texture((N, N), -1.0, 1.5, seed=5)  # the right half holds other content
    r = measure_registration(ref, img, roi=(0, 0, N, N))
    assert r.offset_px == pytest.approx((0.3, 0.2), abs=0.005)


def test_an_offset_made_by_the_simulation_engine():
    """The reference camera images one scene twice, the second time with every target moved by (+0.3, -0.2) of
    its ground pixel across (x) and along (y) track: the simulated bands' offset is that, within 0.02 px."""
    from satchain.config.system import load_preset
    from satchain.engine.simulate import simulate
    from satchain.scene.layout import Scene
    from satchain.scene.targets import SlantedEdge

    system = load_preset("ankarasat3")

    def scene(dx_px, dy_px):
        g = system.gsd_m
        items = tuple(
            SlantedEdge(f"e{k}", center_m=(10.0 + 10 * (k % 3) + dx_px * g, 10.0 + 10 * (k // 3) + dy_px * g),
                        size_m=6.0, angle_deg=a)
            for k, a in enumerate([5.0, 30.0, -20.0, -40.0, 15.0, 40.0])
        )  # fmt: skip
        return Scene(40.0, 30.0, items, background=0.2, pixel_m=0.035)

    r = measure_registration(simulate(scene(0.0, 0.0), system), simulate(scene(0.3, -0.2), system))
    assert np.all(np.abs(np.subtract(r.offset_px, (-0.2, 0.3))) < 0.02), r.offset_px


# -------------------------------------------------------------------------------------------------- refusals


def test_refusals_one_line_never_a_number():
    ref = _ref("texture")
    g = np.random.default_rng(0)
    cases = [
        ((np.full((N, N), 5.0), np.full((N, N), 5.0)), {}, "flat"),
        ((5 + g.normal(0, 0.01, (N, N)), 5 + g.normal(0, 0.01, (N, N))), {}, "share no content"),
        ((ref, ref[:, :-3]), {}, "shapes"),
        ((ref, ref[:40, :40]), {"scale": 2}, "blocks make"),
        ((ref, np.roll(ref, 30, axis=1)), {}, "exceeds max_offset"),
        ((_pixelated(_edge(5.0), (N, N)), _pixelated(_edge(5.0), (N, N), 0.0, 0.3)), {}, "one direction only"),
        ((ref, ref), {"scale": 0}, "scale = 0"),
        ((ref, ref), {"upsample": 0}, "upsample = 0"),
        ((ref, ref), {"roi": (0, 0, 10, 10)}, "too small"),
    ]
    for args, kw, words in cases:
        with pytest.raises(InputError, match=words) as exc:
            measure_registration(*args, **kw)
        assert "\n" not in str(exc.value)


def test_noise_dominated_region_is_refused_by_its_sigma():
    ref, img = _ref("texture"), SCENES["texture"](0.3, 0.3)
    g = np.random.default_rng(1)
    with pytest.raises(InputError, match="max_sigma_px"):
        measure_registration(ref + g.normal(0, 1.0, ref.shape), img + g.normal(0, 1.0, ref.shape),
                             max_sigma_px=0.01)  # fmt: skip


def test_a_region_too_large_for_memory_is_refused_up_front(monkeypatch):
    import satchain.measure.registration as reg
    from satchain.errors import ResourceLimitError

    monkeypatch.setattr(reg, "MAX_PIXELS", 50 * 50)
    with pytest.raises(ResourceLimitError, match="give a roi"):
        measure_registration(_ref("texture"), _ref("texture"))
    assert measure_registration(_ref("texture"), _ref("texture"), roi=(0, 0, 48, 48)).n_pixels > 0


# ------------------------------------------------------------------------------------------------------- CLI

rasterio = pytest.importorskip("rasterio")
from rasterio.transform import Affine  # noqa: E402

from satchain.cli.main import app  # noqa: E402

runner = CliRunner()


def _write(path, bands, *, pitch=0.5, nodata=0):
    ny, nx = bands[0].shape
    transform = Affine(pitch, 0.0, 500000.0, 0.0, -pitch, 4100000.0)
    prof = dict(driver="GTiff", height=ny, width=nx, count=len(bands), dtype="uint16", crs="EPSG:32636",
                transform=transform, nodata=nodata)  # fmt: skip
    with rasterio.open(path, "w", **prof) as d:
        for i, b in enumerate(bands, 1):
            d.write(np.round(b).astype("uint16"), i)


def test_cli_two_band_geotiff_returns_the_injected_offset(tmp_path):
    pan = 2000 + 300 * _texture((128, 128))
    band = 1500 + 200 * _texture((128, 128), 0.30, -0.45)
    band[:6, :] = 0  # nodata rows (the file's nodata value)
    path = tmp_path / "two.tif"
    _write(path, [pan, band])
    r = runner.invoke(app, ["measure", "registration", str(path), "--ref", "1", "--band", "2", "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert np.allclose(d["offset_px"], (0.30, -0.45), atol=0.005)
    assert np.allclose(d["offset_m"], np.multiply(d["offset_px"], 0.5)) and d["pixel_m"] == 0.5
    assert "masked" in d["flags"] and d["ref_band"] == 1 and d["band"] == 2 and len(d["sigma_px"]) == 2
    table = runner.invoke(app, ["measure", "registration", str(path), "--band", "2", "--roi", "8,8,120,120"])
    assert table.exit_code == 0 and "offset ACT dx (px)" in table.stdout and "-0.45" in table.stdout


def test_cli_an_ms_file_against_its_pan_file(tmp_path):
    pan = 2000 + 300 * _texture((192, 192), blur=1.0, fmax=0.125)
    ms = 1500 + 200 * _texture((48, 48), 4 * 0.3, 4 * 0.1, blur=1.0, pixel=4.0, fmax=0.125)
    _write(tmp_path / "pan.tif", [pan], pitch=0.5)
    _write(tmp_path / "ms.tif", [ms, ms], pitch=2.0)
    args = ["measure", "registration", str(tmp_path / "pan.tif"), "--with", str(tmp_path / "ms.tif"), "--band", "2"]
    r = runner.invoke(app, [*args, "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["scale"] == 4 and d["pixel_m"] == 2.0 and np.allclose(d["offset_px"], (0.3, 0.1), atol=0.02)
    # the other way round (the coarse file as IMAGE): the same offset, negated
    back = runner.invoke(app, ["measure", "registration", str(tmp_path / "ms.tif"), "--ref", "2", "--with",
                               str(tmp_path / "pan.tif"), "--band", "1", "--json"])  # fmt: skip
    assert back.exit_code == 0, back.output
    assert np.allclose(json.loads(back.stdout)["offset_px"], (-0.3, -0.1), atol=0.02)


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        (["--band", "3"], "band = 3"),
        (["--band", "0"], "--band = 0"),
        (["--band", "2", "--ref", "0"], "--ref = 0"),
        ([], "--band"),
        (["--band", "2", "--roi", "0,0,200,10"], "roi"),
    ],
)
def test_cli_bad_input_is_one_line_exit_2(tmp_path, extra, words):
    path = tmp_path / "two.tif"
    _write(path, [2000 + 300 * _texture((64, 64)), 2000 + 300 * _texture((64, 64), 0.2, 0.2)])
    r = runner.invoke(app, ["measure", "registration", str(path), *extra])
    assert r.exit_code == 2, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and words in lines[0], r.stderr


def test_cli_grids_that_do_not_meet_are_refused(tmp_path):
    np.save(tmp_path / "a.npy", _texture((64, 64)))
    np.save(tmp_path / "b.npy", _texture((32, 32)))
    r = runner.invoke(app, ["measure", "registration", str(tmp_path / "a.npy"), "--with", str(tmp_path / "b.npy")])
    assert r.exit_code == 2 and "not both georeferenced" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    _write(tmp_path / "pan.tif", [2000 + 300 * _texture((64, 64))], pitch=0.5)
    _write(tmp_path / "ms.tif", [2000 + 300 * _texture((16, 16))], pitch=1.3)
    r = runner.invoke(app, ["measure", "registration", str(tmp_path / "pan.tif"), "--with", str(tmp_path / "ms.tif")])
    assert r.exit_code == 2 and "integer ratio" in r.stderr, r.output


def test_floor_is_stated():
    assert 0 < FLOOR_PX <= 0.002
