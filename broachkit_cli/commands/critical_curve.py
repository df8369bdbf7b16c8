"""``broachkit critical-curve``: both lines of Fig. 23 against the autopilot course.

The heteroclinic connection of the crest saddle to the neighbouring crest saddle is
solved once as a boundary-value problem and continued in ``chi_c``
(:func:`ship_models.analysis.critical_curve.critical_curve`): the heteroclinic line, to
its fold. The capsizing threshold (the lowest Fn at which the upslope branch capsizes,
:func:`ship_models.analysis.threshold_curve.threshold_curve`) is computed at every
``--threshold-step`` degrees of the range, with its mechanism per course and the courses
between which the two lines part. Degrees on the command line, radians inside.

Examples::

    broachkit critical-curve --chi-c 0:30 --out out/critical_curve
    broachkit critical-curve --chi-c 0:30:5 --json
    broachkit critical-curve --chi-c 0,10,20 --vessel my_ship.toml
"""

from __future__ import annotations

import argparse
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
    finite,
    numerical_failure_exit,
    parse_list,
    prepare_out,
    print_json,
    ship_from_args,
)
from ..progress import StatusLine

NAME = "critical-curve"
HELP = "capsizing threshold and heteroclinic Fn against the autopilot course (Fig. 23)"


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
    parser.add_argument(
        "--threshold-step", dest="threshold_step", type=float, default=5.0, metavar="DEG",
        help="capsizing threshold every DEG degrees of the range (default 5; 0: none)",
    )  # fmt: skip
    add_json(parser)


def threshold_courses(deg: np.ndarray, step: float) -> np.ndarray:
    """Courses (deg) of the threshold: every ``step`` from the first requested course."""
    if step <= 0:
        return np.zeros(0)
    lo, hi = float(np.min(deg)), float(np.max(deg))
    out = np.arange(lo, hi + 1e-9, step)
    return out if out.size else np.array([lo])


def _ship(args: argparse.Namespace) -> tuple[Any, Any]:
    ns = argparse.Namespace(**vars(args))
    ns.chi_c = 0.0
    ns.Fn = args.Fn_guess
    return ship_from_args(ns)


def plot_curve(curve: Any, path: Path, *, paper: bool = True, thresholds: Any = None) -> Path:
    """Both lines of Fig. 23 as a PNG: the heteroclinic Fn and the capsizing threshold."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ship_models.paper import PAPER_CHI_C_DEG, PAPER_FN_BRACKET

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    ok = curve.converged
    ax.plot(curve.chi_c_deg[ok], curve.Fn[ok], "-", color="k", lw=1.2,
            label="heteroclinic Fn (connection continued)")  # fmt: skip
    if thresholds is not None and len(thresholds.chi_c):
        het = thresholds.is_heteroclinic_mask()
        c, f, e = thresholds.chi_c_deg, thresholds.Fn, thresholds.error
        ax.errorbar(c[het], f[het], yerr=e[het], fmt="o", color="tab:red", ms=5, capsize=2,
                    label="capsizing threshold = heteroclinic")  # fmt: skip
        ax.errorbar(c[~het], f[~het], yerr=e[~het], fmt="s", color="tab:red", mfc="white",
                    ms=5, capsize=2, label="capsizing threshold, another mechanism")  # fmt: skip
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
    ax.set_ylabel("nominal Froude number Fn")
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.set_title("Critical condition for capsizing due to broaching")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def run(args: argparse.Namespace) -> int:
    """Run the command; a numerical failure is one line on stderr (exit 1), never a traceback."""
    return numerical_failure_exit(NAME, _run, args)


def _run(args: argparse.Namespace) -> int:
    """Compute the curve; print it (or JSON); write files under ``--out``. 0 on success."""
    from ship_models.analysis.critical_curve import critical_curve
    from ship_models.analysis.threshold_curve import threshold_curve

    deg = parse_courses(str(args.chi_c))
    if args.threshold_step != 0:  # 0: no threshold (the help's promise)
        finite("--threshold-step", args.threshold_step, low=0.0, high=90.0, unit="deg")
    th_deg = threshold_courses(deg, args.threshold_step)
    all_deg = np.union1d(deg, th_deg)
    workers = check_workers(args.workers)
    out = prepare_out(args.out)
    model, params = _ship(args)
    t0 = time.perf_counter()
    with StatusLine(enabled=not args.json) as status:
        curve = critical_curve(
            np.radians(all_deg),
            model=model,
            params=params,
            workers=workers,
            progress=lambda pt: status.show(
                f"continuing the connection: chi_c = {math.degrees(float(pt.p)):.2f} deg"
            ),
        )
        tc = None
        if th_deg.size:
            status.show(f"capsizing threshold at {th_deg.size} course(s) (fates of the branch)")
            tc = threshold_curve(np.radians(th_deg), model=model, params=params,
                                 heteroclinic=curve, workers=workers)  # fmt: skip
    elapsed = time.perf_counter() - t0
    result = {
        "vessel": model.vessel.name,
        "method": "bvp-continuation",
        "H_over_lambda": params["H_over_lambda"],
        "lambda_over_L": params["lambda_over_L"],
        **curve.to_json(),
        **(tc.to_json() if tc is not None else {}),
        "elapsed_s": elapsed,  # the whole computation: the line and the thresholds
    }
    if out is not None:
        write_atomic(out / "critical_curve.csv", curve.to_csv)
        write_json(out / "critical_curve.json", result)
        write_atomic(out / "critical_curve.png", lambda p: plot_curve(curve, p, thresholds=tc))
        names = ["critical_curve.csv", "critical_curve.json", "critical_curve.png"]
        if tc is not None:
            write_atomic(out / "threshold_curve.csv", tc.to_csv)
            names.append("threshold_curve.csv")
        result["files"] = [str(out / n) for n in names]
    if args.json:
        print_json(result)
    else:
        sys.stdout.write(
            f"{model.vessel.name}: heteroclinic Fn by continuing the connection "
            f"({curve.status.name}, {elapsed:.1f} s)\n   chi_c (deg)   Fn_heteroclinic\n"
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
        if tc is not None:
            sys.stdout.write(
                "capsizing threshold (lowest Fn at which the upslope branch capsizes):\n"
                "   chi_c (deg)   Fn_threshold         mechanism\n"
            )
            for c, t in zip(tc.chi_c_deg, tc.thresholds, strict=True):
                if math.isfinite(t.Fn):
                    val = f"{t.Fn:.5f} +- {t.error:.0e}"
                    row = f"{val:18s}   {t.mechanism} ({t.status.name})"
                else:  # no threshold: say why, as the heteroclinic table does
                    row = f"{'-':18s}   {t.status.name}: {t.message}"
                sys.stdout.write(f"   {c:10.3f}   {row}\n")
            sys.stdout.write(f"   {tc.message}\n")
        if args.out is not None:
            sys.stdout.write(f"wrote {args.out}/critical_curve.{{csv,json,png}}\n")
    ok = curve.success and (tc is None or tc.status.name == "SUCCESS")
    return 0 if ok else 1
