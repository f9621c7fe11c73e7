"""Reference reproduction: the paper's Table 1 (MTF and CTF columns) and its stated figures."""

import numpy as np
import pytest

from satchain.presets.paper import read_table1
from satchain.report.budget import DirectionalMTF
from satchain.tf import ctf as ctf
from satchain.tf.budget import SystemOTF, mtf_budget


@pytest.fixture(scope="module")
def alt_mtf(ankarasat3):
    return DirectionalMTF(SystemOTF(ankarasat3), "alt")


def test_paper_method_ctf_reproduces_table1(alt_mtf, table1_path):
    """Issue requirement: the paper-method CTF within 0.003 of Table 1's CTF column from 33 cy/mm up."""
    t = read_table1(table1_path)
    got = ctf.ctf_fourier_synthesis(t.f_cy_per_mm, alt_mtf)
    rows = t.f_cy_per_mm >= 33
    assert np.max(np.abs(got[rows] - t.ctf[rows])) < 0.003
    # and, with 10 harmonics, the low rows too (documented: 0.0015 in the lead's check)
    assert np.max(np.abs(got - t.ctf)) < 0.003


def test_coltman_ctf_differs_from_table1_as_documented(alt_mtf, table1_path):
    """Coltman's physical square-wave response is 4/pi*MTF near cutoff and -> 1 at low frequency; the paper's
    column is that divided by the truncated series' Gibbs overshoot (~1.18)."""
    t = read_table1(table1_path)
    col = ctf.coltman_ctf(t.f_cy_per_mm, alt_mtf)
    hi = (t.f_cy_per_mm > 60) & (t.system_mtf > 0.01)  # only the fundamental passes: 3f beyond cutoff
    np.testing.assert_allclose(col[hi], 4 / np.pi * alt_mtf(t.f_cy_per_mm[hi]), rtol=1e-9)
    np.testing.assert_allclose(col[hi] / t.ctf[hi], 1.179, rtol=0.02)
    assert col[0] > 0.97 and t.ctf[0] < 0.85


def test_gsd_and_nyquist_of_reference(ankarasat3):
    # paper: pitch 5.88 um "corresponds to 85.0 L/mm Nyquist", GSD 49 cm (stated "at 549 km"; 567 km gives it)
    assert ankarasat3.nyquist_alt_cy_per_mm == pytest.approx(85.0, abs=0.05)
    assert ankarasat3.gsd_alt_m == pytest.approx(0.49, abs=5e-4)
    assert ankarasat3.replace({"orbit.altitude_m": 549e3}).gsd_alt_m == pytest.approx(0.4744, abs=5e-4)


def test_paper_detector_limited_claim(ankarasat3):
    # paper: Airy diameter < 4.88 pixel pitches even at 1 um; satchain's criterion Q < 2 agrees at 1 um
    at_1um = ankarasat3.replace({"optics.wavelength_m": 1e-6})
    assert at_1um.airy_diameter_px[0] < 4.88
    assert at_1um.limited_by == "detector"


def test_mtf_vanishes_where_table_says(ankarasat3, table1_path):
    t = read_table1(table1_path)
    got = mtf_budget(ankarasat3, t.f_cy_per_mm).alt["system"]
    assert np.all(got[t.f_cy_per_mm >= 166] < 1e-4)
