"""Issue 21, point 3: figures of plain data drawn by helper processes give the same files as drawn here, a
helper's failure is reported (not a half-written run), and SATCHAIN_FIGURE_PROCESSES is validated."""

import numpy as np
import pytest

from satchain import load_preset
from satchain.engine.timepath import time_path
from satchain.errors import ConfigError, SatchainError
from satchain.report._jobs import FigureJobs, figure_processes
from satchain.report.motion_plot import plot_line_of_sight


def _path():
    system = load_preset("ankarasat3").replace({"motion.oscillation": [{"axis": "act", "amplitude_px": 0.5,
                                                                         "frequency_hz": 40.0}]})  # fmt: skip
    return time_path(system, 60, seed=3)


def test_a_helper_draws_the_same_figure_as_this_process(tmp_path):
    tp = _path()
    with FigureJobs(0) as here:
        here.submit(plot_line_of_sight, tp, 60, tmp_path / "a.png")
    with FigureJobs(1) as helper:
        helper.submit(plot_line_of_sight, tp, 60, tmp_path / "b.png")
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()


def test_a_failing_figure_is_reported_with_its_error(tmp_path):
    for n in (0, 1):  # drawn here or by the helper (whichever takes it first): the same error
        with pytest.raises(SatchainError, match="figure could not be drawn: AttributeError"):
            with FigureJobs(n) as jobs:
                jobs.submit(plot_line_of_sight, None, 60, tmp_path / "c.png")
    assert not (tmp_path / "c.png").exists()


def test_an_error_in_the_caller_kills_the_helpers(tmp_path):
    with pytest.raises(RuntimeError, match="caller"):
        with FigureJobs(1) as jobs:
            jobs.submit(plot_line_of_sight, _path(), 60, tmp_path / "d.png")
            jobs.start()
            raise RuntimeError("caller failed")
    assert jobs._procs == []


def test_the_process_count_is_validated(monkeypatch):
    monkeypatch.setenv("SATCHAIN_FIGURE_PROCESSES", "two")
    with pytest.raises(ConfigError, match="SATCHAIN_FIGURE_PROCESSES = 'two'"):
        figure_processes()
    monkeypatch.setenv("SATCHAIN_FIGURE_PROCESSES", "2")
    assert figure_processes() == 2


def test_return_values_come_back_from_the_helper_and_from_here():
    from satchain.report.gallery import item_thumbnail
    from satchain.scene import Scene, SlantedEdge

    scene = Scene(20.0, 20.0, (SlantedEdge("e", center_m=(10.0, 10.0), size_m=16.0),), pixel_m=0.25)
    fp, det = np.full((10, 10), 0.3), np.full((4, 4), 0.5)
    args = (scene, {"id": "e", "kind": "slanted_edge"}, (2.0, 2.0, 18.0, 18.0), 0.25, fp, 1.0, det, 4.0)
    got = []
    for n in (0, 1):
        with FigureJobs(n) as jobs:
            i = jobs.submit(item_thumbnail, *args)
        got.append(jobs.result(i))
    assert got[0] == got[1] and [p["title"] for p in got[0]["panels"]] == ["ground truth", "focal plane", "detector"]
    assert got[0]["panels"][0]["width"] == 64  # 16 m at 0.25 m


def test_a_helper_that_dies_at_start_leaves_its_calls_to_this_process(tmp_path, monkeypatch):
    """A helper that cannot import (here: a module that does not exist) dies before drawing: the run's own
    process draws every call and the run goes on."""
    tp = _path()
    jobs = FigureJobs(1)
    jobs.launch(("satchain.no_such_module",))
    with jobs:
        jobs.submit(plot_line_of_sight, tp, 60, tmp_path / "e.png")
    assert (tmp_path / "e.png").is_file()


def test_calls_submitted_after_start_go_to_the_waiting_helper():
    """A run hands figures to its helpers while it still computes: a call submitted after start() is taken by
    the (idle, waiting) helper before this process waits, and its value comes back."""
    import os
    import time

    jobs = FigureJobs(1)
    jobs.launch()
    jobs.start()
    with jobs:
        time.sleep(0.2)  # the helper is idle, waiting for calls
        i = jobs.submit(os.getpid)
        deadline = time.monotonic() + 60
        while i not in jobs._results and time.monotonic() < deadline:
            time.sleep(0.02)
        assert i in jobs._results  # drawn before wait(): by the helper
        j = jobs.submit(os.getpid)
    assert jobs.result(i) != os.getpid() and jobs.result(j) is not None
