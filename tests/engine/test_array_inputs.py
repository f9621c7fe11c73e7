"""Arrays in the Python API (issue 29, item 8): ``satchain.simulate`` takes integer arrays as
``satchain.simulate_image`` does (DN scaled by the type's range, wider integers only with ``input_scale``), and
``simulate_image`` takes a transform as an ``affine.Affine`` or a 6-sequence in its order, refusing anything else."""

from __future__ import annotations

import numpy as np
import pytest
from affine import Affine

import satchain
from satchain.errors import ConfigError, InputError, ParameterTypeError

PX = 0.098  # 140 px -> 28 output pixels of the preset's 0.49 m GSD


def _edge(n: int = 140) -> np.ndarray:
    """A tilted edge of reflectance 0.1 | 0.8."""
    y, x = np.mgrid[0:n, 0:n]
    return np.where((x - n / 2) + (y - n / 2) * np.tan(np.deg2rad(5)) > 0, 0.8, 0.1)


@pytest.fixture(scope="module")
def system():
    return satchain.load_preset("ankarasat3")


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
def test_simulate_scales_uint_dn_by_the_types_range_as_simulate_image_does(system, dtype):
    full = np.iinfo(dtype).max
    dn = np.round(_edge() * full).astype(dtype)
    img = satchain.simulate(dn, system, pixel_m=PX)
    # reflectance, not DN: the plateaus are 0.1 and 0.8 of the type's range
    assert 0.05 < img.min() and img.max() < 0.9
    ref = satchain.simulate(dn.astype(np.float64) / full, system, pixel_m=PX)
    np.testing.assert_allclose(img, ref, atol=1e-6)
    np.testing.assert_allclose(img, satchain.simulate_image(dn, system, pixel_m=PX).image, atol=1e-6)


def test_simulate_refuses_a_wide_integer_without_input_scale_as_simulate_image_does(system):
    dn = np.round(_edge() * 1000).astype(np.int64)
    for call in (satchain.simulate, satchain.simulate_image):
        with pytest.raises(InputError, match=r"int64.*input_scale"):
            call(dn, system, pixel_m=PX)
    img = satchain.simulate(dn, system, pixel_m=PX, input_scale=1e-3)
    np.testing.assert_allclose(img, satchain.simulate(dn / 1000.0, system, pixel_m=PX), atol=1e-6)
    via = satchain.simulate_image(dn, system, pixel_m=PX, input_scale=1e-3).image
    np.testing.assert_allclose(img, via, atol=1e-6)


def test_simulate_image_takes_a_transform_as_a_six_sequence_in_affines_order(system):
    t = Affine(PX, 0.0, 5e5, 0.0, -PX, 4.4e6)
    ref = satchain.simulate_image(_edge(), system, transform=t)
    for seq in (tuple(t)[:6], list(tuple(t)[:6]), np.array(tuple(t)[:6])):
        r = satchain.simulate_image(_edge(), system, transform=seq)
        assert r.transform == ref.transform
        np.testing.assert_array_equal(r.image, ref.image)
    # the output's origin is the input's, its pixel the GSD
    assert (ref.transform.c, ref.transform.f) == (5e5, 4.4e6)
    assert ref.transform.a == pytest.approx(system.gsd_act_m, rel=1e-9)


@pytest.mark.parametrize(
    "bad", [(0.07, 0, 0, 0, -0.07), "0.07,0,0,0,-0.07,0", {"a": 0.07}, (0.07, 0, 0, 0, -0.07, "x"), 0.07]
)
def test_simulate_image_refuses_another_transform_by_name(system, bad):
    with pytest.raises(ParameterTypeError, match=r"transform.*Affine") as e:
        satchain.simulate_image(_edge(), system, transform=bad)
    assert type(bad).__name__ in str(e.value)


def test_simulate_image_names_a_gdal_geotransform_given_as_a_sequence(system):
    gdal = (5e5, PX, 0.0, 4.4e6, 0.0, -PX)  # (c, a, b, f, d, e): in Affine's order its pixels are not square
    with pytest.raises(ConfigError, match=r"from_gdal"):
        satchain.simulate_image(_edge(), system, transform=gdal)
    r = satchain.simulate_image(_edge(), system, transform=Affine.from_gdal(*gdal))
    assert (r.transform.c, r.transform.f) == (5e5, 4.4e6)
