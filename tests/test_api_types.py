"""Issue 18, point 8: every public entry point refuses a wrong type with a one-line SatchainError naming the
parameter and the value (never a foreign AttributeError / TypeError / pydantic ValidationError), before any
work; bools, strings and NaN are never taken for numbers, in the API or in system and run configuration files."""

import math
import tracemalloc

import numpy as np
import pytest

import satchain
from satchain.errors import ConfigError, ParameterTypeError, ResourceLimitError, SatchainError

SYSTEM = satchain.load_preset("ankarasat3")
TRUTH = {"format": "satchain-scene-truth/1", "items": []}
IMG = np.zeros((64, 64))
RUN_DIR_IMG = np.zeros((64, 64), complex)


def _system_with(section: str, key: str, value):
    d = SYSTEM.to_dict()
    d[section] = {**d[section], key: value}
    return lambda: satchain.ImagingSystem.from_dict(d)


# (call, the parameter the message must name, the value as the message shows it)
HOSTILE = {
    "run(42)": (lambda: satchain.run(42), "config", "42"),
    "run([1, 2])": (lambda: satchain.run([1, 2]), "config", "[1, 2]"),
    "run(progress=5)": (lambda: satchain.run(None, progress=5), "progress", "5"),
    "run(out_dir=3.5)": (lambda: satchain.run(None, out_dir=3.5), "out_dir", "3.5"),
    "run(unknown=1)": (lambda: satchain.run(None, unknown=1), "unknown", "run()"),
    "run seed=True": (lambda: satchain.run({"simulation": {"seed": True}}), "simulation.seed", "True"),
    "run pixel_m='0.035'": (lambda: satchain.run({"scene": {"pixel_m": "0.035"}}), "scene.pixel_m", "'0.035'"),
    "run pixel_m=nan": (lambda: satchain.run({"scene": {"pixel_m": math.nan}}), "scene.pixel_m", "nan"),
    "run noise=1": (lambda: satchain.run({"simulation": {"noise": 1}}), "simulation.noise", "1"),
    "run niirs tolerance False": (lambda: satchain.run({"tolerances": {"niirs": False}}), "tolerances.niirs", "False"),
    "predict(None, truth)": (lambda: satchain.predict(None, TRUTH), "system", "None"),
    "predict(system, 'nosuch.json')": (lambda: satchain.predict(SYSTEM, "nosuch.json"), "truth", "'nosuch.json'"),
    "predict(system, 42)": (lambda: satchain.predict(SYSTEM, 42), "truth", "42"),
    "predict wedge_threshold='a'": (
        lambda: satchain.predict(SYSTEM, TRUTH, wedge_threshold="a"),
        "wedge_threshold",
        "'a'",
    ),
    "predict()": (lambda: satchain.predict(), "system", "predict()"),
    "load_system(None)": (lambda: satchain.load_system(None), "path_or_preset", "None"),
    "load_system(42)": (lambda: satchain.load_system(42), "path_or_preset", "42"),
    "ImagingSystem(orbit=5)": (lambda: satchain.ImagingSystem(orbit=5), "orbit", "5"),
    "ImagingSystem()": (lambda: satchain.ImagingSystem(), "optics", "missing"),
    "altitude_m = true": (_system_with("orbit", "altitude_m", True), "orbit.altitude_m", "True"),
    "altitude_m = '500000'": (_system_with("orbit", "altitude_m", "500000"), "orbit.altitude_m", "'500000'"),
    "altitude_m = nan": (_system_with("orbit", "altitude_m", math.nan), "orbit.altitude_m", "nan"),
    "tdi_stages = true": (_system_with("detector", "tdi_stages", True), "detector.tdi_stages", "True"),
    "wavelengths_m = [5e-7, true]": (
        _system_with("optics", "wavelengths_m", [5e-7, True]),
        "optics.wavelengths_m",
        "True",
    ),
    "turbulence = 1": (_system_with("atmosphere", "turbulence", 1), "atmosphere.turbulence", "1"),
    "predict_quality(None)": (lambda: satchain.predict_quality(None), "system", "None"),
    "predict_quality df='a'": (lambda: satchain.predict_quality(SYSTEM, df_cy_per_px="a"), "df_cy_per_px", "'a'"),
    "measure_edge(None)": (lambda: satchain.measure_edge(None), "image", "None"),
    "measure_edge('x.tif')": (lambda: satchain.measure_edge("x.tif"), "image", "'x.tif'"),
    "measure_edge complex image": (lambda: satchain.measure_edge(RUN_DIR_IMG), "image", "complex"),
    "measure_edge pixel_m='0.035'": (lambda: satchain.measure_edge(IMG, pixel_m="0.035"), "pixel_m", "'0.035'"),
    "measure_edge pixel_m=True": (lambda: satchain.measure_edge(IMG, pixel_m=True), "pixel_m", "True"),
    "measure_edge oversampling=True": (lambda: satchain.measure_edge(IMG, oversampling=True), "oversampling", "True"),
    "measure_edge debias='yes'": (lambda: satchain.measure_edge(IMG, debias="yes"), "debias", "'yes'"),
    "measure_star cycles=True": (lambda: satchain.measure_star(IMG, cycles=True), "cycles", "True"),
    "measure_star cycles='16'": (lambda: satchain.measure_star(IMG, cycles="16"), "cycles", "'16'"),
    "measure_star center='ab'": (lambda: satchain.measure_star(IMG, cycles=16, center="ab"), "center", "'ab'"),
    "measure_star no cycles": (lambda: satchain.measure_star(IMG), "cycles", "measure_star()"),
    "measure_bars periods_px='8,12'": (
        lambda: satchain.measure_bars(IMG, periods_px="8,12", group_rois=[]),
        "periods_px",
        "'8,12'",
    ),
    "measure_bars no group_rois": (lambda: satchain.measure_bars(IMG, periods_px=[8]), "group_rois", "measure_bars()"),
    "measure_wedge direction=5": (
        lambda: satchain.measure_wedge(IMG, line_width_px=lambda y: y, direction=5),
        "direction",
        "5",
    ),
    "measure_wedge(None)": (lambda: satchain.measure_wedge(None, line_width_px=2.0), "image", "None"),
    "measure_auto truth=None": (lambda: satchain.measure_auto(IMG, None), "truth", "None"),
    "measure_auto truth='t.json'": (lambda: satchain.measure_auto(IMG, "t.json"), "truth", "'t.json'"),
    "measure_auto pixel_m=True": (lambda: satchain.measure_auto(IMG, TRUTH, pixel_m=True), "pixel_m", "True"),
    "measure_auto origin_m='0,0'": (lambda: satchain.measure_auto(IMG, TRUTH, origin_m="0,0"), "origin_m", "'0,0'"),
    "measure_snr truth=None": (lambda: satchain.measure_snr(IMG, None, pixel_m=0.5), "truth", "None"),
    "measure_snr pixel_m='0.5'": (lambda: satchain.measure_snr(IMG, TRUTH, pixel_m="0.5"), "pixel_m", "'0.5'"),
    "find_edges(None)": (lambda: satchain.find_edges(None), "image", "None"),
    "find_edges min_length_px=True": (
        lambda: satchain.find_edges(IMG, min_length_px=True),
        "min_length_px",
        "True",
    ),
    "measure_found_edges pixel_m='0.5'": (
        lambda: satchain.measure_found_edges(IMG, pixel_m="0.5"),
        "pixel_m",
        "'0.5'",
    ),
    "simulate seed=True": (lambda: satchain.simulate(IMG, SYSTEM, pixel_m=0.1, seed=True), "seed", "True"),
    "simulate pixel_m='0.035'": (lambda: satchain.simulate(IMG, SYSTEM, pixel_m="0.035"), "pixel_m", "'0.035'"),
    "simulate system=None": (lambda: satchain.simulate(IMG, None, pixel_m=0.1), "system", "None"),
    "SystemOTF(None)": (lambda: satchain.SystemOTF(None), "system", "None"),
    "SystemOTF('ankarasat3')": (lambda: satchain.SystemOTF("ankarasat3"), "system", "'ankarasat3'"),
    "load_layout(42)": (lambda: satchain.load_layout(42), "source", "42"),
    "read_truth(42)": (lambda: satchain.read_truth(42), "source", "42"),
    "load_run_config(42)": (lambda: satchain.load_run_config(42), "path", "42"),
    "compare(None, None)": (lambda: satchain.compare(None, None), "tolerances", "compare()"),
    "coltman_ctf('x', 'y')": (lambda: satchain.coltman_ctf("x", "y"), "f", "'x'"),
}


@pytest.mark.parametrize("name", list(HOSTILE))
def test_hostile_call_is_refused_with_one_line_naming_the_parameter(name):
    call, param, shown = HOSTILE[name]
    with pytest.raises(SatchainError) as info:
        call()
    msg = str(info.value)
    assert "\n" not in msg and len(msg) < 400, msg
    assert param in msg and shown in msg, msg
    assert "pydantic" not in msg and "For further information" not in msg, msg


def test_type_errors_are_also_type_errors_and_value_errors():
    """A ParameterTypeError is caught by ``except TypeError`` (Python's habit) and ``except ValueError``."""
    for exc_type in (TypeError, ValueError, ConfigError):
        with pytest.raises(exc_type):
            satchain.measure_edge(IMG, pixel_m="0.5")
    assert issubclass(ParameterTypeError, SatchainError)


def test_correct_calls_still_work_and_numpy_numbers_are_numbers():
    """The checks refuse only wrong types: numpy scalars, ints for floats and paths are accepted."""
    y, x = np.mgrid[0:80, 0:80]
    edge = 0.2 + 0.6 * (x - 40 > 0.1 * (y - 40))
    r = satchain.measure_edge(edge.astype(float), pixel_m=np.float32(0.5), oversampling=np.int64(4))
    assert r.f_cy_per_m_ground is not None
    assert satchain.predict_quality(SYSTEM, df_cy_per_px=np.float64(0.002)).giqe5 > 0
    cfg = satchain.RunConfig.from_dict({"scene": {"pixel_m": 1}, "simulation": {"seed": np.int64(3)}})
    assert cfg.scene.pixel_m == 1.0 and cfg.simulation.seed == 3
    assert satchain.load_system("ankarasat3") == SYSTEM


def test_predict_quality_refuses_a_huge_frequency_grid_before_allocating():
    """df = 1e-9 cy/px would need ~9e8 samples per axis (hundreds of GiB): refused at once with the figure."""
    tracemalloc.start()
    with pytest.raises(ResourceLimitError, match=r"df_cy_per_px = 1e-09: .* GiB of memory; must be >= ") as info:
        satchain.predict_quality(SYSTEM, df_cy_per_px=1e-9)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 50 * 2**20  # nothing big was allocated
    need_gib = float(str(info.value).split("need about ")[1].split(" GiB")[0])
    assert need_gib > 100  # ~9.3e8 points x ~400 bytes
    assert satchain.predict_quality(SYSTEM, df_cy_per_px=2e-6).giqe5 == pytest.approx(
        satchain.predict_quality(SYSTEM).giqe5, abs=1e-3
    )  # a fine grid below the limit still runs, and agrees with the default
