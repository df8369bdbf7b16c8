"""Does any B-series pitch give thrust up to the wave celerity? (Umeda 1999 Eq. 5, T(u; n)).

The paper's control is the nominal Froude number: the revolution ``n`` is set so that
the thrust balances the calm-water resistance at ``u0 = Fn sqrt(g L)``. At a given
``n`` the advance ratio grows with the speed, ``J(u) = u (1 - w_P) / (n D_p)``, so on
the orbit that reaches the wave celerity ``c`` the propeller works at
``J_c = J_0 c / u0`` with ``J_0 = J(u0)``, the nominal advance ratio. ``J_0`` is fixed
by the thrust loading of the nominal point,

.. math::

    \\frac{K_T(J_0)}{J_0^2} = \\frac{R(u_0)}{(1 - t_P)\\,\\rho D_p^2 u_0^2 (1 - w_P)^2}

(the identity ``T = rho n^2 D^4 K_T`` with ``n = u_a / (J D)``; e.g. Carlton 2012,
*Marine Propellers and Propulsion*, 3rd ed., ch. 6), which does not depend on the pitch:
a coarser pitch lowers ``n`` and raises ``J_0`` together with the zero-thrust advance
ratio ``J_T0`` of the Wageningen B-series (Oosterveld & van Oossanen 1975, "Further
computer-analyzed data of the Wageningen B-screw series", ISP 22(251):251-262, their
K_T polynomial, valid for P/D 0.5-1.4). The thrust stays positive up to ``c`` only if
``J_T0 / J_0 > c / u0``. This study evaluates, for the default vessel at its critical
Fn and each P/D of the series' range, ``J_0``, ``J_T0``, ``J_c`` and the effective
thrust at ``c`` (``(1 - t_P) rho n^2 D^4 K_T(J_c)``, with the polynomial extrapolated
beyond ``J_T0`` as in ``propeller_method = "bseries"``).

Result (2026-12-04, default vessel, Fn 0.3016, c/u0 = 1.620, R(c) = 289 kN):
``J_T0 / J_0`` rises with the pitch, from 1.36 (P/D 0.5) through 1.47 (0.8, the
default) to 1.71 (1.4), and passes c/u0 at P/D = 1.2: from there on the series gives
positive thrust up to the celerity. But the thrust there is small against the
resistance whatever the pitch: T(c) = -27, -12, +0.1, +4.5 kN at P/D 0.5, 0.8, 1.2,
1.4, i.e. -9 % ... +1.6 % of R(c). So a coarser pitch does answer "thrust up to c",
but it cannot supply what the surge balance near c lacks; the thrust loading of the
nominal point (set by R(u0), D_p, w_P, t_P) fixes T(c) to within a few per cent of
R(c) for every pitch of the series. The critical Fn with each pitch is in
``studies/README.md``.

Writes ``propeller_pitch.csv`` and ``propeller_pitch.png`` to ``--out`` (default
``out/propeller_pitch``). Run: ``python studies/propeller_pitch.py [--out DIR] [--fn FN]``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

#: Pitch ratios of the study: the range of the Wageningen B-series regression.
PITCH_RATIOS = (0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.3, 1.4)


def pitch_case(P_over_D: float, Fn: float) -> dict[str, float]:
    """Advance ratios and thrust at the celerity for one pitch ratio (default vessel)."""
    from ship_models import Umeda4DOF
    from ship_models.hydro.propeller import bseries_zero_thrust_J
    from ship_models.vessel import Coefficient, load_vessel, parse_vessel

    d = load_vessel("purse_seiner").to_dict()
    d["vessel"]["propeller_method"] = "bseries"
    v = parse_vessel(d).with_overrides(
        {"propulsion.P_over_D": Coefficient(P_over_D, "-", "studies/propeller_pitch.py", "assumed")}
    )
    F = Umeda4DOF(v).forces
    lam_L = float(v.get("waves.lambda_over_L"))
    u0 = float(F.nominal_speed(Fn))
    c = float(F.celerity(lam_L))
    n = float(F.revolutions(Fn))
    w = float(F.w_P)
    J0 = u0 * (1.0 - w) / (n * F.D_p)
    JT0 = bseries_zero_thrust_J(
        P_over_D, float(v.get("propulsion.AE_over_A0")), int(v.get("propulsion.n_blades"))
    )
    Tc = float(F.thrust_force(c, n))
    Rc = float(F.resistance_force(c))
    return {
        "P_over_D": P_over_D,
        "n": n,
        "J_0": J0,
        "J_T0": JT0,
        "J_c": J0 * c / u0,
        "JT0_over_J0": JT0 / J0,
        "c_over_u0": c / u0,
        "T_c_kN": Tc / 1e3,
        "R_c_kN": Rc / 1e3,
        "T_c_over_R_c": Tc / Rc,
    }


def run(out: Path, Fn: float) -> list[dict[str, float]]:
    """All pitch ratios; CSV and figure in ``out``."""
    from studies._common import new_figure, save_csv, save_figure

    rows = [pitch_case(pd, Fn) for pd in PITCH_RATIOS]
    cols = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    save_csv(
        out / "propeller_pitch.csv",
        cols,
        meta={"study": "B-series pitch against thrust at wave celerity", "Fn": Fn},
    )
    fig = new_figure((8.0, 3.2))
    ax1, ax2 = fig.subplots(1, 2)
    ax1.plot(cols["P_over_D"], cols["JT0_over_J0"], "o-", label="J_T0 / J_0 (zero thrust)")
    ax1.plot(cols["P_over_D"], cols["c_over_u0"], "k--", label="c / u0 (needed)")
    ax1.set_xlabel("P/D")
    ax1.set_ylabel("advance ratio / nominal")
    ax1.set_title(f"zero-thrust J against J at c (Fn {Fn:.4f})")
    ax1.legend()
    ax2.plot(cols["P_over_D"], cols["T_c_kN"], "o-", label="effective thrust T(c)")
    ax2.axhline(0.0, color="k", lw=0.8)
    ax2.set_xlabel("P/D")
    ax2.set_ylabel("kN")
    ax2.set_title(f"at the celerity (R(c) = {rows[0]['R_c_kN']:.0f} kN)")
    ax2.legend()
    save_figure(fig, out / "propeller_pitch.png")
    return rows


def main(argv: list[str] | None = None) -> int:
    """Command line: ``--out DIR``, ``--fn FN``."""
    from studies._common import output_dir

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=None, help="output root (default ./out)")
    ap.add_argument("--fn", type=float, default=0.3016, help="nominal Froude number")
    a = ap.parse_args(argv)
    if not 0.05 <= a.fn <= 0.6:
        ap.error(f"--fn must be in [0.05, 0.6], got {a.fn}")
    rows = run(output_dir("propeller_pitch", a.out), a.fn)
    for r in rows:
        sys.stdout.write(" ".join(f"{k}={v:.5g}" for k, v in r.items()) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
