"""A step's ``summary.json`` holds its results only; the run's clock goes beside it.

Issue 28 asks that a main job interrupted and resumed gives byte-identical results.
Wall-clock seconds and reuse counts differ on every run, so they live in
``timings.json`` (:func:`studies._common.write_summary`), and a rerun of a study on
the same inputs writes the same ``summary.json`` bytes.
"""

from __future__ import annotations

import json

from studies import fig06_09_eigen
from studies._common import RUN_KEYS, split_run_record, write_summary


def test_run_keys_are_moved_at_any_depth_and_results_kept():
    doc = {
        "Fn": 0.3,
        "seconds": 1.5,
        "bvp": {"Fn": 0.30161, "elapsed_s": 0.8, "status": "SUCCESS"},
        "sweep": {"tasks": 23, "workers": 2, "reused": 4, "wall_s": 9.0},
        "rows": [{"Fn": 0.2, "elapsed_s": 1.0}, {"Fn": 0.25}],
    }
    results, record = split_run_record(doc)
    assert results == {
        "Fn": 0.3,
        "bvp": {"Fn": 0.30161, "status": "SUCCESS"},
        "sweep": {"tasks": 23},
        "rows": [{"Fn": 0.2}, {"Fn": 0.25}],
    }
    assert record == {
        "seconds": 1.5,
        "bvp": {"elapsed_s": 0.8},
        "sweep": {"workers": 2, "reused": 4, "wall_s": 9.0},
        "rows": {"0": {"elapsed_s": 1.0}},
    }
    assert doc["seconds"] == 1.5  # the caller's summary is left whole
    assert "seconds" in RUN_KEYS


def test_write_summary_writes_both_files(tmp_path):
    path = write_summary(tmp_path, {"Fn": 0.3, "seconds": 2.0})
    assert json.loads(path.read_text()) == {"Fn": 0.3}
    assert json.loads((tmp_path / "timings.json").read_text()) == {"seconds": 2.0}


def test_a_study_rerun_writes_the_same_summary_bytes(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    fig06_09_eigen.compute(a)
    fig06_09_eigen.compute(b)
    assert (a / "summary.json").read_bytes() == (b / "summary.json").read_bytes()
    assert "seconds" in json.loads((a / "timings.json").read_text())
    assert not set(RUN_KEYS) & set(json.loads((a / "summary.json").read_text()))
