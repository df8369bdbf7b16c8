"""Figs. 2-5 of Umeda (1999): fixed points against the autopilot course, Fn = 0.3248.

The two ``chi_c = 0`` fixed points of the uncoupled surge model (Brent's method on the
surge force, the paper's "regula falsi") are lifted to the 8-state model and traced
by pseudo-arclength continuation in ``chi_c`` from 0 to 50 deg
(:func:`ship_models.analysis.trace_in_chi_c`). Also traces both points in ``Fn`` at
``chi_c = 10 deg``.

Writes to ``--out`` (default ``out/fig02_05``):

- ``fig02_position.png``  xi_G/lambda against chi_c (paper Fig. 2)
- ``fig03_speed.png``     u/c and v/c against chi_c (paper Fig. 3)
- ``fig04_angles.png``    heading chi and rudder delta (deg) against chi_c (paper Fig. 4)
- ``fig05_roll.png``      roll phi (deg) against chi_c (paper Fig. 5)
- ``fixed_points_vs_fn.png`` xi_G/lambda and u/c against Fn at chi_c = 10 deg
- ``fixed_points_chi_c.csv``, ``fixed_points_fn.csv``: every branch row, all states
- ``branch_chi_c_<crest|trough>.npz`` (+ ``.json``): the branches (``Branch.load``)
- ``summary.json``

At a fixed point ``r = chi' = 0`` and ``p_roll = phi' = 0``; they are in the CSV but
not plotted. Run: ``python studies/fig02_05_fixed_points.py [--out DIR]``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ship_models.paper import PAPER_FN
from studies._common import (
    begin_step,
    finish_summary,
    new_figure,
    save_figure,
    save_table,
    study_main,
    write_atomic_group,
)

FN = PAPER_FN
CHI_C_DEG = 10.0
CHI_C_MAX_DEG = 50.0
COLORS = {"crest": "tab:red", "trough": "tab:blue"}


def _primary_end(br: Any) -> int:
    """Last row index before the first fold (the whole branch if none)."""
    folds = br.find("fold")
    return folds[0].index if folds else len(br) - 1


def _rows(br: Any, label: str, c: float, free: str) -> list[dict[str, Any]]:
    k_end = _primary_end(br)
    rows = []
    for k in range(len(br)):
        x = br.x[k]
        rows.append(
            {
                "branch": label,
                "segment": "primary" if k <= k_end else "past_fold",
                free: float(np.degrees(br.p[k])) if free == "chi_c_deg" else float(br.p[k]),
                "xi_G": float(np.mod(x[0], 1.0)),
                "u": float(x[1]),
                "u_over_c": float(x[1] / c),
                "v": float(x[2]),
                "v_over_c": float(x[2] / c),
                "chi_deg": float(np.degrees(x[3])),
                "r_deg_s": float(np.degrees(x[4])),
                "phi_deg": float(np.degrees(x[5])),
                "p_roll_deg_s": float(np.degrees(x[6])),
                "delta_deg": float(np.degrees(x[7])),
                "saddle_index": int(br.n_unstable[k]),
            }
        )
    return rows


def _write_csv(path: Path, rows: list[dict[str, Any]], meta: dict[str, Any]) -> None:
    header = list(rows[0])
    save_table(path, header, [[r[h] for h in header] for r in rows], meta=meta)


def _plot_vs_course(branches: dict[str, Any], c: float, out: Path) -> list[str]:
    """Figs. 2-5: one PNG per group of states, primary segments (up to a fold)."""
    specs = [
        (
            "fig02_position.png",
            "Fig. 2",
            [("xi_G", r"$\xi_G/\lambda$", lambda x: np.mod(x[:, 0], 1))],
        ),
        (
            "fig03_speed.png",
            "Fig. 3",
            [("u/c", "$u/c$", lambda x: x[:, 1] / c), ("v/c", "$v/c$", lambda x: x[:, 2] / c)],
        ),
        (
            "fig04_angles.png",
            "Fig. 4",
            [
                ("chi", r"heading $\chi$ (deg)", lambda x: np.degrees(x[:, 3])),
                ("delta", r"rudder $\delta$ (deg)", lambda x: np.degrees(x[:, 7])),
            ],
        ),
        (
            "fig05_roll.png",
            "Fig. 5",
            [("phi", r"roll $\phi$ (deg)", lambda x: np.degrees(x[:, 5]))],
        ),
    ]
    written = []
    for fname, tag, quantities in specs:
        fig = new_figure((6, 2.6 * len(quantities) + 1.0))
        axes = fig.subplots(len(quantities), 1, sharex=True, squeeze=False)
        for ax, (_, ylabel, fn) in zip(axes[:, 0], quantities, strict=True):
            for label, br in branches.items():
                k = _primary_end(br) + 1
                chi = np.degrees(br.p[:k])
                plot_by_stability(ax, chi, fn(br.x[:k]), br.n_unstable[:k], COLORS.get(label, "k"))
                for sp in br.find("fold")[:1]:
                    xs = np.asarray(sp.x)[None, :]
                    _mark_fold(ax, float(np.degrees(sp.p)), float(fn(xs)[0]))
            ax.set_ylabel(ylabel)
            ax.grid(alpha=0.3)
            lo, hi = ax.get_ylim()
            if lo < 0.0 < hi:
                ax.axhline(0.0, color="0.6", lw=0.6)
        axes[-1, 0].set_xlabel("autopilot course $\\chi_c$ (deg)")
        axes[0, 0].set_title(f"{tag}: fixed points for Fn = {FN} (our vessel)")
        axes[-1, 0].set_xlim(0, CHI_C_MAX_DEG)
        _legend(fig, branches)
        save_figure(fig, out / fname)
        written.append(fname)
    return written


def plot_by_stability(ax: Any, x: np.ndarray, y: np.ndarray, n_unstable: np.ndarray,
                      color: str) -> None:  # fmt: skip
    """Draw a branch solid where it is stable (saddle index 0), dashed where unstable."""
    unstable = np.asarray(n_unstable) > 0
    for flag, style in ((False, "-"), (True, "--")):
        yy = np.where(unstable == flag, y, np.nan)
        # join each run to its neighbour so the line has no gap at a change of stability
        edge = np.nonzero(np.diff(unstable.astype(int)) != 0)[0]
        for e in edge:
            if unstable[e] == flag:
                yy[e + 1] = y[e + 1]
            else:
                yy[e] = y[e]
        ax.plot(x, yy, style, color=color)


def _mark_fold(ax: Any, x: float, y: float) -> None:
    """Mark a fold; its label goes towards the inside of the axes (no overlap with the frame)."""
    ax.plot(x, y, "kx", ms=8)
    lo, hi = ax.get_ylim()
    below = y > 0.5 * (lo + hi)
    ax.annotate(f"fold {x:.1f} deg", (x, y), textcoords="offset points",
                xytext=(-8, -10 if below else 8), va="top" if below else "bottom",
                ha="right", fontsize=8)  # fmt: skip


def _legend(fig: Any, branches: dict[str, Any]) -> None:
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=COLORS.get(label, "k"), label=f"near the {label}")
               for label in branches]  # fmt: skip
    handles += [
        Line2D([], [], color="0.3", ls="-", label="stable"),
        Line2D([], [], color="0.3", ls="--", label="unstable (saddle index >= 1)"),
    ]
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=7, frameon=False)


def compute(out: Path, progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Trace the fixed points, write figures and data into ``out``; return a summary."""
    from ship_models.analysis import find_fixed_point, trace_in_chi_c, trace_in_fn
    from studies._model import default_model

    say, t0 = begin_step(out, progress)
    model = default_model()  # one per process (shared by the steps it runs)
    params = model.default_params().replace(Fn=FN, chi_c=math.radians(CHI_C_DEG))
    c = model.celerity(params)
    say("tracing the chi_c = 0 fixed points in chi_c from 0 to 50 deg")
    branches = trace_in_chi_c(model, params, chi_c_max=math.radians(CHI_C_MAX_DEG))
    rows: list[dict[str, Any]] = []
    for label, br in branches.items():
        write_atomic_group(out, lambda d, b=br, n=label: b.save(d / f"branch_chi_c_{n}.npz"))
        rows += _rows(br, label, c, "chi_c_deg")
    meta = {
        "study": "Umeda (1999) Figs. 2-5, default vessel",
        "units": "u, v m/s; angles deg, rates deg/s; xi_G = xi_G/lambda in [0, 1)",
        "params": json.dumps(params.as_dict()),
        "celerity_m_s": c,
    }
    _write_csv(out / "fixed_points_chi_c.csv", rows, meta)
    figures = _plot_vs_course(branches, c, out)

    say("tracing both fixed points in Fn at chi_c = 10 deg")
    fn_rows: list[dict[str, Any]] = []
    fig = new_figure((6, 6.0))
    axes = fig.subplots(2, 1, sharex=True)
    fn_branches = {}
    for label in ("crest", "trough"):
        fp = find_fixed_point(model, params, label)
        br = trace_in_fn(model, fp.x, params, fn_min=0.05, fn_max=0.48)
        fn_branches[label] = br
        fn_rows += _rows(br, label, c, "Fn")
        for ax, y in zip(axes, (np.mod(br.state("xi_G"), 1), br.state("u") / c), strict=True):
            plot_by_stability(ax, br.p, y, br.n_unstable, COLORS[label])
    _write_csv(out / "fixed_points_fn.csv", fn_rows, meta)
    axes[0].set_ylabel(r"$\xi_G/\lambda$")
    axes[1].set_ylabel("$u/c$")
    axes[1].set_xlabel("nominal Froude number Fn")
    axes[0].set_title(f"fixed points for $\\chi_c$ = {CHI_C_DEG:g} deg against Fn (our vessel)")
    _legend(fig, fn_branches)
    for ax in axes:
        ax.grid(alpha=0.3)
    save_figure(fig, out / "fixed_points_vs_fn.png")
    figures.append("fixed_points_vs_fn.png")

    summary: dict[str, Any] = {"Fn": FN, "figures": figures, "branches": {}}
    for label, br in branches.items():
        k = _primary_end(br)
        folds = br.find("fold")
        summary["branches"][label] = {
            "start_xi_G": float(br.x[0, 0]),
            "start_u_over_c": float(br.x[0, 1] / c),
            "status": br.status.name,
            "first_fold_chi_c_deg": float(np.degrees(folds[0].p)) if folds else None,
            "primary_end_chi_c_deg": float(np.degrees(br.p[k])),
            "saddle_index_primary": sorted({int(s) for s in br.n_unstable[1 : k + 1]}),
            "chi_sign_primary": float(np.sign(np.median(br.state("chi")[1 : k + 1]))),
            "delta_sign_primary": float(np.sign(np.median(br.state("delta")[1 : k + 1]))),
        }
    summary["fn_branches"] = {
        label: {
            "Fn_range": [float(br.p.min()), float(br.p.max())],
            "saddle_index": sorted({int(s) for s in br.n_unstable}),
            "folds_Fn": [float(sp.p) for sp in br.find("fold")],
        }
        for label, br in fn_branches.items()
    }
    return finish_summary(out, summary, t0)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: ``python studies/fig02_05_fixed_points.py --out DIR``."""
    return study_main(__doc__, "out/fig02_05", compute, argv)


if __name__ == "__main__":
    raise SystemExit(main())
