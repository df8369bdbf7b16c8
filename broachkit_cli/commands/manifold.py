"""``broachkit manifold``: both branches of the unstable manifold of a saddle and their fates.

Degrees on the command line, radians inside. The saddle is the fixed point near the
wave crest by default (``--saddle``); the downslope branch starts along ``+v_u``
(``xi_G`` increasing), the upslope branch along ``-v_u``. Fates: ``capsize``,
``periodic``, ``recurrent``, ``equilibrium:<label>``, ``saddle:<label>``,
``undecided`` (see :mod:`ship_models.analysis.manifold`). ``--out DIR`` also writes
each branch's time series as CSV.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

from ..files import write_atomic
from ..options import add_out, add_ship, finite, json_safe, prepare_out, ship_from_args
from ..progress import StatusLine

NAME = "manifold"
HELP = "unstable manifold of the crest saddle (both branches) and where each goes"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit manifold``."""
    add_ship(parser)
    parser.add_argument("--saddle", default="crest", help="label of the saddle (default crest)")
    parser.add_argument(
        "--eps", type=float, default=1e-6, help="nondimensional start distance (default 1e-6)"
    )
    parser.add_argument(
        "--t-max", type=float, default=600.0, help="time limit per branch in s (default 600)"
    )
    parser.add_argument(
        "--capsize-angle",
        type=float,
        default=None,
        help="capsize roll angle in degrees (default: vanishing angle of GZ)",
    )
    add_out(parser, None, "the branches' time series as CSV")


def run(args: argparse.Namespace) -> int:
    """Compute the manifold and print the fates; returns 0 (1 if a fate is undecided)."""
    from ship_models.analysis.manifold import unstable_manifold

    finite("--t-max", args.t_max, low=0.0, high=1e5, unit="s")
    finite("--eps", args.eps, low=0.0, high=0.1)
    angle = None
    if args.capsize_angle is not None:
        angle = math.radians(finite("--capsize-angle", args.capsize_angle, low=0.0, high=180.0))
    out = prepare_out(args.out)
    model, params = ship_from_args(args)

    with StatusLine(enabled=not args.json) as status:
        man = unstable_manifold(
            model,
            params,
            args.saddle,
            eps=args.eps,
            t_max=args.t_max,
            capsize_angle=angle,
            progress=lambda branch, t: status.show(f"{branch}: t = {t:8.1f} s"),
        )
    result = {
        "vessel": model.vessel.name,
        "params": params.as_dict(),
        "chi_c_deg": math.degrees(params["chi_c"]),
        **man.to_json(),
    }
    if out is not None:
        files = {}
        for name, br in man.branches.items():
            files[name] = str(write_atomic(out / f"manifold_{name}.csv", br.trajectory.to_csv))
        result["files"] = files
    if args.json:
        sys.stdout.write(json.dumps(json_safe(result), indent=2) + "\n")
    else:
        sp = man.saddle
        sys.stdout.write(
            f"{model.vessel.name}: Fn = {params['Fn']:.6g}, chi_c = {args.chi_c:g} deg, "
            f"saddle {sp.label} at xi_G/lambda = {sp.x[0]:.5f} "
            f"(unstable eigenvalue {sp.eigen.values[0].real:.5g} 1/s)\n"
        )
        for name, br in man.branches.items():
            via = " -> ".join(f"{v.label}@{v.shift:+d}" for v in br.fate.visits)
            via = f" via {via}" if via else ""
            sys.stdout.write(f"  {name:9s}: {br.fate.label}{via} (t = {br.fate.t:.1f} s)\n")
    undecided = any(b.fate.kind == "undecided" for b in man.branches.values())
    return 1 if undecided else 0
