"""``broachkit periodic``: one overtaken-by-waves cycle, its period and Floquet multipliers.

The ship overtaken by waves at ``--fn``/``--chi-c`` is a rotation orbit on the
wave-relative coordinate (``xi_G/lambda`` falls by one per period). It is found from a
settled simulation and corrected by orthogonal collocation
(:func:`ship_models.analysis.cycles.simulated_cycle`; where the simulation does not
settle, continued there from ``Fn = 0.1``), its nontrivial Floquet multipliers from the
collocation system (:meth:`continuation.periodic.PeriodicOrbitProblem.floquet`). With
``--shooting`` the return-map shooting solver
(:func:`ship_models.analysis.sudden_change.periodic_orbit`) solves the same cycle
independently and the differences are printed. A cycle that rolls past the angle of
vanishing stability is a capsize, not a cycle: the command says so and exits with 1.

With ``--out DIR``: ``periodic.csv`` (one period of the states, angles in degrees),
``periodic.json`` and ``periodic.png`` (time histories), each written atomically.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..cycle_options import START_FN, emit, roll_verdict
from ..files import csv_text, write_atomic, write_json, write_text
from ..options import (
    add_out,
    add_ship,
    check_chi_c_deg,
    finite,
    prepare_out,
    ship_from_args,
)
from .cycles import _start_cycle

NAME = "periodic"
HELP = "one overtaken-by-waves cycle: its period, Floquet multipliers and stability"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit periodic``."""
    add_ship(parser)
    parser.set_defaults(Fn=START_FN)
    parser.add_argument(
        "--shooting",
        action="store_true",
        help="also solve the cycle by the return-map shooting solver and compare",
    )
    add_out(parser, None, "periodic.csv/.json/.png")


def compute(model: Any, params: Any, shooting: bool) -> tuple[dict[str, Any], Any]:
    """The cycle and its JSON summary (angles in degrees)."""
    from continuation.periodic import PeriodicOrbitProblem
    from ship_models.analysis.events import capsize_angle

    orbit = _start_cycle(model, params)
    prob = PeriodicOrbitProblem.from_orbit(orbit, "Fn")
    fn = orbit.param("Fn")
    fl = prob.floquet(prob.reference, fn)
    mu = np.asarray(fl.multipliers)
    mu = mu[np.argsort(-np.abs(mu))]
    i_phi, i_chi = model.state_index("phi"), model.state_index("chi")
    chi_c = float(orbit.param("chi_c"))
    max_roll = float(np.degrees(np.max(np.abs(orbit.X[:, i_phi]))))
    vanishing = float(np.degrees(capsize_angle(model)))
    n_unstable = int(np.sum(np.abs(mu) > 1.0))
    i_xi = model.state_index("xi_G")
    doc: dict[str, Any] = {
        "vessel": model.vessel.name,
        "Fn": float(orbit.param("Fn")),
        "chi_c_deg": math.degrees(chi_c),
        "status": "SUCCESS",
        "T": float(orbit.T),
        "waves_per_period": float(orbit.X[0, i_xi] - orbit.X[-1, i_xi]),
        "multipliers": [
            {"re": float(m.real), "im": float(m.imag), "abs": float(abs(m))} for m in mu
        ],  # fmt: skip
        "trivial_multiplier_error": float(fl.trivial_error),
        "stable": n_unstable == 0,
        "n_unstable": n_unstable,
        "collocation_error_estimate": float(prob.record(prob.reference, fn)["error"]),
        "n_intervals": int(orbit.mesh.n_intervals),
        "degree": int(orbit.mesh.degree),
        "max_roll_deg": max_roll,
        "max_heading_deg": float(np.degrees(np.max(np.abs(orbit.X[:, i_chi] - chi_c)))),
        "vanishing_angle_deg": vanishing,
        "rolls_past_vanishing_angle": max_roll >= vanishing,
    }
    if shooting:
        from ship_models.analysis.cycles import compare_with_shooting, section_state
        from ship_models.analysis.sudden_change import periodic_orbit

        # from the collocation cycle's section state: the calm-water start need not
        # settle on it (it may broach first)
        sh = periodic_orbit(model, orbit.params, x_guess=section_state(orbit, 0.0)[0])
        doc["shooting"] = {"status": sh.status.name, "T": float(sh.period)}
        if sh.status.ok:
            cmp = compare_with_shooting(orbit, sh)
            doc["shooting"].update(
                dT=cmp.dT, d_state_scaled=cmp.d_state, d_multiplier_abs=cmp.d_multiplier
            )
    return doc, orbit


def _samples(orbit: Any) -> dict[str, np.ndarray]:
    model = orbit.system
    t = np.linspace(0.0, orbit.T, 401)
    x = orbit(t)
    from ship_models.columns import state_columns

    return {"t": t, **state_columns(model.state_names, x)}


def _plot(path: Path, cols: dict[str, np.ndarray], doc: dict[str, Any]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = {**cols, "xi_rel": cols["xi_G"] - cols["xi_G"][0]}
    panels = [("xi_rel", "xi_G/lambda - start"), ("u", "u (m/s)"), ("chi_deg", "chi (deg)"),
              ("phi_deg", "phi (deg)"), ("delta_deg", "delta (deg)")]  # fmt: skip
    fig, axes = plt.subplots(len(panels), 1, figsize=(6.0, 8.0), sharex=True)
    for ax, (key, label) in zip(axes, panels, strict=True):
        ax.plot(cols["t"], cols[key], lw=1.0)
        ax.set_ylabel(label, fontsize=8)
    axes[2].axhline(doc["chi_c_deg"], color="k", lw=0.6, ls=":", label="chi_c")
    axes[2].legend(fontsize=7)
    axes[-1].set_xlabel("t (s)")
    mods = ", ".join(f"{m['abs']:.3g}" for m in doc["multipliers"][:3])
    axes[0].set_title(
        f"{doc['vessel']}: cycle at Fn = {doc['Fn']:g}, chi_c = {doc['chi_c_deg']:g} deg; "
        f"T = {doc['T']:.4f} s, |mu| = {mods}", fontsize=8,
    )  # fmt: skip
    fig.tight_layout()
    write_atomic(path, lambda p: fig.savefig(p, dpi=120, format="png"))
    plt.close(fig)


def write_files(out: Path, doc: dict[str, Any], orbit: Any) -> list[Path]:
    """CSV, JSON and PNG of the cycle into ``out``, each atomically."""
    cols = _samples(orbit)
    meta = {k: doc[k] for k in ("vessel", "Fn", "chi_c_deg", "T")}
    cycle = {k: c.tolist() for k, c in cols.items()}
    paths = [
        write_text(out / "periodic.csv", csv_text(cols, meta)),
        write_json(out / "periodic.json", {**doc, "cycle": cycle}),
    ]
    _plot(out / "periodic.png", cols, doc)
    paths.append(out / "periodic.png")
    return paths


def run(args: argparse.Namespace) -> int:
    """Solve the cycle; 0 unless it rolls past the angle of vanishing stability (1)."""
    finite("--fn", args.Fn, low=0.0)
    check_chi_c_deg("--chi-c", args.chi_c)
    out = prepare_out(args.out)
    model, params = ship_from_args(args)
    doc, orbit = compute(model, params, bool(args.shooting))
    if out is not None:
        doc["files"] = [str(p) for p in write_files(out, doc, orbit)]
    emit(args, doc, _text)
    return 1 if doc["rolls_past_vanishing_angle"] else 0


def _text(doc: dict[str, Any]) -> str:
    mods = ", ".join(
        f"{m['re']:.4g}{m['im']:+.4g}i" if abs(m["im"]) > 0 else f"{m['re']:.4g}"
        for m in doc["multipliers"]
    )
    lines = [
        f"{doc['vessel']}, overtaken-by-waves cycle at Fn = {doc['Fn']:g}, "
        f"chi_c = {doc['chi_c_deg']:g} deg: period T = {doc['T']:.8g} s "
        f"({doc['waves_per_period']:.6g} wave per period)",
        f"  Floquet multipliers: {mods}",
        f"  {'stable' if doc['stable'] else 'UNSTABLE'} ({doc['n_unstable']} outside the unit "
        f"circle); collocation error estimate {doc['collocation_error_estimate']:.2g} on "
        f"{doc['n_intervals']} x {doc['degree']}",
    ]
    sh = doc.get("shooting")
    if sh is not None:
        if "dT" in sh:
            lines.append(
                f"  shooting solver: T = {sh['T']:.8g} s; collocation - shooting: dT = "
                f"{sh['dT']:.2g} s, states {sh['d_state_scaled']:.2g} (scaled), "
                f"|mu| {sh['d_multiplier_abs']:.2g}"
            )
        else:
            lines.append(f"  shooting solver: {sh['status']}")
    lines.append(roll_verdict(doc))
    return "\n".join(lines)
