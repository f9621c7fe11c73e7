"""The edge angle's 1-sigma that the check rows carry (satchain.comparison.edge_angle_sigma_deg) against the
scatter of the angle measured on independently rendered noisy edges (tests/measure/_render.py)."""

import numpy as np
import pytest
from _render import render_edge

from satchain.comparison import edge_angle_sigma_deg
from satchain.measure.edge import measure_edge


@pytest.mark.parametrize(("shape", "angle_deg", "cnr"), [((60, 40), 8.0, 40.0)])
def test_angle_sigma_matches_the_scatter_of_noisy_edges(shape, angle_deg, cnr):
    low, high = 0.1, 0.9
    img = low + (high - low) * render_edge(shape, angle_deg, q=1.0, eps=0.0)
    rng = np.random.default_rng(7)
    angles, n_lines = [], None
    for _ in range(30):
        r = measure_edge(img + rng.normal(0.0, (high - low) / cnr, shape))
        angles.append(r.angle_deg)
        n_lines = r.n_lines
    sigma = edge_angle_sigma_deg(cnr=cnr, n_lines=n_lines, width_px=shape[1], angle_deg=angle_deg)
    # 30 draws: the sample std is within +-35 % (2.5 sigma) of the true one
    assert np.std(angles, ddof=1) == pytest.approx(sigma, rel=0.35)
    assert abs(np.mean(angles) - angle_deg) < 3 * sigma / np.sqrt(30) + 0.01  # unbiased
