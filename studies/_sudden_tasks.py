"""Worker tasks of the sudden-change study (Figs. 16-23), run by :mod:`continuation.sweep`.

The study's independent pieces -- one bisection per initial position (Figs. 16, 22)
and per course (Fig. 23 squares), one row of an outcome map per Froude number -- are
tasks of :func:`continuation.sweep.run_sweep` on local worker processes (one per core
by default; the count is the study's ``workers`` argument), checkpointed under the
step's output folder.

The old periodic orbits are computed once (:func:`compute_orbits`, in a worker while
the parent solves the connecting orbit) and handed to the tasks as a pickle file; a
task's result depends only on its key and those orbits, so the tables are identical
to a serial run (the same calls on the same numbers).

- :func:`compute_orbits` -- the (0.1, 0 deg) and (0.3, 45 deg) orbits, pickled; their digest.
- :func:`orbit_digest` -- a digest of the orbits' numbers (the sweep's ``context``).
- :func:`task` -- one task (``key["task"]``: ``"row"`` or ``"boundary"``).
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import pickle
from pathlib import Path
from typing import Any

import numpy as np

from continuation.atomic import write_atomic
from studies._model import default_model

_LOADED: dict[str, dict[str, Any]] = {}


def orbit_digest(orbits: dict[str, Any]) -> str:
    """sha256 of the orbits' section states, periods and parameters (run-independent)."""
    h = hashlib.sha256()
    for name in sorted(orbits):
        o = orbits[name]
        h.update(name.encode())
        h.update(np.ascontiguousarray(o.x_section, dtype=float).tobytes())
        h.update(np.float64(o.period).tobytes())
        h.update(np.asarray(o.params.values, dtype=float).tobytes())
    return h.hexdigest()


def compute_orbits(
    path: str, from_1: tuple[float, float], from_2: tuple[float, float] | None, steps: int = 3
) -> dict[str, Any]:
    """The old periodic orbits of the study, pickled to ``path``.

    ``from_1`` from a calm-water start; ``from_2`` by following it in ``steps`` steps
    (:func:`~ship_models.analysis.sudden_change.follow_orbit`); also the message of the
    calm-water attempt at ``from_2``. Both are ``(Fn, chi_c_deg)``; without ``from_2``
    only the first orbit (``"from_1"``) is computed.

    Returns
    -------
    dict
        ``{"digest": orbit_digest, "direct_2_message": str}``.

    Raises
    ------
    RuntimeError
        If the followed orbit does not converge.
    """
    from ship_models.analysis.sudden_change import follow_orbit, periodic_orbit

    model = default_model()  # one per process (shared by the steps it runs)
    base = model.default_params()
    p1 = base.replace(Fn=from_1[0], chi_c=math.radians(from_1[1]))
    orbits = {"from_1": periodic_orbit(model, p1, throw=True)}
    message = ""
    if from_2 is not None:
        p2 = base.replace(Fn=from_2[0], chi_c=math.radians(from_2[1]))
        message = periodic_orbit(model, p2).message
        orb2 = follow_orbit(orbits["from_1"], p2, steps=steps)
        if not orb2.success:
            raise RuntimeError(f"no periodic orbit at {from_2}: {orb2.message}")
        orbits["from_2"] = orb2
    data = pickle.dumps(orbits, protocol=pickle.HIGHEST_PROTOCOL)
    write_atomic(Path(path), lambda p: Path(p).write_bytes(data))
    _LOADED.pop(str(Path(path).resolve()), None)
    return {"digest": orbit_digest(orbits), "direct_2_message": message}


def load_orbits(path: str) -> dict[str, Any]:
    """The pickled orbits of :func:`compute_orbits` (read once per process).

    An orbit of the default vessel is given this process's shared model
    (:func:`studies._model.default_model`, the same vessel, class and options) instead of
    the copy unpickled with it, so that the tasks and the other steps this process runs
    share one model and its solvers' setup.
    """
    key = str(Path(path).resolve())
    if key not in _LOADED:
        orbits = pickle.loads(Path(key).read_bytes())
        shared = default_model()
        for name, o in orbits.items():
            m = o.system
            if (type(m) is type(shared) and m.options == shared.options
                    and m.vessel == shared.vessel):  # fmt: skip
                orbits[name] = dataclasses.replace(o, system=shared)
        _LOADED[key] = orbits
    return _LOADED[key]


def _none_if_nan(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


def task(key: dict[str, Any]) -> dict[str, Any]:
    """One task of the study's sweep.

    ``key["task"] == "row"``: the outcomes of one row of an outcome map
    (:func:`~ship_models.analysis.sudden_change.sudden_change_map` at ``key["Fn"]``
    over ``key["xi_0"]``); ``"boundary"``: the bisection
    :func:`~ship_models.analysis.sudden_change.sudden_change_boundary` at
    ``key["xi_0"]``, trying the brackets ``key["Fn_brackets"]`` in turn until one
    brackets a change; its ``"end_runs"`` are the first runs at that bracket's ends
    (``[Fn, outcome, t]``), the map's cells at those ``Fn`` and this position. Both
    from the orbit ``key["orbit"]`` of the pickle ``key["orbits"]``, to the new course
    ``key["chi_c"]`` (rad).

    Raises
    ------
    ValueError
        For an unknown task.
    KeyboardInterrupt
        If a run was interrupted (so that no partial result is checkpointed).
    """
    from continuation import Status
    from ship_models.analysis.sudden_change import sudden_change_boundary, sudden_change_map

    orb = load_orbits(key["orbits"])[key["orbit"]]
    model = orb.system
    chi = float(key["chi_c"])
    if key["task"] == "row":
        mp = sudden_change_map(
            model, None, chi, [float(v) for v in key["xi_0"]], [float(key["Fn"])], orbit=orb
        )
        if mp.status is Status.INTERRUPTED:
            raise KeyboardInterrupt
        return {
            "outcomes": [str(v) for v in mp.outcomes[0]],
            "times": [_none_if_nan(float(v)) for v in mp.times[0]],
            "elapsed_s": mp.elapsed,
        }
    if key["task"] == "boundary":
        b = None
        for lo, hi in key["Fn_brackets"]:
            b = sudden_change_boundary(
                model, None, chi, float(key["xi_0"]), (float(lo), float(hi)), float(key["tol"]),
                orbit=orb,
            )  # fmt: skip
            if b.status is not Status.NO_BRACKET:
                break
        assert b is not None
        if b.status is Status.INTERRUPTED:
            raise KeyboardInterrupt
        # the first runs at the bracket's ends: cells of the outcome map (end rows)
        ends = [[fn, out, _none_if_nan(t)] for fn, out, t in b.end_runs]
        return {**b.to_json(), "end_runs": ends}
    raise ValueError(f"`task` must be 'row' or 'boundary', got {key['task']!r}")


__all__ = [
    "compute_orbits",
    "load_orbits",
    "orbit_digest",
    "task",
]
