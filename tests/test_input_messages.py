"""Issue 29, item 19: messages that say what is wrong -- a table where an array of tables is wanted, a misspelt
key (named with the closest valid one, without the missing-key lines that follow from it), a star centre outside
the image, a line time that would overflow the jitter fit."""

from __future__ import annotations

import sys
import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

from satchain.cli.main import app
from satchain.config.system import ImagingSystem
from satchain.errors import ConfigError, InputError

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent / "measure"))
from _render_jitter import render_wobbly_edge  # noqa: E402

SYSTEM_TOML = """name = "mycamera"
[orbit]
altitude_m = 567000.0
[optics]
aperture_diameter_m = 0.70
f_number = 9.72
obscuration_ratio = 0.33
wavelengths_m = [5.5e-7, 6.5e-7, 7.5e-7]
[detector]
pitch_m = 5.88e-6
fill_factor = 1.0
[motion]
smear_px = 1.0
"""


def _budget(tmp_path, text: str):
    path = tmp_path / "mycamera.toml"
    path.write_text(text)
    return CliRunner().invoke(app, ["budget", "--system", str(path)])


def test_oscillation_written_as_a_table_says_to_write_an_array_of_tables(tmp_path):
    text = SYSTEM_TOML + '[motion.oscillation]\naxis = "act"\namplitude_px = 1.0\nfrequency_hz = 50.0\n'
    r = _budget(tmp_path, text)
    assert r.exit_code == 2
    assert "motion.oscillation must be an array of tables: write [[motion.oscillation]]" in r.output
    assert "tuple" not in r.output
    # the same oscillation as an array of tables is accepted
    assert _budget(tmp_path, text.replace("[motion.oscillation]", "[[motion.oscillation]]")).exit_code == 0


@pytest.mark.parametrize("value", ['"act"', "1.5", "true", '["act"]', "[1, 2]", '[{ axis = "act", amplitude_px = 1.0, '
                                   'frequency_hz = 50.0 }, "alt"]', '2026-01-01'])  # fmt: skip
def test_oscillation_in_any_form_but_an_array_of_tables_says_what_it_must_be(tmp_path, value):
    """``oscillation = "act"`` gave 'Input should be a valid tuple': every form but an array of tables is named,
    with the keys an oscillation table takes."""
    r = _budget(tmp_path, SYSTEM_TOML + f"oscillation = {value}\n")
    assert r.exit_code == 2, r.output
    line = " ".join(r.output.split())
    assert "motion.oscillation must be an array of tables" in line and "[[motion.oscillation]]" in line
    assert "axis, amplitude_px, frequency_hz" in line
    assert "tuple" not in line and "valid dictionary" not in line and "unexpected" not in line


@pytest.mark.parametrize(
    ("good", "bad", "section"),
    [
        ("aperture_diameter_m", "aperture_diametr_m", "optics"),
        ("f_number", "f_numbr", "optics"),
        ("wavelengths_m", "wavelength_m", "optics"),
        ("pitch_m", "pitch", "detector"),
        ("fill_factor", "fill_factr", "detector"),
        ("altitude_m", "altitude", "orbit"),
    ],
)
def test_a_misspelt_key_is_named_with_the_closest_valid_one_and_nothing_else(tmp_path, good, bad, section):
    r = _budget(tmp_path, SYSTEM_TOML.replace(f"\n{good} =", f"\n{bad} ="))
    assert r.exit_code == 2
    line = r.output.strip()
    assert f"{section}.{bad}: unknown key; did you mean {good}?" in line, line
    assert "required key is missing" not in line and "give " not in line, line
    assert line.count(";") == 1, line  # one complaint: the misspelt key


def test_an_unknown_key_nested_in_an_array_of_tables_and_the_python_api():
    with pytest.raises(
        ConfigError, match=r"motion\.oscillation\[1\]\.amplitude: unknown key; did you mean amplitude_px"
    ):
        ImagingSystem.from_dict(
            {
                "orbit": {"altitude_m": 5e5},
                "optics": {"aperture_diameter_m": 0.5, "f_number": 10.0, "wavelengths_m": [6e-7]},
                "detector": {"pitch_m": 5e-6},
                "motion": {
                    "oscillation": [
                        {"axis": "act", "amplitude_px": 1.0, "frequency_hz": 5.0},
                        {"axis": "act", "amplitude": 1.0, "frequency_hz": 5.0},
                    ]
                },
            }
        )
    from satchain.config.sections import Optics

    with pytest.raises(ConfigError, match=r"wavelength_m: unknown key; did you mean wavelengths_m\?") as err:
        Optics(aperture_diameter_m=0.5, f_number=10.0, wavelength_m=[6e-7])
    assert "missing" not in str(err.value)


def test_a_key_far_from_every_valid_one_lists_the_allowed_keys(tmp_path):
    r = _budget(tmp_path, SYSTEM_TOML.replace("[orbit]\n", "[orbit]\nbanana = 3\n"))
    assert r.exit_code == 2
    assert "orbit.banana: unknown key; allowed: altitude_m, " in r.output


def _star(size=121, centre=60.3):
    y, x = np.mgrid[0:size, 0:size] - centre
    return (100 + 50 * np.cos(16 * np.arctan2(y, x))).astype("float32")


@pytest.mark.parametrize(("center", "roi"), [("500,20", None), ("-5,20", None), ("5,60", "10,10,110,110")])
def test_star_center_outside_the_image_names_center_and_the_extent(tmp_path, center, roi):
    import tifffile

    path = tmp_path / "star.tif"
    tifffile.imwrite(path, _star())
    args = ["measure", "star", str(path), "--cycles", "16", "--center", center] + (["--roi", roi] if roi else [])
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 2
    assert f"--center = {center}: outside " in r.output, r.output
    extent = (
        "--roi 10,10,110,110 (x in [10, 109], y in [10, 109] px)"
        if roi
        else "the image (x in [0, 120], y in [0, 120] px)"
    )
    assert extent in r.output, r.output
    assert "radius_px = -" not in r.output


def test_measure_star_refuses_a_centre_outside_the_region():
    from satchain.measure.star import measure_star

    with pytest.raises(
        InputError, match=r"center = \(500, 20\): outside the region \(x in \[0, 120\], y in \[0, 120\] px\)"
    ):
        measure_star(_star(), cycles=16, center=(500, 20))
    assert measure_star(_star(), cycles=16, center=(60, 60)).center_xy_px == pytest.approx((60.3, 60.3), abs=0.01)


@pytest.mark.parametrize("line_time", ["1e-300", "1e-200", "1e300", "1e200"])
def test_jitter_line_time_that_would_overflow_is_refused_and_no_warning_leaks(tmp_path, line_time):
    import tifffile

    image, _ = render_wobbly_edge(200, 48, angle_deg=5.0, x0=20.0, amp_px=(0.5,), freq_hz=(50.0,), phase_rad=(0.0,))
    path = tmp_path / "edge.tif"
    tifffile.imwrite(path, image.astype("float32"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = CliRunner().invoke(app, ["measure", "jitter", str(path), "--line-time", line_time])
    assert r.exit_code == 2, r.output
    assert f"--line-time = {float(line_time)!r}: must be in [1e-09, 1000] s" in r.output, r.output
    assert "Warning" not in r.output and "unexpected" not in r.output


@pytest.mark.parametrize("line_time_s", [1e-9, 1e3])
def test_jitter_at_the_ends_of_the_line_time_range_gives_the_motion_without_a_warning(line_time_s):
    from satchain.measure.jitter import measure_jitter

    f_hz = 0.05 / line_time_s  # 0.05 cycles per line
    image, _ = render_wobbly_edge(
        200, 48, angle_deg=5.0, x0=20.0, amp_px=(0.5,), freq_hz=(f_hz,), phase_rad=(0.0,), line_time_s=line_time_s
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = measure_jitter(image, line_time_s=line_time_s)
    assert r.peaks[0].frequency_hz == pytest.approx(f_hz, rel=1e-3)
    assert r.peaks[0].amplitude_px == pytest.approx(0.5, abs=0.02)
    with pytest.raises(ConfigError, match=r"line_time_s = 1e-300: must be in \[1e-09, 1000\] s"):
        measure_jitter(image, line_time_s=1e-300)


def test_a_star_centre_too_near_the_edge_is_named_not_a_radius_nobody_gave():
    from satchain.measure.star import measure_star

    with pytest.raises(InputError, match=r"center = \(2, 60\): 2 px from the region's edge: the star must extend"):
        measure_star(_star(), cycles=16, center=(2, 60))
    with pytest.raises(InputError, match=r"radius_px = 5: the star must extend"):  # a radius given is named
        measure_star(_star(), cycles=16, center=(60, 60), radius_px=5)
