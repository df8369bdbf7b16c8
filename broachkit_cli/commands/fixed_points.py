"""``broachkit fixed-points``: every surf-riding fixed point at one (Fn, chi_c), with eigen-data.

Degrees on the command line, radians inside. With ``--json`` prints one object with a
list ``fixed_points``: for each point its state (angles also in degrees), all
eigenvalues (dimensional 1/s and in the paper's time ``t' = t c / L``), saddle index
and unstable eigenvector (nondimensional, max-norm 1, sign: ``xi_G`` component > 0).

Also holds the ship options shared by ``manifold`` and ``critical``
(:func:`add_ship_arguments`, :func:`ship_from_args`).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from ship_models.paper import PAPER_FN

NAME = "fixed-points"
HELP = "fixed points (surf-riding equilibria) of the ship at one Fn and autopilot course"


def add_ship_arguments(parser: argparse.ArgumentParser, *, fn: bool = True) -> None:
    """Vessel, control and wave options shared by the phase-space commands."""
    parser.add_argument(
        "--vessel",
        default="purse_seiner",
        help="vessel name or path of a vessel TOML file (default: purse_seiner)",
    )
    if fn:
        parser.add_argument(
            "--fn", type=float, default=PAPER_FN, help=f"nominal Froude number (default {PAPER_FN})"
        )
    parser.add_argument(
        "--chi-c", type=float, default=10.0, help="autopilot course in degrees (default 10)"
    )
    parser.add_argument(
        "--h-over-lambda",
        type=float,
        default=None,
        help="wave steepness H/lambda (default: vessel)",
    )
    parser.add_argument(
        "--lambda-over-l",
        type=float,
        default=None,
        help="wavelength over ship length (default: vessel)",
    )
    parser.add_argument("--json", action="store_true", help="print the result as JSON")


def ship_from_args(args: argparse.Namespace) -> tuple[Any, Any]:
    """Build the ship model and its parameters from the shared options.

    Raises
    ------
    ValueError
        For a non-finite or out-of-range option (naming it).
    """
    from ship_models import Umeda4DOF

    chi = float(args.chi_c)
    if not (math.isfinite(chi) and abs(chi) < 85.0):
        raise ValueError(f"--chi-c must be a course in degrees within +-85, got {args.chi_c}")
    model = Umeda4DOF(args.vessel)
    changes: dict[str, float] = {"chi_c": math.radians(chi)}
    if getattr(args, "fn", None) is not None:
        if not (math.isfinite(args.fn) and args.fn > 0):
            raise ValueError(f"--fn must be a positive Froude number, got {args.fn}")
        changes["Fn"] = float(args.fn)
    for opt, name in (("h_over_lambda", "H_over_lambda"), ("lambda_over_l", "lambda_over_L")):
        val = getattr(args, opt, None)
        if val is not None:
            if not (math.isfinite(val) and val > 0):
                raise ValueError(f"--{opt.replace('_', '-')} must be positive, got {val}")
            changes[name] = float(val)
    return model, model.default_params().replace(**changes)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit fixed-points``."""
    add_ship_arguments(parser)


def run(args: argparse.Namespace) -> int:
    """Find the fixed points and print them; returns 0 (1 when there are none)."""
    from ship_models.analysis import fixed_points

    model, params = ship_from_args(args)
    pts = fixed_points(model, params)
    result = {
        "vessel": model.vessel.name,
        "params": params.as_dict(),
        "chi_c_deg": math.degrees(params["chi_c"]),
        "celerity": model.celerity(params),
        "time_scale_L_over_c": model.forces.L / model.celerity(params),
        "fixed_points": [fp.to_json() for fp in pts],
    }
    if args.json:
        sys.stdout.write(json.dumps(result, indent=2) + "\n")
    else:
        sys.stdout.write(
            f"{model.vessel.name}: Fn = {params['Fn']:.6g}, chi_c = {args.chi_c:g} deg: "
            f"{len(pts)} fixed point(s)\n"
        )
        for fp in pts:
            x = fp.x
            lam = fp.eigen.values[0]
            sys.stdout.write(
                f"  {fp.label:10s} xi_G/lambda={x[0]:.5f} u={x[1]:.4f} m/s v={x[2]:.4f} m/s "
                f"chi={math.degrees(x[3]):.3f} phi={math.degrees(x[5]):.3f} "
                f"delta={math.degrees(x[7]):.3f} deg | saddle index {fp.saddle_index}, "
                f"largest Re(lambda) = {lam.real:.5g} 1/s\n"
            )
            if fp.saddle_index >= 1 and lam.imag == 0:
                sys.stdout.write(
                    f"  {'':10s} dominant: {', '.join(fp.eigen.dominant_components())}\n"
                )
    return 0 if pts else 1
