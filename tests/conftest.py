"""Shared test fixtures."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import settings

# CI runs the same (derandomised) hypothesis examples every time; locally they vary from run to run
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

# Runs draw their figures in their own process: the suite's xdist workers already keep every core busy, and a
# figure helper process per run (satchain.report._jobs) costs more CPU to start than it saves. The helpers' path is
# tested on its own (tests/report/test_jobs.py) and end to end by the module fixture of tests/test_pipeline.py.
os.environ.setdefault("SATCHAIN_FIGURE_PROCESSES", "0")

REPO = Path(__file__).resolve().parents[1]
SHARED_TABLE1 = REPO.parent / "shared" / "reference" / "table1.csv"


@pytest.fixture(scope="session")
def ankarasat3():
    from satchain import load_preset

    return load_preset("ankarasat3")


@pytest.fixture(scope="session")
def table1_path():
    """The shared reference Table 1 when the checkout sits beside shared/, else None (packaged copy)."""
    return SHARED_TABLE1 if SHARED_TABLE1.exists() else None


#: A reduced scene (two edges, a star, a wedge) that end-to-end tests run in a few seconds.
REDUCED_SCENE_TOML = """
[scene]
width_m = 170.0
height_m = 140.0
background = 0.2
pixel_m = 0.07

[[items]]
kind = "slanted_edge"
id = "edge_act"
center_m = [35.0, 35.0]
angle_deg = 6.0
measures = "act"

[[items]]
kind = "slanted_edge"
id = "edge_alt"
center_m = [35.0, 102.0]
angle_deg = 7.0
measures = "alt"

[[items]]
kind = "siemens_star"
id = "star"
center_m = [100.0, 35.0]
radius_m = 22.0
cycles = 32

[[items]]
kind = "hyperbolic_wedge"
id = "wedge_h"
origin_m = [75.0, 90.0]
orientation = "horizontal"
"""


@pytest.fixture(scope="session")
def reduced_scene_toml():
    """The reduced end-to-end scene (TOML text); see :data:`REDUCED_SCENE_TOML`."""
    return REDUCED_SCENE_TOML


#: A one-edge scene (an ACT edge on 60 m x 60 m): a whole run in about a second.
TINY_SCENE_TOML = """
[scene]
width_m = 60.0
height_m = 60.0
background = 0.2
pixel_m = 0.07

[[items]]
kind = "slanted_edge"
id = "edge_act"
center_m = [30.0, 30.0]
angle_deg = 6.0
measures = "act"
"""

#: A system file with only the required keys.
MINIMAL_SYSTEM_TOML = """name = "minimal"

[orbit]
altitude_m = 500000.0

[optics]
aperture_diameter_m = 0.5
f_number = 10.0
wavelengths_m = [6e-7]

[detector]
pitch_m = 5e-6
"""


@pytest.fixture(scope="session")
def tiny_scene_toml():
    """The one-edge scene (TOML text); see :data:`TINY_SCENE_TOML`."""
    return TINY_SCENE_TOML


@pytest.fixture(scope="session")
def minimal_system_toml():
    """A system file with only the required keys (TOML text); see :data:`MINIMAL_SYSTEM_TOML`."""
    return MINIMAL_SYSTEM_TOML
