"""Atmospheric OTFs: Fried's turbulence MTF, the Hufnagel-Valley r0, aerosol adjacency."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import integrate, special

from satchain import ConfigError, load_preset
from satchain.tf.atmosphere import aerosol_otf, fried_r0_m, turbulence_otf
from satchain.tf.budget import SystemOTF, mtf_budget


def test_hv57_gives_five_centimetres_looking_up():
    # HV 5/7 is defined by r0 = 5 cm at 0.5 um (zenith, up-looking plane wave)
    assert fried_r0_m(0.5e-6, altitude_m=30e3, looking="up") == pytest.approx(0.05, rel=0.03)


@given(lam=st.floats(0.3e-6, 2e-6))
@settings(max_examples=10, deadline=None)
def test_r0_scales_as_lambda_to_six_fifths(lam):
    ref = fried_r0_m(0.5e-6, altitude_m=600e3)
    assert fried_r0_m(lam, altitude_m=600e3) == pytest.approx(ref * (lam / 0.5e-6) ** 1.2, rel=1e-6)


def test_down_looking_sees_far_less_turbulence_and_zenith_angle_shrinks_r0():
    up = fried_r0_m(0.65e-6, altitude_m=567e3, looking="up")
    down = fried_r0_m(0.65e-6, altitude_m=567e3, looking="down")
    assert down > 100 * up  # the ground layer is weighted by (h/H)^(5/3) ~ 0 for a satellite
    slant = fried_r0_m(0.65e-6, altitude_m=567e3, zenith_deg=60.0)
    assert slant == pytest.approx(down * np.cos(np.radians(60)) ** 0.6, rel=1e-9)


def test_turbulence_long_and_short_exposure():
    lam, f, r0 = 0.6e-6, 5.0, 0.1
    f_at = r0 / (lam * f * 1e3)  # focal frequency where lambda * nu = r0
    assert turbulence_otf(f_at, 0.0, wavelength_m=lam, focal_length_m=f, r0_m=r0) == pytest.approx(np.exp(-3.44))
    fr = np.linspace(0, 3 * f_at, 30)
    long = turbulence_otf(fr, 0.0, wavelength_m=lam, focal_length_m=f, r0_m=r0)
    short = turbulence_otf(fr, 0.0, wavelength_m=lam, focal_length_m=f, r0_m=r0, aperture_diameter_m=0.5)
    assert np.all(short >= long - 1e-15) and np.all(np.diff(long) < 0)
    # isotropic
    assert turbulence_otf(3.0, 4.0, wavelength_m=lam, focal_length_m=f, r0_m=r0) == pytest.approx(
        turbulence_otf(5.0, 0.0, wavelength_m=lam, focal_length_m=f, r0_m=r0)
    )


def test_aerosol_otf_is_hankel_transform_of_its_psf_mixture():
    s, L = 0.25, 50.0
    for f in (0.0, 0.002, 0.01, 0.05):
        diffuse, _ = integrate.quad(
            lambda r, f=f: np.exp(-r / L) / (2 * np.pi * L**2) * special.j0(2 * np.pi * f * r) * 2 * np.pi * r,
            0,
            60 * L,
            limit=500,
        )
        assert aerosol_otf(f, scattered_fraction=s, psf_scale_m=L) == pytest.approx(1 - s + s * diffuse, abs=1e-7)


def test_system_components_and_errors(ankarasat3):
    s = ankarasat3.replace({"atmosphere.turbulence": True, "atmosphere.aerosol_scattered_fraction": 0.1})
    assert {"turbulence", "aerosol"} <= set(SystemOTF(s).component_names)
    assert set(SystemOTF(ankarasat3).component_names).isdisjoint({"turbulence", "aerosol"})
    b = mtf_budget(s, [0.0, 85.0])
    assert b.alt["aerosol"][0] == 1.0 and b.alt["aerosol"][1] == pytest.approx(0.9, abs=1e-6)
    np.testing.assert_allclose(b.alt["system"], np.prod([v for k, v in b.alt.items() if k != "system"], axis=0))
    with pytest.raises(ConfigError, match="atmosphere.aerosol_scattered_fraction = 1.5"):
        load_preset("ankarasat3").replace({"atmosphere.aerosol_scattered_fraction": 1.5})
    with pytest.raises(ConfigError, match="looking = 'sideways'"):
        fried_r0_m(0.5e-6, altitude_m=1e3, looking="sideways")
