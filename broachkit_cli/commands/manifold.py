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
import dataclasses
import math
import sys

from ..files import write_atomic
from ..options import add_out, add_ship, finite, prepare_out, print_json, ship_from_args
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


#: How often an undecided branch is recomputed with twice the time limit.
UNDECIDED_RETRIES = 2


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
        # an undecided branch is not one side or the other: look longer, twice
        t_max = float(args.t_max)
        for _ in range(UNDECIDED_RETRIES):
            open_ = [n for n, b in man.branches.items() if b.fate.kind == "undecided"
                     and b.fate.status.name == "MAX_STEPS"]  # fmt: skip
            if not open_:
                break
            t_max *= 2.0
            more = unstable_manifold(
                model, params, man.saddle, eps=args.eps, t_max=t_max, capsize_angle=angle,
                branches=tuple(open_), points=man.points,
                progress=lambda branch, t: status.show(f"{branch} (longer): t = {t:8.1f} s"),
            )  # fmt: skip
            man = dataclasses.replace(man, branches={**man.branches, **more.branches})
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
        print_json(result)
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
            if len(br.fate.visits) > 6:
                v = br.fate.visits
                via = (f" via {v[0].label}@{v[0].shift:+d} -> ... -> {v[-1].label}@{v[-1].shift:+d}"
                       f" ({len(v)} saddle passages)")  # fmt: skip
            sys.stdout.write(f"  {name:9s}: {br.fate.label}{via} (t = {br.fate.t:.1f} s)\n")
            if br.fate.kind == "undecided":
                sys.stdout.write(
                    f"             undecided after {br.fate.t:.0f} s (the window was doubled "
                    f"{UNDECIDED_RETRIES} times): neither side is claimed; --t-max longer\n"
                )
            elif br.fate.kind == "recurrent":
                sys.stdout.write(
                    "             bounded, no settled period: a chaotic attractor or a "
                    f"transient longer than {br.fate.t:.0f} s (no capsize within it)\n"
                )
    undecided = any(b.fate.kind == "undecided" for b in man.branches.values())
    return 1 if undecided else 0
