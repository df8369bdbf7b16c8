"""``broachkit critical``: the capsizing threshold at one autopilot course, and its mechanism.

``"Fn"`` is always the capsizing threshold: the lowest Fn at which the upslope branch of
the crest saddle's unstable manifold capsizes (Umeda 1999's criterion, Figs. 10-15).

``--method threshold`` (default) computes it by a scan and bisection of the branch's
fates (:func:`ship_models.analysis.threshold.capsizing_threshold`) and names what sets
it: ``"heteroclinic"`` where it is the heteroclinic connection (the paper's finding at
chi_c = 10 deg), otherwise the loss of the overtaken cycle (period doubling, fold,
crisis), with the cycle's bifurcations. The JSON has ``"Fn"``, ``"error"``,
``"mechanism"``, ``"Fn_heteroclinic"``, ``"Fn_heteroclinic_error"``,
``"is_heteroclinic"`` and the evidence (the fates at ``Fn -+ 0.002``).

``--method bvp`` (the connection by collocation), ``--method bisection`` (bisection of
the first passage of the neighbouring saddle) and ``--method both`` compute the
**heteroclinic** Fn only (``"Fn_heteroclinic"``) and check it against the ship's own
fates just below and above it: ``"is_threshold"`` says whether it passes, and ``"Fn"``
is that value only if it does (otherwise null, exit status 1).
Degrees on the command line, radians inside.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from typing import Any

from ..options import (
    add_fn_guess,
    add_ship,
    check_fn,
    finite,
    numerical_failure_exit,
    print_json,
    ship_from_args,
)
from ..progress import StatusLine
from ..wave_info import wave_force_fields

NAME = "critical"
HELP = "capsizing threshold Fn at one course, its mechanism and the heteroclinic Fn"


def _bisection(model: Any, params: Any, args: argparse.Namespace) -> dict[str, Any]:
    from ship_models.analysis.critical import critical_fn

    with StatusLine(enabled=not args.json) as status:
        res = critical_fn(
            model,
            params,
            method="bisection",
            Fn_bracket=(args.Fn_min, args.Fn_max),
            tol=1e-5 if args.tol is None else args.tol,
            progress=lambda ev: status.show(
                f"bisection: Fn = {ev.Fn:.8f}: {ev.outcome or 'undecided'}"
            ),
            t_max=args.t_max,
            criterion=args.criterion,
        )
    doc = _heteroclinic(model, params, res.to_json(), res.Fn, res.error)
    doc["not_a_connection"] = _not_a_connection(res)
    if doc["not_a_connection"]:
        doc["is_threshold"] = False
        doc["Fn"] = None
        doc["Fn_heteroclinic"] = None
        doc["message"] = doc["not_a_connection"] + "; " + doc["message"]
    return doc


def _not_a_connection(res: Any) -> str:
    """Why a bisection's switch is not the heteroclinic connection ('' if it may be)."""
    if not res.bracket or not res.evaluations:
        return ""
    hi = min(res.evaluations, key=lambda ev: abs(ev.Fn - res.bracket[1]))
    visits = getattr(hi.fate, "visits", ())
    if any(v.label == "crest" and v.shift == -1 for v in visits):
        return ""
    return (
        f"the bisection's switch at Fn = {res.Fn:.6f} is not the connection: at its upper end "
        "the upslope branch capsizes without reaching the neighbouring crest saddle"
    )


def _evidence(model: Any, params: Any, Fn: float, d: float, t_max: float) -> dict[str, Any]:
    """The upslope branch's fates at ``Fn -+ d`` (one fate each)."""
    from ship_models.analysis.threshold import CAPSIZE, SURVIVE, fates_at

    below, above = fates_at(model, params, [Fn - d, Fn + d], t_max=t_max)
    return {
        "distance": d,
        "below": below.to_json(),
        "above": above.to_json(),
        "passed": below.outcome == SURVIVE and above.outcome == CAPSIZE,
    }


def _heteroclinic(
    model: Any, params: Any, doc: dict[str, Any], Fn: float, error: float | None
) -> dict[str, Any]:
    """A heteroclinic method's JSON: its value checked against the fates at ``-+ 0.002``."""
    doc = {k: v for k, v in doc.items() if k != "fn_critical"}
    doc["quantity"] = "heteroclinic connection"
    doc["Fn_heteroclinic"] = Fn if Fn is not None and math.isfinite(Fn) else None
    doc["Fn_heteroclinic_error"] = error
    ok = doc.get("status") == "SUCCESS" and doc["Fn_heteroclinic"] is not None
    check = _evidence(model, params, Fn, CHECK_DISTANCE, 1200.0) if ok else None
    doc["threshold_check"] = check
    doc["is_threshold"] = bool(check and check["passed"])
    doc["Fn"] = Fn if doc["is_threshold"] else None
    if ok and not doc["is_threshold"]:
        doc["message"] = (
            f"the heteroclinic Fn {Fn:.6f} is not the capsizing threshold here: the upslope "
            f"branch {check['below']['fate']} at Fn - {CHECK_DISTANCE:g} and "
            f"{check['above']['fate']} at Fn + {CHECK_DISTANCE:g} (run --method threshold); "
            + str(doc.get("message", ""))
        )
    return doc


#: Distance in Fn of the fates that check a heteroclinic value (the issue's 0.002).
CHECK_DISTANCE = 0.002


def _threshold(model: Any, params: Any, args: argparse.Namespace) -> dict[str, Any]:
    from ship_models.analysis.threshold import capsizing_threshold

    tol = 2e-4 if args.tol is None else args.tol
    step = max(0.002, 2 * tol)
    with StatusLine(enabled=not args.json) as status:
        res = capsizing_threshold(
            model,
            params,
            t_max=args.t_max,
            tol=tol,
            step=step,
            coarse_step=max(0.01, step),
            Fn_range=(args.Fn_min, args.Fn_max) if args.fn_range_given else None,
            progress=lambda s: status.show(f"threshold: Fn = {s.Fn:.6f}: {s.label}"),
        )
    doc = {"method": "threshold", **res.to_json()}
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
    return _heteroclinic(model, params, {"method": "bvp", **res.to_json()}, res.Fn, res.error)


def _both(model: Any, params: Any, args: argparse.Namespace) -> dict[str, Any]:
    bvp = _bvp(model, params, args)
    bis = _bisection(model, params, args)
    ok = bvp["status"] == "SUCCESS" and bis["status"] == "SUCCESS"
    f_b, f_s = bvp["Fn_heteroclinic"], bis["Fn_heteroclinic"]
    diff = f_b - f_s if f_b is not None and f_s is not None else None
    bound = (bvp.get("Fn_heteroclinic_error") or 0.0) + (bis.get("error") or 0.0)
    agree = diff is not None and abs(diff) <= bound
    if agree:
        why = f"the two agree within their error bounds ({bound:.1e})"
    elif bis.get("not_a_connection"):
        why = bis["not_a_connection"]
    elif diff is None:
        why = "one of the two found no connection"
    else:
        why = (f"they differ by {diff:.1e}, more than their error bounds ({bound:.1e}): "
               "the fates switch more than once in the bracket")  # fmt: skip
    status = ("SUCCESS" if ok and agree else
              (bvp["status"] if bvp["status"] != "SUCCESS" else
               bis["status"] if bis["status"] != "SUCCESS" else "REJECTED"))  # fmt: skip
    return {
        "method": "both",
        "quantity": "heteroclinic connection",
        "Fn": bvp["Fn"] if agree else None,
        "Fn_heteroclinic": f_b,
        "is_threshold": bool(agree and bvp["is_threshold"]),
        "bracket": bis["bracket"],
        "difference": diff,
        "agree": agree,
        "why": why,
        "status": status,
        "message": why,
        "bvp": bvp,
        "bisection": bis,
    }


#: ``--method`` choices: name -> function(model, params, args) -> JSON-ready dict.
METHODS: dict[str, Callable[[Any, Any, argparse.Namespace], dict[str, Any]]] = {
    "threshold": _threshold,
    "bisection": _bisection,
    "bvp": _bvp,
    "both": _both,
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit critical``."""
    add_ship(parser, fn=False)
    parser.add_argument(
        "--method",
        choices=sorted(METHODS),
        default="threshold",
        help=(
            "threshold (default): the lowest capsizing Fn and its mechanism; bvp, bisection, "
            "both: the heteroclinic Fn, checked against the fates just below and above it"
        ),
    )
    add_fn_guess(parser)
    parser.add_argument(
        "--fn-min", dest="Fn_min", type=float, default=None,
        help="lower end of the Fn search (default: the surf-riding window of this wave)",
    )  # fmt: skip
    parser.add_argument(
        "--fn-max", dest="Fn_max", type=float, default=None,
        help="upper end of the Fn search (default: the surf-riding window of this wave)",
    )  # fmt: skip
    parser.add_argument(
        "--tol", type=float, default=None,
        help="final bracket width in Fn (threshold 2e-4, bisection 1e-5)",
    )  # fmt: skip
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
    return numerical_failure_exit(NAME, _run, args)


def _window(model: Any, params: Any, args: argparse.Namespace) -> None:
    """``--fn-min``/``--fn-max`` default to the surf-riding window of the sea state at hand
    (:func:`ship_models.analysis.fn_window.surf_riding_window`), within the resistance fit."""
    from ship_models.analysis.fn_window import surf_riding_window

    from ..options import fn_limit

    args.fn_range_given = args.Fn_min is not None or args.Fn_max is not None
    if args.Fn_min is None or args.Fn_max is None:
        w = surf_riding_window(model, params)
        lo, hi = (w.Fn_lo, w.Fn_hi) if w.exists else (0.05, fn_limit(model))
        if args.Fn_min is None:
            args.Fn_min = max(lo, 0.1)
        if args.Fn_max is None:
            args.Fn_max = min(hi, fn_limit(model))
    if not args.Fn_min < args.Fn_max:
        raise ValueError(
            f"--fn-min must be below --fn-max, got {args.Fn_min:g}, {args.Fn_max:g} (without "
            "them: the Fn range with surf-riding equilibria in this wave)"
        )


def _run(args: argparse.Namespace) -> int:
    """Locate the critical Fn; returns 0 on success, 1 otherwise."""
    for name, value in (("--fn-min", args.Fn_min), ("--fn-max", args.Fn_max)):
        if value is not None:
            finite(name, value, low=0.0)
    if args.tol is not None:
        finite("--tol", args.tol, low=0.0, high=0.1)
    finite("--t-max", args.t_max, low=0.0, high=1e5, unit="s")
    model, params = ship_from_args(args)
    for name, value in (("--fn-min", args.Fn_min), ("--fn-max", args.Fn_max)):
        if value is not None:
            check_fn(model, name, value)
    if args.Fn_guess is not None:
        check_fn(model, "--fn-guess", args.Fn_guess)
    _window(model, params, args)
    result = {"vessel": model.vessel.name, **METHODS[args.method](model, params, args)}
    result.update(wave_force_fields(model, params))  # issue 25: which wave forces were used
    ok = result["status"] == "SUCCESS" and result.get("Fn") is not None
    if args.json:
        print_json(result)
    elif args.method == "threshold" and result["Fn"] is None:
        sys.stderr.write(
            f"broachkit critical: no capsizing threshold in --fn-min/--fn-max = "
            f"[{result['scanned'][0]:.4g}, {result['scanned'][1]:.4g}] at chi_c = "
            f"{args.chi_c:g} deg (threshold, {result['status']}): {_reason(result)}\n"
        )
    elif args.method == "threshold":
        sys.stdout.write(_threshold_text(model, args, result) + "\n")
    elif result.get("Fn_heteroclinic") is None:
        sys.stderr.write(
            f"broachkit critical: no heteroclinic Fn in --fn-min/--fn-max = "
            f"[{args.Fn_min:.4g}, {args.Fn_max:.4g}] at chi_c = {args.chi_c:g} deg "
            f"({args.method}, {result['status']}): {_reason(result)}\n"
        )
    else:
        head = f"{model.vessel.name}, chi_c = {args.chi_c:g} deg ({args.method}): "
        if args.method == "bisection":
            lo, hi = result["bracket"]
            text = (
                f"heteroclinic Fn = {result['Fn_heteroclinic']:.7f} in [{lo:.7f}, {hi:.7f}] "
                f"({result['fate_lo']} below, {result['fate_hi']} above)"
            )
        elif args.method == "bvp":
            text = (
                f"heteroclinic Fn = {result['Fn_heteroclinic']:.8f} (connecting orbit, "
                f"|G| = {result['residual_norm']:.1e}, error estimate "
                f"{_num(result.get('error'))})"
            )
        else:
            lo, hi = result["bracket"]
            text = (
                f"bvp Fn = {result['Fn_heteroclinic']:.8f}; bisection bracket "
                f"[{lo:.7f}, {hi:.7f}]; {result['why']}"
            )
        chk = (result.get("bvp") or result).get("threshold_check") or {}
        if result.get("is_threshold"):
            verdict = "it is the capsizing threshold (the fates at -+0.002 are survive/capsize)"
        elif chk:
            verdict = (
                "it is NOT the capsizing threshold here: the upslope branch "
                f"{chk['below']['fate']} at Fn - 0.002 and {chk['above']['fate']} at Fn + 0.002 "
                "(run without --method for the threshold)"
            )
        else:
            verdict = "not checked against the fates: " + _reason(result)
        status = result["status"] if result.get("is_threshold") else (
            f"heteroclinic {result['status']}, not the threshold")  # fmt: skip
        sys.stdout.write(head + text + f"; {verdict}; {status}\n")
    return 0 if ok else 1


def _num(x: Any) -> str:
    return "n/a" if x is None else f"{x:.1e}"


def _threshold_text(model: Any, args: argparse.Namespace, r: dict[str, Any]) -> str:
    """The threshold's summary line(s)."""
    head = f"{model.vessel.name}, chi_c = {args.chi_c:g} deg: "
    if r["Fn"] is None:
        return head + f"no capsizing threshold ({r['status']}): {r['message']}"
    het = r["Fn_heteroclinic"]
    ev = r["evidence"]
    lines = [
        head + f"capsizing threshold Fn = {r['Fn']:.5f} +- {r['error']:.1e} "
        f"(mechanism: {r['mechanism']}); {r['status']}",
        "  heteroclinic Fn = "
        + (f"{het:.7f}" if het is not None else "none on this course")
        + (" (the same within their bounds)" if r["is_heteroclinic"] else ""),
        f"  fates: Fn - 0.002 {ev['below']['attractor'] if ev['below'] else '?'}, "
        f"Fn + 0.002 {ev['above']['attractor'] if ev['above'] else '?'}",
        "  " + r["message"],
    ]
    return "\n".join(lines)


def _reason(result: dict[str, Any]) -> str:
    """The one-line reason of a failed search (the library's message)."""
    for part in (result, result.get("bisection") or {}, result.get("bvp") or {}):
        msg = part.get("message")
        if msg:
            return " ".join(str(msg).split())
    return "the method gave no answer"
