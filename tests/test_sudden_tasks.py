"""The sudden-change study's sweep tasks give the serial run's numbers exactly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from continuation.sweep import run_sweep
from ship_models import purse_seiner
from ship_models.analysis.sudden_change import (
    periodic_orbit,
    sudden_change_boundary,
    sudden_change_map,
)
from studies import _sudden_tasks as st


def test_the_worker_count_is_read_from_the_environment_once_at_the_cli(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from broachkit_cli.options import WORKERS_ENV, check_workers
    from continuation.sweep import MAX_WORKERS

    monkeypatch.setenv(WORKERS_ENV, "3")
    assert check_workers(None) == 3
    assert check_workers(2) == 2  # the option wins over the environment
    for bad in ("0", "x", str(MAX_WORKERS + 1)):
        monkeypatch.setenv(WORKERS_ENV, bad)
        with pytest.raises(ValueError, match=WORKERS_ENV):
            check_workers(None)
    monkeypatch.delenv(WORKERS_ENV)
    assert 1 <= check_workers(None) <= MAX_WORKERS
    with pytest.raises(ValueError, match=f"--workers must be at most {MAX_WORKERS}"):
        check_workers(100000)


@pytest.mark.slow
def test_tasks_on_two_workers_equal_the_serial_calls(tmp_path) -> None:
    """Bisection and map row on 2 worker processes == the same calls in this process."""
    path = str(tmp_path / "orbits.pkl")
    info = st.compute_orbits(path, (0.1, 0.0), None)
    model = purse_seiner()
    base = model.default_params()
    orb = periodic_orbit(model, base.replace(Fn=0.1, chi_c=0.0), throw=True)  # independent
    assert info["digest"] == st.orbit_digest({"from_1": orb})
    chi = math.radians(10.0)
    bracket = (0.300, 0.306)
    xi = [0.0, 0.5]
    common = {"orbits": path, "orbit": "from_1", "chi_c": chi, "tol": 2e-3}
    keys = [
        {"task": "boundary", "xi_0": 0.5, "Fn_brackets": [list(bracket)], **common},
        {"task": "row", "Fn": 0.305, "xi_0": xi, **common},
    ]
    res = run_sweep(st.task, keys, backend="processes", workers=2, progress=False)
    assert res.success
    by_task = {r.key["task"]: r.value for r in res.records}

    b = sudden_change_boundary(model, None, chi, 0.5, bracket, 2e-3, orbit=orb).to_json()
    got = dict(by_task["boundary"])
    got.pop("elapsed_s"), b.pop("elapsed_s")
    ends = got.pop("end_runs")
    assert got == b
    assert b["n_runs"] >= 3  # a real bisection, not a trivial bracket failure
    # its first runs at the bracket's ends are the map's cells there (the study takes
    # the map's end rows from them): the same outcome and time, bit for bit
    assert [e[0] for e in ends] == list(bracket)
    for fn, out, t in ends:
        cell = sudden_change_map(model, None, chi, [0.5], [fn], orbit=orb)
        assert out == str(cell.outcomes[0, 0]) and t == float(cell.times[0, 0])

    mp = sudden_change_map(model, None, chi, xi, [0.305], orbit=orb)
    assert by_task["row"]["outcomes"] == [str(v) for v in mp.outcomes[0]]
    assert np.array_equal(
        np.array([np.nan if t is None else t for t in by_task["row"]["times"]]),
        mp.times[0],
        equal_nan=True,
    )
