"""More targets from the paper than one number: what the OCR of its figures gives, beside ours.

The paper's figures survive in the OCR text only as axis tick labels, captions and a
few words (/work/shared/paper/); no curve or data point is readable. So the targets
here are the FRAMES of the figures (the plotted ranges the author chose, which
enclose his curves) and the numbers of the text, each with how it was read and what
it does not say:

========  =====================================================  ==================================
figure    OCR gives                                              target (uncertainty)
========  =====================================================  ==================================
text      Fn* between 0.3247 and 0.3248 at chi_c = 10 deg        Fn*(10 deg) = 0.32475 +- 0.00005
Fig. 23   ordinate 0.30 ... 0.34 (ticks 0.3, .31, .32, .33,      heteroclinic Fn* inside [0.30,
          0.34), abscissa 0 ... 30 deg "auto pilot course"       0.34] for 0 <= chi_c <= 30 deg
                                                                 (the frame; points unreadable)
Figs 2-4  abscissa 0 ... 50 deg; Fig. 3 ordinate 0 ... 1.6,      fixed points drawn to 50 deg at
          Fn = 0.3248                                            Fn = 0.3248 (the frame: not
                                                                 proof that the curves reach 50);
                                                                 if Fig. 3 is u/c (unlabelled),
                                                                 1/cos 50 deg = 1.56 < 1.6 fits
Fig. 21   ordinate 1.3 and 0.35, abscissa -0.5 ... 0             IF the ordinate is u/c (OCR has
          "nondimensional longitudinal position", Fn 0.3248      no label): the manifold's final
                                                                 stage on the downslope has
                                                                 0.35 <= u/c <= 1.3
Figs 6-7  real part -10 ... 2, imaginary about -6 ... 6          eigenvalues (t' = t c/L) inside
          (Fn 0.3248, chi_c 10 deg)                              the frame
Fig. 22   ordinate 0.320 ... 0.330, "Heteroclinic bifurcation"   the experiments' boundary within
                                                                 [0.320, 0.330], below 0.3248
========  =====================================================  ==================================

Figs. 10-12, 17, 18, 20 give only abscissa ranges of trajectories (xi_G/lambda -0.6 to 1,
heading 0-60 deg, xi_G/lambda -3.5 to 0.5, t' 20-30); these are listed in the CSV
as ranges, not compared (what is plotted against them is not readable).

Writes ``paper_targets.csv`` (one row per target: figure, quantity, paper range,
ours, verdict, how read) and ``paper_targets.png`` (four panels: the critical curve
in Fig. 23's frame, the crest and trough branches in Fig. 3's frame, the manifold's
u/c in Fig. 21's frame, the eigenvalues in Figs. 6-7's frame) to ``--out`` (default
``out/paper_targets``).

Run: ``python studies/paper_targets.py [--out DIR] [--vessel NAME_OR_PATH]``.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

#: Frames read from the OCR: (name, figure, (x_lo, x_hi), (y_lo, y_hi), how read).
FRAMES: dict[str, tuple[str, tuple[float, float], tuple[float, float], str]] = {
    "fig23": ("Fig. 23", (0.0, 30.0), (0.30, 0.34),
              "tick labels 0.3, 31, 32, 33, 0.34 and 0-30 'auto pilot course (degrees)'"),
    "fig3": ("Figs. 2-4", (0.0, 50.0), (0.0, 1.6),
             "Fig. 3 ticks 0, 0.4, 0.8, 1.2, 1.6; abscissa 0-50 deg; ordinate unlabelled"),
    "fig21": ("Fig. 21", (-0.5, 0.0), (0.35, 1.3),
              "two ordinate labels 1.3 and 0.35 (unlabelled); abscissa -0.5..0 "
              "'nondimensional longitudinal position'"),
    "fig6": ("Figs. 6-7", (-10.0, 2.0), (-6.0, 6.0),
             "'Real part of eigenvalue' -10..2; imaginary ticks about -6..6 (partly garbled)"),
}  # fmt: skip

#: Abscissa ranges of trajectory figures (listed, not compared).
RANGES_ONLY = (
    ("Figs. 10, 12", "xi_G/lambda", -0.6, 1.0),
    ("Figs. 11, 15", "heading (deg)", 0.0, 60.0),
    ("Fig. 17", "xi_G/lambda", -3.5, 0.5),
    ("Fig. 18", "heading (deg)", 0.0, 70.0),
    ("Fig. 20", "t c / L", 20.0, 30.0),
    ("Fig. 22", "Fn", 0.320, 0.330),
)

PAPER_FN = 0.3248
PAPER_FN_CRIT = (0.3247, 0.3248)


def compute(vessel: str = "purse_seiner") -> dict[str, Any]:
    """Our numbers for every target (see module doc)."""
    from ship_models import Umeda4DOF
    from ship_models.analysis import critical_fn, fixed_points, unstable_manifold
    from ship_models.analysis.critical_curve import critical_curve
    from ship_models.analysis.fixed_points import trace_in_chi_c

    m = Umeda4DOF(vessel)
    p = m.default_params().replace(Fn=PAPER_FN, chi_c=math.radians(10.0))
    c = m.celerity(p)
    out: dict[str, Any] = {"vessel": m.vessel.name}
    crit = critical_fn(m, p, method="bisection", tol=1e-5)
    out["Fn_crit_10"] = (float(crit.Fn), float(crit.error))
    cc = critical_curve(np.radians(np.arange(0.0, 31.0, 1.0)), model=m)
    out["curve"] = (np.degrees(np.asarray(cc.chi_c)), np.asarray(cc.Fn, float),
                    np.asarray(cc.exists, bool))  # fmt: skip
    branches = trace_in_chi_c(m, p, chi_c_max=math.radians(60.0))
    out["branches"] = {}
    for name, br in branches.items():
        x = np.asarray(br.x)
        out["branches"][name] = (np.degrees(np.asarray(br.p)), x[:, 1] / c)
        folds = br.find("fold")
        out[f"fold_{name}"] = math.degrees(float(folds[0].p)) if folds else math.nan
    pts = fixed_points(m, p)
    # the paper's two points (a strongly heeled extra crest-side point is labelled crest-2)
    out["eigen"] = {pt.label: np.asarray(pt.eigen.values_nondim) for pt in pts
                    if pt.label in ("crest", "trough")}  # fmt: skip
    man = unstable_manifold(m, p, "crest", points=pts, t_max=1500.0)
    xs, us = [], []
    for br in man.branches.values():
        x = np.asarray(br.trajectory.x)
        xi = np.mod(x[:, 0], 1.0)
        sel = xi >= 0.5  # the downslope: xi_G/lambda in (-0.5, 0) modulo 1
        xs.append(xi[sel] - 1.0)
        us.append(x[sel, 1] / c)
    out["manifold"] = (np.concatenate(xs), np.concatenate(us))
    return out


def _row(
    figure: str, quantity: str, paper: str, ours: str, verdict: str, how: str
) -> dict[str, str]:
    return {"figure": figure, "quantity": quantity, "paper": paper, "ours": ours,
            "verdict": verdict, "how_read": how}  # fmt: skip


def targets(res: dict[str, Any]) -> list[dict[str, Any]]:
    """Rows of the comparison table."""
    rows: list[dict[str, Any]] = []
    fn, err = res["Fn_crit_10"]
    inside = PAPER_FN_CRIT[0] - 5e-5 <= fn <= PAPER_FN_CRIT[1] + 5e-5
    rows.append(_row("text", "Fn* at chi_c = 10 deg", "0.3247-0.3248", f"{fn:.5f} +- {err:.1e}",
                     "agrees" if inside else "differs",
                     "text: 'between Fn = 0.3247 and Fn = 0.3248'"))  # fmt: skip
    chi, F, ex = res["curve"]
    ok = ex & (chi <= 30.0 + 1e-9)
    lo, hi = (float(np.min(F[ok])), float(np.max(F[ok]))) if ok.any() else (math.nan, math.nan)
    rows.append(_row("Fig. 23", "Fn* over chi_c 0-30 deg", "in [0.30, 0.34]", f"{lo:.4f}-{hi:.4f}",
                     "agrees" if 0.30 <= lo and hi <= 0.34 else "differs",
                     FRAMES["fig23"][3]))  # fmt: skip
    fold = res.get("fold_crest", math.nan)
    rows.append(_row("Figs. 2-4", "crest fixed point traced to 50 deg at Fn 0.3248",
                     "drawn to 50 deg (frame)", f"folds at {fold:.2f} deg",
                     "agrees" if not fold < 50.0 else "differs", FRAMES["fig3"][3]))  # fmt: skip
    xs, us = res["manifold"]
    umin, umax = (float(us.min()), float(us.max())) if us.size else (math.nan, math.nan)
    rows.append(_row("Fig. 21", "u/c of the crest manifold on the downslope (IF u/c)",
                     "0.35-1.3 (frame)", f"{umin:.3f}-{umax:.3f}",
                     "agrees" if 0.35 <= umin and umax <= 1.3 else "differs (if u/c)",
                     FRAMES["fig21"][3]))  # fmt: skip
    for label, ev in sorted(res["eigen"].items()):
        rmin, rmax = float(ev.real.min()), float(ev.real.max())
        imax = float(np.abs(ev.imag).max())
        okf = -10.0 <= rmin and rmax <= 2.0 and imax <= 6.0
        rows.append(_row("Figs. 6-7", f"eigenvalues (t' = t c/L), {label}",
                         "Re in [-10, 2], |Im| <= 6 (frame)",
                         f"Re {rmin:.2f}..{rmax:.3f}, |Im| <= {imax:.2f}",
                         "agrees" if okf else "differs", FRAMES["fig6"][3]))  # fmt: skip
    for fig, q, a, b in RANGES_ONLY:
        rows.append(_row(fig, f"{q} range of the plot", f"{a:g} to {b:g}", "", "not compared",
                         "abscissa ticks"))  # fmt: skip
    return rows


def plot(res: dict[str, Any], path: Path) -> None:
    """Four panels, each our result in the paper figure's frame (grey box)."""
    from studies._common import new_figure, save_figure

    fig = new_figure((10.0, 7.5))
    ax = fig.subplots(2, 2).ravel()

    def frame(a: Any, key: str) -> None:
        _, (x0, x1), (y0, y1), _ = FRAMES[key]
        a.add_patch(__import__("matplotlib.patches", fromlist=["Rectangle"]).Rectangle(
            (x0, y0), x1 - x0, y1 - y0, fill=True, alpha=0.12, color="grey",
            label=f"frame of {FRAMES[key][0]}"))  # fmt: skip

    chi, F, ex = res["curve"]
    frame(ax[0], "fig23")
    ax[0].plot(chi[ex], F[ex], "o-", ms=3, label="ours (connecting orbit)")
    ax[0].errorbar([10.0], [0.32475], yerr=[5e-5], fmt="s", color="k", label="paper, 10 deg")
    ax[0].set(xlabel="autopilot course chi_c (deg)", ylabel="critical Fn", title="Fig. 23")
    ax[0].legend()
    frame(ax[1], "fig3")
    for name, (ch, uc) in res["branches"].items():
        ax[1].plot(ch, uc, label=name)
    fold = res.get("fold_crest", math.nan)
    ax[1].set(xlabel="chi_c (deg)", ylabel="u/c (if Fig. 3 is u/c)",
              title=f"Figs. 2-4, Fn {PAPER_FN}: crest fold {fold:.2f} deg")  # fmt: skip
    ax[1].legend()
    xs, us = res["manifold"]
    frame(ax[2], "fig21")
    ax[2].plot(xs, us, ".", ms=2, label="crest manifold, downslope part")
    ax[2].set(xlabel="xi_G/lambda", ylabel="u/c (if Fig. 21 is u/c)", title="Fig. 21, Fn 0.3248")
    ax[2].legend()
    frame(ax[3], "fig6")
    for label, ev in sorted(res["eigen"].items()):
        ax[3].plot(ev.real, ev.imag, "o", label=label)
    ax[3].set(xlabel="Re (t' = t c/L)", ylabel="Im", title="Figs. 6-7, chi_c 10 deg")
    ax[3].legend()
    save_figure(fig, path)


def main(argv: list[str] | None = None) -> int:
    """Command line."""
    from studies._common import output_dir, save_table

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=None, help="output root (default ./out)")
    ap.add_argument("--vessel", default="purse_seiner", help="vessel name or file")
    a = ap.parse_args(argv)
    out = output_dir("paper_targets", a.out)
    res = compute(a.vessel)
    rows = targets(res)
    cols = ["figure", "quantity", "paper", "ours", "verdict", "how_read"]
    save_table(out / "paper_targets.csv", cols, [[r[k] for k in cols] for r in rows])
    plot(res, out / "paper_targets.png")
    for r in rows:
        sys.stdout.write(" | ".join(str(r[k]) for k in cols[:5]) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
