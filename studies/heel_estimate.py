"""Heel-induced forces from a cited estimate: their effect on the fold and Fig. 23's curves.

The default vessel sets Y_phi, N_phi, K_phi (Umeda 1999 Eqs. 6, 8, 10) to zero; the
only cited numbers that could be read are the captive-model derivatives of Son &
Nomoto's (1981) container ship, transferred as ratios to the drift derivatives
(``[vessel] heel_derivatives_method = "son_nomoto_ratio"``,
:mod:`ship_models.hydro.heel`; an analogy, outside that hull's L/B). This study
compares the default (zero) and that estimate on

- the primes themselves,
- the fold of the crest fixed-point branch in chi_c at the paper's Fn = 0.3248,
- the heteroclinic line of Fig. 23 (its values and its end, the fold in chi_c),
- the capsizing threshold (the project's critical Fn) at a few courses, with its
  mechanism.

Result (2026-12-04): Y'_phi = -0.00248, N'_phi = -0.00584, K'_phi = -0.0101 (a
hundredth of the drift derivatives, as on the container ship). The threshold at
10 deg is unchanged within its error (0.30165 both; the connection moves -2.6e-6),
so is the band; the crest fold at Fn 0.3248 moves from 43.56 to 42.54 deg, the
heteroclinic line's end from 38.97 deg (Fn 0.3311) to 38.26 deg (Fn 0.3283), and the
threshold at 30 and 40 deg (beyond the heteroclinic range) by -0.0011 / -0.0003.

Writes ``heel_estimate.csv`` (one row per case and course) and ``heel_estimate.png``
to ``--out`` (default ``out/heel_estimate``). Takes a few minutes (two critical curves
and the thresholds); ``--quick`` computes the primes, the fold and the 10 deg threshold
only. Run: ``python studies/heel_estimate.py [--out DIR] [--quick]``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

#: Courses (deg) of the capsizing threshold; the heteroclinic line is traced 0-50 deg.
THRESHOLD_COURSES_DEG = (10.0, 20.0, 30.0, 40.0)
CASES = ("none", "son_nomoto_ratio")


def vessel_for(method: str) -> Any:
    """The default vessel with ``[vessel] heel_derivatives_method = method``."""
    from ship_models.vessel import load_vessel, parse_vessel

    d = load_vessel("purse_seiner").to_dict()
    d["vessel"]["heel_derivatives_method"] = method
    return parse_vessel(d)


def _threshold_row(chi_deg: float, t: Any) -> dict[str, Any]:
    return {
        "chi_c_deg": chi_deg,
        "Fn_threshold": t.Fn,
        "error": t.error,
        "mechanism": t.mechanism,
        "Fn_heteroclinic": t.Fn_heteroclinic,
    }


def evaluate(method: str, *, quick: bool = False) -> list[dict[str, Any]]:
    """Rows (one per threshold course) for one heel-derivative method."""
    from ship_models import Umeda4DOF
    from ship_models.analysis.critical_curve import critical_curve
    from ship_models.analysis.threshold import capsizing_threshold
    from ship_models.analysis.threshold_curve import threshold_curve
    from ship_models.paper import PAPER_FN
    from studies.heel_terms import crest_fold_deg

    m = Umeda4DOF(vessel_for(method))
    v = m.vessel
    base = {
        "method": method,
        **{k: v.get(f"hydrodynamics.{k}") for k in ("Y_phi_prime", "N_phi_prime", "K_phi_prime")},
        "crest_fold_deg": crest_fold_deg(m, PAPER_FN),
    }
    if quick:
        t = capsizing_threshold(m, chi_c=math.radians(10.0))
        return [base | _threshold_row(10.0, t)]
    cc = critical_curve(np.radians(np.arange(0.0, 51.0, 1.0)), model=m)
    base |= {"curve_end_deg": math.degrees(float(cc.end_chi_c)), "curve_end_Fn": float(cc.end_Fn)}
    tc = threshold_curve(np.radians(THRESHOLD_COURSES_DEG), model=m, heteroclinic=cc)
    rows = []
    for chi, t in zip(THRESHOLD_COURSES_DEG, tc.thresholds, strict=True):
        rows.append(base | _threshold_row(chi, t))
    rows[0]["_curve"] = (np.degrees(np.asarray(cc.chi_c)), np.asarray(cc.Fn), np.asarray(cc.exists))
    return rows


def run(out: Path, *, quick: bool = False) -> list[dict[str, Any]]:
    """Both cases; CSV (and, unless quick, the figure) in ``out``."""
    from studies._common import new_figure, save_figure, save_table

    rows = [r for method in CASES for r in evaluate(method, quick=quick)]
    cols = [k for k in rows[0] if not k.startswith("_")]
    for r in rows:
        for k in cols:
            r.setdefault(k, float("nan"))
    save_table(out / "heel_estimate.csv", cols, [[r[k] for k in cols] for r in rows])
    if quick:
        return rows
    fig = new_figure((6.5, 4.0))
    ax = fig.subplots()
    for r, style in zip((r for r in rows if "_curve" in r), ("-", "--"), strict=True):
        chi, Fn, ok = r["_curve"]
        ax.plot(chi[ok], Fn[ok], style, label=f"heteroclinic line, heel: {r['method']}")
        sel = [q for q in rows if q["method"] == r["method"]]
        ax.plot(
            [q["chi_c_deg"] for q in sel],
            [q["Fn_threshold"] for q in sel],
            "o" if style == "-" else "s",
            mfc="none",
            label=f"capsizing threshold, heel: {r['method']}",
        )
    ax.axvspan(30.0, 50.0, color="0.9", zorder=0)
    ax.text(31.0, ax.get_ylim()[0], "beyond Fig. 23 (0-30 deg)", va="bottom", fontsize=8)
    ax.set_xlabel("autopilot course chi_c (deg)")
    ax.set_ylabel("critical Fn")
    ax.set_title("heel derivatives: zero vs Son & Nomoto (1981) ratios")
    ax.legend(loc="upper left")
    save_figure(fig, out / "heel_estimate.png")
    return rows


def main(argv: list[str] | None = None) -> int:
    """Command line: ``--out DIR``, ``--quick``."""
    from studies._common import rows_main

    return rows_main(
        __doc__,
        "heel_estimate",
        run,
        argv,
        quick_help="primes, fold and 10 deg only",
        line=lambda r: " ".join(f"{k}={v}" for k, v in r.items() if not k.startswith("_")),
    )


if __name__ == "__main__":
    raise SystemExit(main())
