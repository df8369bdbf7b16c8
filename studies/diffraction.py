"""What diffraction changes: panel-method wave forces beside Froude-Krylov alone.

The default vessel's hull (the form-parameter hull of its particulars, written as
offsets) is solved by the panel method (:mod:`ship_models.hydro.panel`, Capytaine) at
zero speed over lambda/L = 1-3 and headings 0-90 deg; the study writes

* ``diffraction_ratio.png`` / ``.csv``: the surge-force ratio |X_FK + X_D| / |X_FK|
  over lambda/L at chi = 0, 30, 60 deg, and the bound of Capytaine's low-speed option
  at the paper's Fn (chi = 0);
* ``critical_curve_diffraction.png`` / ``.csv``: the critical Fn of the heteroclinic
  bifurcation over the course with the strips' Froude-Krylov forces (the paper's model),
  the panel method's Froude-Krylov part alone, and Froude-Krylov + diffraction;
* ``summary.json``: the numbers quoted in ``studies/README.md``.

Run: ``python -m studies.diffraction --out DIR`` (needs the ``hull`` extra; the panel
tables are cached, about 2-4 minutes the first time on 2 cores).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ship_models import get_vessel_data
from ship_models.analysis.critical_bvp import critical_fn_bvp
from ship_models.analysis.critical_curve import critical_curve
from ship_models.analysis.threshold import capsizing_threshold
from ship_models.hydro.panel import PanelWaveBuilder, hull_mesh, panel_table
from ship_models.paper import PAPER_FN
from ship_models.umeda_4dof import Umeda4DOF
from studies._common import (
    figure_style,
    new_figure,
    output_dir,
    save_csv,
    save_figure,
    write_summary,
)

#: The vessel of the study (the default vessel of the main job).
VESSEL = "purse_seiner"

CHI_CURVE_DEG = (0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0)
LAMBDA = tuple(np.linspace(1.0, 3.0, 41))
CHI_TABLE = tuple(np.arange(0.0, 91.0, 10.0))


def _log(msg: str) -> None:
    sys.stderr.write(msg + "\n")
    sys.stderr.flush()


def ratio_data(
    vessel: str = "purse_seiner", say: Callable[[str], None] | None = None
) -> dict[str, Any]:
    """Surge-force ratios over lambda/L (zero speed; low-speed bound at chi = 0)."""
    data = get_vessel_data(vessel)
    V, F = hull_mesh(data.hull, nx=40, nz=8)
    w = data.forces.waves
    common = dict(L=data.hull.L, x_G=data.info["x_G"], zeta_G=data.info["zeta_G"], rho=w.rho,
                  g=w.g, lambda_over_L=np.array(LAMBDA))  # fmt: skip
    t0 = time.perf_counter()
    tab = panel_table(V, F, chi_deg=np.array(CHI_TABLE), **common,
                      progress=lambda i, n: (say or _log)(f"panel table {i}/{n}"))  # fmt: skip
    fwd = panel_table(V, F, chi_deg=np.array([0.0]), forward_speed_Fn=PAPER_FN, **common)
    r = tab.amplitude_ratio(0)
    return {
        "lambda_over_L": np.array(LAMBDA),
        "ratio_chi0": r[:, 0],
        "ratio_chi30": r[:, 3],
        "ratio_chi60": r[:, 6],
        "ratio_chi0_speed": fwd.amplitude_ratio(0)[:, 0],
        "n_panels": tab.info["n_panels"],
        "seconds": time.perf_counter() - t0,
        "cached": tab.info.get("cached", False),
    }


def thresholds(
    vessel: str = "purse_seiner", say: Callable[[str], None] | None = None
) -> dict[str, Any]:
    """Critical Fn at 10 deg and over the course for three wave-force models."""
    data = get_vessel_data(vessel)
    models = {
        "froude_krylov_strips": Umeda4DOF(data),
        "panel_fk": Umeda4DOF(data.vessel.path or vessel, waves=PanelWaveBuilder(
            diffraction=False, chi_deg=CHI_TABLE)),
        "panel_fk_diffraction": Umeda4DOF(data.vessel.path or vessel, waves=PanelWaveBuilder(
            diffraction=True, chi_deg=CHI_TABLE)),
    }  # fmt: skip
    out: dict[str, Any] = {}
    for name, m in models.items():
        (say or _log)(f"heteroclinic Fn at 10 deg: {name}")
        c10 = critical_fn_bvp(math.radians(10.0), model=m)
        (say or _log)(f"heteroclinic line: {name}")
        cur = critical_curve(np.radians(CHI_CURVE_DEG), model=m)
        chi_max = (
            float(np.max(np.abs(c10.orbit.x[:, m.state_index("chi")]))) if c10.orbit else math.nan
        )
        (say or _log)(f"capsizing threshold at 10 deg: {name}")
        th10 = capsizing_threshold(m, chi_c=math.radians(10.0), heteroclinic=c10)
        out[name] = {
            "threshold_10deg": th10.Fn if math.isfinite(th10.Fn) else None,
            "threshold_error_10deg": th10.error if math.isfinite(th10.error) else None,
            "mechanism_10deg": th10.mechanism,
            "Fn_10deg": c10.Fn,
            "error_10deg": c10.error,
            "status_10deg": c10.status.name,
            "chi_max_orbit_deg": math.degrees(chi_max),
            "fit_error": float(getattr(m.forces.waves, "fit_error", 0.0)),
            "chi_c_deg": list(CHI_CURVE_DEG),
            "Fn_curve": [float(v) for v in cur.Fn],
        }
    return out


def compute(out: Path, progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Run the study into ``out`` (figures, CSV, ``summary.json``); the summary.

    The main job runs it as its optional step ``diffraction``
    (``broachkit reproduce --only diffraction``; needs the ``hull`` extra).
    """
    say = progress or _log
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    say("panel method: surge-force ratio over lambda/L (Capytaine, cached)")
    rd = ratio_data(VESSEL, say)
    save_csv(out / "diffraction_ratio.csv",
             {k: rd[k] for k in ("lambda_over_L", "ratio_chi0", "ratio_chi30", "ratio_chi60",
                                  "ratio_chi0_speed")},
             meta={"quantity": "|X_FK + X_D| / |X_FK| of the surge force, panel method "
                   "(Capytaine), zero speed; ratio_chi0_speed: low-speed option at "
                   f"Fn = {PAPER_FN}", "panels": rd["n_panels"]})  # fmt: skip
    say("heteroclinic Fn with strips FK, panel FK, panel FK + diffraction")
    th = thresholds(VESSEL, say)
    cols: dict[str, Any] = {"chi_c_deg": np.array(CHI_CURVE_DEG)}
    for name, d in th.items():
        cols[f"Fn_{name}"] = np.array(d["Fn_curve"])
    save_csv(out / "critical_curve_diffraction.csv", cols,
             meta={"quantity": "heteroclinic Fn (the capsizing threshold up to 28 deg for "
                   "the strips' model)"})  # fmt: skip
    with figure_style():
        fig = new_figure((10.0, 4.0))
        ax1, ax2 = fig.subplots(1, 2)
        for key, lab in (
            ("ratio_chi0", "chi = 0"),
            ("ratio_chi30", "chi = 30 deg"),
            ("ratio_chi60", "chi = 60 deg"),
            ("ratio_chi0_speed", f"chi = 0, low-speed option Fn = {PAPER_FN}"),
        ):
            ax1.plot(rd["lambda_over_L"], rd[key], label=lab)  # fmt: skip
        ax1.set_xlabel("lambda / L")
        ax1.set_ylabel("|X_FK + X_D| / |X_FK|")
        ax1.set_title("surge force: diffraction / Froude-Krylov")
        ax1.legend(fontsize=8)
        for name, d in th.items():
            ax2.plot(d["chi_c_deg"], d["Fn_curve"], "o-", label=name)
        ax2.set_xlabel("chi_c (deg)")
        ax2.set_ylabel("heteroclinic Fn")
        ax2.set_title("heteroclinic Fn with and without diffraction")
        ax2.legend(fontsize=8)
        save_figure(fig, out / "diffraction.png")
    summary = {
        "ratio_range_chi0": [float(np.min(rd["ratio_chi0"])), float(np.max(rd["ratio_chi0"]))],
        "ratio_at_1.5": float(np.interp(1.5, rd["lambda_over_L"], rd["ratio_chi0"])),
        "ratio_speed_range_chi0": [
            float(np.min(rd["ratio_chi0_speed"])),
            float(np.max(rd["ratio_chi0_speed"])),
        ],  # fmt: skip
        "panels": rd["n_panels"],
        "table_seconds": rd["seconds"],
        "thresholds": th,
        "figures": ["diffraction.png"],
    }
    write_summary(out, summary)
    return summary


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m studies.diffraction [--out DIR]``."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=None, help="output folder (default: out/diffraction)")
    args = ap.parse_args(argv)
    out = output_dir("diffraction", args.out) if args.out is None else output_dir("", args.out)
    summary = compute(out)
    _log(json.dumps(summary, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
