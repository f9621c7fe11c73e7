"""The radial table of satchain.tf.optics.DiffractionOTF against the closed form summed over wavelength.

A pupil without a pupil FFT (clear or centrally obscured circle, optional ``wfe_rms_waves``) has an OTF that
depends on ``|f|`` only; a call on at least RADIAL_TABLE_MIN_POINTS frequencies interpolates it on a table of
radial_table_intervals steps up to the highest cutoff. The reference here is the closed form written out per
wavelength from satchain.tf.annular's public functions (O'Neill 1956 and Shannon's ATF), with the weights
normalised here; or the same DiffractionOTF evaluated in chunks below the threshold (its exact path).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import Phase, example, given, settings
from hypothesis import strategies as st

from satchain.config.system import Optics, load_preset
from satchain.errors import InputError
from satchain.tf.annular import annular_mtf, optical_cutoff_cy_per_mm, shannon_atf
from satchain.tf.budget import SystemOTF
from satchain.tf.optics import RADIAL_TABLE_MIN_POINTS, DiffractionOTF, radial_table_intervals

M = RADIAL_TABLE_MIN_POINTS
# each example costs ~0.3 s: no shrinking (a failure prints its example as drawn)
FAST = settings(max_examples=10, deadline=None, phases=(Phase.explicit, Phase.reuse, Phase.generate))


def _optics(eps, nodes, f_number, wfe=0.0) -> Optics:
    """``nodes``: (wavelength m, relative weight) pairs."""
    return Optics(
        aperture_diameter_m=0.5,
        f_number=f_number,
        wavelengths_m=tuple(lam for lam, _ in nodes),
        wavelength_weights=tuple(w for _, w in nodes),
        obscuration_ratio=eps,
        wfe_rms_waves=wfe,
    )


def _cutoffs(optics) -> list[float]:
    return [optical_cutoff_cy_per_mm(lam, optics.f_number) for lam in optics.wavelengths_m]


def _closed_form(f, optics) -> np.ndarray:
    """sum_i w_i annular_mtf_i(|f|) ATF_i(|f|), w normalised; wfe in waves at the weight-averaged wavelength, so
    ``wfe lam_eff / lam_i`` waves at ``lam_i``."""
    lams = np.asarray(optics.wavelengths_m, dtype=float)
    raw = optics.wavelength_weights
    w = np.ones(lams.size) if raw is None else np.asarray(raw, dtype=float)
    w = w / w.sum()
    lam_eff = float(np.sum(w * lams))
    f = np.abs(np.asarray(f, dtype=float))
    out = np.zeros(f.shape)
    for wi, lam in zip(w, lams, strict=True):
        mono = annular_mtf(f, wavelength_m=lam, f_number=optics.f_number, obscuration_ratio=optics.obscuration_ratio)
        if optics.wfe_rms_waves > 0:
            cutoff = optical_cutoff_cy_per_mm(lam, optics.f_number)
            mono = mono * shannon_atf(f / cutoff, optics.wfe_rms_waves * lam_eff / lam)
        out += wi * mono
    return out


def _boundary_freqs(optics, *, half_steps=4, per_step=256) -> np.ndarray:
    """Radii densely packed (``per_step`` a table step, ``half_steps`` steps either side) around each wavelength's
    cutoff and its O'Neill region boundaries ``v = eps``, ``(1 -/+ eps) / 2``: where the closed form has kinks."""
    cuts = _cutoffs(optics)
    step = max(cuts) / radial_table_intervals(cuts)  # the table's own step
    eps = optics.obscuration_ratio
    offsets = step * np.linspace(-half_steps, half_steps, 2 * half_steps * per_step + 1)
    pts = [c * v0 + offsets for c in cuts for v0 in (1.0, eps, (1.0 - eps) / 2.0, (1.0 + eps) / 2.0) if v0 > 0]
    return np.abs(np.concatenate(pts))


def _engine_grid(top, ny=1024, nx=2046):
    """fx >= 0 (an rfft's columns), fy symmetric (fft rows, -f and +f), to 1.1 x the highest cutoff; the distinct
    |fy| rows times the columns (513 x 1024) are >= RADIAL_TABLE_MIN_POINTS, so the table is used."""
    span = 2.2 * top
    return np.fft.rfftfreq(nx) * span, np.fft.fftfreq(ny) * span


def _table_error(optics) -> float:
    """Max |table - closed form| over an engine-like outer grid and over the boundary radii (tiled up to
    RADIAL_TABLE_MIN_POINTS), each call >= RADIAL_TABLE_MIN_POINTS frequencies."""
    otf = DiffractionOTF(optics, radial_table=True)
    fx, fy = _engine_grid(max(_cutoffs(optics)))
    got = otf(fx[None, :], fy[:, None])
    assert got.shape == (fy.size, fx.size) and got.dtype == np.float64
    # the reference on the distinct |fy| rows (fy's -f and +f rows are the same radii), then spread to all rows
    afy, inverse = np.unique(np.abs(fy), return_inverse=True)
    ref = _closed_form(np.hypot(fx[None, :], afy[:, None]), optics)[inverse]
    err_grid = float(np.max(np.abs(got - ref)))
    pts = _boundary_freqs(optics)
    tiled = np.resize(pts, max(M, pts.size))  # copies of the boundary radii: one call on >= M frequencies
    got = otf(tiled, 0.0)
    err_pts = float(np.max(np.abs(got - np.resize(_closed_form(pts, optics), tiled.size))))
    return max(err_grid, err_pts)


_nodes = st.lists(
    st.tuples(st.floats(400e-9, 1000e-9), st.floats(1e-3, 1.0)),  # (wavelength m, relative weight)
    min_size=1,
    max_size=11,
)
# a long wavelength carrying most of the weight, with a short one setting the table's top: its cutoff is 0.4 x the
# top, so its table step in v is 2.5 x that of a single wavelength
_DOMINANT_LONG_05 = ((400e-9, 0.1), (1000e-9, 1.0))
_DOMINANT_LONG_095 = ((400e-9, 0.1), (995e-9, 1.0))


@FAST
@given(eps=st.floats(0.0, 0.5), nodes=_nodes, f_number=st.floats(3.0, 20.0))
@example(eps=0.5, nodes=_DOMINANT_LONG_05, f_number=8.0)
def test_table_within_2e8_of_the_closed_form_for_obscurations_up_to_half(eps, nodes, f_number):
    err = _table_error(_optics(eps, nodes, f_number))
    assert err > 0.0  # the table path did run (the closed form itself would agree to rounding)
    assert err <= 2e-8, f"eps = {eps}, nodes = {nodes}, F# = {f_number}: max |table - closed form| = {err:.3e}"


@FAST
@given(eps=st.floats(0.5, 0.95, exclude_min=True), nodes=_nodes, f_number=st.floats(3.0, 20.0))
@example(eps=0.95, nodes=_DOMINANT_LONG_095, f_number=8.0)
def test_table_within_1e6_of_the_closed_form_for_obscurations_up_to_095(eps, nodes, f_number):
    err = _table_error(_optics(eps, nodes, f_number))
    assert err > 0.0
    assert err <= 1e-6, f"eps = {eps}, nodes = {nodes}, F# = {f_number}: max |table - closed form| = {err:.3e}"


@pytest.mark.parametrize("eps", [0.0, 0.3323, 0.9])
def test_zero_beyond_the_highest_cutoff_and_one_at_zero(eps):
    optics = _optics(eps, ((450e-9, 1.0), (700e-9, 2.0), (900e-9, 0.5)), 9.72)
    top = max(_cutoffs(optics))
    rng = np.random.default_rng(7)
    beyond = [np.nextafter(top, np.inf)]
    for _ in range(63):
        beyond.append(np.nextafter(beyond[-1], np.inf))  # the first 64 doubles past the cutoff
    beyond = np.concatenate([beyond, top * (1.0 + rng.uniform(1e-12, 9.0, 4096)), [top * 1e6, 1e300, 1.7e308]])
    f = np.zeros(M)  # the rest: f = 0
    f[: beyond.size] = beyond
    theta = rng.uniform(0.0, 2.0 * np.pi, M)
    out = DiffractionOTF(optics, radial_table=True)(f * np.cos(theta), f * np.sin(theta))
    assert np.count_nonzero(out[: beyond.size]) == 0  # exactly 0, at every angle
    assert np.max(np.abs(out[beyond.size :] - 1.0)) <= 1e-12


@pytest.mark.parametrize(
    "lam_m, f_number, eps",
    [(500e-9, 9.72, 0.0), (649.61e-9, 9.72, 0.3323), (1000e-9, 9.72, 0.0)],
)
def test_zero_at_the_highest_cutoff(lam_m, f_number, eps):
    # annular_mtf (and so the closed-form path) is exactly 0 at and beyond the cutoff; the table at f = cutoff
    optics = _optics(eps, ((lam_m, 1.0),), f_number)
    cutoff = optical_cutoff_cy_per_mm(lam_m, f_number)
    f = np.zeros(M)
    f[0] = cutoff
    assert float(annular_mtf(cutoff, wavelength_m=lam_m, f_number=f_number, obscuration_ratio=eps)) == 0.0
    assert DiffractionOTF(optics, radial_table=True)(f, 0.0)[0] == 0.0


def test_fewer_points_give_the_closed_form_exactly():
    optics = _optics(0.3323, ((480e-9, 0.5), (620e-9, 1.0), (910e-9, 0.7)), 9.72)
    otf = DiffractionOTF(optics, radial_table=True)
    top = max(_cutoffs(optics))
    pts = _boundary_freqs(optics)
    f = np.concatenate([pts, np.linspace(0.0, 1.2 * top, M - 1 - pts.size)])  # one short of the threshold
    ref = _closed_form(f, optics)
    small = otf(f, 0.0)
    assert np.max(np.abs(small - ref)) <= 1e-15
    np.testing.assert_array_equal(small, otf._sum(f))
    # the threshold is RADIAL_TABLE_MIN_POINTS: one more point takes the table, which differs (within its bound)
    big = otf(np.append(f, 0.5 * top), 0.0)[:-1]
    assert 0.0 < np.max(np.abs(big - ref)) <= 2e-8
    # an outer grid whose distinct rows stay below the threshold: the closed form too
    fx, fy = np.linspace(0.0, 1.2 * top, 300), np.linspace(-1.2 * top, 1.2 * top, 257)
    grid = otf(fx[None, :], fy[:, None])
    assert np.max(np.abs(grid - _closed_form(np.hypot(fx[None, :], fy[:, None]), optics))) <= 1e-15


def test_non_finite_frequencies():
    optics = _optics(0.3323, ((649.61e-9, 1.0),), 9.72)
    otf = DiffractionOTF(optics, radial_table=True)
    top = max(_cutoffs(optics))
    f = np.linspace(0.0, 1.1 * top, M)
    # NaN or inf: refused with the same message on either path (small: closed form; large: the table's size)
    for bad in (np.nan, np.inf, -np.inf):
        for n in (16, M):
            g = f[:n].copy()
            g[n // 2] = bad
            with pytest.raises(InputError, match="fx_cy_per_mm: contains 1 NaN/inf"):
                otf(g, 0.0)
    # the table's own guard: a radius whose table index is not finite leaves the call to the closed form
    assert otf._radial_lookup(np.array([0.0, np.nan, 1.0])) is None
    assert otf._radial_lookup(np.array([0.0, np.inf])) is None
    # a finite radius that overflows the table index (1.7e308 * N / top = inf): the closed form's exact 0
    g = f.copy()
    g[-1] = 1.7e308
    out = otf(g, 0.0)
    assert out[-1] == 0.0
    np.testing.assert_array_equal(out, otf._sum(g))  # the whole call took the closed form
    assert np.max(np.abs(out - _closed_form(g, optics))) <= 1e-15


def _chunked(fn, fx, fy, rows_per_chunk):
    """``fn(fx[None, :], fy[:, None])`` evaluated in row blocks, each below RADIAL_TABLE_MIN_POINTS points."""
    assert rows_per_chunk * fx.size < M
    return np.concatenate(
        [fn(fx[None, :], fy[i : i + rows_per_chunk, None]) for i in range(0, fy.size, rows_per_chunk)]
    )


def _exact_chunks_error(optics) -> float:
    """Max |table - exact| on >= RADIAL_TABLE_MIN_POINTS radii (the boundary radii and a sweep to 1.1 x the top),
    the exact values from the same DiffractionOTF called on chunks below the threshold (its closed-form path)."""
    otf = DiffractionOTF(optics, radial_table=True)
    pts = _boundary_freqs(optics, per_step=64)
    f = np.concatenate([pts, np.linspace(0.0, 1.1 * max(_cutoffs(optics)), max(M - pts.size, 0))])
    got = otf(f, 0.0)
    exact = np.concatenate([otf(c, 0.0) for c in np.array_split(f, 4)])  # each chunk < M: the closed form
    # the exact path is the closed form with wfe scaled by lam_eff / lam_i (written out here)
    assert np.max(np.abs(exact - _closed_form(f, optics))) <= 1e-15
    return float(np.max(np.abs(got - exact)))


@settings(max_examples=5, deadline=None, phases=(Phase.explicit, Phase.reuse, Phase.generate))
@given(
    eps=st.floats(0.0, 0.5),
    nodes=st.lists(st.tuples(st.floats(400e-9, 1000e-9), st.floats(1e-3, 1.0)), min_size=1, max_size=4),
    f_number=st.floats(3.0, 20.0),
    fraction=st.floats(0.05, 1.0),
)
def test_table_with_wavefront_error_matches_exact_chunks(eps, nodes, f_number, fraction):
    # wfe up to where Shannon's ATF first reaches 0 at some wavelength: 0.18 waves at the shortest, i.e.
    # wfe lam_eff / lam_min <= 0.18 (wfe is in waves at lam_eff); beyond, see test_table_with_a_clipped_atf
    lams, w = np.array([n[0] for n in nodes]), np.array([n[1] for n in nodes])
    wfe = fraction * 0.18 * lams.min() / float(np.sum(w * lams) / w.sum())
    err = _exact_chunks_error(_optics(eps, nodes, f_number, wfe))
    assert 0.0 < err <= 2e-8, f"eps = {eps}, nodes = {nodes}, F# = {f_number}, wfe = {wfe}: {err:.3e}"


@pytest.mark.parametrize(
    "nodes, wfe",
    [(((650e-9, 1.0),), 0.25), (((500e-9, 1.0), (800e-9, 1.0)), 0.17)],  # 0.17 waves: 0.221 at 500 nm
)
def test_table_with_a_clipped_atf(nodes, wfe):
    # Shannon's ATF is clipped at 0 where (W / 0.18)^2 (1 - 4 (v - 1/2)^2) > 1: a kink in the slope that the
    # table's linear interpolation would smooth over: such a system keeps the closed form (exactly)
    err = _exact_chunks_error(_optics(0.0, nodes, 9.72, wfe))
    assert err == 0.0, f"nodes = {nodes}, wfe = {wfe}: max |table - exact| = {err:.3e}"


@pytest.mark.parametrize("preset, band", [("ankarasat3", None), ("ankarasat3-pms", 1)])
def test_system_otf_table_matches_exact_chunks(preset, band):
    system = load_preset(preset)
    system = system if band is None else system.for_band(band)
    assert not system.optics.needs_pupil_fft
    otf = SystemOTF(system, radial_table=True)
    fx, fy = _engine_grid(otf.cutoff_cy_per_mm)  # as the engine's band spectra: fx >= 0, fy = -f..f
    got = otf(fx[None, :], fy[:, None], exclude=("detector",))
    exact = _chunked(lambda x, y: otf(x, y, exclude=("detector",)), fx, fy, max(1, (M - 1) // fx.size))
    err = float(np.max(np.abs(got - exact)))
    assert 0.0 < err <= 1e-7, f"{preset} band {band}: max |table - exact| = {err:.3e}"
    # its diffraction component alone against the closed form written out here
    table = otf.components(fx[None, :], fy[:, None])["diffraction"]
    afy, inverse = np.unique(np.abs(fy), return_inverse=True)
    ref = _closed_form(np.hypot(fx[None, :], afy[:, None]), system.optics)[inverse]
    err = float(np.max(np.abs(table - ref)))
    assert 0.0 < err <= 2e-8, f"{preset} band {band}: max |diffraction table - closed form| = {err:.3e}"


@pytest.mark.parametrize("preset", ["ankarasat3", "ankarasat3-pms"])
def test_without_radial_table_every_value_is_the_closed_form(preset):
    """The default (a single-band system, satchain run's main image): no table, even on a whole spectrum -- the
    values are bit for bit those of the closed form evaluated in chunks below the threshold."""
    system = load_preset(preset)
    otf = SystemOTF(system)
    top = max(_cutoffs(system.optics))
    fx = np.linspace(0.0, top, 1024)[None, :]
    fy = np.linspace(-top, top, 1024)[:, None]
    whole = otf(fx, fy, exclude=("detector",))
    chunks = np.concatenate([otf(fx, c, exclude=("detector",)) for c in np.array_split(fy, 8)])
    assert np.array_equal(whole, chunks)
    assert not otf._diffraction.radial_table and otf._diffraction._table is None
