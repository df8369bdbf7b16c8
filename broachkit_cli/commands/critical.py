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

from ..options import (
    add_fn_guess,
    add_ship,
    check_fn,
    finite,
    json_safe,
    ship_from_args,
)
from ..progress import StatusLine
from ..wave_info import wave_force_fields

NAME = "critical"
HELP = "critical Fn of capsizing due to broaching (heteroclinic bifurcation) at one course"


def _bisection(model: Any, params: Any, args: argparse.Namespace) -> dict[str, Any]:
    from ship_models.analysis.critical import critical_fn

    with StatusLine(enabled=not args.json) as status:
        res = critical_fn(
            model,
            params,
            method="bisection",
            Fn_bracket=(args.Fn_min, args.Fn_max),
            tol=args.tol,
            progress=lambda ev: status.show(
                f"bisection: Fn = {ev.Fn:.8f}: {ev.outcome or 'undecided'}"
            ),
            t_max=args.t_max,
            criterion=args.criterion,
        )
    return _with_fn(res.to_json(), res.Fn)


def _with_fn(doc: dict[str, Any], Fn: float) -> dict[str, Any]:
    """The result's JSON with the critical value under its one name, ``"Fn"``."""
    doc = {k: v for k, v in doc.items() if k != "fn_critical"}
    doc["Fn"] = Fn
    return doc


def _bvp(model: Any, params: Any, args: argparse.Namespace) -> dict[str, Any]:
    from ship_models.analysis.critical import critical_fn

    res = critical_fn(
        model,
        params,
        method="bvp",
        Fn_guess=args.Fn_guess,
        guess_bracket=(args.Fn_min, args.Fn_max),
        check=True,
    )
    return _with_fn({"method": "bvp", **res.to_json()}, res.Fn)


def _both(model: Any, params: Any, args: argparse.Namespace) -> dict[str, Any]:
    bvp = _bvp(model, params, args)
    bis = _bisection(model, params, args)
    ok = bvp["status"] == "SUCCESS" and bis["status"] == "SUCCESS"
    return {
        "method": "both",
        "Fn": bvp["Fn"],
        "bracket": bis["bracket"],
        "difference": bvp["Fn"] - bis["Fn"],
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
    add_ship(parser, fn=False)
    parser.add_argument(
        "--method", choices=sorted(METHODS), default="bisection", help="how to locate it"
    )
    add_fn_guess(parser)
    parser.add_argument(
        "--fn-min", dest="Fn_min", type=float, default=0.25, help="lower end of the Fn search"
    )
    parser.add_argument(
        "--fn-max", dest="Fn_max", type=float, default=0.40, help="upper end of the Fn search"
    )
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
    finite("--fn-min", args.Fn_min, low=0.0)
    finite("--fn-max", args.Fn_max, low=0.0)
    if not args.Fn_min < args.Fn_max:
        raise ValueError(f"--fn-min must be below --fn-max, got {args.Fn_min}, {args.Fn_max}")
    finite("--tol", args.tol, low=0.0, high=args.Fn_max - args.Fn_min)
    finite("--t-max", args.t_max, low=0.0, high=1e5, unit="s")
    model, params = ship_from_args(args)
    check_fn(model, "--fn-min", args.Fn_min)
    check_fn(model, "--fn-max", args.Fn_max)
    if args.Fn_guess is not None:
        check_fn(model, "--fn-guess", args.Fn_guess)
    result = {"vessel": model.vessel.name, **METHODS[args.method](model, params, args)}
    result.update(wave_force_fields(model, params))  # issue 25: which wave forces were used
    if args.json:
        sys.stdout.write(json.dumps(json_safe(result), indent=2) + "\n")
    elif result["status"] != "SUCCESS" and not math.isfinite(result.get("Fn") or math.nan):
        sys.stderr.write(
            f"broachkit critical: no critical Fn in --fn-min/--fn-max = [{args.Fn_min:g}, "
            f"{args.Fn_max:g}] at chi_c = {args.chi_c:g} deg ({args.method}, "
            f"{result['status']}): {_reason(result)}\n"
        )
    else:
        head = f"{model.vessel.name}, chi_c = {args.chi_c:g} deg ({args.method}): "
        if args.method == "bisection":
            lo, hi = result["bracket"]
            text = (
                f"critical Fn = {result['Fn']:.7f} in [{lo:.7f}, {hi:.7f}] "
                f"({result['fate_lo']} below, {result['fate_hi']} above)"
            )
        elif args.method == "bvp" and result["status"] != "SUCCESS":
            text = f"no critical Fn: {result['message']}"
        elif args.method == "bvp":
            text = (
                f"critical Fn = {result['Fn']:.8f} (connecting orbit, "
                f"|G| = {result['residual_norm']:.1e}, error estimate {result.get('error')}, "
                f"mesh change {result.get('delta_Fn_mesh')}, T change {result.get('delta_Fn_T')})"
            )
        else:
            lo, hi = result["bracket"]
            text = (
                f"bvp Fn = {result['Fn']:.8f}; bisection bracket "
                f"[{lo:.7f}, {hi:.7f}]; difference {result['difference']:.1e}"
            )
        sys.stdout.write(head + text + f"; {result['status']}\n")
    return 0 if result["status"] == "SUCCESS" else 1


def _reason(result: dict[str, Any]) -> str:
    """The one-line reason of a failed search (the library's message)."""
    for part in (result, result.get("bisection") or {}, result.get("bvp") or {}):
        msg = part.get("message")
        if msg:
            return " ".join(str(msg).split())
    return "the method gave no answer"
