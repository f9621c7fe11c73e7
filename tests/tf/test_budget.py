"""The system MTF budget: product of components, cuts, Nyquist, MTFA, and the paper's Table 1."""

import numpy as np
import pytest

from satchain import ConfigError, ImagingSystem
from satchain.presets.paper import read_table1
from satchain.tf.budget import SystemOTF, default_frequencies_cy_per_mm, mtf_at_nyquist, mtf_budget, mtfa
from satchain.tf.detector import pixel_otf
from satchain.tf.motion import smear_otf
from satchain.tf.optics import annular_mtf


def test_system_is_product_of_named_components(ankarasat3):
    s = ankarasat3
    f = np.linspace(0, 200, 41)
    b = mtf_budget(s, f)
    lam, F, p = s.optics.wavelengths_m[0], s.f_number, s.detector.pitch_y_m
    diff = annular_mtf(f, wavelength_m=lam, f_number=F, obscuration_ratio=s.optics.obscuration_ratio)
    det = np.abs(pixel_otf(0.0, f, active_width_x_m=p, active_width_y_m=p))
    sm = np.abs(smear_otf(0.0, f, smear_alt_m=s.motion.smear_px * p))
    np.testing.assert_allclose(b.alt["diffraction"], diff, atol=1e-12)
    np.testing.assert_allclose(b.alt["detector"], det, atol=1e-12)
    np.testing.assert_allclose(b.alt["smear"], sm, atol=1e-12)
    np.testing.assert_allclose(b.alt["system"], diff * det * sm, atol=1e-12)
    # across-track has no along-track smear
    np.testing.assert_allclose(b.act["smear"], 1.0)
    np.testing.assert_allclose(b.act["system"], diff * det, atol=1e-12)


def test_optional_components_appear_only_when_present(ankarasat3):
    assert set(SystemOTF(ankarasat3).component_names) == {"diffraction", "detector", "smear"}
    s = ankarasat3.replace(
        {
            "motion.jitter_rms_px": 0.2,
            "detector.charge_diffusion_length_m": 2e-6,
            "detector.tdi_stages": 16,
            "detector.tdi_sync_error": 0.01,
            "motion.smear_px": 0.0,
        }
    )
    assert set(SystemOTF(s).component_names) == {
        "diffraction",
        "detector",
        "jitter",
        "charge_diffusion",
        "tdi_sync",
    }
    b = mtf_budget(s, [40.0, 85.0])
    prod = np.prod([b.alt[k] for k in ("diffraction", "detector", "jitter", "charge_diffusion", "tdi_sync")], axis=0)
    np.testing.assert_allclose(b.alt["system"], prod)
    # tdi sync acts along-track only
    np.testing.assert_allclose(b.act["tdi_sync"], 1.0)


def test_mtf_at_nyquist_reproduces_paper(ankarasat3):
    # the paper: "At the Nyquist frequency, it has a relatively high value, 12.28%" (ALT)
    ny = mtf_at_nyquist(ankarasat3)
    assert ny["alt"] == pytest.approx(0.1228, abs=0.002)
    assert ny["act"] > ny["alt"]  # no smear across-track


def test_preset_reproduces_table1_mtf_column(ankarasat3, table1_path):
    """Issue requirement: ALT system MTF within 0.005 of Table 1's MTF column at every row."""
    t = read_table1(table1_path)
    got = mtf_budget(ankarasat3, t.f_cy_per_mm).alt["system"]
    assert np.max(np.abs(got - t.system_mtf)) < 0.005


def test_packaged_table_equals_shared_reference(table1_path):
    if table1_path is None:
        pytest.skip("shared/reference/table1.csv not beside the checkout")
    a, b = read_table1(), read_table1(table1_path)
    np.testing.assert_array_equal(a.system_mtf, b.system_mtf)
    np.testing.assert_array_equal(a.f_cy_per_mm, b.f_cy_per_mm)


def test_table1_units_inconsistency_is_what_the_docs_say(ankarasat3):
    """The focal column is 2x the nadir mapping of the printed ground frequency (lines, not cycles)."""
    from satchain import units

    t = read_table1()
    mapped = units.ground_to_focal_cy_per_mm(
        t.ground_cy_per_m, focal_length_m=ankarasat3.focal_length_m, range_m=ankarasat3.orbit.range_m
    )
    np.testing.assert_allclose(t.focal_column, 2 * mapped, rtol=2e-4)


def test_default_grid_contains_nyquist_and_cutoff(ankarasat3):
    f = default_frequencies_cy_per_mm(ankarasat3)
    assert np.any(np.isclose(f, ankarasat3.nyquist_alt_cy_per_mm))
    assert f[-1] >= np.max(ankarasat3.optical_cutoff_cy_per_mm)
    assert np.all(np.diff(f) > 0) and f[0] == 0


def test_mtfa_closed_forms():
    f = np.linspace(0, 1, 1001)
    assert mtfa(f, 1 - f) == pytest.approx(0.5 - 0.125, abs=1e-9)  # int_0^0.5 (1-f) df
    assert mtfa(f, 1 - f, threshold=0.5) == pytest.approx(0.125, abs=1e-9)  # int_0^0.5 (0.5-f) df
    with pytest.raises(ConfigError, match="f_max_cy_per_px = 2"):
        mtfa(f, 1 - f, f_max_cy_per_px=2)


def test_negative_frequency_rejected(ankarasat3):
    with pytest.raises(ConfigError, match="f_cy_per_mm: must be >= 0"):
        mtf_budget(ankarasat3, [-1.0, 2.0])


def test_aberrated_system_uses_pupil_fft_and_lowers_mtf():
    s = ImagingSystem.from_dict(
        {
            "orbit": {"altitude_m": 5e5},
            "detector": {"pitch_m": 5e-6},
            "optics": {
                "aperture_diameter_m": 0.5,
                "f_number": 10,
                "wavelengths_m": [6e-7],
                "zernike_rms_waves": {"4": 0.1},
            },
        }
    )
    clean = s.replace({"optics.zernike_rms_waves": {}})
    f = [30.0, 60.0, 100.0]
    a, c = mtf_budget(s, f).alt["diffraction"], mtf_budget(clean, f).alt["diffraction"]
    assert np.all(a < c)
