"""Figs. 6-9 of Umeda (1999): eigenvalues and unstable eigenvectors, Fn = 0.3248, chi_c = 10 deg.

Both fixed points (near the crest and near the trough) are found by
:func:`ship_models.analysis.fixed_points` and linearised with the exact CasADi
Jacobian. As in the paper, eigenvalues are in the nondimensional time
``t' = t c / L`` and eigenvector components in the nondimensional states
``(xi_G/lambda, u/c, v/c, chi, r L/U, phi, p L/U, delta)``
(:mod:`ship_models.analysis.eigen`), numbered 1-8 as in the paper's Eq. (1).

Writes to ``--out`` (default ``out/fig06_09``):

- ``fig06_eigenvalues_crest.png``, ``fig07_eigenvalues_trough.png`` (complex plane)
- ``fig08_eigenvector_crest.png``, ``fig09_eigenvector_trough.png`` (bar charts)
- ``eigenvalues.csv`` (both points, dimensional and nondimensional),
  ``eigenvectors.csv`` (unstable eigenvector, nondimensional, max-norm 1)
- ``summary.json`` (saddle indices, dominant components and motions)

Run: ``python studies/fig06_09_eigen.py [--out DIR]``.
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
)

FN = PAPER_FN
CHI_C_DEG = 10.0
LABELS = ("xi_G/lambda", "u'", "v'", "chi", "r'", "phi", "p'", "delta")


def compute(out: Path, progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Compute the eigen-structure of both fixed points; write figures and data."""
    from ship_models.analysis import fixed_points
    from studies._model import default_model

    say, t0 = begin_step(out, progress)
    model = default_model()  # one per process (shared by the steps it runs)
    params = model.default_params().replace(Fn=FN, chi_c=math.radians(CHI_C_DEG))
    say(f"fixed points and their eigen-structure at Fn = {FN}, chi_c = {CHI_C_DEG:g} deg")
    pts = {fp.label: fp for fp in fixed_points(model, params)}
    ev_rows, vec_rows, figures = [], [], []
    summary: dict[str, Any] = {"Fn": FN, "chi_c_deg": CHI_C_DEG, "points": {}}
    fig_no = {"crest": (6, 8), "trough": (7, 9)}
    for label in ("crest", "trough"):
        fp = pts[label]
        es = fp.eigen
        for lam, lam_n in zip(es.values, es.values_nondim, strict=True):
            ev_rows.append(
                {
                    "point": label,
                    "re": float(lam.real),
                    "im": float(lam.imag),
                    "re_nondim": float(lam_n.real),
                    "im_nondim": float(lam_n.imag),
                }
            )
        vec = es.unstable_vector(0)
        for i, (name, comp) in enumerate(zip(es.state_names, vec, strict=True), 1):
            vec_rows.append({"point": label, "component": i, "state": name, "value": float(comp)})
        n_val, n_vec = fig_no[label]
        # eigenvalues in the complex plane (paper Figs. 6-7)
        fig = new_figure((5.2, 4.2))
        ax = fig.subplots()
        z = es.values_nondim
        unstable = z.real > 0
        ax.plot(z.real[~unstable], z.imag[~unstable], "o", color="tab:blue", label="Re < 0")
        ax.plot(z.real[unstable], z.imag[unstable], "s", color="tab:red", label="Re > 0")
        ax.axvline(0, color="0.5", lw=0.8)
        ax.axhline(0, color="0.5", lw=0.8)
        ax.set_xlabel(r"real part of eigenvalue ($t' = t c/L$)")
        ax.set_ylabel("imaginary part of eigenvalue")
        ax.set_title(
            f"Fig. {n_val}: eigenvalues near the wave {label}\n"
            f"Fn = {FN}, $\\chi_c$ = {CHI_C_DEG:g} deg, saddle index {es.saddle_index}"
        )
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
        name = f"fig{n_val:02d}_eigenvalues_{label}.png"
        save_figure(fig, out / name)
        figures.append(name)
        # unstable eigenvector components (paper Figs. 8-9)
        fig = new_figure((5.2, 3.8))
        ax = fig.subplots()
        ax.bar(np.arange(1, 9), vec, color=["tab:red" if abs(c) >= 0.5 else "0.6" for c in vec])
        ax.set_xticks(np.arange(1, 9))
        ax.set_xticklabels([f"{i}\n{lab}" for i, lab in enumerate(LABELS, 1)], fontsize=7)
        ax.axhline(0, color="k", lw=0.6)
        ax.set_ylim(-1.1, 1.1)
        ax.set_ylabel("component (nondimensional, max-norm 1)")
        ax.set_title(
            f"Fig. {n_vec}: unstable eigenvector near the wave {label}\n"
            f"eigenvalue {es.values_nondim[0].real:.3f} (nondim.)"
        )
        ax.grid(alpha=0.3, axis="y")
        name = f"fig{n_vec:02d}_eigenvector_{label}.png"
        save_figure(fig, out / name)
        figures.append(name)
        summary["points"][label] = {
            "x": [float(v) for v in fp.x],
            "saddle_index": es.saddle_index,
            "unstable_eigenvalue": float(es.values[0].real),
            "unstable_eigenvalue_nondim": float(es.values_nondim[0].real),
            "eigenvalues_nondim": [[float(v.real), float(v.imag)] for v in z],
            "unstable_eigenvector_nondim": [float(v) for v in vec],
            "dominant_components": list(es.dominant_components()),
            "motion_weights": es.motion_weights(),
            "dominant_motions": list(es.dominant_motions()),
        }
    meta = {
        "study": "Umeda (1999) Figs. 6-9, default vessel",
        "params": json.dumps(params.as_dict()),
        "nondim": "t' = t c/L; states (xi_G/lambda, u/c, v/c, chi, r L/U, phi, p L/U, delta)",
    }
    for fname, rows in (("eigenvalues.csv", ev_rows), ("eigenvectors.csv", vec_rows)):
        header = list(rows[0])
        save_table(out / fname, header, [[r[h] for h in header] for r in rows], meta=meta)
    summary["figures"] = figures
    return finish_summary(out, summary, t0)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: ``python studies/fig06_09_eigen.py --out DIR``."""
    return study_main(__doc__, "out/fig06_09", compute, argv)


if __name__ == "__main__":
    raise SystemExit(main())
