"""The overtaken-by-waves cycle continued in Fn (chi_c = 10 deg) and in chi_c (Fn = 0.3).

The collocated rotation orbit (ship_models.analysis.cycles) from Fn = 0.1 up to where
its period grows without bound; the limit fitted by T = a - b ln|Fn* - Fn| against the
heteroclinic Fn of the connection BVP (critical_fn_bvp). Then the cycle at Fn = 0.3
continued in chi_c both ways.

Writes to ``--out`` (default ``out/cycles``): ``cycles_vs_fn.png``,
``cycles_vs_chi_c.png``, ``cycles_fn.csv``, ``cycles_chi_c.csv``, ``cycles.json``.

Run: ``python studies/cycles_vs_fn.py [--out DIR]``.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from studies._common import new_figure, save_csv, save_figure, write_results, write_summary

CHI_C_DEG = 10.0
FN_CHI = 0.3


#: Collocation error tolerance of the cycles (states in their own units).
CYCLE_ERROR_TOL = 1e-5


def _panels(cb: Any, x: np.ndarray, xlabel: str, mark: float, mark_label: str, path: Path) -> None:
    fig = new_figure((7.0, 5.0))
    ax = fig.subplots(2, 2)
    st = cb.n_unstable == 0
    for a, y, lab in (
        (ax[0, 0], cb.T, "period T (s)"),
        (ax[1, 0], np.degrees(cb.max_roll), "max |phi| (deg)"),
        (ax[1, 1], np.degrees(cb.max_heading), "max |chi - chi_c| (deg)"),
    ):
        a.plot(x, y, "-", color="0.6", lw=0.8)
        a.plot(x[st], y[st], ".", ms=3, label="stable")
        a.plot(x[~st], y[~st], "x", ms=3, label="unstable")
        if math.isfinite(mark):
            a.axvline(mark, color="r", lw=0.8, ls="--", label=mark_label)
        a.set_xlabel(xlabel)
        a.set_ylabel(lab)
    ax[0, 0].legend()
    a = ax[0, 1]
    if math.isfinite(mark):
        d = np.abs(mark - x)
        ok = d > 0
        a.semilogx(d[ok], cb.T[ok], ".", ms=3)
        a.set_xlabel(f"|{mark_label} - {xlabel}|")
        a.set_ylabel("T (s)")
        a.set_title("T = a - b ln|p* - p|")
    else:  # no end in range: the Floquet multipliers instead
        a.plot(x, cb.mu_max, ".-", ms=3)
        a.axhline(1.0, color="r", lw=0.8, ls="--")
        a.set_xlabel(xlabel)
        a.set_ylabel("max |Floquet multiplier|")
    save_figure(fig, path)


def _no_nan(obj: Any) -> Any:
    """NaN -> None (strict JSON)."""
    if isinstance(obj, dict):
        return {k: _no_nan(v) for k, v in obj.items()}
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def compute(out: Path, progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Run the study and write its files (atomically); returns the JSON summary.

    ``summary.json`` holds the summary (the main job's step record and the report's
    source); the CSVs have angles in degrees (``*_deg``), as every CSV of the job.
    """
    say = progress or (lambda msg: None)
    from ship_models.analysis.cycles import cycle_at, cycle_branch, simulated_cycle
    from ship_models.analysis.events import capsize_angle
    from studies._model import default_model, heteroclinic

    out.mkdir(parents=True, exist_ok=True)
    model = default_model()  # the default vessel, one per process
    chi = math.radians(CHI_C_DEG)
    t0 = time.perf_counter()
    say("connection at 10 deg")
    fn_het = float(heteroclinic(CHI_C_DEG).Fn)  # solved once per process (studies._model)
    say("cycle at Fn 0.1 (simulated, then collocated)")
    o = simulated_cycle(model, model.default_params().replace(Fn=0.1, chi_c=chi))
    t1 = time.perf_counter()
    say("cycle continued in Fn")
    # 1e-5 in the states (m/s, rad, ...): the limit Fn* moves by 1.2e-7 against 1e-6, at
    # half the cost (measured 2026-12-04)
    cb = cycle_branch(o, "Fn", p_max=0.4, period_max=60.0, error_tol=CYCLE_ERROR_TOL)
    t_fn = time.perf_counter() - t1
    _panels(cb, cb.p, "Fn", fn_het, "Fn* (BVP)", out / "cycles_vs_fn.png")
    save_csv(out / "cycles_fn.csv", {"Fn": cb.p, "T": cb.T,
             "max_roll_deg": np.degrees(cb.max_roll),
             "max_heading_deg": np.degrees(cb.max_heading), "mu_max": cb.mu_max,
             "mu_lead_real": cb.mu_lead.real, "n_unstable": cb.n_unstable},
             meta={"chi_c_deg": CHI_C_DEG, "Fn_bvp": fn_het, "Fn_fit": cb.limit})  # fmt: skip
    # ---- in chi_c at Fn = 0.3
    say("cycle continued in chi_c at Fn 0.3")
    o3 = cycle_at(o, Fn=FN_CHI)
    cc = cycle_branch(o3, "chi_c", p_min=0.0, p_max=math.radians(60.0), ds=0.02, ds_max=0.05,
                      period_max=60.0, direction="both", error_tol=CYCLE_ERROR_TOL)  # fmt: skip
    _panels(cc, np.degrees(cc.p), "chi_c (deg)", math.degrees(cc.limit), "chi_c* (fit)",
            out / "cycles_vs_chi_c.png")  # fmt: skip
    save_csv(out / "cycles_chi_c.csv", {"chi_c_deg": np.degrees(cc.p), "T": cc.T,
             "max_roll_deg": np.degrees(cc.max_roll),
             "max_heading_deg": np.degrees(cc.max_heading), "mu_max": cc.mu_max,
             "n_unstable": cc.n_unstable},
             meta={"Fn": FN_CHI, "chi_c_fit_deg": math.degrees(cc.limit)})  # fmt: skip
    summary = {
        "chi_c_deg": CHI_C_DEG,
        "Fn_bvp": fn_het,
        "Fn_fit_log": cb.limit,
        "Fn_fit_saddle_focus": cb.limit_saddle_focus,
        "Fn_last_row": float(cb.p[-1]),
        "difference_fit_minus_bvp": cb.limit - fn_het,
        "Fn_lost_stability": cb.lost_stability_at,
        "max_roll_deg": float(np.degrees(np.max(cb.max_roll))),
        "vanishing_angle_deg": float(np.degrees(capsize_angle(model))),
        "fn_branch": {"status": cb.status.name, "rows": len(cb.p), "seconds": t_fn},
        "chi_c_branch": {
            "Fn": FN_CHI,
            "status": cc.status.name,
            "message": cc.message,
            "chi_c_limit_deg": math.degrees(cc.limit),
            "chi_c_lost_stability_deg": math.degrees(cc.lost_stability_at),
            "max_roll_deg": float(np.degrees(np.max(cc.max_roll))),
        },  # fmt: skip
        "seconds": time.perf_counter() - t0,
    }
    summary = _no_nan(summary)
    summary["figures"] = ["cycles_vs_fn.png", "cycles_vs_chi_c.png"]
    write_results(out / "cycles.json", summary)
    write_summary(out, summary)
    return summary


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: ``python studies/cycles_vs_fn.py --out DIR``."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out/cycles"))
    args = ap.parse_args(argv)
    print(json.dumps(_no_nan(compute(args.out)), indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
