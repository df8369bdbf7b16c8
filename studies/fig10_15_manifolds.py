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

Planes as in the paper: xi_G/lambda vs u/c (Figs. 10, 14), heading vs u/c (Figs. 11,
15), roll vs heading (Fig. 12), roll vs rudder (Fig. 13); both sides of the switch get
all four planes.

Writes to ``--out`` (default ``out/fig10_15``): ``fig10_..fig15_*.png``,
``manifold_<case>_<branch>.csv`` (time series), ``critical.json``, ``summary.json``.
Run: ``python studies/fig10_15_manifolds.py [--out DIR]``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

if __package__ in (None, ""):  # run as a script: make the `studies` package importable
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from studies._common import new_figure, save_csv, save_figure, write_json

CHI_C_DEG = 10.0
PAPER_FN = 0.3248
#: Width of the Fn search below the first-passage bracket for the final-fate switch.
FINAL_SEARCH_WIDTH = 1e-3
COLORS = {"downslope": "tab:red", "upslope": "tab:blue"}
STYLES = {"downslope": "-", "upslope": "--"}
#: The paper's planes: (file tag, x quantity, y quantity).
PLANES = (
    ("position", "xi", "u_c"),
    ("heading", "chi", "u_c"),
    ("roll_heading", "phi", "chi"),
    ("roll_rudder", "phi", "delta"),
)
LABELS = {
    "xi": r"$\xi_G/\lambda$ (unwrapped)",
    "u_c": "$u/c$",
    "chi": r"heading $\chi$ (deg)",
    "phi": r"roll $\phi$ (deg)",
    "delta": r"rudder $\delta$ (deg)",
}


def _quantities(x: np.ndarray, c: float) -> dict[str, np.ndarray]:
    return {
        "xi": x[:, 0],
        "u_c": x[:, 1] / c,
        "chi": np.degrees(x[:, 3]),
        "phi": np.degrees(x[:, 5]),
        "delta": np.degrees(x[:, 7]),
    }


def _visible(traj: Any, xi_s: float) -> np.ndarray:
    """Samples to draw: stop two and a half waves behind the saddle (surging goes on)."""
    xi = traj.x[:, 0]
    beyond = np.nonzero(xi < xi_s - 2.5)[0]
    k = int(beyond[0]) if beyond.size else xi.size
    return np.arange(k)


def _plot_case(man: Any, c: float, out: Path, numbers: dict[str, str], title: str) -> list[str]:
    """One PNG per plane for one Fn; ``numbers`` maps plane tag -> paper figure number."""
    written = []
    sp = man.saddle
    for tag, qx, qy in PLANES:
        fig = new_figure((6.0, 4.4))
        ax = fig.subplots()
        for name, br in man.branches.items():
            sel = _visible(br.trajectory, sp.x[0])
            q = _quantities(br.trajectory.x[sel], c)
            ax.plot(
                q[qx],
                q[qy],
                STYLES[name],
                color=COLORS[name],
                lw=1.6 if name == "downslope" else 1.1,
                label=f"{name}: {br.fate.label}",
            )
            if br.fate.kind == "capsize":
                ax.plot(q[qx][-1], q[qy][-1], "x", color=COLORS[name], ms=9)
        for fp in man.points:
            if fp.saddle_index > 1:
                continue
            for shift in (0, -1, -2) if qx == "xi" else (0,):
                x = np.array(fp.x)
                x[0] += shift
                q = _quantities(x[None, :], c)
                marker = "o" if fp.label == sp.label else "s"
                ax.plot(q[qx], q[qy], marker, mfc="none", color="k", ms=7)
                if shift == 0 or fp.label == sp.label:
                    lab = fp.label if shift == 0 else f"{fp.label}@{shift:+d}"
                    ax.annotate(
                        lab,
                        (q[qx][0], q[qy][0]),
                        textcoords="offset points",
                        xytext=(5, 5),
                        fontsize=7,
                    )
        ax.set_xlabel(LABELS[qx])
        ax.set_ylabel(LABELS[qy])
        ax.set_title(f"Fig. {numbers[tag]}: {title}" if tag in numbers else title)
        ax.legend(loc="best")
        name = (f"fig{int(numbers[tag]):02d}_" if tag in numbers else "extra_") + (
            f"{tag}_Fn{man.params['Fn']:.6f}.png"
        )
        save_figure(fig, out / name)
        written.append(name)
    return written


def _save_series(man: Any, c: float, out: Path, case: str) -> list[str]:
    files = []
    for name, br in man.branches.items():
        tr = br.trajectory
        q = _quantities(np.asarray(tr.x), c)
        cols = {"t": tr.t}
        cols.update({n: tr.x[:, i] for i, n in enumerate(tr.state_names)})
        cols.update(
            {
                "u_over_c": q["u_c"],
                "chi_deg": q["chi"],
                "phi_deg": q["phi"],
                "delta_deg": q["delta"],
            }
        )
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
                "units": "t s; xi_G = xi_G/lambda unwrapped; u, v m/s; angles rad (and deg cols)",
            },
        )
        files.append(fname)
    return files


def compute(out: Path, progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Bisection for the critical Fn, manifolds on both sides; figures and data in ``out``."""
    from ship_models import purse_seiner
    from ship_models.analysis import (
        build_global_picture,
        critical_fn,
        fixed_points,
        unstable_manifold,
    )
    from ship_models.analysis.global_picture import compare_pictures

    say = progress or (lambda msg: None)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    model = purse_seiner()
    base = model.default_params().replace(chi_c=math.radians(CHI_C_DEG))
    c = model.celerity(base)
    say(f"bisection of Fn on the upslope branch's first passage (chi_c = {CHI_C_DEG:g} deg)")
    crit = critical_fn(
        model,
        base["chi_c"],
        tol=1e-5,
        progress=lambda e: say(f"  Fn = {e.Fn:.7f}: {e.outcome or 'undecided'}"),
    )
    write_json(out / "critical.json", crit.to_json())
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
        base["chi_c"],
        fn_bracket=(lo - FINAL_SEARCH_WIDTH, lo),
        tol=1e-6,
        criterion="final",
        progress=lambda e: say(f"  Fn = {e.Fn:.7f}: {e.outcome or 'undecided'}"),
    )
    write_json(out / "critical_final_fate.json", final.to_json())
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
    for case, fn in cases.items():
        say(f"unstable manifold of the crest saddle at Fn = {fn:.7f} ({case})")
        p = base.replace(Fn=fn)
        pts = fixed_points(model, p)
        man = unstable_manifold(model, p, "crest", points=pts, t_max=1500.0)
        mans[case] = man
        if case == "above":
            nums = {"position": "10", "heading": "11", "roll_heading": "12", "roll_rudder": "13"}
            title = f"Fn = {fn:.6f} (just above critical), $\\chi_c$ = {CHI_C_DEG:g} deg"
        elif case == "below":
            nums = {"position": "14", "heading": "15"}
            title = f"Fn = {fn:.6f} (just below critical), $\\chi_c$ = {CHI_C_DEG:g} deg"
        else:
            nums = {}
            title = f"Fn = {fn} (the paper's value), $\\chi_c$ = {CHI_C_DEG:g} deg"
        figures += _plot_case(man, c, out, nums, title)
        data += _save_series(man, c, out, case)
        summary["cases"][case] = {"Fn": fn, **man.to_json()}
    say("global picture at the 'below' and 'above' cases")
    g_lo = build_global_picture(model, base.replace(Fn=cases["below"]), t_max=1500.0)
    g_hi = build_global_picture(model, base.replace(Fn=cases["above"]), t_max=1500.0)
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
    summary["seconds"] = round(time.perf_counter() - t0, 2)
    write_json(out / "summary.json", summary, default=str)
    return summary


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: ``python studies/fig10_15_manifolds.py --out DIR``."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out/fig10_15"))
    args = ap.parse_args(argv)
    s = compute(args.out, progress=lambda m: print(m, flush=True))
    print(json.dumps({k: s[k] for k in ("critical", "seconds")}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
