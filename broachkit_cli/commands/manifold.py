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
from pathlib import Path

from .fixed_points import add_ship_arguments, ship_from_args

NAME = "manifold"
HELP = "unstable manifold of the crest saddle (both branches) and where each goes"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit manifold``."""
    add_ship_arguments(parser)
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
    parser.add_argument("--out", type=Path, default=None, help="write the branches as CSV here")


def run(args: argparse.Namespace) -> int:
    """Compute the manifold and print the fates; returns 0 (1 if a fate is undecided)."""
    from ship_models.analysis.manifold import unstable_manifold

    model, params = ship_from_args(args)
    if not (math.isfinite(args.t_max) and args.t_max > 0):
        raise ValueError(f"--t-max must be a positive time in s, got {args.t_max}")
    if not (math.isfinite(args.eps) and 0 < args.eps < 0.1):
        raise ValueError(f"--eps must be in (0, 0.1), got {args.eps}")
    angle = None
    if args.capsize_angle is not None:
        if not (math.isfinite(args.capsize_angle) and 0 < args.capsize_angle <= 180):
            raise ValueError(f"--capsize-angle must be in (0, 180] deg, got {args.capsize_angle}")
        angle = math.radians(args.capsize_angle)

    def progress(branch: str, t: float) -> None:
        sys.stderr.write(f"\r{branch}: t = {t:8.1f} s ")
        sys.stderr.flush()

    man = unstable_manifold(
        model,
        params,
        args.saddle,
        eps=args.eps,
        t_max=args.t_max,
        capsize_angle=angle,
        progress=None if args.json else progress,
    )
    if not args.json:
        sys.stderr.write("\n")
    result = {
        "vessel": model.vessel.name,
        "params": params.as_dict(),
        "chi_c_deg": math.degrees(params["chi_c"]),
        **man.to_json(),
    }
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        files = {}
        for name, br in man.branches.items():
            files[name] = str(br.trajectory.to_csv(args.out / f"manifold_{name}.csv"))
        result["files"] = files
    if args.json:
        sys.stdout.write(json.dumps(result, indent=2) + "\n")
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
