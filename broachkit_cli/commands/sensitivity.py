"""``broachkit sensitivity`` and ``broachkit calibrate``: how far to trust the critical Fn.

``broachkit sensitivity --chi-c 10 [--json] [--keys K1,K2] [--samples N] [--out DIR]``
differentiates the critical connection with respect to every coefficient of the
vessel (:func:`ship_models.analysis.sensitivity.critical_fn_sensitivity`), prints the
elasticities sorted by size and the uncertainty band of the vessel file's
uncertainties (:func:`~ship_models.analysis.sensitivity.uncertainty_band`; with
``--samples N`` also the spread of N re-solved connections), and with ``--out``
writes ``sensitivity.json`` and the tornado figure ``tornado.png``.

``broachkit calibrate --target fn_crit=0.32475 --chi-c 10 --coefficient NAME``
solves the named coefficient so that the critical Fn equals the target
(:func:`ship_models.analysis.calibration.calibrate`), writes the calibrated vessel
file (``--out``) and with ``--curve`` recomputes the critical curve against the
course for both vessels. A calibration, never a prediction.

Degrees on the command line, radians inside.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

from ..files import write_json
from ..options import parse_list, prepare_out, prepare_out_file

NAME = "sensitivity"
HELP = "sensitivity of the critical Fn to every vessel coefficient, and its uncertainty band"


def _chi(value: float, flag: str = "--chi-c") -> float:
    v = float(value)
    if not (math.isfinite(v) and abs(v) < 85.0):
        raise ValueError(f"`{flag}` must be a course in degrees with |chi_c| < 85, got {value}")
    return math.radians(v)


def _vessel(name: str) -> Any:
    from ship_models.vessel import load_vessel

    return load_vessel(name)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit sensitivity``."""
    parser.add_argument("--vessel", default="purse_seiner", help="vessel name or TOML path")
    parser.add_argument("--chi-c", type=float, default=10.0, help="course in degrees (10)")
    parser.add_argument(
        "--keys",
        default=None,
        help="comma-separated dotted keys / factor names (default: every coefficient)",
    )
    parser.add_argument(
        "--samples",
        type=int,
        default=0,
        help="re-solve the connection for N sampled coefficient sets (default 0)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the samples")
    parser.add_argument("--top", type=int, default=25, help="rows shown / in the figure")
    parser.add_argument("--out", type=Path, default=None, help="directory for JSON and PNG")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")


#: What is differentiated, and when it is the capsizing threshold's derivative.
QUANTITY = (
    "derivatives of the heteroclinic Fn (the connection, by one adjoint solve); they are the "
    "capsizing threshold's where its mechanism is heteroclinic (`broachkit critical`: the "
    "default vessel up to 28 deg), not beyond"
)


def run(args: argparse.Namespace) -> int:
    """Run ``broachkit sensitivity``; returns the exit code."""
    from ship_models.analysis.sensitivity import (
        critical_fn_sensitivity,
        tornado_figure,
        uncertainty_band,
    )

    chi = _chi(args.chi_c)
    if args.samples < 0:
        raise ValueError(f"`--samples` must be >= 0, got {args.samples}")
    if args.top < 1:
        raise ValueError(f"`--top` must be >= 1, got {args.top}")
    prepare_out(args.out)  # checked before anything is computed
    vessel = _vessel(args.vessel)
    keys = None if args.keys is None else [k.strip() for k in args.keys.split(",") if k.strip()]

    def progress(key: str) -> None:
        if not args.json:
            sys.stderr.write(f"  {key}\n")

    sens = critical_fn_sensitivity(chi, vessel=vessel, keys=keys, progress=progress)
    band = None
    have = {e.key for e in sens.entries}
    resolved = sens.connection.orbit.problem.system.vessel
    needed = [k for k in vessel.uncertainties if k in resolved.coefficients]
    if needed and all(k in have for k in needed):  # a --keys subset gives no band
        band = uncertainty_band(sens, vessel, n_samples=args.samples, seed=args.seed)
    doc: dict[str, Any] = {
        "quantity": QUANTITY,
        "sensitivity": sens.to_json(),
    }
    if band is not None:
        doc["band"] = band.to_json()
    if args.out is not None:
        write_json(args.out / "sensitivity.json", doc)
        tornado_figure(sens, args.out / "tornado.png", top=args.top, band=band)
        doc["files"] = [str(args.out / "sensitivity.json"), str(args.out / "tornado.png")]
    if args.json:
        sys.stdout.write(json.dumps(doc, indent=2) + "\n")
        return 0
    out = sys.stdout
    out.write(
        f"heteroclinic Fn = {sens.Fn:.8f} at chi_c = {args.chi_c:g} deg "
        f"({len(sens.entries)} coefficients, {sens.elapsed:.0f} s)\n{QUANTITY}\n"
    )
    out.write(
        f"{'coefficient':<34} {'status':<10} {'value':>12} {'dFn/dtheta':>12} {'elast.':>9}\n"
    )
    for e in sens.entries[: args.top]:
        el = "-" if e.elasticity is None else f"{e.elasticity:+.4f}"
        out.write(f"{e.key:<34} {e.status:<10} {e.value:>12.5g} {e.dFn_dtheta:>+12.4e} {el:>9}\n")
    if band is not None:
        lo, hi = band.band
        out.write(
            f"standard uncertainty of Fn* (linear): {band.sigma_linear:.5f}; "
            f"{band.coverage:g}-sigma band [{lo:.5f}, {hi:.5f}]\n"
        )
        if band.samples.size:
            out.write(
                f"sampled: {band.samples.size} connections, std {band.sigma_sampled:.5f} "
                f"({band.failed} failed)\n"
            )
        out.write("dominant: " + ", ".join(f"{k} ({v:.4f})" for k, v in band.contributions[:3]))
        out.write("\n")
    for f in doc.get("files", []):
        out.write(f"wrote {f}\n")
    return 0


# ----------------------------------------------------------------------------- calibrate
CALIBRATE_NAME = "calibrate"
CALIBRATE_HELP = "solve one vessel coefficient so that the critical Fn equals a target"


def _target(text: str) -> float:
    name, sep, val = text.partition("=")
    if not sep or name.strip().lower() not in ("fn_crit", "fn"):
        raise ValueError(f"`--target` must be fn_crit=VALUE, got {text!r}")
    try:
        v = float(val)
    except ValueError:
        raise ValueError(f"`--target` value must be a number, got {val!r}") from None
    if not (math.isfinite(v) and 0 < v < 1.5):
        raise ValueError(f"`--target` Fn must be in (0, 1.5), got {v}")
    return v


def add_calibrate_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit calibrate``."""
    parser.add_argument("--target", required=True, help="fn_crit=VALUE: the target critical Fn")
    parser.add_argument("--chi-c", type=float, default=10.0, help="course of the target (deg)")
    parser.add_argument(
        "--coefficient",
        default="hydrodynamics.wave_surge_scale",
        help="key of the coefficient solved for, dotted or its last part when unique "
        "(default hydrodynamics.wave_surge_scale)",
    )
    parser.add_argument("--vessel", default="purse_seiner", help="vessel name or TOML path")
    parser.add_argument(
        "--target-source",
        default=None,
        help="where the target comes from (default: Umeda 1999's 0.3247-0.3248 at 10 deg)",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help="calibrated vessel file, or a folder for <vessel>_calibrated.toml "
        "(default <vessel>_calibrated.toml here)",
    )
    parser.add_argument(
        "--curve",
        default=None,
        help="courses in degrees for the critical curves, e.g. 0:30:5 or 0,10,20",
    )
    parser.add_argument("--json", action="store_true", help="print the result as JSON")


def _courses(text: str) -> list[float]:
    vals = parse_list(text, "--curve")
    return [_chi(float(v), "--curve") for v in vals]


def run_calibrate(args: argparse.Namespace) -> int:
    """Run ``broachkit calibrate``; returns the exit code."""
    from ship_models.analysis.calibration import (
        PAPER_TARGET_SOURCE,
        calibrate,
        calibrated_curves,
    )

    target = _target(args.target)
    chi = _chi(args.chi_c)
    courses = None if args.curve is None else _courses(args.curve)
    vessel = _vessel(args.vessel)
    # the file is checked before anything is computed (a folder: <folder>/<vessel>_...)
    out = prepare_out_file(args.out or Path("."), f"{vessel.name}_calibrated.toml")
    src = args.target_source or PAPER_TARGET_SOURCE
    cal = calibrate(args.coefficient, target, chi, vessel=vessel, target_source=src)
    path = cal.write(out)
    doc: dict[str, Any] = {"calibration": cal.to_json(), "file": str(path)}
    curves = None
    if courses is not None:
        curves = calibrated_curves(cal, courses, vessel=vessel)
        doc["curves"] = curves.to_json()
    if args.json:
        sys.stdout.write(json.dumps(doc, indent=2) + "\n")
        return 0 if cal.success else 1
    o = sys.stdout
    o.write(f"CALIBRATION (not a prediction): {cal.message}\n")
    o.write(f"critical Fn before: {cal.Fn_before:.8f}; wrote {path}\n")
    if curves is not None:
        o.write(f"{'chi_c (deg)':>11} {'Fn predicted':>13} {'Fn calibrated':>14}\n")
        for c, a, b in zip(curves.chi_c, curves.predicted.Fn, curves.calibrated.Fn, strict=True):
            o.write(f"{math.degrees(c):>11.3g} {a:>13.6f} {b:>14.6f}\n")
        o.write(
            f"curve status: predicted {curves.predicted.status.name}, calibrated "
            f"{curves.calibrated.status.name}\n"
        )
    return 0 if cal.success else 1
