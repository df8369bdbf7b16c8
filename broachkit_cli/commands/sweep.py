"""``broachkit sweep boundary|courses|surface``: parallel, resumable ship sweeps.

One task per bisection (or per wavelength of the surface), run on local processes (one
per core, default), a Dask ``LocalCluster`` of ``--workers N`` started for the run, or
a running Dask scheduler (``--scheduler tcp://HOST:PORT``); every finished task is
checkpointed under ``OUT/checkpoints``, so running the same command again resumes
without redoing any finished task (:mod:`continuation.sweep`). Writes CSV + JSON + PNG.

Examples::

    broachkit sweep boundary --chi-c 10 --initial fn=0.1,chi_c=0 --positions 21 --out out/b
    broachkit sweep courses --chi-c 0:40:5 --workers 2 --out out/c
    broachkit sweep surface --chi-c 10 --h-over-lambda 0.02:0.11:10 \\
        --lambda-over-l 0.75:2.5:8 --out out/s
"""

from __future__ import annotations

import argparse
import logging
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from continuation.atomic import json_safe

from ..files import write_json, write_text
from ..options import MAX_LIST_VALUES, add_backend, backend_options, parse_list, prepare_out

NAME = "sweep"
HELP = "parallel, resumable sweeps: sudden-change boundary, Fig. 23 squares, critical surface"

log = logging.getLogger(__name__)

#: The paper's wave (Umeda 1999): H/lambda = 1/9.2, lambda/L = 1.5.
PAPER_WAVE = (1 / 9.2, 1.5)


# ----------------------------------------------------------------------- parsing
def parse_steps(text: str, flag: str) -> np.ndarray:
    """``"a:b:step"`` (inclusive), ``"a,b,c"`` or ``"a"`` -> values (courses in degrees)."""
    return parse_list(text, flag)


def parse_count(text: str, flag: str) -> np.ndarray:
    """``"a:b:n"`` (``n`` equally spaced values), ``"a,b,c"`` or ``"a"`` -> positive values."""
    grid = None
    try:
        if ":" in text:
            a, b, n = text.split(":")
            grid = (float(a), float(b), int(n))
            if grid[2] < 1 or grid[1] < grid[0]:
                raise ValueError
            count = grid[2]
        else:
            vals = np.array([float(s) for s in text.split(",")])
            count = vals.size
    except ValueError:
        raise ValueError(f"{flag} must be 'start:stop:count' or 'a,b,c', got {text!r}") from None
    if count > MAX_LIST_VALUES:  # checked before a grid is allocated
        raise ValueError(f"{flag} gives {count} values; at most {MAX_LIST_VALUES}")
    if grid is not None:
        vals = np.linspace(*grid)
    if vals.size == 0 or not np.all(np.isfinite(vals)) or np.any(vals <= 0):
        raise ValueError(f"{flag} must give positive numbers, got {text!r}")
    return vals


def parse_initial(text: str) -> tuple[float, float]:
    """``"fn=0.1,chi_c=0"`` (chi_c in degrees) -> ``(Fn, chi_c_deg)``."""
    try:
        d = {k.strip().lower(): float(v) for k, v in (p.split("=") for p in text.split(","))}
        out = (d.pop("fn"), d.pop("chi_c", 0.0))
        if d or not (out[0] > 0 and math.isfinite(out[1])):
            raise ValueError
    except (ValueError, KeyError):
        raise ValueError(f"--initial must be 'fn=F,chi_c=DEG', got {text!r}") from None
    return out


# ----------------------------------------------------------------------- arguments
def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--vessel", default="purse_seiner", help="vessel name or TOML file")
    p.add_argument("--out", type=Path, required=True, help="folder for CSV, JSON, PNG, checkpoints")
    add_backend(p, "the tasks")
    p.add_argument(
        "--retry-failed", action="store_true", help="rerun tasks whose checkpoint is a failure"
    )
    p.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="progress bar (default: only on a terminal)",
    )


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit sweep``."""
    sub = parser.add_subparsers(dest="sweep", metavar="SWEEP", required=True)
    b = sub.add_parser("boundary", help="critical Fn per initial position (Figs. 16/22)")
    b.add_argument("--chi-c", type=float, default=10.0, help="new course, degrees (default 10)")
    b.add_argument("--initial", default="fn=0.1,chi_c=0", help="old controls 'fn=F,chi_c=DEG'")
    b.add_argument("--positions", type=int, default=21, help="initial positions in [0, 1)")
    b.add_argument("--tol", type=float, default=2e-4, help="bisection width in Fn")
    b.add_argument("--fn-bracket", dest="Fn_bracket", default=None, help="'lo,hi' (default: auto)")
    b.add_argument("--follow-steps", type=int, default=0, help="follow the old orbit from (0.1, 0)")
    b.add_argument("--no-map", action="store_true", help="skip the outcome map")
    b.add_argument("--t-max", type=float, default=600.0, help="time limit of each run (s)")
    b.add_argument(
        "--method", choices=("bisection", "bvp"), default="bisection",
        help="bvp: also the boundary as a landing BVP at each bisected position (slower)",
    )  # fmt: skip
    _common(b)
    c = sub.add_parser("courses", help="critical Fn per course (Fig. 23 squares)")
    c.add_argument("--chi-c", default="0:30:10", help="courses 'a:b:step' or 'a,b' (degrees)")
    c.add_argument("--initial", default="fn=0.1,chi_c=0", help="old controls 'fn=F,chi_c=DEG'")
    c.add_argument("--xi-0", type=float, default=0.5, help="initial position (xi_G/lambda)_0")
    c.add_argument("--tol", type=float, default=2e-4, help="bisection width in Fn")
    c.add_argument("--t-max", type=float, default=600.0, help="time limit of each run (s)")
    _common(c)
    s = sub.add_parser("surface", help="critical Fn over wave steepness and length")
    s.add_argument("--chi-c", type=float, default=10.0, help="course, degrees (default 10)")
    s.add_argument("--h-over-lambda", default="0.02:0.11:10", help="'a:b:count' or 'a,b,c'")
    s.add_argument("--lambda-over-l", default="0.75:2.5:8", help="'a:b:count' or 'a,b,c'")
    s.add_argument(
        "--check", type=int, default=3, help="sample points re-checked by bisection (default 3)"
    )
    s.add_argument(
        "--thresholds", type=int, default=2,
        help="sample points where the capsizing threshold is computed, to say whether the "
             "surface of the connection is the threshold there (default 2)",
    )  # fmt: skip
    _common(s)


def _run_options(args: argparse.Namespace) -> dict[str, Any]:
    opts: dict[str, Any] = {
        "store": args.out / "checkpoints",
        "progress": args.progress,
        "retry_failed": args.retry_failed,
    }
    opts.update(backend_options(args))
    return opts


# ----------------------------------------------------------------------- outputs
def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _write_json(path: Path, data: dict[str, Any]) -> None:
    write_json(path, data, default=str, indent=1)


def _boundary(args: argparse.Namespace) -> tuple[dict[str, Any], bool]:
    from ship_models.analysis.sweeps import MAP_OFFSETS, boundary_sweep

    bracket = None
    if args.Fn_bracket:
        try:
            bracket = tuple(float(v) for v in args.Fn_bracket.split(","))
            if len(bracket) != 2:
                raise ValueError
        except ValueError:
            raise ValueError(f"--fn-bracket must be 'lo,hi', got {args.Fn_bracket!r}") from None
    if not 1 <= args.positions <= MAX_LIST_VALUES:
        raise ValueError(
            f"--positions must be an integer in [1, {MAX_LIST_VALUES}], got {args.positions}"
        )
    r = boundary_sweep(
        args.vessel, args.chi_c, initial=parse_initial(args.initial), positions=args.positions,
        tol=args.tol, Fn_bracket=bracket, map_offsets=None if args.no_map else MAP_OFFSETS,
        follow_steps=args.follow_steps, t_max=args.t_max, method=args.method,
        **_run_options(args),
    )  # fmt: skip
    out = args.out
    r.boundaries.write_csv(out / "boundary.csv")
    if r.bvp is not None:
        from ship_models.analysis.capsize_boundary import ROW_HEADER

        with (out / "boundary_bvp.csv").open("w") as fh:
            fh.write(",".join(ROW_HEADER) + "\n")
            for row in r.bvp.rows():
                fh.write(",".join(str(v) for v in row) + "\n")
    if r.outcomes is not None:
        r.outcomes.write_csv(out / "boundary_map.csv")
    data = {
        "chi_c_deg": r.chi_c_deg,
        "initial": args.initial,
        "heteroclinic_Fn": json_safe(r.heteroclinic_Fn),
        "xi_0": json_safe(r.xi_0),
        "Fn": json_safe(r.Fn),
        "boundaries": r.boundaries.to_json(),
        "outcome_map": None if r.outcomes is None else r.outcomes.to_json(),
        "bvp": None if r.bvp is None else json_safe(r.bvp.to_json()),
    }
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5.6, 3.9))
    if r.outcomes is not None:
        style = {"capsize": ("x", "tab:red"), "periodic": ("o", "tab:blue")}
        for rec in r.outcomes.records:
            if rec.done:
                m, col = style.get(rec.value["outcome"], ("^", "tab:gray"))
                ax.plot(rec.key["xi_0"], rec.key["Fn"], m, color=col, mfc="none", ms=5)
    ok = np.isfinite(r.Fn)
    ax.plot(r.xi_0[ok], r.Fn[ok], "D-", color="tab:green", ms=3, lw=0.8, label="boundary")
    if r.bvp is not None:
        for seg in r.bvp.segments:
            ax.plot(seg.xi_0, seg.Fn, "-", color="tab:purple", lw=1.0)
        pts = [p for p in r.bvp.points if p.success]
        ax.plot([p.xi_0 for p in pts], [p.Fn for p in pts], "*", color="tab:purple", ms=7,
                label="boundary by BVP (landing)")  # fmt: skip
    if math.isfinite(r.heteroclinic_Fn):
        ax.axhline(r.heteroclinic_Fn, color="k", lw=0.8, ls="--", label="heteroclinic Fn")
    ax.set_xlabel("initial position (xi_G/lambda)_0")
    ax.set_ylabel("nominal Froude number Fn")
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.set_title(f"Sudden change to chi_c = {r.chi_c_deg:g} deg from {args.initial}", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "boundary.png", dpi=120)
    plt.close(fig)
    parts = [r.boundaries] + ([r.outcomes] if r.outcomes is not None else [])
    if r.bvp is not None:
        n_bvp = sum(p.success for p in r.bvp.points)
        return data, _Outcome(parts, [f"{n_bvp} of {len(r.bvp.points)} landing BVPs converged"],
                              failed_checks=len(r.bvp.points) - n_bvp)  # fmt: skip
    return data, _Outcome(parts)


def _courses(args: argparse.Namespace) -> tuple[dict[str, Any], bool]:
    from ship_models.analysis.sweeps import courses_sweep

    degs = parse_steps(args.chi_c, "--chi-c")
    if np.any(np.abs(degs) >= 85):
        raise ValueError(f"--chi-c courses must be within +-85 deg, got {args.chi_c!r}")
    r = courses_sweep(
        args.vessel, degs, initial=parse_initial(args.initial), xi_0=args.xi_0, tol=args.tol,
        t_max=args.t_max, **_run_options(args),
    )  # fmt: skip
    out = args.out
    r.boundaries.write_csv(out / "courses.csv")
    data = {
        "chi_c_deg": json_safe(r.chi_c_deg),
        "Fn": json_safe(r.Fn),
        "heteroclinic_Fn": json_safe(r.heteroclinic_Fn),
        "xi_0": r.xi_0,
        "boundaries": r.boundaries.to_json(),
    }
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5.6, 3.9))
    ok = np.isfinite(r.heteroclinic_Fn)
    ax.plot(r.chi_c_deg[ok], r.heteroclinic_Fn[ok], "o-", ms=3, label="heteroclinic bifurcation")
    ok = np.isfinite(r.Fn)
    ax.plot(r.chi_c_deg[ok], r.Fn[ok], "s", mfc="none", ms=8, label="sudden change (bisection)")
    ax.set_xlabel("autopilot course chi_c (deg)")
    ax.set_ylabel("critical nominal Froude number")
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "courses.png", dpi=120)
    plt.close(fig)
    return data, _Outcome([r.boundaries])


def _surface(args: argparse.Namespace) -> tuple[dict[str, Any], bool]:
    from ship_models.analysis.sweeps import surface_sweep

    hs = parse_count(args.h_over_lambda, "--h-over-lambda")
    ls = parse_count(args.lambda_over_l, "--lambda-over-l")
    if args.check < 0:
        raise ValueError(f"--check must be a non-negative integer, got {args.check}")
    if args.thresholds < 0:
        raise ValueError(f"--thresholds must be a non-negative integer, got {args.thresholds}")
    r = surface_sweep(
        args.vessel, args.chi_c, H_over_lambda=hs, lambda_over_L=ls, check=args.check,
        thresholds=args.thresholds, **_run_options(args),
    )  # fmt: skip
    out = args.out
    lines = ["lambda_over_L,H_over_lambda,Fn,Fn_surge"]
    for i, lL in enumerate(r.lambda_over_L):
        for j, h in enumerate(r.H_over_lambda):
            cells = [float(lL), float(h), float(r.Fn[i, j]), float(r.Fn_surge[i, j])]
            lines.append(",".join("" if math.isnan(v) else repr(v) for v in cells))
    write_text(out / "surface.csv", "\n".join(lines) + "\n")
    data = {
        "chi_c_deg": r.chi_c_deg,
        "H_over_lambda": json_safe(r.H_over_lambda),
        "lambda_over_L": json_safe(r.lambda_over_L),
        "Fn": json_safe(r.Fn),
        "Fn_surge_chi_c_0": json_safe(r.Fn_surge),
        "reasons": list(r.reasons),
        "checks_by_bisection": list(r.checks),
        "quantity": "heteroclinic Fn (the connection); see capsizing_thresholds for where it "
        "is the capsizing threshold",
        "capsizing_thresholds": list(r.thresholds),
        "sweep": r.sweep.to_json(),
        "check_sweep": None if r.check_sweep is None else r.check_sweep.to_json(),
    }
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, z, title in (
        (axes[0], r.Fn, f"heteroclinic Fn, chi_c = {r.chi_c_deg:g} deg"),
        (axes[1], r.Fn_surge, "surge-only threshold, chi_c = 0"),
    ):
        zm = np.ma.masked_invalid(z)
        if zm.count() >= 4 and r.H_over_lambda.size > 1 and r.lambda_over_L.size > 1:
            cs = ax.contourf(r.H_over_lambda, r.lambda_over_L, zm, levels=12, cmap="viridis")
            fig.colorbar(cs, ax=ax, label="critical Fn")
        H, L = np.meshgrid(r.H_over_lambda, r.lambda_over_L)
        ax.plot(H[zm.mask], L[zm.mask], "k.", ms=3, label="no connection")
        ax.plot(*PAPER_WAVE, "r*", ms=10, label="Umeda (1999) wave")
        ax.set_xlabel("wave steepness H/lambda")
        ax.set_title(title, fontsize=9)
        ax.legend(fontsize=7, loc="upper right")
    axes[0].set_ylabel("wavelength lambda/L")
    fig.tight_layout()
    fig.savefig(out / "surface.png", dpi=120)
    plt.close(fig)
    for c in r.checks:
        log.info(
            "check lambda/L = %g, H/lambda = %g: connection Fn %.7f, bisection [%s, %s]: %s "
            "(outside by %s; bisection %s)",
            c["lambda_over_L"], c["H_over_lambda"], c["Fn"], c["Fn_lower"], c["Fn_upper"],
            {True: "agrees", False: "DISAGREES", None: "inconclusive"}[c["agrees"]],
            c["difference"], c["status"],
        )  # fmt: skip
    agree = sum(c["agrees"] is True for c in r.checks)
    notes = [f"{agree} of {len(r.checks)} checks by bisection agree"] if r.checks else []
    if r.thresholds:
        het = sum(t["is_heteroclinic"] is True for t in r.thresholds)
        notes.append(
            f"the surface is the capsizing threshold at {het} of {len(r.thresholds)} sampled "
            "sea states (" + "; ".join(
                f"H/lambda {t['H_over_lambda']:.3g}, lambda/L {t['lambda_over_L']:.3g}: "
                f"{t['Fn'] if t['Fn'] is None else format(t['Fn'], '.5f')} ({t['mechanism']})"
                for t in r.thresholds) + ")"
        )  # fmt: skip
    if args.check and not r.checks and r.sweep.status.name != "INTERRUPTED":
        notes.append("no converged point to check")
    parts = [r.sweep] + ([r.check_sweep] if r.check_sweep is not None else [])
    return data, _Outcome(parts, notes, failed_checks=len(r.checks) - agree)


@dataclass
class _Outcome:
    """What a sweep ran (its task sweeps), what its checks found, and its one status."""

    parts: list[Any]
    notes: list[str] = field(default_factory=list)
    failed_checks: int = 0

    @property
    def status(self) -> str:
        """``INTERRUPTED``, ``FAILED`` (a task failed), ``CHECK_FAILED`` or ``SUCCESS``.

        ``SUCCESS`` is a claim: every task finished with a value *and* every check
        agreed; a sweep whose checks failed never reports it.
        """
        if any(p.status.name == "INTERRUPTED" for p in self.parts):
            return "INTERRUPTED"
        if any(p.n_failed for p in self.parts):
            return "FAILED"
        if self.failed_checks:
            return "CHECK_FAILED"
        return "SUCCESS"

    def summary(self, kind: str, out: Path) -> str:
        """The sweep's one-line summary."""
        n = sum(p.n_tasks for p in self.parts)
        done = sum(len(p.records) - p.n_failed for p in self.parts)
        failed = sum(p.n_failed for p in self.parts)
        reused = sum(p.n_reused for p in self.parts)
        secs = sum(p.elapsed_s for p in self.parts)
        counts = f"{done} of {n} tasks done ({reused} from checkpoints), {failed} failed"
        extra = "".join(f"; {t}" for t in self.notes)
        return f"sweep {kind}: {self.status}: {counts}{extra}; {secs:.1f} s; results in {out}"


def run(args: argparse.Namespace) -> int:
    """Run one sweep and print its one-line summary.

    Returns 0 when every task succeeded and every check agreed, 1 if a task failed or a
    check disagreed, 130 if interrupted (finished tasks are kept in the checkpoints).
    """
    prepare_out(args.out)  # checked (created, writable) before anything is computed
    _run_options(args)  # worker counts checked before anything starts
    fn = {"boundary": _boundary, "courses": _courses, "surface": _surface}[args.sweep]
    data, outcome = fn(args)
    data = {"status": outcome.status, **data}
    _write_json(args.out / f"{args.sweep}.json", data)
    log.info("wrote %s/%s.{csv,json,png}", args.out, args.sweep)
    sys.stdout.write(outcome.summary(args.sweep, args.out) + "\n")
    if outcome.status == "INTERRUPTED":
        sys.stderr.write("interrupted: run the same command again to resume\n")
        return 130
    return 0 if outcome.status == "SUCCESS" else 1
