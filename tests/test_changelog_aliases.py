"""Renamed JSON keys stay beside their new names until satchain 0.2 (``measure edge`` / ``measure auto``, their
``--json`` and ``-o`` files), and CHANGELOG.md lists every renamed name of :mod:`satchain._deprecate` with its
replacement, so the two stay in agreement."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.special import ndtr
from typer.testing import CliRunner

from satchain._deprecate import REMOVED_IN, RENAMED
from satchain.cli.measure import measure_app
from satchain.cli.output import renamed_json_keys
from satchain.io.images import write_npy

ROOT = Path(__file__).resolve().parents[1]
CHANGELOG = ROOT / "CHANGELOG.md"
runner = CliRunner()


@pytest.fixture(scope="module")
def edge_npy(tmp_path_factory):
    """A point-sampled Gaussian-blurred edge tilted by 5 deg (NPY: the pixel size on the command line)."""
    y, x = np.mgrid[0:64, 0:64].astype(float)
    t = np.deg2rad(5.0)
    path = tmp_path_factory.mktemp("edge") / "edge.npy"
    write_npy(path, 0.1 + 0.7 * ndtr(((x - 31.6) * np.cos(t) - (y - 31.5) * np.sin(t)) / 0.5))
    return path


def _invoke(args):
    r = runner.invoke(measure_app, args)
    assert r.exit_code == 0, r.output
    return r


def test_measure_edge_json_keeps_the_renamed_keys_beside_the_new_ones(edge_npy, tmp_path):
    printed = json.loads(_invoke(["edge", str(edge_npy), "--pixel-m", "0.5", "--json"]).stdout)
    _invoke(["edge", str(edge_npy), "--pixel-m", "0.5", "-o", str(tmp_path / "o")])
    written = json.loads((tmp_path / "o" / "edge.json").read_text())
    for d in (printed, written):
        assert d["angle_deg"] == pytest.approx(5.0, abs=0.05)
        assert d["edge_angle_deg"] == d["angle_deg"]
        assert d["mtf_at_nyquist_sigma"] > 0 and d["mtf_at_nyquist_std"] == d["mtf_at_nyquist_sigma"]
        keys = list(d)
        assert keys.index("edge_angle_deg") == keys.index("angle_deg") + 1  # right beside it


def test_measure_auto_json_keeps_the_renamed_key_in_every_edge(tmp_path):
    from satchain.scene import Scene, SlantedEdge, render_scene_to_file

    scene = Scene(20.0, 20.0, (SlantedEdge("edge", center_m=(10.0, 10.0), size_m=16.0, angle_deg=6.0),), pixel_m=0.25)
    files = render_scene_to_file(scene, tmp_path / "scene.tif")
    d = json.loads(_invoke(["auto", str(files["tiff"]), "--truth", str(files["truth"]), "--json"]).stdout)
    assert len(d["slanted_edges"]) == 1
    for e in d["slanted_edges"]:
        assert e["mtf_at_nyquist_std"] == e["mtf_at_nyquist_sigma"]


def test_the_python_dicts_keep_only_the_new_names():
    """The aliases are added where the JSON is written: ``to_dict()`` stays canonical (the old attribute warns)."""
    from satchain.cli.output import with_renamed_keys

    payload = {"angle_deg": 1.0, "mtf_at_nyquist_sigma": 0.1, "slanted_edges": [{"mtf_at_nyquist_sigma": 0.2}]}
    out = with_renamed_keys("edge", payload)
    assert out["edge_angle_deg"] == 1.0 and "edge_angle_deg" not in payload
    auto = with_renamed_keys("auto", payload)
    assert auto["slanted_edges"] == [{"mtf_at_nyquist_sigma": 0.2, "mtf_at_nyquist_std": 0.2}]
    assert payload["slanted_edges"] == [{"mtf_at_nyquist_sigma": 0.2}]
    assert with_renamed_keys("edge", {"angle_deg": 1.0, "edge_angle_deg": 2.0})["edge_angle_deg"] == 2.0


def _changelog_items() -> list[str]:
    """CHANGELOG.md's list items, each joined onto one line (an item's continuation lines are indented)."""
    items: list[str] = []
    for line in CHANGELOG.read_text(encoding="utf-8").splitlines():
        if line.startswith("- "):
            items.append(line[2:])
        elif line.startswith("  ") and items:
            items[-1] += " " + line.strip()
        else:
            items.append(line)
    return items


@pytest.mark.parametrize("owner, old, new", RENAMED)
def test_changelog_lists_every_renamed_name_with_its_replacement(owner, old, new):
    items = [it for it in _changelog_items() if f"`{owner}.{old}`" in it or f"`{owner}({old}=" in it]
    assert any(f"`{owner}.{new}`" in it or f"`{owner}({new}=" in it for it in items), (
        f"CHANGELOG.md: no item names {owner}.{old} with its replacement {new}"
    )


JSON_RENAMES = [
    (out, o, n) for out, places in renamed_json_keys().items() for r in places.values() for o, n in r.items()
]


@pytest.mark.parametrize("output, old, new", JSON_RENAMES)
def test_changelog_lists_every_renamed_json_key(output, old, new):
    items = [it for it in _changelog_items() if f"`{old}`" in it and f"`{new}`" in it and "JSON" in it]
    items = [it for it in items if f"{output}.json" in it and f"{REMOVED_IN}.0" in it]
    assert items, f"CHANGELOG.md: no item names {output}.json's {old} beside {new} until {REMOVED_IN}.0"


def test_every_warned_rename_in_the_code_is_in_the_mapping():
    """A ``warn_renamed(owner, old, new)`` in the package is one of :data:`RENAMED` (so in the changelog)."""
    calls = set()
    for path in (ROOT / "src" / "satchain").rglob("*.py"):
        if path.name == "_deprecate.py":  # its own example
            continue
        text = path.read_text(encoding="utf-8")
        calls |= set(re.findall(r'warn_renamed\(\s*"(\w+)",\s*"(\w+)",\s*"(\w+)"', text))
    assert calls and calls <= set(RENAMED)


def test_changelog_is_keep_a_changelog():
    text = CHANGELOG.read_text(encoding="utf-8")
    assert text.startswith("# Changelog")
    assert "## [Unreleased]" in text and re.search(r"^## \[0\.1\.0\]", text, re.M)
    assert "keepachangelog.com" in text
