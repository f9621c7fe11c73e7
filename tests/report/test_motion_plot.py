"""Issue 20, point 6: the run report's line-of-sight figure shows where each row crosses the near-vertical
edges against the ACT displacement the time path predicts for that row (an edge moves by minus it)."""

import math

import numpy as np
from PIL import Image

import satchain
from satchain import load_preset
from satchain.engine.timepath import time_path
from satchain.measure.auto import measure_auto
from satchain.report.motion_plot import edge_tracks, plot_line_of_sight, row_displacements
from satchain.scene import Scene, SlantedEdge

OSC = {"motion.oscillation": [{"axis": "act", "amplitude_px": 1.0, "frequency_hz": 60.0}]}


def test_the_edge_crossings_follow_the_predicted_row_displacement(tmp_path):
    system = load_preset("ankarasat3").replace(OSC)
    scene = Scene(60.0, 60.0, (SlantedEdge("e", center_m=(30.0, 30.0), size_m=50.0, measures="act"),), pixel_m=0.07)
    sim = satchain.simulate_image(scene.render(), system, pixel_m=0.07)
    summaries = measure_auto(sim.image, scene.truth(), pixel_m=system.gsd_act_m).to_dict()["slanted_edges"]
    [(ident, rows, x)] = edge_tracks(summaries)
    tp = time_path(system, sim.image.shape[0], seed=0)
    _, dx = row_displacements(tp, sim.image.shape[0])
    predicted = -(dx[rows.astype(int)] - np.polyval(np.polyfit(rows, dx[rows.astype(int)], 1), rows))
    assert ident == "e" and rows.size > 60
    assert np.ptp(predicted) > 0.2  # the oscillation really bends the edge within its rows
    assert math.sqrt(np.mean((x - predicted) ** 2)) < 0.02
    plot_line_of_sight(tp, sim.image.shape[0], tmp_path / "los.png", summaries)
    with Image.open(tmp_path / "los.png") as im:
        assert im.size == (900, 850)  # three panels


def test_edges_without_positions_or_along_track_are_not_tracked():
    rows = list(range(20))
    assert edge_tracks([{"id": "a", "direction": "ALT", "lines": rows, "edge_position_px": rows}]) == []
    assert edge_tracks([{"id": "b", "direction": "ACT", "lines": None, "edge_position_px": None}]) == []
    [(_, r, x)] = edge_tracks(
        [{"id": "c", "direction": "ACT", "lines": rows, "edge_position_px": [2 + 0.1 * v for v in rows]}]
    )
    assert np.allclose(x, 0.0, atol=1e-12) and r.size == 20  # a straight edge: nothing moved it
