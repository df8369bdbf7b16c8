r"""The capsizing threshold against the autopilot course, beside the heteroclinic line.

Umeda (1999), Fig. 23 draws the heteroclinic bifurcation (filled circles) and the
sudden-change experiments (squares) against the course and finds them close. For a
given vessel this module computes both lines: the heteroclinic Fn by continuing the
connection (:func:`~ship_models.analysis.critical_curve.critical_curve`) and the
capsizing threshold at each course (:func:`~ship_models.analysis.threshold.capsizing_threshold`,
seeded with the connection's Fn), with the mechanism per course and the courses between
which the two lines part (the last course whose threshold is heteroclinic and the
first whose is not).

The courses are independent and run on forked copies of the process
(:class:`continuation.sweep.forked.ForkedTasks`, ``workers``).
"""

from __future__ import annotations

import csv
import io
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.status import Status
from continuation.sweep.forked import ForkedTasks
from continuation.typing import FloatArray

from ..contracts import VesselModel
from .critical_curve import CriticalCurve, critical_curve
from .params import course, ship_model, ship_params
from .threshold import CapsizingThreshold, ThresholdSettings, capsizing_threshold


@dataclass(frozen=True, eq=False)
class ThresholdCurve:
    """Both lines of Fig. 23 for one vessel.

    Attributes
    ----------
    chi_c : ndarray, shape (K,)
        Courses of the threshold (rad).
    thresholds : tuple of CapsizingThreshold, shape (K,)
    heteroclinic : CriticalCurve
        The heteroclinic line (its own courses).
    parting : (float, float) or None
        ``(last heteroclinic course, first non-heteroclinic course)`` in rad, or None if
        the threshold is heteroclinic at every course (or at none).
    status : Status
        ``SUCCESS`` when every course's threshold is ``SUCCESS`` (or does not exist).
    message : str
    elapsed : float
    """

    chi_c: FloatArray
    thresholds: tuple[CapsizingThreshold, ...]
    heteroclinic: CriticalCurve
    parting: tuple[float, float] | None
    status: Status
    message: str
    elapsed: float = 0.0

    @property
    def Fn(self) -> FloatArray:
        """Threshold at each course (NaN where none)."""
        return np.array([t.Fn for t in self.thresholds], float)

    @property
    def error(self) -> FloatArray:
        """Its error estimates."""
        return np.array([t.error for t in self.thresholds], float)

    @property
    def Fn_heteroclinic(self) -> FloatArray:
        """The heteroclinic Fn at the threshold's courses (NaN where none)."""
        return np.array([t.Fn_heteroclinic for t in self.thresholds], float)

    def is_heteroclinic_mask(self) -> np.ndarray:
        """Boolean array: the threshold is the heteroclinic Fn at that course."""
        return np.array([t.is_heteroclinic for t in self.thresholds], bool)

    @property
    def mechanisms(self) -> tuple[str, ...]:
        """Mechanism per course."""
        return tuple(t.mechanism for t in self.thresholds)

    @property
    def chi_c_deg(self) -> FloatArray:
        """Courses in degrees."""
        return np.degrees(self.chi_c)

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary (degrees)."""

        def num(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        return {
            "threshold": {
                "chi_c_deg": [float(c) for c in self.chi_c_deg],
                "Fn": [num(t.Fn) for t in self.thresholds],
                "error": [num(t.error) for t in self.thresholds],
                "mechanism": list(self.mechanisms),
                "Fn_heteroclinic": [num(t.Fn_heteroclinic) for t in self.thresholds],
                "is_heteroclinic": [t.is_heteroclinic for t in self.thresholds],
                "confirmed": [t.confirmed for t in self.thresholds],
                "status": [t.status.name for t in self.thresholds],
                "message": [t.message for t in self.thresholds],
                "evidence": [
                    {
                        "below": t.below.to_json() if t.below else None,
                        "above": t.above.to_json() if t.above else None,
                    }
                    for t in self.thresholds
                ],
                "bifurcations": [
                    t.bifurcations.to_json() if t.bifurcations else None for t in self.thresholds
                ],
            },
            "parting_chi_c_deg": (
                [math.degrees(a) for a in self.parting] if self.parting else None
            ),
            "threshold_status": self.status.name,
            "threshold_message": self.message,
            "threshold_elapsed_s": self.elapsed,
        }

    def to_csv(self, path: Any) -> None:
        """One row per course: threshold, its error, mechanism, heteroclinic Fn, evidence."""
        buf = io.StringIO()
        w = csv.writer(buf)
        w.writerow(["chi_c_deg", "Fn_threshold", "error", "mechanism", "Fn_heteroclinic",
                    "is_heteroclinic", "fate_below", "fate_above", "status"])  # fmt: skip
        for c, t in zip(self.chi_c_deg, self.thresholds, strict=True):
            w.writerow([f"{c:.6g}", f"{t.Fn:.8g}", f"{t.error:.3g}", t.mechanism,
                        f"{t.Fn_heteroclinic:.8g}", int(t.is_heteroclinic),
                        t.below.attractor if t.below else "", t.above.attractor if t.above else "",
                        t.status.name])  # fmt: skip
        with open(path, "w", encoding="utf-8", newline="") as fh:
            fh.write(buf.getvalue())


def _het_at(curve: CriticalCurve, chi: float) -> tuple[float, float]:
    """The heteroclinic Fn and its error at course ``chi`` (NaN if the curve has none)."""
    i = np.flatnonzero(np.isclose(curve.chi_c, chi, rtol=0, atol=1e-9))
    if i.size and curve.converged[i[0]] and np.isfinite(curve.Fn[i[0]]):
        err = curve.error[i[0]] if curve.error.size else math.nan
        return float(curve.Fn[i[0]]), float(err)
    return math.nan, math.nan


def threshold_curve(
    chi_c: Sequence[float] | FloatArray,
    *,
    model: VesselModel | None = None,
    params: Any = None,
    heteroclinic: CriticalCurve | None = None,
    workers: int = 1,
    settings: ThresholdSettings | None = None,
    progress: Callable[[CapsizingThreshold], None] | None = None,
) -> ThresholdCurve:
    """The capsizing threshold at each course, beside the heteroclinic line.

    Parameters
    ----------
    chi_c : array_like, shape (K,)
        Courses (rad).
    model, params
        As for :func:`~ship_models.analysis.threshold.capsizing_threshold`.
    heteroclinic : CriticalCurve, optional
        The heteroclinic line; computed at ``chi_c`` if not given. Courses it does not
        hold are computed without a connection (scanned about the curve's end ``Fn``).
    workers : int
        Processes (courses on forked copies of this one).
    settings : ThresholdSettings, optional
    progress : callable, optional
        Called with each course's result, in course order, once all are done.

    Returns
    -------
    ThresholdCurve
    """
    t0 = time.perf_counter()
    m = ship_model(model)
    base = ship_params(m, params)
    chis = np.array([course(c) for c in np.atleast_1d(np.asarray(chi_c, float))])
    if chis.size == 0:
        raise ValueError("`chi_c` must hold at least one course")
    het = heteroclinic
    if het is None:
        het = critical_curve(chis, model=m, params=base, workers=workers)
    anchor = het.end_Fn if math.isfinite(het.end_Fn) else None
    cfg = settings or ThresholdSettings()

    def one(k: int) -> CapsizingThreshold:
        Fn_h, err_h = _het_at(het, float(chis[k]))
        if not math.isfinite(Fn_h) and het.converged.any():
            # nearest computed course's value anchors the scan
            ok = np.flatnonzero(het.converged)
            j = ok[np.argmin(np.abs(het.chi_c[ok] - chis[k]))]
            a = float(het.Fn[j]) if anchor is None else anchor
        else:
            a = anchor
        return capsizing_threshold(m, base, chi_c=float(chis[k]), Fn_heteroclinic=(Fn_h, err_h),
                                   Fn_anchor=a, settings=cfg)  # fmt: skip

    order = list(range(chis.size))
    with ForkedTasks(one, order, children=max(0, min(workers, chis.size) - 1)) as run:
        results = run.results()
    ths = tuple(results[k] for k in order)
    if progress is not None:
        for t in ths:
            progress(t)
    parting = None
    flags = [t.is_heteroclinic for t in ths]
    for k in range(1, len(ths)):
        if flags[k - 1] and not flags[k] and math.isfinite(ths[k].Fn):
            parting = (float(chis[k - 1]), float(chis[k]))
            break
    bad = [t for t in ths if t.status not in (Status.SUCCESS, Status.NO_SOLUTION)]
    status = Status.SUCCESS if not bad else bad[0].status
    n_ok = sum(t.success for t in ths)
    msg = f"{n_ok}/{len(ths)} courses with a threshold"
    if parting:
        msg += (
            f"; the threshold is the heteroclinic Fn up to chi_c = {math.degrees(parting[0]):.4g}"
            f" deg and below it from {math.degrees(parting[1]):.4g} deg"
        )
    elif ths and all(flags):
        msg += "; the threshold is the heteroclinic Fn at every course"
    if bad:
        msg += "; not SUCCESS at chi_c = " + ", ".join(
            f"{t.chi_c_deg:.4g} deg ({t.status.name})" for t in bad
        )
    return ThresholdCurve(chis, ths, het, parting, status, msg, time.perf_counter() - t0)


__all__ = ["ThresholdCurve", "threshold_curve"]
