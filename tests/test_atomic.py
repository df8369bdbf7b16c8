"""Files written atomically and strict JSON (continuation.atomic)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from continuation.atomic import json_safe, write_json, write_text


def test_json_safe_replaces_non_finite_values_in_nested_numpy_data():
    """NaN and inf become null wherever they sit: plain floats, NumPy scalars, arrays
    (also 2-D) inside lists, tuples and dicts; finite values and other types pass."""
    data = {
        "a": math.nan,
        "b": np.float64(math.inf),
        "c": np.array([[1.0, np.nan], [-np.inf, 2.5]]),
        "d": (1, "x", [np.int64(3), None]),
    }
    out = json_safe(data)
    assert out == {"a": None, "b": None, "c": [[1.0, None], [None, 2.5]],
                   "d": [1, "x", [3, None]]}  # fmt: skip
    assert type(out["d"][2][0]) is int
    json.dumps(out, allow_nan=False)  # strict JSON


def test_write_json_and_text_leave_no_temporary_file(tmp_path):
    p = write_json(tmp_path / "r.json", {"v": np.array([0.5, np.nan])})
    assert json.loads(p.read_text()) == {"v": [0.5, None]}
    write_text(tmp_path / "t.txt", "one\n")
    assert sorted(f.name for f in tmp_path.iterdir()) == ["r.json", "t.txt"]


def test_a_failed_writer_keeps_the_old_file(tmp_path):
    from continuation.atomic import write_atomic

    target = tmp_path / "keep.txt"
    target.write_text("old")

    def broken(tmp):
        tmp.write_text("half")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError, match="disk full"):
        write_atomic(target, broken)
    assert target.read_text() == "old"
    assert [f.name for f in tmp_path.iterdir()] == ["keep.txt"]
