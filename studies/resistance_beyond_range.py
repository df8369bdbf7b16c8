"""How much high-speed resistance the paper's threshold needs: Fn* against R beyond Holtrop's range.

The default resistance is Holtrop's regression, valid for trawlers to Fn 0.38
(Holtrop & Mennen 1982), while the orbit that sets the threshold runs up to the wave
celerity (Fn 0.49 at lambda/L = 1.5). The paper's resistance was measured. This study
replaces R(u) by a measured-curve table (``resistance_method = "table"``, the C2
spline of :mod:`ship_models.hydro.curves`) equal to Holtrop's below ``Fn_lo`` and
raised by a factor ``1 + a`` above ``Fn_hi`` (smoothstep blend in between), and
finds the critical Fn at chi_c = 10 deg (bisection of the upslope manifold's fate,
tolerance 1e-5) for each ``a``. Below Fn_lo nothing changes, so neither do the
commanded revolutions near the threshold (Fn* < 0.38).

Result (2026-12-04, default vessel; the table has 129 speeds from Fn 0.01 to 0.65 and
reproduces the default R(u) to 2e-7, Fn* to 1e-8 at a = 0): blend 0.38-0.45:
a = 0 / 0.25 / 0.45 / 0.5 gives Fn* = 0.30161 / 0.31342 / 0.32455 / 0.32767 (R(c) 289 /
362 / 420 / 434 kN): about +45 % above Fn 0.45 reproduces the paper's 0.32475. Blend
0.45-0.52, a = 0.5: 0.30894.
These are what-if numbers for the size of the effect, not an estimate of the
resistance.

Writes ``resistance_beyond_range.csv`` and ``resistance_beyond_range.png`` to
``--out`` (default ``out/resistance_beyond_range``).

Run: ``python studies/resistance_beyond_range.py [--out DIR] [--quick]``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

#: (Fn_lo, Fn_hi, factors a) of the cases.
CASES: tuple[tuple[float, float, tuple[float, ...]], ...] = (
    (0.38, 0.45, (0.0, 0.25, 0.45, 0.5)),
    (0.45, 0.52, (0.5,)),
)


def smoothstep(Fn: Any, lo: float, hi: float) -> Any:
    """0 below ``lo``, 1 above ``hi``, C1 cubic blend ``3s^2 - 2s^3`` in between."""
    s = np.clip((np.asarray(Fn, float) - lo) / (hi - lo), 0.0, 1.0)
    return s * s * (3.0 - 2.0 * s)


def raised_vessel(a: float, lo: float, hi: float) -> Any:
    """The default vessel with R(u) given as a table: Holtrop's x (1 + a smoothstep)."""
    import tomllib

    from ship_models import Umeda4DOF
    from ship_models.vessel import DATA_DIR, parse_vessel

    base = Umeda4DOF("purse_seiner").forces
    sg = math.sqrt(base.g * base.L)
    u = np.linspace(0.01, 0.65, 129) * sg  # dense: a = 0 reproduces the default (tested)
    R = base.resistance_force(u) * (1.0 + a * smoothstep(u / sg, lo, hi))
    with open(DATA_DIR / "purse_seiner.toml", "rb") as fh:
        doc = tomllib.load(fh)
    doc["vessel"]["resistance_method"] = "table"
    doc["curves"] = {
        "resistance": {"x": [float(x) for x in u], "y": [float(y) for y in R], "x_unit": "m/s",
                       "y_unit": "N", "status": "assumed",
                       "source": f"what-if: Holtrop x (1 + {a} smoothstep(Fn {lo}..{hi}))"}
    }  # fmt: skip
    return parse_vessel(doc)


def run(out: Path, *, quick: bool = False) -> list[dict[str, float]]:
    """Every case; ``quick``: the first two factors of the first blend only."""
    from ship_models import Umeda4DOF
    from ship_models.analysis import critical_fn
    from studies._common import new_figure, save_csv, save_figure

    rows: list[dict[str, float]] = []
    cases = CASES[:1] if quick else CASES
    for lo, hi, factors in cases:
        for a in factors[:2] if quick else factors:
            m = Umeda4DOF(raised_vessel(a, lo, hi))
            cr = critical_fn(m, chi_c=math.radians(10.0), method="bisection", tol=1e-5)
            c = float(m.forces.celerity(m.vessel.get("waves.lambda_over_L")))
            rows.append({"Fn_lo": lo, "Fn_hi": hi, "a": a, "Fn_crit_10": float(cr.Fn),
                         "error": float(cr.error),
                         "R_at_c_kN": float(m.forces.resistance_force(c)) / 1e3})  # fmt: skip
    cols = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    note = "what-if resistance above Holtrop's range; not an estimate"
    meta = {"chi_c_deg": 10.0, "paper_Fn": "0.3247-0.3248", "note": note}
    save_csv(out / "resistance_beyond_range.csv", cols, meta=meta)
    fig = new_figure((6.0, 4.0))
    ax = fig.subplots()
    for lo, hi, _ in cases:
        sel = [r for r in rows if r["Fn_lo"] == lo]
        ax.plot([100 * r["a"] for r in sel], [r["Fn_crit_10"] for r in sel], "o-",
                label=f"raised from Fn {lo} (full above {hi})")  # fmt: skip
    ax.axhspan(0.3247, 0.3248, color="k", alpha=0.3, label="paper 0.3247-0.3248")
    ax.set(xlabel="resistance increase above the blend (%)", ylabel="critical Fn at 10 deg",
           title="Fn* against resistance beyond Holtrop's range")  # fmt: skip
    ax.legend()
    save_figure(fig, out / "resistance_beyond_range.png")
    return rows


def main(argv: list[str] | None = None) -> int:
    """Command line: ``--out DIR``, ``--quick``."""
    from studies._common import rows_main

    return rows_main(__doc__, "resistance_beyond_range", run, argv, quick_help="two cases only")


if __name__ == "__main__":
    raise SystemExit(main())
