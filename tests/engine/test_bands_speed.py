"""What simulate_bands does to be fast (benchmarks/bench_bands.py) changes no image beyond its stated accuracy:
each band's OTF over fewer quadrature nodes (engine.bands.band_otf) within 1e-3 of the system's own 11-node OTF
at every frequency up to the optics' cutoff, and the scene rendered once per grey layout giving exactly the images
of the unchanged engine rendering window by window."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from satchain import load_preset
from satchain.config.sections_light import RESPONSE_NODES
from satchain.engine.bands import band_seed, simulate_bands
from satchain.engine.bands_shared import OTF_TOLERANCE, band_otf, band_params
from satchain.engine.sensor import sensor_from_system
from satchain.engine.simulate import SimParams, Simulator
from satchain.engine.sources import SceneSource
from satchain.scene.layout import Scene, layout_from_dict, paper_layout
from satchain.scene.spectral import layout_for_band
from satchain.scene.targets import SlantedEdge
from satchain.tf.budget import SystemOTF

PMS = "ankarasat3-pms"


@pytest.fixture(scope="module")
def pms():
    return load_preset(PMS)


def _grid(cutoff: float, n: int = 97) -> tuple[np.ndarray, np.ndarray]:
    f = np.linspace(-cutoff, cutoff, n)
    return f[None, :], f[:, None]


@pytest.mark.parametrize("name", ["blue", "green", "red", "nir"])
def test_band_otf_within_1e3_of_the_11_node_otf_up_to_cutoff(pms, name):
    """Every MS band of the preset: fewer optics wavelengths than the system's RESPONSE_NODES, the same centroid,
    and the system MTF (every component) within 1e-3 of the 11-node one on a 2-D grid up to the optics' cutoff --
    so a fortiori up to the band's Nyquist."""
    i = pms.band_index(name)
    s = pms.for_band(i)
    assert len(s.optics.wavelengths_m) == RESPONSE_NODES
    light = band_otf(s, pms.bands[i])
    lam, w = np.asarray(light.system.optics.wavelengths_m), np.asarray(light.system.optics.wavelength_weights)
    assert len(lam) < RESPONSE_NODES
    assert np.sum(lam * w) / np.sum(w) == pytest.approx(pms.bands[i].center_wavelength_m, rel=1e-6)
    own = SystemOTF(s)
    fx, fy = _grid(own.cutoff_cy_per_mm)
    delta = np.abs(np.abs(light(fx, fy)) - np.abs(own(fx, fy)))
    assert delta.max() < OTF_TOLERANCE
    ny = 0.5e-3 / s.detector.pitch_x_m  # cy/mm at the band's Nyquist
    fx, fy = _grid(ny, 41)
    assert np.abs(np.abs(light(fx, fy)) - np.abs(own(fx, fy))).max() < OTF_TOLERANCE


@settings(max_examples=12, deadline=None)
@given(centre_nm=st.floats(550.0, 900.0), fwhm_nm=st.floats(10.0, 150.0), order=st.sampled_from([1, 2, 4]))
def test_band_otf_never_exceeds_its_tolerance(pms, centre_nm, fwhm_nm, order):
    """Any (super-)Gaussian band: the OTF band_otf gives stays within 1e-3 of the system's own up to its cutoff
    (wide bands keep more nodes, or all of them)."""
    b = pms.bands[3].model_copy(update={"response": pms.bands[3].response.model_copy(
        update={"center_m": centre_nm * 1e-9, "fwhm_m": fwhm_nm * 1e-9, "order": order})})  # fmt: skip
    system = pms.model_copy(update={"bands": (*pms.bands[:3], b, pms.bands[4])})
    s = system.for_band(3)
    own, light = SystemOTF(s), band_otf(s, system.bands[3])
    fx, fy = _grid(own.cutoff_cy_per_mm, 61)
    assert np.abs(np.abs(light(fx, fy)) - np.abs(own(fx, fy))).max() < OTF_TOLERANCE


@pytest.fixture(scope="module")
def paper_whole():
    scene = paper_layout()
    return scene, scene.render((0, 0, *scene.shape_px(1.75)), pixel_m=1.75)


@settings(max_examples=8, deadline=None)
@given(r0=st.integers(0, 120), c0=st.integers(0, 80), h=st.integers(1, 40), w=st.integers(1, 40))
def test_a_window_of_the_whole_render_is_the_window_rendered(paper_whole, r0, c0, h, w):
    """What one render per layout relies on: the renderer's pixel does not depend on the window asked for."""
    scene, whole = paper_whole
    assert np.array_equal(scene.render((r0, c0, h, w), pixel_m=1.75), whole[r0 : r0 + h, c0 : c0 + w])


def _engine_alone(layout, system, i, pixel_m, *, seed, margin_as_system=True, units="dn", noise=True):
    """Band i formed by the unchanged engine on its own, the scene rendered window by window (no offsets), with
    the band's far margin (band_params) or the engine's default one."""
    from satchain.engine.bands import band_response

    s = system.for_band(i)
    src = SceneSource(layout_for_band(layout, *band_response(system, i)), pixel_m=pixel_m)
    params = band_params(SimParams(), system, s) if margin_as_system else SimParams()
    sim = Simulator(s, input_pixel_m=pixel_m, input_shape=src.shape_px, motion_seed=seed, params=params,
                    otf=band_otf(s, system.bands[i]))  # fmt: skip
    return sim.run(src, sensor=sensor_from_system(s), units=units, noise=noise, seed=band_seed(seed, i))


@pytest.mark.parametrize("spectral", [False, True])
def test_shared_render_gives_each_band_the_engine_image_exactly(pms, spectral):
    """A grey scene (one render shared by PAN, blue and NIR) and a material scene (one render per band: green's
    dropped for red's): every band equals the engine's image of that band formed alone (its scene rendered window
    by window), noise and DN included."""
    if spectral:
        scene = layout_from_dict({"scene": {"width_m": 19.6, "height_m": 19.6, "background_material": "dry_grass"},
                                  "items": [{"kind": "slanted_edge", "id": "e", "center_m": [10.0, 10.0],
                                             "size_m": 12.0, "bright_material": "concrete",
                                             "dark_material": "asphalt"}]})  # fmt: skip
    else:
        scene = Scene(19.6, 19.6, (SlantedEdge("e", center_m=(10.0, 10.0), size_m=12.0, angle_deg=5.0),), 0.2)
    which = ["green", "red"] if spectral else ["pan", "blue", "nir"]
    got = simulate_bands(scene, pms, pixel_m=0.49, units="dn", noise=True, seed=4, bands=which)
    for name in which:
        i = pms.band_index(name)
        assert np.array_equal(got[name].image, _engine_alone(scene, pms, i, 0.49, seed=4)), name


def test_ms_far_margin_at_the_systems_ground_distance_changes_images_below_1e4(pms):
    """An MS band's coarse frame extends 32 of its pixels (the 128 PAN pixels' 62.7 m) instead of 128: on a
    scene of full-contrast edges up to its border (reflectance 0.02-0.98), every pixel of every MS band within
    1e-4 of the image with the engine's default 128-pixel margin."""
    items = (SlantedEdge("a", center_m=(9.8, 9.8), size_m=19.6, angle_deg=5.0, bright=0.98, dark=0.02),)
    scene = Scene(19.6, 19.6, items, 0.5)
    got = simulate_bands(scene, pms, pixel_m=0.49, noise=False, bands=["blue", "nir"])
    for name in ("blue", "nir"):
        i = pms.band_index(name)
        assert band_params(SimParams(), pms, pms.for_band(i)).far_margin_px == 32
        ref = _engine_alone(scene, pms, i, 0.49, seed=0, margin_as_system=False, units="reflectance", noise=False)
        assert np.abs(got[name].image - ref).max() < 1e-4, name


def test_shared_stage1_and_transform_change_images_below_1e6(pms, monkeypatch):
    """At 0.07 m the four MS bands share one pixel grid: one stage 1 (decimated by 2 with the low-pass made for
    blue's cutoff, the widest: bands_shared.group_decimation) and one transform of the coarse frame, which each band
    restricts to its own band. Each equals the engine's band formed alone from its own coarse grid (blue and green
    by D = 1, red and NIR by D = 2 with their own low-pass) within 1e-6 of the 0.02-0.98 edge (3e-7 measured)."""
    import satchain.engine.simulate as engine

    calls = {"decimate": 0, "frame_spectrum": 0}

    def counting(name):
        method = getattr(engine.Simulator, name)

        def counted(self, *a, **k):
            calls[name] += 1
            return method(self, *a, **k)

        return counted

    for name in calls:
        monkeypatch.setattr(engine.Simulator, name, counting(name))
    items = (SlantedEdge("a", center_m=(9.8, 9.8), size_m=14.0, angle_deg=5.0, bright=0.98, dark=0.02),)
    scene = Scene(19.6, 19.6, items, 0.5)
    got = simulate_bands(scene, pms, pixel_m=0.07, noise=False, bands=["blue", "green", "red", "nir"])
    assert calls == {"decimate": 1, "frame_spectrum": 1}
    monkeypatch.undo()
    for name in ("blue", "green", "red", "nir"):
        ref = _engine_alone(scene, pms, pms.band_index(name), 0.07, seed=0, units="reflectance", noise=False)
        assert np.abs(got[name].image - ref).max() <= 1e-6, name
