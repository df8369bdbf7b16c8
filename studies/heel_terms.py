"""Heel-induced forces Y_phi, N_phi, K_phi (Umeda 1999 Eqs. 6, 8, 10): their effect.

The paper's model has the heel-induced hydrodynamic sway force, yaw and roll moments
(``Y_phi(u) phi``, ``N_phi(u) phi``, ``K_phi(u) phi``), measured for its ship by
circular-motion tests (its refs. 2, 14). No regression of them for this hull form
could be read here from a citable text (neither the paper's refs. 22-25 nor one for
fishing vessels), so the default vessel keeps them at zero (status ``assumed``; the one
cited analogy estimate readable here, Son & Nomoto's 1981 ratios, is an option compared
in ``studies/heel_estimate.py``) and this study measures how much they could matter: each prime
(``Y'_phi = Y_phi / (rho/2 L d u^2)``, ``N'_phi = N_phi / (rho/2 L^2 d u^2)``,
``K'_phi = K_phi / (rho/2 L d^2 u^2)``, as in ``ship_models.vessel.SCHEMA``) is set
to each value of a symmetric grid and

- the fold of the crest fixed-point branch in chi_c at the paper's Fn = 0.3248
  (Figs. 2-5; 43.56 deg with the heel terms at zero),
- the critical Fn at chi_c = 10 deg (bisection of the upslope manifold's fate),
- the critical curve's end (its fold in chi_c) and its value at 0, 10, 20, 30 deg

are recomputed. The grid (|Y'_phi|, |N'_phi| up to 0.05, |K'_phi| up to 0.02) is
a range for a sensitivity study, NOT an estimate: about a tenth of |Y'_v| = 0.46,
the hull's sway derivative (Inoue et al. 1981), for the sway force.

Result (2026-12-04, default vessel; ``out/heel_terms``): the critical Fn at 10 deg
moves by at most 1e-4 over the grid (0.30152-0.30169 against 0.30161; dFn*/dY'_phi =
-0.0016, dFn*/dN'_phi = +0.0011 by the adjoint, ``broachkit sensitivity``), but the
crest fold at Fn 0.3248 moves from 43.56 deg to 34.6 (N'_phi = -0.05) ... 53.9 deg
(+0.05) and the critical curve's end from 38.97 deg to 33.5 ... 49.6 deg; Y'_phi moves
them by about 1 deg. K'_phi alone changes nothing: with Y_phi = N_phi = 0 no equation
but roll's depends on phi (roll is one-way coupled, tested), which is also why GM,
T_phi and the roll damping have no elasticity in the default vessel.

Writes ``heel_terms.csv`` (one row per case) and ``heel_terms.png`` (the three
quantities against each prime) to ``--out`` (default ``out/heel_terms``).

Run: ``python studies/heel_terms.py [--out DIR] [--quick]``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

#: (prime, values) of the parametric grid (not estimates; see module doc).
GRID: dict[str, tuple[float, ...]] = {
    "hydrodynamics.Y_phi_prime": (-0.05, -0.025, 0.025, 0.05),
    "hydrodynamics.N_phi_prime": (-0.05, -0.025, 0.025, 0.05),
    "hydrodynamics.K_phi_prime": (-0.02, -0.01, 0.01, 0.02),
}
CURVE_COURSES_DEG = (0.0, 10.0, 20.0, 30.0)


def crest_fold_deg(model: Any, Fn: float) -> float:
    """chi_c (deg) of the first fold of the crest branch traced from chi_c = 0 (nan if none)."""
    from ship_models.analysis.fixed_points import trace_in_chi_c

    p = model.default_params().replace(Fn=Fn)
    branches = trace_in_chi_c(model, p, chi_c_max=math.radians(60.0))
    br = branches["crest"]
    folds = br.find("fold")
    return math.degrees(float(folds[0].p)) if folds else float("nan")


def evaluate_case(overrides: dict[str, float], *, curve: bool = True) -> dict[str, float]:
    """Crest fold, critical Fn at 10 deg and the critical curve for one set of primes."""
    from ship_models import Umeda4DOF
    from ship_models.analysis.critical import critical_fn
    from ship_models.analysis.critical_curve import critical_curve
    from ship_models.paper import PAPER_FN
    from ship_models.vessel import Coefficient, load_vessel

    v = load_vessel("purse_seiner")
    if overrides:
        v = v.with_overrides(
            {
                k: Coefficient(
                    val, "-", "parametric study (studies/heel_terms.py), not an estimate", "assumed"
                )
                for k, val in overrides.items()
            }  # fmt: skip
        )
    m = Umeda4DOF(v)
    row: dict[str, float] = {k.split(".")[1]: overrides.get(k, 0.0) for k in GRID}
    row["crest_fold_deg"] = crest_fold_deg(m, PAPER_FN)
    crit = critical_fn(m, chi_c=math.radians(10.0), method="bisection", tol=1e-5)
    row["Fn_crit_10"] = float(crit.Fn)
    row["Fn_crit_10_error"] = float(crit.error)
    if curve:
        cc = critical_curve(np.radians(np.arange(0.0, 51.0, 1.0)), model=m)
        row["curve_end_deg"] = math.degrees(float(cc.end_chi_c))
        row["curve_end_Fn"] = float(cc.end_Fn)
        chi = np.degrees(np.asarray(cc.chi_c))
        for c in CURVE_COURSES_DEG:
            i = int(np.argmin(np.abs(chi - c)))
            ok = bool(cc.exists[i]) and abs(chi[i] - c) < 1e-9
            row[f"curve_Fn_{int(c)}"] = float(cc.Fn[i]) if ok else float("nan")
    return row


def run(out: Path, *, quick: bool = False) -> list[dict[str, float]]:
    """All cases (the zero case first); ``quick``: only the extreme values, no curves."""
    from studies._common import new_figure, save_csv, save_figure

    rows = [evaluate_case({}, curve=not quick)]
    for key, values in GRID.items():
        for val in values if not quick else (values[0], values[-1]):
            rows.append(evaluate_case({key: val}, curve=not quick))
    cols = {k: np.array([r.get(k, np.nan) for r in rows]) for k in rows[0]}
    save_csv(
        out / "heel_terms.csv",
        cols,
        meta={"study": "heel-induced derivatives, parametric (not estimates)", "Fn_fold": 0.3248},
    )
    fig = new_figure((10.0, 3.2))
    axes = fig.subplots(1, 3)
    base = rows[0]
    for ax, (qty, label) in zip(
        axes,
        (("crest_fold_deg", "crest-branch fold chi_c (deg), Fn 0.3248"),
         ("Fn_crit_10", "critical Fn at chi_c = 10 deg"),
         ("curve_end_deg", "critical-curve fold chi_c (deg)")),
        strict=True,
    ):  # fmt: skip
        for key in GRID:
            name = key.split(".")[1]
            sel = [base] + [r for r in rows[1:] if r[name] != 0.0]
            x = np.array([r[name] for r in sel])
            y = np.array([r.get(qty, np.nan) for r in sel])
            order = np.argsort(x)
            ax.plot(x[order], y[order], "o-", label=name.replace("_prime", "'"))
        ax.set_xlabel("heel derivative (prime)")
        ax.set_title(label)
    axes[0].legend()
    save_figure(fig, out / "heel_terms.png")
    return rows


def main(argv: list[str] | None = None) -> int:
    """Command line: ``--out DIR``, ``--quick``."""
    from studies._common import rows_main

    return rows_main(__doc__, "heel_terms", run, argv, quick_help="extreme values only, no curves")


if __name__ == "__main__":
    raise SystemExit(main())
