"""Duplicate result field names are retired with a versioned warning: the old name still reads the same value
for one minor version and says which version removes it; ``to_dict()`` carries the canonical name only (the
command line's JSON outputs write the former key beside it until then: tests/test_changelog_aliases.py)."""

from __future__ import annotations

import json
import re
import warnings

import numpy as np
import pytest

from satchain.errors import SatchainDeprecationWarning
from satchain.measure import measure_edge


@pytest.fixture(scope="module")
def edge():
    """A 5 deg slanted edge with a Gaussian blur, averaged exactly over each pixel (erf of the distance)."""
    from scipy.special import erf

    y, x = np.mgrid[0:60, 0:60].astype(float)
    t = np.deg2rad(5.0)
    d = (x - 30.0) * np.cos(t) - (y - 30.0) * np.sin(t)
    return measure_edge(0.1 + 0.6 * 0.5 * (1 + erf(d / (1.2 * np.sqrt(2)))))


@pytest.mark.parametrize("old, new", [("mtf_at_nyquist_std", "mtf_at_nyquist_sigma"), ("edge_angle_deg", "angle_deg")])
def test_old_name_warns_with_versions_and_reads_the_canonical_value(edge, old, new):
    with pytest.warns(SatchainDeprecationWarning) as rec:
        value = getattr(edge, old)
    assert value == getattr(edge, new)
    msg = str(rec[0].message)
    assert f"EdgeResult.{old}" in msg and f"EdgeResult.{new}" in msg
    assert re.search(r"deprecated in satchain \d+\.\d+ and will be removed in \d+\.\d+", msg)
    assert issubclass(SatchainDeprecationWarning, DeprecationWarning)
    assert rec[0].filename == __file__  # points at the caller, not at satchain


def test_canonical_names_do_not_warn_and_json_has_no_duplicates(edge):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = json.loads(json.dumps(edge.to_dict(), allow_nan=False))
        assert edge.mtf_at_nyquist_sigma > 0 and edge.angle_deg == pytest.approx(5.0, abs=0.1)
    assert "mtf_at_nyquist_std" not in d and "edge_angle_deg" not in d
    assert d["mtf_at_nyquist_sigma"] == pytest.approx(edge.mtf_at_nyquist_sigma)


def test_retired_parameter_name_warns_and_means_the_same(edge):
    """``measure_edge(saturation_level=...)`` is ``full_scale`` under its former name: it warns, naming the
    versions, and gives the same result."""
    from scipy.special import erf

    y, x = np.mgrid[0:60, 0:60].astype(float)
    d = (x - 30.0) * np.cos(np.deg2rad(5.0)) - (y - 30.0) * np.sin(np.deg2rad(5.0))
    img = np.floor(500 + 3000 * 0.5 * (1 + erf(d / (1.2 * np.sqrt(2)))))
    img[40, 50:53] = 4095
    with pytest.warns(SatchainDeprecationWarning, match=r"saturation_level is deprecated in satchain 0\.1"):
        old = measure_edge(img, saturation_level=4095)
    new = measure_edge(img, full_scale=4095)
    assert old.flags == new.flags and "clipping" in new.flags
    assert old.mtf_at_nyquist == new.mtf_at_nyquist
