"""``broachkit critical-curve``: critical Fn against the autopilot course (Umeda 1999, Fig. 23).

The heteroclinic connection of the crest saddle to the neighbouring crest saddle is
solved once as a boundary-value problem and continued in ``chi_c``
(:func:`ship_models.analysis.critical_curve.critical_curve`). Degrees on the command
line, radians inside.

Examples::

    broachkit critical-curve --chi-c 0:30 --out out/critical_curve
    broachkit critical-curve --chi-c 0:30:5 --json
    broachkit critical-curve --chi-c 0,10,20 --vessel my_ship.toml
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..files import write_atomic, write_json
from ..options import (
    CHI_C_MAX_DEG,
    add_fn_guess,
    add_json,
    add_out,
    add_vessel,
    add_wave,
    check_workers,
    json_safe,
    parse_list,
    prepare_out,
    ship_from_args,
)
from ..progress import StatusLine

NAME = "critical-curve"
HELP = "critical Fn against the autopilot course by continuing the heteroclinic connection"


def parse_courses(text: str) -> np.ndarray:
    """Courses in degrees from ``"a:b"`` (step 1), ``"a:b:step"``, ``"a,b,c"`` or ``"a"``.

    Raises
    ------
    ValueError
        Naming ``--chi-c`` for an unreadable, empty or out-of-range list.
    """
    deg = parse_list(text, "--chi-c", default_step=1.0)
    if np.any(np.abs(deg) >= CHI_C_MAX_DEG):
        raise ValueError(
            f"--chi-c courses must be finite and within +-{CHI_C_MAX_DEG:g} deg, got {text!r}"
        )
    return deg


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit critical-curve``."""
    parser.add_argument(
        "--chi-c",
        dest="chi_c",
        default="0:30",
        help="courses in degrees: 'start:stop[:step]' (step 1) or 'a,b,c' (default 0:30)",
    )
    add_vessel(parser)
    add_wave(parser)
    add_fn_guess(parser)
    add_out(parser, None, "the CSV, JSON and PNG (optional)")
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="processes solving the courses (default: one per core; 1: all in this process)",
    )
    add_json(parser)


def _ship(args: argparse.Namespace) -> tuple[Any, Any]:
    ns = argparse.Namespace(**vars(args))
    ns.chi_c = 0.0
    ns.Fn = args.Fn_guess
    return ship_from_args(ns)


def plot_curve(curve: Any, path: Path, *, paper: bool = True) -> Path:
    """The critical curve ``Fn(chi_c)`` as a PNG (the paper's Fig. 23 line)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ship_models.paper import PAPER_CHI_C_DEG, PAPER_FN_BRACKET

    fig, ax = plt.subplots(figsize=(5.2, 3.6))
    ok = curve.converged
    ax.plot(curve.chi_c_deg[ok], curve.Fn[ok], "o-", ms=3, label="BVP, this vessel")
    for c, f in curve.folds:
        ax.plot([np.degrees(c)], [f], "k^", ms=5, label="end (fold in chi_c)")
    if paper:
        ax.errorbar(
            [PAPER_CHI_C_DEG],
            [0.5 * sum(PAPER_FN_BRACKET)],
            yerr=[0.5 * (PAPER_FN_BRACKET[1] - PAPER_FN_BRACKET[0])],
            fmt="s", color="tab:red", ms=5, capsize=3,
            label="Umeda (1999), measured coeff.",
        )  # fmt: skip
    ax.set_xlabel("autopilot course chi_c (deg)")
    ax.set_ylabel("critical nominal Froude number Fn")
    ax.set_title("Critical condition for capsizing due to broaching")
    ax.grid(alpha=0.3)
    ax.legend(loc="center left", fontsize=7)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


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
    """Compute the curve; print it (or JSON); write files under ``--out``. 0 on success."""
    from ship_models.analysis.critical_curve import critical_curve

    deg = parse_courses(str(args.chi_c))
    workers = check_workers(args.workers)
    out = prepare_out(args.out)
    model, params = _ship(args)
    t0 = time.perf_counter()
    with StatusLine(enabled=not args.json) as status:
        curve = critical_curve(
            np.radians(deg),
            model=model,
            params=params,
            workers=workers,
            progress=lambda pt: status.show(
                f"continuing the connection: chi_c = {math.degrees(float(pt.p)):.2f} deg"
            ),
        )
    elapsed = time.perf_counter() - t0
    result = {
        "vessel": model.vessel.name,
        "method": "bvp-continuation",
        "H_over_lambda": params["H_over_lambda"],
        "lambda_over_L": params["lambda_over_L"],
        "elapsed_s": elapsed,
        **curve.to_json(),
    }
    if out is not None:
        write_atomic(out / "critical_curve.csv", curve.to_csv)
        write_json(out / "critical_curve.json", result)
        write_atomic(out / "critical_curve.png", lambda p: plot_curve(curve, p))
        result["files"] = [str(out / n) for n in ("critical_curve.csv", "critical_curve.json",
                                                  "critical_curve.png")]  # fmt: skip
    if args.json:
        sys.stdout.write(json.dumps(json_safe(result), indent=2) + "\n")
    else:
        sys.stdout.write(
            f"{model.vessel.name}: critical Fn by continuing the heteroclinic connection "
            f"({curve.status.name}, {elapsed:.1f} s)\n   chi_c (deg)   Fn_critical\n"
        )
        for c, f, ok, e, why in zip(
            curve.chi_c_deg, curve.Fn, curve.converged, curve.error, curve.reasons, strict=True
        ):
            if ok:
                sys.stdout.write(f"   {c:10.3f}   {f:.7f}   (error estimate {e:.1e})\n")
            else:
                sys.stdout.write(f"   {c:10.3f}   {'-':9s}   {why}\n")
        for c, f in curve.folds:
            sys.stdout.write(
                f"   fold of the critical curve: chi_c = {math.degrees(c):.3f} deg, Fn = {f:.5f}\n"
            )
        sys.stdout.write(f"   {curve.message}\n")
        if args.out is not None:
            sys.stdout.write(f"wrote {args.out}/critical_curve.{{csv,json,png}}\n")
    return 0 if curve.success else 1
