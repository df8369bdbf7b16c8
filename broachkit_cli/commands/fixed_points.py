"""``broachkit fixed-points``: every surf-riding fixed point at one (Fn, chi_c), with eigen-data.

Degrees on the command line, radians inside. With ``--json`` prints one object with a
list ``fixed_points``: for each point its state (angles also in degrees), all
eigenvalues (dimensional 1/s and in the paper's time ``t' = t c / L``), saddle index
and unstable eigenvector (nondimensional, max-norm 1, sign: ``xi_G`` component > 0).

The ship options are the shared ones of :mod:`broachkit_cli.options`.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from typing import Any

from ..blas import one_blas_thread
from ..options import add_ship, emit, ship_from_args

NAME = "fixed-points"
HELP = "fixed points (surf-riding equilibria) of the ship at one Fn and autopilot course"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit fixed-points``."""
    add_ship(parser)


def run(args: argparse.Namespace) -> int:
    """Find the fixed points and print them; returns 0 (1 when there are none)."""
    with one_blas_thread():  # every system here is small: the ship's states
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
    emit(args, result, lambda doc: _text(doc, pts, args.chi_c))
    return 0 if pts else 1


def _text(doc: dict[str, Any], pts: Sequence[Any], chi_c_deg: float) -> str:
    """The fixed points ``pts`` of the result ``doc``, one line each (angles in degrees)."""
    lines = [
        f"{doc['vessel']}: Fn = {doc['params']['Fn']:.6g}, chi_c = {chi_c_deg:g} deg: "
        f"{len(pts)} fixed point(s)"
    ]
    for fp in pts:
        x = fp.x
        lam = fp.eigen.values[0]
        lines.append(
            f"  {fp.label:10s} xi_G/lambda={x[0]:.5f} u={x[1]:.4f} m/s v={x[2]:.4f} m/s "
            f"chi={math.degrees(x[3]):.3f} phi={math.degrees(x[5]):.3f} "
            f"delta={math.degrees(x[7]):.3f} deg | saddle index {fp.saddle_index}, "
            f"largest Re(lambda) = {lam.real:.5g} 1/s"
        )
        if fp.saddle_index >= 1 and lam.imag == 0:
            lines.append(f"  {'':10s} dominant: {', '.join(fp.eigen.dominant_components())}")
    return "\n".join(lines)
