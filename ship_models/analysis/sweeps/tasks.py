"""The tasks of the ship sweeps: one independent solve per JSON key (``run_task``)."""

from __future__ import annotations

import logging
import math
from typing import Any

from continuation.errors import ContinuationError
from continuation.status import Status

from .context import _finite, _model, _orbit, _params, _surge
from .critical_line import critical_line
from .surge import SurgeThreshold, surge_threshold

log = logging.getLogger(__name__)


def _bracketed(b: Any, n_runs: int, **extra: Any) -> dict[str, Any]:
    """The record of a bracketing search ``b``: its Fn (None unless it succeeded), the
    final bracket, ``extra`` fields, the count of runs, status and message.

    Raises
    ------
    KeyboardInterrupt
        The search was interrupted (the task is not finished).
    """
    if b.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    return {
        "Fn": b.Fn if b.success else None,
        "Fn_lower": b.bracket[0],
        "Fn_upper": b.bracket[1],
        **extra,
        "n_runs": n_runs,
        "status": b.status.name,
        "message": b.message,
    }


def _boundary(key: dict[str, Any]) -> dict[str, Any]:
    from ..sudden_change import sudden_change_boundary

    m = _model(key["vessel"])
    orb = _orbit(key)
    chi = math.radians(float(key["chi_c_deg"]))
    b = None
    for lo, hi in key["Fn_brackets"]:
        b = sudden_change_boundary(
            m, None, chi, float(key["xi_0"]), (float(lo), float(hi)), float(key["tol"]),
            orbit=orb, t_max=float(key.get("t_max", 600.0)),
        )  # fmt: skip
        if b.status is not Status.NO_BRACKET:
            break
    assert b is not None
    return _bracketed(b, b.n_runs, outcome_lower=b.outcomes[0], outcome_upper=b.outcomes[1])


def _outcome(key: dict[str, Any]) -> dict[str, Any]:
    from ..sudden_change import sudden_change

    m = _model(key["vessel"])
    orb = _orbit(key)
    pt = orb.params.replace(Fn=float(key["Fn"]), chi_c=math.radians(float(key["chi_c_deg"])))
    r = sudden_change(m, None, pt, float(key["xi_0"]), orbit=orb, t_max=float(key["t_max"]))
    if r.fate.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    return {"outcome": r.outcome, "t_decided_s": _finite(r.t)}


def _line(key: dict[str, Any]) -> dict[str, Any]:
    m = _model(key["vessel"])
    line = critical_line(
        m,
        math.radians(float(key["chi_c_deg"])),
        float(key["lambda_over_L"]),
        key["H_over_lambda"],
        tol=float(key.get("tol", 1e-9)),
    )
    return line.to_json()


def _surge_line(key: dict[str, Any]) -> dict[str, Any]:
    s = _surge(key["vessel"])
    out = []
    for h in key["H_over_lambda"]:
        try:
            t = surge_threshold(s, float(h), float(key["lambda_over_L"]), tol=float(key["tol"]))
        except (ContinuationError, ValueError) as exc:
            t = SurgeThreshold(math.nan, (math.nan, math.nan), Status.UNDECIDED, str(exc))
        out.append(t)
    return {
        "H_over_lambda": [float(h) for h in key["H_over_lambda"]],
        "Fn": [_finite(t.Fn) for t in out],
        "status": [t.status.name for t in out],
        "reason": [t.message for t in out],
    }


def _bisect(key: dict[str, Any]) -> dict[str, Any]:
    from ..critical_bisection import upslope_bisection as critical_fn_bisection

    m = _model(key["vessel"])
    b = critical_fn_bisection(
        math.radians(float(key["chi_c_deg"])), model=m, params=_params(m, key),
        Fn_bracket=(float(key["Fn_bracket"][0]), float(key["Fn_bracket"][1])),
        tol=float(key["tol"]), t_max=float(key.get("t_max", 600.0)),
    )  # fmt: skip
    return _bracketed(b, b.n_evaluations)


def _threshold(key: dict[str, Any]) -> dict[str, Any]:
    """The capsizing threshold at one sea state and course, seeded by the connection's Fn."""
    from ..threshold import capsizing_threshold

    m = _model(key["vessel"])
    het = key.get("Fn_heteroclinic")
    t = capsizing_threshold(
        m, _params(m, key), chi_c=math.radians(float(key["chi_c_deg"])),
        Fn_heteroclinic=(math.nan if het is None else float(het), math.nan),
        locate_bifurcations=bool(key.get("locate_bifurcations", False)),
    )  # fmt: skip
    if t.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    return {
        "Fn": _finite(t.Fn),
        "error": _finite(t.error),
        "mechanism": t.mechanism,
        "is_heteroclinic": t.is_heteroclinic,
        "confirmed": t.confirmed,
        "status": t.status.name,
        "message": t.message,
    }


_TASKS = {
    "threshold": _threshold,
    "boundary": _boundary,
    "outcome": _outcome,
    "line": _line,
    "surge-line": _surge_line,
    "bisect": _bisect,
}


def run_task(key: dict[str, Any]) -> dict[str, Any]:
    """Run one ship task (``key["task"]``: one of ``_TASKS``: threshold, boundary, outcome,
    line, surge-line, bisect).

    The function handed to :func:`continuation.sweep.run_sweep`: module level, JSON in,
    JSON out (``None`` for values that do not exist), no timings (so the table does
    not depend on the machine's load).

    Raises
    ------
    ValueError
        For an unknown task.
    """
    fn = _TASKS.get(key.get("task"))
    if fn is None:
        raise ValueError(f"`task` must be one of {', '.join(_TASKS)}, got {key.get('task')!r}")
    return fn(key)
