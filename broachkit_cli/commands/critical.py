"""``broachkit critical``: critical Fn of the heteroclinic bifurcation at one autopilot course.

The Fn where the upslope branch of the crest saddle's unstable manifold switches from
periodic motion to capsize (Umeda 1999, Figs. 10-15 and 23). ``--method bisection``
bisects Fn on that fate (:func:`ship_models.analysis.critical.critical_fn`) and
prints the critical Fn and its bracket; other methods (e.g. a boundary-value
solution of the connection) plug in as further ``--method`` choices.
Degrees on the command line, radians inside.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
from collections.abc import Callable
from typing import Any

from ship_models.paper import PAPER_FN

from .fixed_points import add_ship_arguments, ship_from_args

NAME = "critical"
HELP = "critical Fn of capsizing due to broaching (heteroclinic bifurcation) at one course"


def _bisection(model: Any, params: Any, args: argparse.Namespace) -> dict[str, Any]:
    from ship_models.analysis.critical import critical_fn

    def progress(ev: Any) -> None:
        if not args.json:
            sys.stderr.write(f"  Fn = {ev.Fn:.8f}: {ev.outcome or 'undecided'}\n")

    res = critical_fn(
        model,
        params,
        method="bisection",
        Fn_bracket=(args.fn_min, args.fn_max),
        tol=args.tol,
        progress=progress,
        t_max=args.t_max,
        criterion=args.criterion,
    )
    return {"fn_critical": res.Fn, **res.to_json()}


def _bvp(model: Any, params: Any, args: argparse.Namespace) -> dict[str, Any]:
    from ship_models.analysis.critical import critical_fn

    res = critical_fn(
        model,
        params,
        method="bvp",
        Fn_guess=args.fn_guess,
        guess_bracket=(args.fn_min, args.fn_max),
        check=True,
    )
    return {"method": "bvp", "fn_critical": res.Fn, **res.to_json()}


def _both(model: Any, params: Any, args: argparse.Namespace) -> dict[str, Any]:
    bvp = _bvp(model, params, args)
    bis = _bisection(model, params, args)
    ok = bvp["status"] == "SUCCESS" and bis["status"] == "SUCCESS"
    return {
        "method": "both",
        "fn_critical": bvp["fn_critical"],
        "bracket": bis["bracket"],
        "difference": bvp["fn_critical"] - bis["fn_critical"],
        "status": "SUCCESS"
        if ok
        else (bvp["status"] if bis["status"] == "SUCCESS" else bis["status"]),
        "bvp": bvp,
        "bisection": bis,
    }


#: ``--method`` choices: name -> function(model, params, args) -> JSON-ready dict.
METHODS: dict[str, Callable[[Any, Any, argparse.Namespace], dict[str, Any]]] = {
    "bisection": _bisection,
    "bvp": _bvp,
    "both": _both,
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit critical``."""
    add_ship_arguments(parser, fn=False)
    parser.add_argument(
        "--method", choices=sorted(METHODS), default="bisection", help="how to locate it"
    )
    parser.add_argument(
        "--fn-guess",
        type=float,
        default=PAPER_FN,
        help=f"bvp: Fn of the unstable-manifold simulation that seeds the orbit ({PAPER_FN})",
    )
    parser.add_argument("--fn-min", type=float, default=0.25, help="lower end of the Fn search")
    parser.add_argument("--fn-max", type=float, default=0.40, help="upper end of the Fn search")
    parser.add_argument("--tol", type=float, default=1e-5, help="bracket width in Fn (1e-5)")
    parser.add_argument(
        "--criterion",
        choices=("first_passage", "final"),
        default="first_passage",
        help=(
            "bisection: compare the side on which the upslope branch leaves the first "
            "neighbouring saddle (default; switches at the heteroclinic connection) or "
            "its final fate (switches at secondary connections too)"
        ),
    )
    parser.add_argument(
        "--t-max", type=float, default=1500.0, help="time limit per simulation in s (1500)"
    )


def run(args: argparse.Namespace) -> int:
    """Run the command; a numerical failure is one line on stderr (exit 1), never a traceback."""
    from continuation.errors import ContinuationError

    try:
        return _run(args)
    except ContinuationError as exc:
        logging.getLogger(__name__).debug("%s failed", NAME, exc_info=True)
        sys.stderr.write(f"broachkit {NAME}: {exc}\n")
        return 1


def _run(args: argparse.Namespace) -> int:
    """Locate the critical Fn; returns 0 on success, 1 otherwise."""
    for opt in ("fn_min", "fn_max", "tol", "t_max", "fn_guess"):
        val = getattr(args, opt)
        if not (math.isfinite(val) and val > 0):
            raise ValueError(f"--{opt.replace('_', '-')} must be positive, got {val}")
    if not args.fn_min < args.fn_max:
        raise ValueError(f"--fn-min must be below --fn-max, got {args.fn_min}, {args.fn_max}")
    model, params = ship_from_args(args)
    result = {"vessel": model.vessel.name, **METHODS[args.method](model, params, args)}
    if args.json:
        sys.stdout.write(json.dumps(result, indent=2) + "\n")
    else:
        head = f"{model.vessel.name}, chi_c = {args.chi_c:g} deg ({args.method}): "
        if args.method == "bisection":
            lo, hi = result["bracket"]
            text = (
                f"critical Fn = {result['fn_critical']:.7f} in [{lo:.7f}, {hi:.7f}] "
                f"({result['fate_lo']} below, {result['fate_hi']} above)"
            )
        elif args.method == "bvp" and result["status"] != "SUCCESS":
            text = f"no critical Fn: {result['message']}"
        elif args.method == "bvp":
            text = (
                f"critical Fn = {result['fn_critical']:.8f} (connecting orbit, "
                f"|G| = {result['residual_norm']:.1e}, error estimate {result.get('error')}, "
                f"mesh change {result.get('delta_Fn_mesh')}, T change {result.get('delta_Fn_T')})"
            )
        else:
            lo, hi = result["bracket"]
            text = (
                f"bvp Fn = {result['fn_critical']:.8f}; bisection bracket "
                f"[{lo:.7f}, {hi:.7f}]; difference {result['difference']:.1e}"
            )
        sys.stdout.write(head + text + f"; {result['status']}\n")
    return 0 if result["status"] == "SUCCESS" else 1
