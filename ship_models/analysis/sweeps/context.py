"""Shared pieces of the ship sweeps: offsets, per-process model and orbit caches, the
vessel context of checkpoints, and running a list of task keys on the sweep layer."""

from __future__ import annotations

import hashlib
import logging
import math
from collections.abc import Callable
from typing import Any

from continuation.errors import ContinuationError
from continuation.params import Params
from continuation.sweep import SweepResult, file_digest, run_sweep

log = logging.getLogger(__name__)


#: Sudden-change Fn offsets from the heteroclinic Fn: the first bisection bracket, and a
#: wider one tried when the first does not bracket the switch (as the Fig. 16-23 study).
BRACKET_OFFSETS = ((-0.004, 0.003), (-0.03, 0.01))
#: Fn offsets of the outcome map from the heteroclinic Fn (the Fig. 16 study's grid).
MAP_OFFSETS = (-0.004, -0.0015, -0.0005, 0.0005, 0.003)

_MODELS: dict[str, Any] = {}
_ORBITS: dict[str, Any] = {}


# ----------------------------------------------------------------------- vessel, model
def vessel_context(vessel: str) -> str:
    """Content hash of the vessel file behind a name or path (the tasks' context).

    Raises
    ------
    ValueError
        For an unknown vessel.
    """
    from ship_models import get_vessel_data

    data = get_vessel_data(vessel)
    path = getattr(data.vessel, "path", None)
    if path:
        return file_digest(path)
    return hashlib.sha256(repr(data.vessel).encode()).hexdigest()  # pragma: no cover


def _model(vessel: str) -> Any:
    """The 4-DOF model of a vessel, built once per process."""
    if vessel not in _MODELS:
        from ship_models import get_model

        _MODELS[vessel] = get_model(vessel)
    return _MODELS[vessel]


def _surge(vessel: str) -> Any:
    key = f"surge:{vessel}"
    if key not in _MODELS:
        from ship_models.surge import SurgeModel

        _MODELS[key] = SurgeModel(_model(vessel).data)
    return _MODELS[key]


def _params(m: Any, key: dict[str, Any], **changes: float) -> Params:
    base = m.default_params()
    wave = {k: float(key[k]) for k in ("H_over_lambda", "lambda_over_L") if k in key}
    return base.replace(**wave, **changes)


def _orbit(key: dict[str, Any]) -> Any:
    """The old periodic orbit of a sudden change, computed once per process.

    ``key["Fn_from"], key["chi_c_from_deg"]``; with ``key["follow_steps"] > 0`` it is
    followed from the (0.1, 0 deg) orbit in that many steps
    (:func:`~ship_models.analysis.sudden_change.follow_orbit`), as for Fig. 22.
    """
    from ..sudden_change import follow_orbit, periodic_orbit

    m = _model(key["vessel"])
    p_from = _params(m, key, Fn=float(key["Fn_from"]), chi_c=math.radians(key["chi_c_from_deg"]))
    steps = int(key.get("follow_steps", 0))
    tag = repr((key["vessel"], tuple(p_from.values), steps))
    if tag not in _ORBITS:
        if steps > 0:
            first = periodic_orbit(m, p_from.replace(Fn=0.1, chi_c=0.0), throw=True)
            orb = follow_orbit(first, p_from, steps=steps)
            if not orb.success:
                raise ContinuationError(f"no periodic orbit at the old controls: {orb.message}")
        else:
            orb = periodic_orbit(m, p_from, throw=True)
        _ORBITS[tag] = orb
    return _ORBITS[tag]


def _finite(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


_RUN_OPTIONS = ("store", "backend", "workers", "scheduler", "progress", "retry_failed")


def _vessel_ref(vessel: Any) -> str:
    """A vessel name as given; a vessel file as its absolute path (workers elsewhere)."""
    from pathlib import Path

    if not isinstance(vessel, str) or not vessel:
        raise ValueError(f"`vessel` must be a vessel name or a .toml path, got {vessel!r}")
    p = Path(vessel)
    return str(p.resolve()) if p.suffix == ".toml" or p.is_file() else vessel


def _run(
    task: Callable[[dict[str, Any]], dict[str, Any]],
    keys: list[dict[str, Any]],
    vessel: str,
    desc: str,
    run: dict[str, Any],
) -> SweepResult:
    """``task(key)`` for every key on :func:`continuation.sweep.run_sweep`, the vessel's
    content as the checkpoints' context; ``run`` the caller's run options (named when
    unknown)."""
    bad = set(run) - set(_RUN_OPTIONS)
    if bad:
        raise ValueError(f"unknown sweep option(s): {', '.join(sorted(bad))}")
    return run_sweep(task, keys, context=vessel_context(vessel), desc=desc, **run)


def _wave(m: Any, H_over_lambda: float | None, lambda_over_L: float | None) -> dict[str, float]:
    p = m.default_params()
    return {
        "H_over_lambda": float(p["H_over_lambda"] if H_over_lambda is None else H_over_lambda),
        "lambda_over_L": float(p["lambda_over_L"] if lambda_over_L is None else lambda_over_L),
    }
