r"""The exact surf-riding threshold over the Level 2 wave cases on the sweep engine.

:func:`exact_threshold_sweep` computes what
:func:`~ship_models.assessment.exact.exact_threshold_grid` computes in one process, as
tasks (:func:`run_block`, named ``"surf-riding-block"`` in the sweep's records) run
by :func:`continuation.sweep.run_sweep`: on local
processes, a Dask ``LocalCluster`` or a running Dask scheduler, checkpointed and
resumable, without a change.

One task is a block of ``columns_per_task`` consecutive wavelengths ``lambda_i / L``
over every steepness ``s_j``, and inside the block the grid is continued exactly as in
:func:`~ship_models.assessment.exact.exact_threshold_grid` (which each task calls): one
connection from the manifold's fate at the block's middle wavelength and the middle
steepness, natural-parameter steps across the block's wavelengths, pseudo-arclength
continuation in ``H / lambda`` along each column. So each block costs one cold start
(a bisection of the manifold's fate, about 0.5 s) and the rest is continuation.

The two paths differ only in where each column's continuation starts (the neighbour
in the block instead of the neighbour in the whole grid), so the branch rows differ and
the spline through them differs within its error estimate (``ExactGrid.error``);
``tests/test_assessment_sweep.py`` compares them cell by cell against that estimate.
A block's value depends only on its key (vessel file content, wavelengths,
steepnesses, step), so the table is the same on every backend.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from continuation.typing import FloatArray

from .exact import ExactGrid

#: Name of the task in the sweep's keys and records.
TASK = "surf-riding-block"
#: Default wavelengths per task: 8 tasks on the standard's 80 wavelengths, so that two
#: workers share them evenly and one cold start serves 10 columns.
COLUMNS_PER_TASK = 10


def _none_nan(rows: Any) -> list[Any]:
    """Nested lists of floats with NaN as ``None`` (the sweep's JSON has no NaN)."""
    a = np.asarray(rows, dtype=float)
    return [[float(v) if math.isfinite(v) else None for v in r] for r in a]


def _nan_none(rows: list[list[Any]]) -> FloatArray:
    return np.array([[math.nan if v is None else float(v) for v in r] for r in rows], dtype=float)


def run_block(key: dict[str, Any]) -> dict[str, Any]:
    """The task: the exact threshold on one block of wavelengths (JSON in, JSON out).

    ``key``: ``vessel`` (name or absolute path), ``lambda_over_L`` (the block's
    wavelengths), ``H_over_lambda`` (every steepness, increasing), ``ds_max`` (largest
    continuation step). Returns ``Fn_cr`` and ``error`` (rows per wavelength, ``None``
    where missing), ``column_status`` and ``steps``; no timings (the table must not
    depend on the machine's load).
    """
    from ship_models.analysis.sweeps.context import _surge

    from .exact import exact_threshold_grid

    model = _surge(key["vessel"])
    lam = np.asarray(key["lambda_over_L"], dtype=float)
    s = np.asarray(key["H_over_lambda"], dtype=float)
    try:
        g = exact_threshold_grid(model, lam, s, ds_max=float(key["ds_max"]))
    except ValueError as exc:  # no start anywhere in the block: say so per column
        nan = np.full((lam.size, s.size), math.nan)
        return {
            "Fn_cr": _none_nan(nan),
            "error": _none_nan(nan),
            "column_status": [f"no start: {exc}"] * lam.size,
            "steps": 0,
        }
    if any(st == "interrupted" for st in g.column_status):
        raise KeyboardInterrupt  # an interrupted block is not a result to checkpoint
    return {
        "Fn_cr": _none_nan(g.Fn_cr),
        "error": _none_nan(g.error),
        "column_status": list(g.column_status),
        "steps": int(g.steps),
    }


def block_keys(
    vessel: str,
    lambda_over_L: FloatArray,
    steepness: FloatArray,
    *,
    columns_per_task: int = COLUMNS_PER_TASK,
    ds_max: float | None = None,
) -> list[dict[str, Any]]:
    """The sweep's task keys: consecutive blocks of ``columns_per_task`` wavelengths.

    ``ds_max`` defaults to that of :func:`~ship_models.assessment.exact.exact_threshold_grid`
    on the whole grid (1/8 of the steepness range), so both paths take the same steps.
    """
    lam = [float(v) for v in np.asarray(lambda_over_L, dtype=float)]
    s = [float(v) for v in np.asarray(steepness, dtype=float)]
    ds = (s[-1] - s[0]) / 8.0 if ds_max is None else float(ds_max)
    n = int(columns_per_task)
    return [
        {
            "task": TASK,
            "vessel": vessel,
            "first_column": i,
            "lambda_over_L": lam[i : i + n],
            "H_over_lambda": s,
            "ds_max": ds,
        }
        for i in range(0, len(lam), n)
    ]


def exact_threshold_sweep(
    vessel: str | Path,
    lambda_over_L: FloatArray,
    steepness: FloatArray,
    *,
    columns_per_task: int = COLUMNS_PER_TASK,
    ds_max: float | None = None,
    **run: Any,
) -> ExactGrid:
    """The exact threshold over the grid as sweep tasks (module doc).

    Parameters
    ----------
    vessel : str or Path
        A registered vessel name or a vessel file (sent to the workers as its absolute
        path; the file's content is the checkpoints' context).
    lambda_over_L : array_like, shape (n_lambda,)
    steepness : array_like, shape (n_s,)
        Increasing.
    columns_per_task : int
        Wavelengths per task (default :data:`COLUMNS_PER_TASK`).
    ds_max : float, optional
        Largest continuation step (default 1/8 of the steepness range, as
        :func:`~ship_models.assessment.exact.exact_threshold_grid`).
    **run
        Where and how to run: ``backend`` (``"processes"``, ``"dask"``, ``"serial"``),
        ``workers``, ``scheduler``, ``store`` (checkpoint folder), ``progress``,
        ``retry_failed`` (:func:`continuation.sweep.run_sweep`).

    Returns
    -------
    ExactGrid
        ``engine`` names the backend and the task count. Columns of a failed task are
        NaN with status ``"task failed: ..."``; after Ctrl-C the blocks not finished
        are NaN with status ``"interrupted"`` (running the same sweep with the same
        ``store`` resumes).

    Raises
    ------
    ValueError
        Bad grid, ``columns_per_task``, vessel or run option (named).
    """
    from ship_models.analysis.sweeps.context import _run, _vessel_ref

    t0 = time.perf_counter()
    lam = np.atleast_1d(np.asarray(lambda_over_L, dtype=float))
    s = np.atleast_1d(np.asarray(steepness, dtype=float))
    if lam.size == 0 or not np.all(np.isfinite(lam)) or np.any(lam <= 0):
        raise ValueError("`lambda_over_L` must be positive numbers")
    if s.size < 2 or not np.all(np.isfinite(s)) or np.any(np.diff(s) <= 0):
        raise ValueError("`steepness` must be increasing with at least 2 values")
    if isinstance(columns_per_task, bool) or not isinstance(columns_per_task, int):
        raise ValueError(f"`columns_per_task` must be an integer, got {columns_per_task!r}")
    if columns_per_task < 1:
        raise ValueError(f"`columns_per_task` must be at least 1, got {columns_per_task}")
    ref = _vessel_ref(str(vessel) if isinstance(vessel, Path) else vessel)
    keys = block_keys(ref, lam, s, columns_per_task=columns_per_task, ds_max=ds_max)
    res = _run(run_block, keys, ref, "exact surf-riding threshold", run)
    Fn = np.full((lam.size, s.size), math.nan)
    err = np.full_like(Fn, math.nan)
    status = ["interrupted"] * lam.size
    steps = 0
    for rec in res.records:
        i0, n = int(rec.key["first_column"]), len(rec.key["lambda_over_L"])
        if not rec.done:
            why = rec.errors[-1] if rec.errors else "no value"
            status[i0 : i0 + n] = [f"task failed: {why}"] * n
            continue
        v = rec.value
        Fn[i0 : i0 + n] = _nan_none(v["Fn_cr"])
        err[i0 : i0 + n] = _nan_none(v["error"])
        status[i0 : i0 + n] = list(v["column_status"])
        steps += int(v["steps"])
    tasks = f"{len(keys)} task{'s' if len(keys) != 1 else ''}"
    engine = f"sweep ({res.backend}, {tasks} of {columns_per_task} wavelengths)"
    return ExactGrid(lam, s, Fn, err, status, steps, time.perf_counter() - t0, engine)


__all__ = ["COLUMNS_PER_TASK", "TASK", "block_keys", "exact_threshold_sweep", "run_block"]
