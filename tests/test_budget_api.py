"""Issue 31, point 1: ``satchain.budget(system)`` is the typed budget that ``satchain budget --json`` prints."""

import dataclasses
import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import satchain
from satchain.cli.main import app
from satchain.errors import ParameterTypeError


def _minimal(aperture_m=0.5, f_number=10.0, pitch_m=5e-6, altitude_m=500e3):
    return satchain.ImagingSystem.from_dict(
        {
            "name": "minimal",
            "orbit": {"altitude_m": altitude_m},
            "optics": {"aperture_diameter_m": aperture_m, "f_number": f_number, "wavelengths_m": [6e-7]},
            "detector": {"pitch_m": pitch_m},
        }
    )


def _cli_json(*args: str) -> dict:
    r = CliRunner().invoke(app, ["budget", *args, "--json"])
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


def test_to_dict_is_what_budget_json_prints_for_the_preset():
    b = satchain.budget(satchain.load_preset("ankarasat3"))
    assert b.to_dict() == _cli_json("--preset", "ankarasat3")


def test_to_dict_is_what_budget_json_prints_for_a_minimal_system_file_and_frequencies(tmp_path, minimal_system_toml):
    path = tmp_path / "minimal.toml"
    path.write_text(minimal_system_toml, encoding="utf-8")
    s = satchain.load_system(path)
    assert satchain.budget(s).to_dict() == _cli_json("--system", str(path))
    freqs = [0.0, 10.0, 42.5, 100.0]
    b = satchain.budget(s, freqs)
    assert b.to_dict() == _cli_json("--system", str(path), "--freqs", "0,10,42.5,100")
    assert b.to_dict()["frequencies_cy_per_mm"] == freqs


def test_attributes_are_the_dicts_figures_typed_and_the_result_frozen_with_a_short_repr():
    s = satchain.load_preset("ankarasat3")
    b = satchain.budget(s)
    d = b.to_dict()
    assert isinstance(b, satchain.SystemBudget)
    assert b.system is s and b.system_name == "ankarasat3"
    assert (b.gsd_m, b.gsd_act_m, b.gsd_alt_m) == (d["derived"]["gsd_m"], d["derived"]["gsd_act_m"],
                                                   d["derived"]["gsd_alt_m"])  # fmt: skip
    assert b.q == d["derived"]["q_effective"] and b.limited_by == "detector"
    assert (b.mtf_at_nyquist_act, b.mtf_at_nyquist_alt) == (d["mtf_at_nyquist"]["act"], d["mtf_at_nyquist"]["alt"])
    assert (b.mtfa_act, b.mtfa_alt) == (d["mtfa"]["act"], d["mtfa"]["alt"])
    assert (b.rer, b.rer_act, b.rer_alt) == (d["quality"]["rer"], d["quality"]["rer_act"], d["quality"]["rer_alt"])
    assert b.snr == d["quality"]["snr"] and b.signal_snr == d["radiometry"]["snr"]
    assert b.niirs == d["quality"]["giqe5"]
    for f in dataclasses.fields(b):
        if f.name not in ("system", "results", "system_name", "limited_by"):
            assert type(getattr(b, f.name)) is float, f.name
    with pytest.raises(dataclasses.FrozenInstanceError):
        b.gsd_m = 1.0  # type: ignore[misc]
    d["derived"]["gsd_m"] = -1.0  # to_dict hands back a copy
    assert b.to_dict()["derived"]["gsd_m"] == b.gsd_m
    text = repr(b)
    assert len(text) < 160 and "ankarasat3" in text and "NIIRS 5.200" in text and "\n" not in text
    assert hash(b) == hash(satchain.budget(s)) and b == satchain.budget(s)


def test_the_old_home_still_imports():
    from satchain.prediction.budget import DirectionalMTF, budget_results
    from satchain.report import budget as report_budget

    assert report_budget.budget_results is budget_results and report_budget.DirectionalMTF is DirectionalMTF


def _closed_forms(s, b):
    pitch = (s.detector.pitch_x_m * s.detector.pitch_y_m) ** 0.5
    assert b.gsd_m == pytest.approx(s.orbit.altitude_m * pitch / s.focal_length_m, rel=1e-12)
    assert b.gsd_m == pytest.approx(s.orbit.altitude_m * pitch / (s.optics.aperture_diameter_m * s.f_number), rel=1e-12)
    assert b.q == pytest.approx(s.optics.effective_wavelength_m * s.f_number / pitch, rel=1e-12)


def test_closed_forms_for_the_preset():
    s = satchain.load_preset("ankarasat3")
    b = satchain.budget(s)
    _closed_forms(s, b)
    assert b.gsd_m == pytest.approx(567e3 * 5.88e-6 / (0.70 * 9.72), rel=1e-12)
    assert b.q == pytest.approx(6.4961e-7 * 9.72 / 5.88e-6, rel=1e-12)


@settings(max_examples=12, deadline=None)
@given(
    aperture_m=st.floats(0.2, 1.5),
    f_number=st.floats(4.0, 20.0),
    pitch_m=st.floats(2e-6, 15e-6),
    altitude_m=st.floats(300e3, 900e3),
)
def test_closed_forms_for_a_varied_minimal_system(aperture_m, f_number, pitch_m, altitude_m):
    s = _minimal(aperture_m, f_number, pitch_m, altitude_m)
    b = satchain.budget(s)
    _closed_forms(s, b)
    assert b.gsd_m == pytest.approx(altitude_m * pitch_m / (aperture_m * f_number), rel=1e-12)
    assert b.q == pytest.approx(6e-7 * f_number / pitch_m, rel=1e-12)
    assert b.limited_by == ("detector" if b.q < 2 else "optics")


@pytest.mark.parametrize(
    ("args", "name"),
    [
        (("ankarasat3",), "system"),
        ((None,), "system"),
        ((42,), "system"),
        ((satchain.load_preset("ankarasat3"), "10,20"), "f_cy_per_mm"),
        ((satchain.load_preset("ankarasat3"), True), "f_cy_per_mm"),
        ((satchain.load_preset("ankarasat3"), {"f": 1.0}), "f_cy_per_mm"),
    ],
)
def test_a_wrong_type_is_refused_naming_the_parameter(args, name):
    with pytest.raises(ParameterTypeError, match=rf"^budget\(\): {name} = .*: must be"):
        satchain.budget(*args)


def test_an_unknown_argument_is_refused():
    with pytest.raises(ParameterTypeError, match="budget"):
        satchain.budget(satchain.load_preset("ankarasat3"), otf=None)  # type: ignore[call-arg]


def test_mtf_at_nyquist_falls_as_the_wavefront_error_grows():
    s = satchain.load_preset("ankarasat3")
    budgets = [satchain.budget(s.replace({"optics.wfe_rms_waves": w})) for w in (0.0, 0.03, 0.06, 0.1)]
    for axis in ("act", "alt"):
        values = [getattr(b, f"mtf_at_nyquist_{axis}") for b in budgets]
        assert all(values[i] > values[i + 1] for i in range(len(values) - 1)), (axis, values)
    assert budgets[0].gsd_m == budgets[-1].gsd_m and budgets[0].q == budgets[-1].q
