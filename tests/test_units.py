"""units.py: every conversion both ways, against hand-computed values for the reference system."""

import pytest
from hypothesis import given
from hypothesis import strategies as st

from satchain import units
from satchain.errors import ConfigError

F_M, H_M, P_M = 6.804, 567e3, 5.88e-6  # AnkaraSat-3: f = 0.70 m * 9.72, 567 km, 5.88 um

pos = st.floats(min_value=1e-6, max_value=1e6, allow_nan=False, allow_infinity=False)


def test_reference_system_scales():
    # 1 cy/m on the ground is a 1 m period; in the focal plane 1 m * f/H = 12.0 um -> 83.33 cy/mm
    assert units.ground_to_focal_cy_per_mm(1.0, focal_length_m=F_M, range_m=H_M) == pytest.approx(1000 / 12.0)
    assert units.gsd_m(P_M, focal_length_m=F_M, range_m=H_M) == pytest.approx(0.49, rel=1e-12)
    assert units.nyquist_cy_per_mm(P_M) == pytest.approx(1 / (2 * 5.88e-3))
    # Nyquist in cy/px is 0.5 by definition, on the ground 1/(2 GSD)
    assert units.cy_per_mm_to_cy_per_px(units.nyquist_cy_per_mm(P_M), pitch_m=P_M) == pytest.approx(0.5)
    ny_ground = units.focal_to_ground_cy_per_m(units.nyquist_cy_per_mm(P_M), focal_length_m=F_M, range_m=H_M)
    assert ny_ground == pytest.approx(1 / (2 * 0.49))


@given(f=pos, focal=st.floats(0.01, 50), rng=st.floats(1e3, 1e8))
def test_focal_ground_round_trip(f, focal, rng):
    g = units.focal_to_ground_cy_per_m(f, focal_length_m=focal, range_m=rng)
    assert units.ground_to_focal_cy_per_mm(g, focal_length_m=focal, range_m=rng) == pytest.approx(f, rel=1e-12)


@given(f=pos, pitch=st.floats(1e-7, 1e-4))
def test_mm_px_round_trip(f, pitch):
    px = units.cy_per_mm_to_cy_per_px(f, pitch_m=pitch)
    assert units.cy_per_px_to_cy_per_mm(px, pitch_m=pitch) == pytest.approx(f, rel=1e-12)


@given(f=pos, gsd=st.floats(0.01, 100))
def test_ground_px_round_trip(f, gsd):
    px = units.cy_per_m_ground_to_cy_per_px(f, gsd_m=gsd)
    assert units.cy_per_px_to_cy_per_m_ground(px, gsd_m=gsd) == pytest.approx(f, rel=1e-12)


@given(f=pos, focal=st.floats(0.01, 50), rng=st.floats(1e3, 1e8), pitch=st.floats(1e-7, 1e-4))
def test_three_scales_commute(f, focal, rng, pitch):
    """focal cy/mm -> cy/px directly equals focal -> ground -> cy/px with the GSD of that pitch."""
    direct = units.cy_per_mm_to_cy_per_px(f, pitch_m=pitch)
    g = units.focal_to_ground_cy_per_m(f, focal_length_m=focal, range_m=rng)
    via = units.cy_per_m_ground_to_cy_per_px(g, gsd_m=units.gsd_m(pitch, focal_length_m=focal, range_m=rng))
    assert via == pytest.approx(direct, rel=1e-10)


@given(n=pos)
def test_lines_and_line_pairs(n):
    assert units.lines_to_line_pairs(units.line_pairs_to_lines(n)) == pytest.approx(n)
    assert units.line_pairs_to_lines(n) == pytest.approx(2 * n)


def test_paper_nyquist_in_lines():
    # the paper's "85.0 L/mm Nyquist" is 85 line *pairs* per mm = 170 lines/mm
    assert units.line_pairs_to_lines(units.nyquist_cy_per_mm(P_M)) == pytest.approx(170.07, abs=0.01)


def test_period_and_inches():
    assert units.period_m_to_cy_per_m(16.0) == pytest.approx(1 / 16)
    assert units.period_m_to_cy_per_m(units.period_m_to_cy_per_m(2.5)) == pytest.approx(2.5)
    assert units.m_to_inches(units.inches_to_m(20.8)) == pytest.approx(20.8)
    assert units.m_to_inches(0.49) == pytest.approx(19.2913, abs=1e-4)


@pytest.mark.parametrize(
    "call",
    [
        lambda: units.gsd_m(-1e-6, focal_length_m=1, range_m=1),
        lambda: units.focal_to_ground_cy_per_m(1.0, focal_length_m=0, range_m=1),
        lambda: units.cy_per_mm_to_cy_per_px(1.0, pitch_m=float("nan")),
        lambda: units.period_m_to_cy_per_m(0.0),
    ],
)
def test_bad_scales_raise_config_error(call):
    with pytest.raises(ConfigError, match=r"= .*must"):
        call()
