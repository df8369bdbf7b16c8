r"""The ship's critical Fn: connecting-orbit BVP against bisection by simulation.

Run on demand (not a test): ``python benchmarks/critical_bvp_vs_bisection.py
[--repeat 3] [--full] [--json PATH]`` (about a minute; ``--full`` runs all 31
bisections instead of extrapolating from 4).

Two comparisons, in one run, on the default vessel (Umeda's purse seiner with
estimated coefficients, ``H/lambda = 0.1087``, ``lambda/L = 1.5``):

1. One course, ``chi_c = 10 deg``, to 1e-6 in Fn:

   * **BVP**: :func:`ship_models.analysis.critical_bvp.critical_fn_bvp` with its
     defaults: one simulation of the upslope manifold at the vessel's default Fn
     (``ship_models.paper.PAPER_FN``, the paper's value) as the guess, then Newton on
     the collocation system (Fn unknown). Its error is measured against a reference
     solve on a 2.5x finer, longer mesh; it is about 1e-7.
   * **bisection (lean)**: :func:`ship_models.analysis.critical_bisection.upslope_bisection`,
     fate of the upslope manifold (periodic vs captured, decided by terminal events
     as soon as the branch passes the next crest or turns back) by CVODES (rtol
     1e-9), from the bracket (0.28, 0.33) to a width of 1e-6 (18 simulations);
   * **bisection (project tool)**: :func:`ship_models.analysis.critical.critical_fn`
     with ``method="bisection"`` (``broachkit critical --method bisection``), whose
     fate classifier also identifies the periodic attractor by Poincare returns, from
     its default bracket (0.25, 0.40) to 1e-6; timed once (it takes seconds per course).

2. The whole curve, ``chi_c = 0, 1, ..., 30 deg``:

   * **continuation**: :func:`ship_models.analysis.critical_curve.critical_curve` (one
     BVP solve at 15 deg, pseudo-arclength in ``chi_c``, each course corrected
     exactly);
   * **31 bisections** (lean) as above; by default 4 of them (0, 10, 20, 30 deg) are
     timed and the total is extrapolated as ``31 x`` their mean (``--full``: all 31);
     for the project tool, ``31 x`` its time at 10 deg.

Times are wall-clock (``time.perf_counter``), the median of ``--repeat`` runs after
one untimed warm-up of each method (CasADi functions are compiled once per process
and mesh size; the warm-up hides that one-off cost from both sides). One BLAS thread
is forced before NumPy is imported.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

BRACKET = (0.28, 0.33)
TOL = 1e-6
SUBSET_DEG = (0.0, 10.0, 20.0, 30.0)


def _timed(fn: Callable[[], Any], repeat: int) -> tuple[Any, float, list[float]]:
    fn()  # warm-up
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times), times


def run(repeat: int = 3, full: bool = False) -> dict[str, Any]:
    """Run both comparisons; return the numbers (also printed by :func:`main`)."""
    from ship_models import purse_seiner
    from ship_models.analysis.critical_bisection import upslope_bisection
    from ship_models.analysis.critical_bvp import critical_fn_bvp
    from ship_models.analysis.critical_curve import critical_curve

    model = purse_seiner()
    chi10 = math.radians(10.0)
    res: dict[str, Any] = {
        "repeat": repeat,
        "tol": TOL,
        "bracket": list(BRACKET),
        "load_average_start": list(os.getloadavg()),
        "cpus": os.cpu_count(),
    }

    # ---- 1. one course
    bvp, t_bvp, ts_bvp = _timed(lambda: critical_fn_bvp(chi10, model=model), repeat)
    bis, t_bis, ts_bis = _timed(
        lambda: upslope_bisection(chi10, model=model, Fn_bracket=BRACKET, tol=TOL), repeat
    )
    ref = critical_fn_bvp(
        chi10, model=model, interval_length=0.3, start_distance=1e-4, end_distance=1e-3
    )
    res["one_course"] = {
        "chi_c_deg": 10.0,
        "bvp_Fn": bvp.Fn,
        "bvp_s": t_bvp,
        "bvp_runs_s": ts_bvp,
        "bvp_error_vs_refined": bvp.Fn - ref.Fn,
        "refined_Fn": ref.Fn,
        "bisection_Fn": bis.Fn,
        "bisection_bracket": list(bis.bracket),
        "bisection_runs": bis.n_evaluations,
        "bisection_s": t_bis,
        "bisection_runs_s": ts_bis,
        "bvp_minus_bisection": bvp.Fn - bis.Fn,
        "speedup": t_bis / t_bvp,
    }

    try:
        from ship_models.analysis.critical import critical_fn
    except ImportError:  # the project tool is optional here
        critical_fn = None
    if critical_fn is not None:
        t0 = time.perf_counter()
        tool = critical_fn(model, chi_c=chi10, method="bisection", tol=TOL)
        t_tool = time.perf_counter() - t0
        res["one_course"].update(
            {
                "tool_Fn": tool.Fn,
                "tool_bracket": list(tool.bracket),
                "tool_runs": tool.n_evaluations,
                "tool_s": t_tool,
                "tool_status": tool.status.name,
                "speedup_vs_tool": t_tool / t_bvp,
            }
        )

    # ---- 2. the curve
    curve, t_curve, ts_curve = _timed(lambda: critical_curve(model=model), repeat)
    degs = np.arange(31.0) if full else np.array(SUBSET_DEG)
    b_times, b_vals = [], []
    for d in degs:
        t0 = time.perf_counter()
        b = upslope_bisection(math.radians(d), model=model, Fn_bracket=BRACKET, tol=TOL)
        b_times.append(time.perf_counter() - t0)
        b_vals.append(b.Fn)
    k = degs.astype(int)
    t_31 = float(np.sum(b_times)) if full else 31.0 * float(np.mean(b_times))
    res["curve"] = {
        "status": curve.status.name,
        "courses": int(curve.chi_c.size),
        "continuation_s": t_curve,
        "continuation_runs_s": ts_curve,
        "bisection_courses_deg": degs.tolist(),
        "bisection_s_each": b_times,
        "bisection_Fn": b_vals,
        "curve_Fn_at_those": curve.Fn[k].tolist(),
        "max_abs_difference": float(np.max(np.abs(curve.Fn[k] - np.array(b_vals)))),
        "bisection_31_s": t_31,
        "bisection_31_extrapolated": not full,
        "speedup": t_31 / t_curve,
        "Fn": curve.Fn.tolist(),
    }
    if "tool_s" in res["one_course"]:
        res["curve"]["tool_31_s_extrapolated"] = 31.0 * res["one_course"]["tool_s"]
        res["curve"]["speedup_vs_tool"] = res["curve"]["tool_31_s_extrapolated"] / t_curve
    res["load_average_end"] = list(os.getloadavg())
    return res


def main(argv: list[str] | None = None) -> int:
    """Command line: print the comparison; write JSON with ``--json``."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--full", action="store_true", help="time all 31 bisections")
    ap.add_argument(
        "--json",
        type=Path,
        default=Path(__file__).resolve().parent / "results" / "critical_bvp_vs_bisection.json",
    )
    args = ap.parse_args(argv)
    if args.repeat < 1:
        raise ValueError(f"--repeat must be >= 1, got {args.repeat}")
    r = run(args.repeat, args.full)
    o, c = r["one_course"], r["curve"]
    lines = [
        "critical Fn of the purse seiner, chi_c = 10 deg, accuracy 1e-6 in Fn",
        f"  BVP         Fn = {o['bvp_Fn']:.8f}  (error vs refined {o['bvp_error_vs_refined']:+.1e})"
        f"  {o['bvp_s']:.3f} s",
        f"  bisection   Fn = {o['bisection_Fn']:.8f}  bracket [{o['bisection_bracket'][0]:.8f}, "
        f"{o['bisection_bracket'][1]:.8f}], {o['bisection_runs']} runs  {o['bisection_s']:.3f} s",
        f"  difference {o['bvp_minus_bisection']:+.1e};  speed-up bisection/BVP = "
        f"{o['speedup']:.1f}x",
        *(
            [
                f"  project tool (critical_fn) Fn = {o['tool_Fn']:.8f}  bracket "
                f"[{o['tool_bracket'][0]:.8f}, {o['tool_bracket'][1]:.8f}], {o['tool_runs']} "
                f"runs  {o['tool_s']:.2f} s;  speed-up tool/BVP = {o['speedup_vs_tool']:.1f}x"
            ]
            if "tool_s" in o
            else []
        ),
        f"critical curve, {c['courses']} courses 0..30 deg",
        f"  continuation  {c['continuation_s']:.2f} s ({c['status']})",
        f"  31 bisections {c['bisection_31_s']:.2f} s"
        + (" (extrapolated from 0, 10, 20, 30 deg)" if c["bisection_31_extrapolated"] else ""),
        f"  max |curve - bisection| at the timed courses: {c['max_abs_difference']:.1e}",
        f"  speed-up = {c['speedup']:.1f}x"
        + (
            f";  vs 31 x project tool ({c['tool_31_s_extrapolated']:.0f} s, extrapolated): "
            f"{c['speedup_vs_tool']:.0f}x"
            if "tool_31_s_extrapolated" in c
            else ""
        ),
        f"load average (1 min) at start/end: {r['load_average_start'][0]:.2f} / "
        f"{r['load_average_end'][0]:.2f} on {r['cpus']} CPUs",
    ]
    print("\n".join(lines))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(r, indent=2))
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
