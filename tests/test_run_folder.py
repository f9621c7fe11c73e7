"""Replacing a run folder keeps the files satchain did not write (issue 29, item 9: a rerun deleted the user's
``mynotes.txt`` without a word). manifest.json lists what satchain wrote; everything else is the user's."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from typer.testing import CliRunner

from satchain._safety import MARKER, OWNER
from satchain.cli.main import app
from satchain.errors import SatchainIOError
from satchain.io.runfolder import swap_in, written_files

ONE_EDGE_SCENE = """
[scene]
width_m = 70.0
height_m = 70.0
background = 0.2

[[items]]
kind = "slanted_edge"
id = "edge"
center_m = [35.0, 35.0]
angle_deg = 6.0
measures = "act"
"""


def _folder(path: Path, files: dict[str, str], *, listed: list[str] | None) -> Path:
    """A run folder as satchain leaves one: its marker, ``files`` and a manifest listing ``listed`` (None: a
    manifest without a list, as satchain wrote before it had one)."""
    path.mkdir()
    (path / MARKER).write_text('{"tool": "satchain", "kind": "run", "format": 1}\n')
    for rel, text in files.items():
        (path / rel).parent.mkdir(parents=True, exist_ok=True)
        (path / rel).write_text(text)
    manifest = {"satchain_version": "test"} | ({} if listed is None else {"files": listed})
    (path / "manifest.json").write_text(json.dumps(manifest))
    return path


def _tree(path: Path) -> dict[str, str]:
    return {p.relative_to(path).as_posix(): p.read_text() for p in sorted(path.rglob("*")) if p.is_file()}


OURS = {"results.json": "old results", "figures/edge.png": "old figure", "figures/gone.png": "a target since removed"}
MINE = {"mynotes.txt": "my notes", "figures/annotated.png": "my drawing", "extra/deep/data.csv": "1,2"}


def test_a_rerun_keeps_the_users_files_and_replaces_satchains(tmp_path):
    listed = [*OURS, "manifest.json", MARKER]
    out = _folder(tmp_path / "run", OURS | MINE, listed=listed)
    (out / "empty_dir_of_mine").mkdir()
    os.symlink("mynotes.txt", out / "link_to_notes")
    staging = _folder(tmp_path / ".run.staging-1", {"results.json": "new", "figures/edge.png": "new"}, listed=[])
    kept = swap_in(staging, out)
    assert set(kept) == {*MINE, "empty_dir_of_mine/", "link_to_notes"}
    tree = _tree(out)
    assert {k: tree[k] for k in MINE} == MINE  # the user's files, as they were
    assert tree["results.json"] == "new" and tree["figures/edge.png"] == "new"
    assert "figures/gone.png" not in tree  # satchain's, listed, not written again: removed
    assert (out / "empty_dir_of_mine").is_dir() and os.readlink(out / "link_to_notes") == "mynotes.txt"
    assert not staging.exists() and not list(tmp_path.glob(".run.old-*")) and not (out / OWNER).exists()


def test_the_manifest_lists_every_file_satchain_wrote(tmp_path):
    staging = _folder(tmp_path / "s", {"results.json": "r", "figures/a.png": "a"}, listed=[])
    (staging / OWNER).write_text("{}")  # the process's, removed on publishing: not a file of the run
    assert written_files(staging) == sorted([MARKER, "figures/a.png", "manifest.json", "results.json"])


def test_a_failed_swap_leaves_the_old_folder_and_the_users_files(tmp_path, monkeypatch):
    out = _folder(tmp_path / "run", OURS | MINE, listed=[*OURS])
    before = _tree(out)
    staging = _folder(tmp_path / ".run.staging-1", {"results.json": "new"}, listed=[])
    real = os.replace

    def fail_into_place(src, dst):
        if Path(src) == staging:
            raise OSError("disk gone")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", fail_into_place)
    with pytest.raises(OSError, match="disk gone"):
        swap_in(staging, out)
    assert _tree(out) == before


def test_a_users_file_where_this_run_writes_one_is_refused_unchanged(tmp_path):
    """Not listed as satchain's (the user's), at a path the new run writes: refused, nothing changed."""
    out = _folder(tmp_path / "run", OURS | {"curves/star_mtf.csv": "mine"}, listed=[*OURS])
    before = _tree(out)
    staging = _folder(tmp_path / ".run.staging-1", {"curves/star_mtf.csv": "new"}, listed=[])
    with pytest.raises(SatchainIOError, match=r"curves/star_mtf\.csv.*not listed in its manifest\.json"):
        swap_in(staging, out)
    assert _tree(out) == before


def test_a_manifest_without_a_list_keeps_all_but_the_files_this_run_writes(tmp_path):
    """A run folder from before manifest.json listed its files: a file at a path this run writes is satchain's;
    any other is kept (nothing is deleted that cannot be shown to be satchain's)."""
    out = _folder(tmp_path / "run", OURS | MINE, listed=None)
    staging = _folder(tmp_path / ".run.staging-1", {"results.json": "new", "figures/edge.png": "new"}, listed=[])
    kept = swap_in(staging, out)
    assert set(kept) == {*MINE, "figures/gone.png"}
    assert _tree(out)["results.json"] == "new" and _tree(out)["mynotes.txt"] == "my notes"


@pytest.fixture
def one_edge(tmp_path):
    (tmp_path / "scene.toml").write_text(ONE_EDGE_SCENE)
    (tmp_path / "run.toml").write_text('[scene]\nlayout = "scene.toml"\npixel_m = 0.245\n')
    return ["run", "--config", str(tmp_path / "run.toml"), "-o"]


def test_cli_rerun_keeps_mynotes_and_says_so(tmp_path, one_edge):
    out = _folder(tmp_path / "RUN2", OURS | {"mynotes.txt": "my notes"}, listed=[*OURS])
    r = CliRunner().invoke(app, [*one_edge, str(out)])
    assert r.exit_code == 0, r.output
    assert (out / "mynotes.txt").read_text() == "my notes" and not (out / "figures" / "gone.png").exists()
    assert "kept 1 file satchain did not write" in r.stdout and "mynotes.txt" in r.stdout
    manifest = json.loads((out / "manifest.json").read_text())
    assert "report.html" in manifest["files"] and "mynotes.txt" not in manifest["files"]


def test_cli_refuses_a_folder_that_is_not_a_run_folder(tmp_path, one_edge):
    mine = tmp_path / "thesis"
    mine.mkdir()
    (mine / "chapter1.tex").write_text("precious")
    (mine / "manifest.json").write_text("{}")  # a manifest of something else is no licence
    r = CliRunner().invoke(app, [*one_edge, str(mine)])
    assert r.exit_code == 2 and "not a satchain run directory" in r.stderr
    assert sorted(p.name for p in mine.iterdir()) == ["chapter1.tex", "manifest.json"]
    assert (mine / "chapter1.tex").read_text() == "precious"
