"""Figs. 21 and 23 of Umeda (1999) by the connecting orbit: critical Fn as a boundary-value problem.

The capsizing boundary is the heteroclinic bifurcation where the upslope branch of
the crest saddle's unstable manifold lands on the neighbouring crest saddle (one
wavelength back). Here it is solved directly (:mod:`ship_models.analysis.critical_bvp`):

- Fig. 21 idea: the connecting orbit at the critical Fn for ``chi_c = 10 deg`` beside
  the simulated upslope manifold just below (periodic motion) and just above
  (broaching/capsize) the critical Fn found by bisection, in the paper's planes
  (``xi_G/lambda`` vs ``u/c``, heading vs ``u/c``, roll vs heading, roll vs rudder);
- Fig. 23: the critical Fn against the autopilot course 0-30 deg by continuing the
  connection in ``chi_c``, with bisection-by-simulation checks at a few courses;
- the critical Fn at 10 deg by both methods beside the paper's 0.3247-0.3248 (which
  is for the paper's measured coefficients; ours are estimated, see
  ``studies/README.md``).

Writes to ``--out`` (default ``out/fig21_23``): ``fig21_connection.png``,
``critical_curve_methods.png``, ``critical_curve.csv``, ``connection_orbit_10deg.csv``,
``methods_10deg.csv``, ``bisection_checks.csv``, ``summary.json``.

Run: ``python studies/fig21_23_connection.py [--out DIR] [--quick]``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ship_models.paper import PAPER_FN_BRACKET
from studies._common import (
    PLANE_LABELS,
    begin_step,
    finish_summary,
    new_figure,
    paper_quantities,
    save_csv,
    save_figure,
    save_table,
    state_columns,
    study_main,
    write_atomic,
)

CHI_C_DEG = 10.0
PAPER_FN = PAPER_FN_BRACKET
CHECK_COURSES_DEG = (0.0, 20.0, 30.0)
#: Courses of the capsizing threshold (the lowest capsizing Fn and its mechanism).
THRESHOLD_COURSES_DEG = (10.0, 25.0, 30.0, 38.0)


def _planes(model: Any, c: float) -> list[tuple[str, str, Callable[[np.ndarray], tuple]]]:
    """The paper's planes (Figs. 10-13): (x label, y label, mapping of states (N, 8))."""
    L = float(model.forces.L)
    names = model.state_names

    def plane(qx: str, qy: str) -> Callable[[np.ndarray], tuple]:
        def f(x: np.ndarray) -> tuple:
            q = paper_quantities(x, names, c, L)
            return q[qx], q[qy]

        return f

    return [
        (PLANE_LABELS["xi_unwrapped"], PLANE_LABELS["u_c"], plane("xi_unwrapped", "u_c")),
        (PLANE_LABELS["chi"], PLANE_LABELS["r_nd"], plane("chi", "r_nd")),
        (PLANE_LABELS["xi_unwrapped"], PLANE_LABELS["chi"], plane("xi_unwrapped", "chi")),
        (PLANE_LABELS["phi"], PLANE_LABELS["p_nd"], plane("phi", "p_nd")),
    ]


def compute(
    out: Path, progress: Callable[[str], None] | None = None, *, quick: bool = False
) -> dict[str, Any]:
    """Solve the connection, the curve and the bisection checks; write figures and data."""
    from continuation.dynamics import simulate
    from ship_models.analysis.critical_bisection import upslope_bisection
    from ship_models.analysis.critical_bvp import check_critical_bvp
    from ship_models.analysis.critical_curve import critical_curve
    from ship_models.analysis.events import capsize_event
    from ship_models.analysis.upslope import upslope_branch
    from studies._model import bisection_near, default_model, heteroclinic

    say, t_all = begin_step(out, progress)
    model = default_model()  # one per process (shared by the steps it runs)
    chi10 = math.radians(CHI_C_DEG)
    summary: dict[str, Any] = {"chi_c_deg": CHI_C_DEG, "paper_Fn_10deg": list(PAPER_FN)}

    say("critical Fn at chi_c = 10 deg by the boundary-value problem")
    conn = heteroclinic(CHI_C_DEG)  # solved once per process (studies._model)
    t_bvp = conn.elapsed
    # the check of critical_fn_bvp(check=True) on this solution (not solved again)
    chk = check_critical_bvp(conn) if conn.orbit is not None and conn.orbit.success else None
    say(f"  Fn = {conn.Fn:.8f} ({t_bvp:.2f} s); bisection by simulation to 1e-6")
    bis = bisection_near(
        lambda b: upslope_bisection(chi10, model=model, Fn_bracket=b, tol=1e-6),
        conn.Fn, 5e-5, (0.28, 0.33),
    )  # fmt: skip
    say(f"  bisection: Fn in [{bis.bracket[0]:.8f}, {bis.bracket[1]:.8f}] ({bis.elapsed:.2f} s)")
    summary["bvp"] = conn.to_json()
    if chk is not None:
        summary["bvp"]["delta_Fn_mesh"] = chk.delta_mesh["Fn"]
        summary["bvp"]["delta_Fn_T"] = chk.delta_T["Fn"]
    summary["bisection"] = {
        "Fn": bis.Fn,
        "bracket": list(bis.bracket),
        "n_runs": bis.n_evaluations,
        "elapsed_s": bis.elapsed,
        "status": bis.status.name,
    }
    summary["difference_bvp_minus_bisection"] = conn.Fn - bis.Fn
    save_table(
        out / "methods_10deg.csv",
        ["method", "Fn_critical", "lower", "upper"],
        [
            ["bvp", conn.Fn, conn.Fn, conn.Fn],
            ["bisection", bis.Fn, bis.bracket[0], bis.bracket[1]],
            [
                "paper (measured coefficients)",
                0.5 * (PAPER_FN[0] + PAPER_FN[1]),
                PAPER_FN[0],
                PAPER_FN[1],
            ],
        ],
        meta={
            "chi_c_deg": CHI_C_DEG,
            "source": "Umeda (1999) Figs. 14-15 for the paper row",
            "times": "the methods' seconds are in timings.json (bvp, bisection)",
        },
    )
    o = conn.orbit
    save_csv(
        out / "connection_orbit_10deg.csv",
        {
            "t": o.t,
            **state_columns(o.state_names, np.column_stack([o.state(n) for n in o.state_names])),
        },
        meta={
            "Fn_critical": conn.Fn,
            "chi_c_deg": CHI_C_DEG,
            "units": "SI, angles deg, rates deg/s",
        },
    )

    # ---- Fig. 21 idea: the connection beside the manifold on both sides
    say("upslope manifolds at the ends of the bisection bracket")
    p10 = model.default_params().replace(chi_c=chi10)
    lo_run = upslope_branch(model, p10.replace(Fn=bis.bracket[0]))
    hi_run = upslope_branch(model, p10.replace(Fn=bis.bracket[1]))
    # the captured branch stops when it turns back; follow it on to capsize
    hi_more = simulate(
        model,
        hi_run.trajectory.x[-1],
        p10.replace(Fn=bis.bracket[1]),
        (0.0, 600.0),
        events=[capsize_event(model)],
        dt=0.05,
    )
    runs = {
        f"manifold, Fn = {bis.bracket[0]:.7f} (periodic)": np.asarray(lo_run.trajectory.x),
        f"manifold, Fn = {bis.bracket[1]:.7f} ({hi_more.terminal_event or 'captured'})": (
            np.vstack([hi_run.trajectory.x, hi_more.x])
        ),
    }
    c = model.celerity(p10)
    fig = new_figure((9.0, 7.4))
    axes = fig.subplots(2, 2).ravel()
    for ax, (xl, yl, f) in zip(axes, _planes(model, c), strict=True):
        for (label, x), col in zip(runs.items(), ("tab:green", "tab:red"), strict=True):
            x = x[x[:, 0] > o.x_to[0] - 0.45]  # the part up to just beyond the next crest
            ax.plot(*f(x), color=col, lw=0.9, label=label)
        ax.plot(*f(o.x), color="k", lw=2.0, ls="--", label=f"connection, Fn = {conn.Fn:.8f}")
        ends = np.vstack([o.x_from, o.x_to])
        ax.plot(*f(ends), "ko", ms=5, mfc="w", label="crest saddle and its shift")
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncol=2,
               fontsize=7, frameon=False)  # fmt: skip
    fig.suptitle(
        f"Connecting orbit at the critical Fn, chi_c = {CHI_C_DEG:g} deg "
        "(cf. Umeda 1999, Figs. 10-15, 21)"
    )
    save_figure(fig, out / "fig21_connection.png")

    # ---- Fig. 23: the critical curve
    say("critical curve 0-40 deg by continuation of the connection (to its fold)")
    courses = np.radians(np.arange(0.0, 41.0, 5.0 if quick else 1.0))
    curve = critical_curve(courses, model=model, start=conn)
    say(f"  {curve.message} ({curve.elapsed:.2f} s)")
    write_atomic(out / "critical_curve.csv", curve.to_csv)
    summary["curve"] = {
        "chi_c_deg": [round(float(v), 9) for v in curve.chi_c_deg],
        "Fn": [float(v) for v in curve.Fn],
        "status": curve.status.name,
        "elapsed_s": curve.elapsed,
        "end_chi_c_deg": math.degrees(curve.end_chi_c) if math.isfinite(curve.end_chi_c) else None,
        "end_Fn": curve.end_Fn if math.isfinite(curve.end_Fn) else None,
    }
    from ship_models.analysis.threshold_curve import threshold_curve

    th_deg = (10.0, 30.0) if quick else THRESHOLD_COURSES_DEG
    say(f"capsizing threshold at {', '.join(f'{d:g}' for d in th_deg)} deg (fates of the branch)")
    tc = threshold_curve(np.radians(th_deg), model=model, heteroclinic=curve, workers=2)
    say(f"  {tc.message} ({tc.elapsed:.1f} s)")
    write_atomic(out / "threshold_curve.csv", tc.to_csv)
    summary["threshold"] = tc.to_json()
    checks = [[CHI_C_DEG, bis.Fn, bis.bracket[0], bis.bracket[1], conn.Fn, bis.status.name]]
    for deg in CHECK_COURSES_DEG if not quick else (30.0,):
        say(f"  bisection check at {deg:g} deg")
        k = int(np.argmin(np.abs(curve.chi_c_deg - deg)))
        chi = math.radians(deg)
        b = bisection_near(
            lambda b, c=chi: upslope_bisection(c, model=model, Fn_bracket=b, tol=1e-5),
            float(curve.Fn[k]), 5e-4, (0.295, 0.315),
        )  # fmt: skip
        checks.append([deg, b.Fn, b.bracket[0], b.bracket[1], float(curve.Fn[k]), b.status.name])
    save_table(
        out / "bisection_checks.csv",
        ["chi_c_deg", "Fn_bisection", "lower", "upper", "Fn_bvp_curve", "status"],
        checks,
    )
    summary["bisection_checks"] = checks
    fig = new_figure((5.6, 4.4))
    ax = fig.subplots()
    ok = curve.converged
    ax.plot(curve.chi_c_deg[ok], curve.Fn[ok], "-", color="k", lw=1.0,
            label="continued heteroclinic connection (BVP)")  # fmt: skip
    ax.plot(
        [r[0] for r in checks], [r[1] for r in checks], "^", mfc="none", ms=8, color="tab:purple",
        label="bisection of the first passage (simulation)",
    )  # fmt: skip
    het = np.array(tc.is_heteroclinic_mask())
    ax.errorbar(tc.chi_c_deg, tc.Fn, yerr=tc.error, fmt="none", ecolor="tab:red", capsize=3)
    ax.plot(tc.chi_c_deg[het], tc.Fn[het], "o", color="tab:red", ms=6,
            label="capsizing threshold = heteroclinic")  # fmt: skip
    ax.plot(tc.chi_c_deg[~het], tc.Fn[~het], "s", color="tab:red", mfc="white", ms=6,
            label="capsizing threshold, another mechanism")  # fmt: skip
    for c, t in zip(tc.chi_c_deg, tc.thresholds, strict=True):
        if not t.is_heteroclinic and math.isfinite(t.Fn):
            short = {"period-doubling cascade and crisis": "PD cascade + crisis",
                     "subcritical period doubling": "subcritical PD"}.get(t.mechanism,
                                                                          t.mechanism)  # fmt: skip
            # below its marker: above it the heteroclinic line and its checks run
            ax.annotate(short, (c, t.Fn), fontsize=7, xytext=(0, -7),
                        textcoords="offset points", ha="center", va="top")  # fmt: skip
    if math.isfinite(curve.end_chi_c):
        ax.plot([math.degrees(curve.end_chi_c)], [curve.end_Fn], "k^", ms=5,
                label="end of the heteroclinic line (fold)")  # fmt: skip
    ax.set_xlabel("autopilot course chi_c (deg)")
    ax.set_ylabel("nominal Froude number Fn")
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.set_title("Heteroclinic Fn and capsizing threshold (Fig. 23)", fontsize=9)
    fig.legend(loc="outside lower center", ncol=1, fontsize=7, frameon=False)
    save_figure(fig, out / "critical_curve_methods.png")
    summary["figures"] = ["fig21_connection.png", "critical_curve_methods.png"]
    return finish_summary(out, summary, t_all)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: ``python studies/fig21_23_connection.py --out DIR``."""
    return study_main(
        __doc__,
        "out/fig21_23",
        compute,
        argv,
        flags=(("quick", "every 5 deg, one bisection check"),),
        shown=("bvp", "bisection", "difference_bvp_minus_bisection", "seconds"),
    )


if __name__ == "__main__":
    raise SystemExit(main())
