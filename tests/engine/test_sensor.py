"""Detector signal chain: noise statistics, reproducibility, clipping, quantisation and errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain import load_preset
from satchain.engine.sensor import SensorModel
from satchain.engine.simulate import SimParams, Simulator, simulate
from satchain.engine.sources import ArraySource
from satchain.errors import ConfigError

BASE = load_preset("ankarasat3")
SENSOR = SensorModel(electrons_per_unit=20000.0, offset_e=100.0, dark_e=50.0, read_noise_e=10.0, full_well_e=60000.0)


def _flat(value=0.5, shape=(512, 512)):
    return np.full(shape, value)


def test_poisson_gaussian_statistics_on_a_flat_field():
    """Mean = offset + gain * value + dark; variance = mean (Poisson) + read^2 (Gaussian)."""
    e = SENSOR.convert(_flat(), origin=(0, 0), units="electrons", noise=True, seed=1)
    mean = 100.0 + 20000.0 * 0.5 + 50.0
    n = e.size
    assert abs(e.mean() - mean) < 5 * np.sqrt((mean + 100.0) / n)
    assert abs(e.var() / (mean + 100.0) - 1.0) < 5 * np.sqrt(2.0 / n)


def test_low_signal_poisson_is_exact():
    """At 3 electrons the shot noise is Poisson: P(0) = e^-3, mean = variance = 3."""
    sensor = SensorModel(electrons_per_unit=1.0)
    e = sensor.convert(_flat(3.0), origin=(0, 0), units="electrons", noise=True, seed=4)
    n = e.size
    assert np.all(e == np.round(e)) and e.min() >= 0
    assert abs(np.mean(e == 0) - np.exp(-3.0)) < 5 * np.sqrt(np.exp(-3.0) / n)
    assert abs(e.mean() - 3.0) < 5 * np.sqrt(3.0 / n)
    assert abs(e.var() / 3.0 - 1.0) < 5 * np.sqrt((2.0 + 1.0 / 3.0) / n)


def test_read_noise_alone_on_zero_signal():
    sensor = SensorModel(electrons_per_unit=1.0, read_noise_e=7.0)
    e = sensor.convert(_flat(0.0), origin=(0, 0), units="electrons", noise=True, seed=2)
    assert abs(e.mean()) < 5 * 7.0 / np.sqrt(e.size)
    assert abs(e.std() / 7.0 - 1.0) < 5 * np.sqrt(0.5 / e.size)


def test_noise_off_is_the_expectation():
    e = SENSOR.convert(_flat(0.25, (8, 8)), origin=(0, 0), units="electrons", noise=False)
    np.testing.assert_allclose(e, 100.0 + 5000.0 + 50.0)


def test_noise_reproducible_from_seed_and_changes_with_it():
    a = SENSOR.convert(_flat(shape=(100, 100)), origin=(0, 0), units="electrons", noise=True, seed=7)
    b = SENSOR.convert(_flat(shape=(100, 100)), origin=(0, 0), units="electrons", noise=True, seed=7)
    c = SENSOR.convert(_flat(shape=(100, 100)), origin=(0, 0), units="electrons", noise=True, seed=8)
    np.testing.assert_array_equal(a, b)
    assert np.count_nonzero(a != c) > 0.9 * a.size


def test_noise_independent_of_block_partition():
    """Converting 64-px-aligned pieces at their origins reproduces the whole image exactly."""
    x = np.random.default_rng(0).uniform(0.1, 0.9, (150, 130))
    whole = SENSOR.convert(x, origin=(0, 0), units="electrons", noise=True, seed=3)
    pieces = np.empty_like(whole)
    for r in (0, 64, 128):
        for c in (0, 64, 128):
            blk = (slice(r, r + 64), slice(c, c + 64))
            pieces[blk] = SENSOR.convert(x[blk], origin=(r, c), units="electrons", noise=True, seed=3)
    np.testing.assert_array_equal(pieces, whole)


def test_noise_of_a_pixel_does_not_depend_on_the_image_extent():
    """A pixel's noise depends only on its own mean and its place in the fixed block grid: a crop of the
    output equals the output of the crop, partial blocks included."""
    x = np.random.default_rng(0).uniform(0.1, 0.9, (100, 100))
    whole = SENSOR.convert(x, origin=(0, 0), units="electrons", noise=True, seed=3)
    crop = SENSOR.convert(x[:70, :50], origin=(0, 0), units="electrons", noise=True, seed=3)
    np.testing.assert_array_equal(crop, whole[:70, :50])


def test_simulated_noise_reproducible_and_nearly_tiling_independent():
    """Same seed -> same image. Different tile budgets change the noise-free values by ~1e-7 (float32
    rounding in different tiles), which may move a Poisson draw by one electron in a rare pixel; the
    noise field itself (generators per fixed output block) does not depend on the tiling."""
    img = np.random.default_rng(0).uniform(0.1, 0.9, (1400, 1260))
    src = ArraySource(img, pixel_m=0.035)
    kw = dict(sensor=SENSOR, units="electrons", noise=True, seed=5)
    sim = Simulator(BASE, input_pixel_m=0.035, input_shape=img.shape)
    a, a2 = sim.run(src, **kw), sim.run(src, **kw)
    np.testing.assert_array_equal(a, a2)
    tiled = Simulator(BASE, input_pixel_m=0.035, input_shape=img.shape, params=SimParams(max_tile_bytes=12 * 2**20))
    b = tiled.run(src, **kw)
    assert len(tiled.tiles) > 1
    differ = a != b
    assert np.count_nonzero(differ) <= 0.01 * a.size and np.max(np.abs(a - b)) <= 1.0


def test_full_well_clipping():
    sensor = SensorModel(electrons_per_unit=1e5, read_noise_e=10.0, full_well_e=30000.0)
    e = sensor.convert(_flat(1.0, (64, 64)), origin=(0, 0), units="electrons", noise=True, seed=0)
    assert np.all(e == 30000.0)
    e = sensor.convert(_flat(0.298, (64, 64)), origin=(0, 0), units="electrons", noise=True, seed=0)
    assert e.max() <= 30000.0 and np.count_nonzero(e == 30000.0) > 0  # 29800 e + noise reaches the well


@pytest.mark.parametrize(
    ("full_well_e", "bits"), [(60000.0, 12), (10000.0, 12), (1e5, 16), (30000.0, 10), (45000.0, 14)]
)
def test_dn_quantisation_range(full_well_e, bits):
    sensor = SensorModel(electrons_per_unit=full_well_e, read_noise_e=20.0, full_well_e=full_well_e, bit_depth=bits)
    x = np.linspace(-0.01, 1.2, 64 * 64).reshape(64, 64)  # from below zero to beyond saturation
    dn = sensor.convert(np.clip(x, 0, None), origin=(0, 0), units="dn", noise=True, seed=0)
    assert np.all(dn == np.floor(dn))
    assert dn.min() == 0 and dn.max() == 2**bits - 1
    # noise-free: floor(electrons / gain), the ADC range spanning the full well (gain = full well / 2^bits)
    clean = sensor.convert(np.array([[0.0, 0.3, 0.5, 1.0, 2.0]]), origin=(0, 0), units="dn", noise=False)
    top = 2**bits - 1
    np.testing.assert_array_equal(clean[0], [0, np.floor(0.3 * 2**bits), 2 ** (bits - 1), top, top])


def test_reflectance_round_trip_without_noise():
    x = np.random.default_rng(1).uniform(0, 1, (16, 16))
    np.testing.assert_allclose(SENSOR.convert(x, origin=(0, 0), units="reflectance", noise=False), x)
    sensor = SensorModel(radiance_per_unit=80.0, radiance_offset=5.0)
    np.testing.assert_allclose(sensor.convert(x, origin=(0, 0), units="radiance", noise=False), 5.0 + 80.0 * x)


def test_errors_name_the_parameter():
    img = np.full((700, 700), 0.2)
    src = ArraySource(img, pixel_m=0.035)
    sim = Simulator(BASE, input_pixel_m=0.035, input_shape=img.shape)
    with pytest.raises(ConfigError, match="units = 'counts'"):
        sim.run(src, units="counts")
    with pytest.raises(ConfigError, match="units = 'dn'.*SensorModel"):
        sim.run(src, units="dn")
    with pytest.raises(ConfigError, match="noise = True"):
        sim.run(src, noise=True)
    with pytest.raises(ConfigError, match="pixel_m"):
        simulate(img, BASE)
    with pytest.raises(ConfigError, match="input_pixel_m = -0.035"):
        Simulator(BASE, input_pixel_m=-0.035, input_shape=img.shape)
    with pytest.raises(ConfigError, match="border = 'mirror'"):
        SimParams(border="mirror")
    with pytest.raises(ConfigError, match="electrons_per_unit = 0"):
        SensorModel(electrons_per_unit=0.0)
    with pytest.raises(ConfigError, match="bit_depth = 40"):
        SensorModel(bit_depth=40)
    with pytest.raises(ConfigError, match="full_well_e"):
        SensorModel().convert(img[:4, :4], origin=(0, 0), units="dn", noise=False)
    with pytest.raises(ConfigError, match="origin"):
        SENSOR.convert(img[:4, :4], origin=(3, 0), units="electrons", noise=True)


@settings(max_examples=30, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**32 - 1), log_mean=st.floats(-3.0, np.log10(199.0)))
def test_low_mean_quantiles_equal_scipy_stats_poisson_ppf(seed, log_mean):
    """Below 200 electrons the shot noise is the exact Poisson quantile: scipy.stats.poisson.ppf itself, taken
    from the same special functions without importing scipy.stats (which costs about a second)."""
    from scipy.stats import poisson

    from satchain.engine.sensor import _poisson_ppf

    rng = np.random.default_rng(seed)
    u = rng.random(4096)
    u[:4] = [1e-300, 1e-12, 1 - 1e-16, 0.5]
    mean = 10.0**log_mean * rng.uniform(0.5, 1.0, u.size)
    np.testing.assert_array_equal(_poisson_ppf(u, mean), poisson.ppf(np.clip(u, 1e-300, 1 - 1e-16), mean))
