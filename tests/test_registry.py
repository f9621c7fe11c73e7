"""One registry of target kinds per layer: scene (ITEM_KINDS, the item classes' ``kind``), truth (typed records),
measure (``MEASURERS``: kind -> result key, measuring function) and report (``REPORT_KINDS``: key, words, colour,
overlay, figure).  Every scene kind has its entry in each layer, and a new kind is one entry per layer: a fake
kind registered in one place is dispatched with no other change."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from satchain.measure.auto import MEASURERS, OBJECT_KINDS, Measurer, measure_auto
from satchain.measure.auto._common import AutoItem
from satchain.report import measure_plots, tables
from satchain.report.kinds import REPORT_KINDS, RESULT_KEYS, ReportKind, measured_entries, overlay_svg
from satchain.scene import ITEM_KINDS, TARGET_KINDS
from satchain.scene.truth import _KINDS as TRUTH_KINDS

SRC = Path(__file__).resolve().parents[1] / "src" / "satchain"


def test_every_scene_kind_has_an_entry_in_each_layer():
    assert set(TARGET_KINDS) | set(OBJECT_KINDS) == set(ITEM_KINDS)
    assert not set(TARGET_KINDS) & set(OBJECT_KINDS)
    assert set(MEASURERS) == set(TARGET_KINDS) == set(REPORT_KINDS) == set(TRUTH_KINDS)
    for kind, cls in ITEM_KINDS.items():
        assert cls.kind == kind
    for kind, m in MEASURERS.items():
        assert m.kind == kind and REPORT_KINDS[kind].key == m.key
    keys = [m.key for m in MEASURERS.values()]
    assert len(set(keys)) == len(keys) and tuple(keys) == RESULT_KEYS
    for e in REPORT_KINDS.values():  # every kind's figure exists and takes the common signature
        assert callable(getattr(measure_plots, e.plot_name))


def _fake_item(ctx, it):
    v = float(np.mean(ctx.refl))
    return AutoItem(str(it["id"]), "fake_kind", None, {"id": it["id"], "mean": v, "flags": ["fake flag"]}), []


def test_a_new_measure_kind_is_one_entry(monkeypatch):
    monkeypatch.setitem(MEASURERS, "fake_kind", Measurer("fake_kind", "fakes", _fake_item))
    truth = {"background": 0.2, "items": [{"kind": "fake_kind", "id": "f1", "bbox_m": [0, 0, 1, 1]}]}
    res = measure_auto(np.full((20, 20), 0.2), truth, pixel_m=1.0)
    d = res.to_dict()
    assert [x["id"] for x in d["fakes"]] == ["f1"] and res.by_kind("fake_kind")[0].id == "f1"
    assert d["fakes"][0]["mean"] == pytest.approx(0.2) and not d["skipped"]


def test_an_unregistered_kind_is_skipped_with_a_reason():
    truth = {"items": [{"kind": "fake_kind", "id": "f1"}, {"kind": "car", "id": "c1"}]}
    d = measure_auto(np.zeros((10, 10)), truth, pixel_m=1.0).to_dict()
    why = {s["id"]: s["reason"] for s in d["skipped"]}
    assert "unknown kind 'fake_kind'" in why["f1"] and "real-world object" in why["c1"]


def test_a_new_report_kind_is_one_entry(monkeypatch, tmp_path):
    drawn = []

    def overlay(it, m, view):
        return [f'<circle r="{view.size:.3f}" data-id="{it["id"]}"/>']

    def plot_fake(result, path, *, title="", pixel_m=None):
        drawn.append((result, title, pixel_m))

    monkeypatch.setattr(measure_plots, "plot_fake", plot_fake, raising=False)
    fake = ReportKind("fake_kind", "fakes", "fake target", "tab:purple", overlay, "plot_fake")
    monkeypatch.setitem(REPORT_KINDS, "fake_kind", fake)
    it = {"kind": "fake_kind", "id": "f1", "bbox_m": [0, 0, 10, 10]}
    svg = overlay_svg(it, {"id": "f1"}, (0, 0, 10, 10), gsd_m=0.5, display_px=120.0)
    assert 'data-id="f1"' in svg and svg.startswith("<svg")
    res = {"fakes": [{"id": "f1", "flags": ["fake flag"]}]}
    assert [(e.kind, x["id"]) for e, x in measured_entries(res)] == [("fake_kind", "f1")]
    assert tables.measurement_flags(res)["f1"] == ["fake flag"]
    REPORT_KINDS["fake_kind"].plot("R", tmp_path / "x.png", title="f1", pixel_m=0.5)
    assert drawn == [("R", "f1", 0.5)]


def test_kind_names_live_in_the_registries_only():
    """The kind and result-key strings appear as literals only where they are defined: the item classes, the
    registries (the result keys: measure/_keys.py, which MEASURERS and the report's registry read)."""
    names = {m.kind for m in MEASURERS.values()} | {m.key for m in MEASURERS.values()}
    allowed = {"scene/targets.py", "scene/layout.py", "measure/auto.py", "measure/_keys.py"}
    found = []
    for p in SRC.rglob("*.py"):
        rel = p.relative_to(SRC).as_posix()
        if rel in allowed:
            continue
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and node.value in names:
                found.append(f"{rel}:{node.lineno} {node.value!r}")
    assert not found, "use the registries' constants: " + ", ".join(found)
