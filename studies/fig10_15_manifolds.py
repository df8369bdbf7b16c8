"""Figs. 10-15 of Umeda (1999): unstable manifolds of the crest saddle, chi_c = 10 deg.

1. The critical Fn of the heteroclinic bifurcation is found for OUR vessel by bisection
   on the fate of the upslope branch (:func:`ship_models.analysis.critical.critical_fn`,
   tolerance 1e-5 in Fn). The paper's 0.3247/0.3248 belong to its measured
   coefficients; ours are estimated, so our switch lies elsewhere.
2. Both branches of the unstable manifold of the crest saddle are computed just above
   (the bracket's upper end: the paper's Figs. 10-13 at Fn = 0.3248) and just below
   (the lower end: Figs. 14-15 at Fn = 0.3247), and also at the paper's Fn = 0.3248.
3. The global picture (fixed points, attractors, manifold branches) on both sides of
   the switch is compared (:mod:`ship_models.analysis.global_picture`).

Planes as in the paper (its axis labels and symbol list): xi_G/lambda vs u/c (Figs. 10,
14), heading vs the nondimensional yaw rate r' = r L/sqrt(u^2+v^2) (Figs. 11, 15),
xi_G/lambda vs heading (Fig. 12), roll vs the nondimensional roll rate p' (Fig. 13);
positions in the paper's window -0.6 .. 1, the end of a branch that drifts back redrawn
shifted by whole waves so that the periodic attractor shows as a closed curve; the
whole simulated branch is drawn (:func:`position_pieces`). Both sides of the switch get
all four planes (``extra_<plane>_<case>.png`` where the paper has no figure).

Writes to ``--out`` (default ``out/fig10_15``): ``fig10_..fig15_*.png``,
``manifold_<case>_<branch>.csv`` (time series), ``critical.json``, ``summary.json``.
Run: ``python studies/fig10_15_manifolds.py [--out DIR]``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ship_models.paper import PAPER_FN
from studies._common import (
    PLANE_LABELS,
    begin_step,
    finish_summary,
    new_figure,
    paper_quantities,
    save_csv,
    save_figure,
    state_columns,
    study_main,
    write_results,
)

CHI_C_DEG = 10.0
#: Width of the Fn search below the first-passage bracket for the final-fate switch.
FINAL_SEARCH_WIDTH = 1e-3
COLORS = {"downslope": "tab:red", "upslope": "tab:blue"}
STYLES = {"downslope": "-", "upslope": "--"}
#: The paper's planes (from its axis labels and symbol list): (file tag, x, y).
#: Figs. 10/14: position vs u/c; Figs. 11/15: heading vs r' (as Fig. 18, whose
#: ordinate -0.1..0.6 against heading 0..70 deg fits r'); Fig. 12: position on the
#: abscissa, heading on the ordinate (the text: the heading grows while the ship
#: stays on the downslope); Fig. 13: roll angle vs p' (as Fig. 19).
PLANES = (
    ("position", "xi", "u_c"),
    ("heading", "chi", "r_nd"),
    ("position_heading", "xi", "chi"),
    ("roll", "phi", "p_nd"),
)
#: The position window of the paper's Figs. 10, 12, 14: -0.6 .. 1.
XI_WINDOW_LOW, XI_WINDOW_HIGH = -0.6, 1.0
#: Wavelengths of the end of a branch redrawn, shifted by whole waves, inside the
#: window: a motion that keeps drifting back (the periodic attractor) shows there.
ATTRACTOR_WAVES = 3.0


def position_pieces(xi: np.ndarray, y: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, bool]]:
    """A branch in the position window: (x, y, is_shifted_copy) pieces to draw.

    The branch is drawn as it runs until it first leaves the window to the left
    (``xi < XI_WINDOW_LOW``); what follows, if anything, is a motion drifting back by
    whole waves. Its last :data:`ATTRACTOR_WAVES` wavelengths are drawn again shifted
    by every whole number of waves that brings them into the window, so that a
    periodic attractor appears as the closed curve it is on the wave-periodic phase
    space (the paper's Figs. 14-15).
    """
    out_left = np.nonzero(xi < XI_WINDOW_LOW)[0]
    if out_left.size == 0:
        return [(xi, y, False)]
    k = int(out_left[0]) + 1
    pieces = [(xi[:k], y[:k], False)]
    rest_xi, rest_y = xi[k:], y[k:]
    if rest_xi.size < 2:
        return pieces
    far = np.nonzero(np.abs(rest_xi - rest_xi[-1]) > ATTRACTOR_WAVES)[0]
    first = int(far[-1]) + 1 if far.size else 0
    txi, ty = rest_xi[first:], rest_y[first:]
    lo = int(np.ceil(XI_WINDOW_LOW - txi.max()))
    hi = int(np.floor(XI_WINDOW_HIGH - txi.min()))
    pieces += [(txi + shift, ty, True) for shift in range(lo, hi + 1)]
    return pieces


LABELS = PLANE_LABELS


def _plot_case(
    man: Any, c: float, L: float, out: Path, numbers: dict[str, str], title: str, case: str
) -> list[str]:
    """One PNG per plane for one Fn; ``numbers`` maps plane tag -> paper figure number."""
    written = []
    sp = man.saddle
    names = man.branches[next(iter(man.branches))].trajectory.state_names
    for tag, qx, qy in PLANES:
        fig = new_figure((6.0, 4.6))
        ax = fig.subplots()
        for name, br in man.branches.items():
            x = np.asarray(br.trajectory.x)
            q = paper_quantities(x, names, c, L)
            style = {"color": COLORS[name], "lw": 1.5 if name == "downslope" else 1.0}
            if qx == "xi":
                pieces = position_pieces(q["xi_unwrapped"], q[qy])
            else:
                pieces = [(q[qx], q[qy], False)]
            for k, (xs, ys, copy) in enumerate(pieces):
                ax.plot(
                    xs,
                    ys,
                    STYLES[name],
                    alpha=0.55 if copy else 1.0,
                    label=f"{name}: {br.fate.label}" if k == 0 else None,
                    **style,
                )
            if br.fate.kind == "capsize":
                xs, ys, _ = pieces[0]
                ax.plot(xs[-1], ys[-1], "x", color=COLORS[name], ms=9)
        for fp in man.points:
            if fp.saddle_index > 1:
                continue
            q = paper_quantities(np.asarray(fp.x)[None, :], names, c, L)
            shifts = (0.0, -1.0) if qx == "xi" else (0.0,)
            for shift in shifts:
                px = q["xi_unwrapped"][0] + shift if qx == "xi" else q[qx][0]
                if qx == "xi" and not XI_WINDOW_LOW <= px <= XI_WINDOW_HIGH:
                    continue
                marker = "o" if fp.label == sp.label else "s"
                ax.plot(px, q[qy][0], marker, mfc="none", color="k", ms=7)
                lab = fp.label if shift == 0 else f"{fp.label}@{int(shift):+d}"
                ax.annotate(
                    lab,
                    (px, q[qy][0]),
                    textcoords="offset points",
                    fontsize=7,
                    xytext=(5, 5) if fp.label == sp.label else (5, -12),
                )
        ax.set_xlabel(LABELS[qx])
        ax.set_ylabel(LABELS[qy])
        if qx == "xi":
            ax.set_xlim(XI_WINDOW_LOW, XI_WINDOW_HIGH)
        ax.set_title(f"Fig. {numbers[tag]}: {title}" if tag in numbers else title, fontsize=9)
        fig.legend(loc="outside lower center", ncol=2, fontsize=7, frameon=False)
        name = (
            f"fig{int(numbers[tag]):02d}_" if tag in numbers else "extra_"
        ) + f"{tag}_{case}.png"
        save_figure(fig, out / name)
        written.append(name)
    return written


def _save_series(man: Any, c: float, L: float, out: Path, case: str) -> list[str]:
    files = []
    for name, br in man.branches.items():
        tr = br.trajectory
        x = np.asarray(tr.x)
        q = paper_quantities(x, tr.state_names, c, L)
        cols = {"t": tr.t, **state_columns(tr.state_names, x)}
        cols.update({"u_over_c": q["u_c"], "r_nondim": q["r_nd"], "p_nondim": q["p_nd"]})
        fname = f"manifold_{case}_{name}.csv"
        save_csv(
            out / fname,
            cols,
            meta={
                "Fn": man.params["Fn"],
                "chi_c_deg": math.degrees(man.params["chi_c"]),
                "branch": name,
                "fate": br.fate.label,
                "eps": man.eps,
                "units": "t s; xi_G = xi_G/lambda unwrapped; u, v m/s; angles deg, rates deg/s; "
                "r_nondim = r L/sqrt(u^2+v^2), p_nondim likewise",
            },
        )
        files.append(fname)
    return files


def compute(out: Path, progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Bisection for the critical Fn, manifolds on both sides; figures and data in ``out``."""
    from ship_models.analysis import (
        build_global_picture,
        critical_fn,
        fixed_points,
        unstable_manifold,
    )
    from ship_models.analysis.global_picture import compare_pictures
    from studies._model import default_model

    say, t0 = begin_step(out, progress)
    model = default_model()  # one per process (shared by the steps it runs)
    base = model.default_params().replace(chi_c=math.radians(CHI_C_DEG))
    c = model.celerity(base)
    L = float(model.forces.L)
    say(f"bisection of Fn on the upslope branch's first passage (chi_c = {CHI_C_DEG:g} deg)")
    crit = critical_fn(
        model,
        base,
        method="bisection",
        tol=1e-5,
        progress=lambda e: say(f"  Fn = {e.Fn:.7f}: {e.outcome or 'undecided'}"),
    )
    write_results(out / "critical.json", crit.to_json())
    if not crit.status.ok and crit.status.name != "SUCCESS":
        say(f"bisection did not succeed: {crit.message}")
    lo, hi = crit.bracket
    # Just below the primary connection, secondary switches (the branch passes crest@-1
    # on the periodic side and turns back at crest@-2, -3, ...) accumulate, so the
    # final fate there can be capsize. The paper's "just below" picture (a periodic
    # attractor) is taken at the highest Fn whose final fate is periodic: a second
    # bisection, on the final fate, below the first-passage bracket.
    say("bisection on the final fate below the first-passage bracket (secondary switches)")
    final = critical_fn(
        model,
        base,
        method="bisection",
        Fn_bracket=(lo - FINAL_SEARCH_WIDTH, lo),
        tol=1e-6,
        criterion="final",
        progress=lambda e: say(f"  Fn = {e.Fn:.7f}: {e.outcome or 'undecided'}"),
    )
    write_results(out / "critical_final_fate.json", final.to_json())
    below = final.bracket[0] if final.status.name == "SUCCESS" else lo
    cases = {"above": hi, "below": below, "paper": PAPER_FN}
    figures: list[str] = []
    data: list[str] = []
    summary: dict[str, Any] = {
        "chi_c_deg": CHI_C_DEG,
        "critical": crit.to_json(),
        "final_fate_switch": final.to_json(),
        "cascade_interval": [final.bracket[1], lo],
        "cases": {},
    }
    mans = {}
    case_points = {}
    for case, fn in cases.items():
        say(f"unstable manifold of the crest saddle at Fn = {fn:.7f} ({case})")
        p = base.replace(Fn=fn)
        pts = fixed_points(model, p)
        man = unstable_manifold(model, p, "crest", points=pts, t_max=1500.0)
        mans[case] = man
        case_points[case] = pts
        if case == "above":
            nums = {"position": "10", "heading": "11", "position_heading": "12", "roll": "13"}
            title = f"Fn = {fn:.6f} (just above critical), $\\chi_c$ = {CHI_C_DEG:g} deg"
        elif case == "below":
            nums = {"position": "14", "heading": "15"}
            title = f"Fn = {fn:.6f} (just below critical), $\\chi_c$ = {CHI_C_DEG:g} deg"
        else:
            nums = {}
            title = f"Fn = {fn} (the paper's value), $\\chi_c$ = {CHI_C_DEG:g} deg"
        figures += _plot_case(man, c, L, out, nums, title, case)
        data += _save_series(man, c, L, out, case)
        summary["cases"][case] = {"Fn": fn, **man.to_json()}
    say("global picture at the 'below' and 'above' cases")
    # the crest manifolds of these two cases were computed above (same eps, t_max)
    g_lo, g_hi = (
        build_global_picture(
            model,
            base.replace(Fn=cases[case]),
            points=case_points[case],
            manifolds={"crest": mans[case]},
            t_max=1500.0,
        )
        for case in ("below", "above")
    )
    diff = compare_pictures(g_lo, g_hi)
    summary["global_picture"] = {
        "below": [(u, v, k) for u, v, k in g_lo.edges(keys=True)],
        "above": [(u, v, k) for u, v, k in g_hi.edges(keys=True)],
        "changed_edges": [list(e) for e in diff.changed_edges],
        "added_nodes": list(diff.added_nodes),
        "removed_nodes": list(diff.removed_nodes),
    }
    summary["figures"] = figures
    summary["data"] = data
    return finish_summary(out, summary, t0, default=str)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: ``python studies/fig10_15_manifolds.py --out DIR``."""
    return study_main(__doc__, "out/fig10_15", compute, argv, shown=("critical", "seconds"))


if __name__ == "__main__":
    raise SystemExit(main())
