"""``broachkit cycles``: the overtaken-by-waves cycle continued in Fn (or chi_c).

The ship overtaken by waves is a rotation orbit on the wave-relative coordinate
(``xi_G/lambda`` falls by one wavelength per period). It is found from a settled
simulation at ``--fn``/``--chi-c`` and corrected by collocation
(:func:`ship_models.analysis.cycles.simulated_cycle`), then continued in ``Fn``
(``--vary fn``, up to ``--fn-max``) or ``chi_c`` (``--vary chi-c``, both ways in
``[--chi-c-min, --chi-c-max]``) by :func:`ship_models.analysis.cycles.cycle_branch`
until its period exceeds ``--period-max``. Near the heteroclinic bifurcation the
period grows like ``T = a - b ln|p* - p|``; the fitted ``p*`` is printed, and with
``--compare`` (``--vary fn`` only) beside the critical Fn of the connecting-orbit
solver (:func:`ship_models.analysis.critical_bvp.critical_fn_bvp`). Also printed:
where the cycle first has a Floquet multiplier outside the unit circle, and its
largest roll against the angle of vanishing stability (a cycle rolling past it is a
capsize, not a cycle, and the command says so and exits with 1).

With ``--out DIR``: ``cycles_<vary>.csv`` (one row per cycle), ``cycles_<vary>.json``
(the summary and the rows) and ``cycles_<vary>.png``, each written atomically.
Degrees on the command line and in the output (``*_deg``), radians inside.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..cycle_options import START_FN, add_branch_options, check_branch_options, emit, roll_verdict
from ..files import csv_text, write_atomic, write_json, write_text
from ..options import (
    add_out,
    add_ship,
    check_chi_c_deg,
    check_fn,
    finite,
    prepare_out,
    ship_from_args,
)

NAME = "cycles"
HELP = "the overtaken-by-waves cycle continued in Fn (or chi_c) to its period blow-up"

#: Branch end statuses that are a complete answer (the period blew up, or the
#: parameter range was covered).
COMPLETE = ("PERIOD_UNBOUNDED", "PARAM_BOUND", "SUCCESS")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit cycles``."""
    add_ship(parser)
    parser.set_defaults(Fn=START_FN)
    parser.add_argument(
        "--vary",
        choices=("fn", "chi-c"),
        default="fn",
        help="the continuation parameter (default fn)",
    )
    parser.add_argument(
        "--fn-max", dest="Fn_max", type=float, default=0.4, help="--vary fn: upper Fn (0.4)"
    )
    parser.add_argument(
        "--chi-c-min", dest="chi_c_min", type=float, default=0.0,
        help="--vary chi-c: lower course in deg (0)",
    )  # fmt: skip
    parser.add_argument(
        "--chi-c-max", dest="chi_c_max", type=float, default=60.0,
        help="--vary chi-c: upper course in deg (60)",
    )  # fmt: skip
    add_branch_options(
        parser, "--vary fn: also solve the heteroclinic connection for its critical Fn"
    )
    add_out(parser, None, "cycles_<vary>.csv/.json/.png")


def check_args(args: argparse.Namespace) -> None:
    """The options' own checks (before the vessel is loaded); ValueError naming one."""
    finite("--fn", args.Fn, low=0.0)
    check_chi_c_deg("--chi-c", args.chi_c)
    check_branch_options(args)
    if args.vary == "fn":
        finite("--fn-max", args.Fn_max, low=0.0)
        if not args.Fn < args.Fn_max:
            raise ValueError(f"--fn-max must be above --fn, got {args.Fn_max} <= {args.Fn}")
    else:
        if args.compare:
            raise ValueError("--compare needs --vary fn (the connection gives a critical Fn)")
        lo = check_chi_c_deg("--chi-c-min", args.chi_c_min)
        hi = check_chi_c_deg("--chi-c-max", args.chi_c_max)
        if not lo <= args.chi_c <= hi or lo == hi:
            raise ValueError(
                f"--chi-c-min/--chi-c-max = [{lo:g}, {hi:g}] must be an interval holding "
                f"--chi-c = {args.chi_c:g}"
            )


def _start_cycle(model: Any, params: Any) -> Any:
    """The cycle at ``params``: simulated there, or continued there from a simulated one
    at ``Fn = START_FN`` on the same course, or at ``Fn = START_FN`` in head-on following
    waves (``chi_c = 0``: course first, then Fn)."""
    from continuation.errors import ContinuationError
    from ship_models.analysis.cycles import cycle_at, simulated_cycle

    Fn, chi_c = float(params["Fn"]), float(params["chi_c"])
    try:
        return simulated_cycle(model, params)
    except ValueError as exc:
        first = exc
    starts = [(START_FN, chi_c), (START_FN, 0.0)]
    for fn0, chi0 in starts:
        if math.isclose(fn0, Fn) and math.isclose(chi0, chi_c):
            continue
        try:
            orbit = simulated_cycle(model, params.replace(Fn=fn0, chi_c=chi0))
            return cycle_at(orbit, chi_c=chi_c, Fn=Fn)
        except (ValueError, ContinuationError):
            continue
    raise ValueError(
        f"no overtaken-by-waves cycle found at Fn = {Fn:g}, chi_c = {math.degrees(chi_c):g} "
        f"deg: {first}; continuation from Fn = {START_FN:g} (this course, and chi_c = 0) "
        "did not reach it either"
    )


def compute(model: Any, params: Any, args: argparse.Namespace) -> tuple[dict[str, Any], Any]:
    """The branch and its JSON summary (angles in degrees)."""
    from ship_models.analysis.cycles import cycle_branch
    from ship_models.analysis.events import capsize_angle

    orbit = _start_cycle(model, params)
    if args.vary == "fn":
        cb = cycle_branch(orbit, "Fn", p_min=0.0, p_max=args.Fn_max, period_max=args.period_max,
                          max_steps=args.max_steps)  # fmt: skip
        scale = 1.0
    else:
        cb = cycle_branch(orbit, "chi_c", p_min=math.radians(args.chi_c_min),
                          p_max=math.radians(args.chi_c_max), ds=0.02, ds_max=0.05,
                          period_max=args.period_max, max_steps=args.max_steps,
                          direction="both")  # fmt: skip
        scale = 180.0 / math.pi
    key = "Fn" if args.vary == "fn" else "chi_c_deg"
    vanishing = float(np.degrees(capsize_angle(model)))
    max_roll = float(np.degrees(np.max(cb.max_roll)))
    doc: dict[str, Any] = {
        "vessel": model.vessel.name,
        "vary": key,
        "Fn": float(params["Fn"]),
        "chi_c_deg": float(args.chi_c),
        "status": cb.status.name,
        "message": " ".join(str(cb.message).split()),
        "rows": len(cb.p),
        f"{key}_first": float(cb.p[0]) * scale,
        f"{key}_last": float(cb.p[-1]) * scale,
        f"{key}_range": [float(np.min(cb.p)) * scale, float(np.max(cb.p)) * scale],
        "T_last": float(cb.T[-1]),
        f"{key}_limit_fit": cb.limit * scale,
        f"{key}_limit_saddle_focus": cb.limit_saddle_focus * scale,
        f"{key}_lost_stability": cb.lost_stability_at * scale,
        "max_roll_deg": max_roll,
        "vanishing_angle_deg": vanishing,
        "rolls_past_vanishing_angle": max_roll >= vanishing,
    }
    if args.compare:
        from ship_models.analysis.critical_bvp import critical_fn_bvp

        crit = critical_fn_bvp(math.radians(args.chi_c), model=model, params=params)
        doc["Fn_bvp"] = float(crit.Fn)
        doc["Fn_bvp_status"] = crit.status.name
        doc["difference_fit_minus_bvp"] = cb.limit - float(crit.Fn)
    return doc, cb


def _rows(cb: Any, key: str, scale: float) -> dict[str, np.ndarray]:
    return {
        key: cb.p * scale,
        "T": cb.T,
        "max_roll_deg": np.degrees(cb.max_roll),
        "max_heading_deg": np.degrees(cb.max_heading),
        "mu_max": cb.mu_max,
        "mu_lead_real": np.asarray(cb.mu_lead).real,
        "n_unstable": np.asarray(cb.n_unstable, dtype=float),
    }


def _plot(path: Path, rows: dict[str, np.ndarray], key: str, doc: dict[str, Any]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = rows[key]
    stable = rows["n_unstable"] == 0
    fig, axes = plt.subplots(3, 1, figsize=(6.0, 7.0), sharex=True)
    for ax, name, label in zip(axes, ("T", "max_roll_deg", "mu_max"),
                               ("period T (s)", "max |phi| (deg)", "max |Floquet multiplier|"),
                               strict=True):  # fmt: skip
        y = rows[name]
        ax.plot(x, y, "-", color="0.6", lw=0.8)
        ax.plot(x[stable], y[stable], ".", ms=3, label="stable")
        ax.plot(x[~stable], y[~stable], "x", ms=3, label="unstable")
        ax.set_ylabel(label)
        for mark, style, lab in (
            (doc.get(f"{key}_limit_fit"), "--", "limit (fit)"),
            (doc.get("Fn_bvp") if key == "Fn" else None, ":", "connection (BVP)"),
        ):
            if mark is not None and math.isfinite(mark):
                ax.axvline(mark, color="r", lw=0.8, ls=style, label=lab)
    axes[1].axhline(doc["vanishing_angle_deg"], color="k", lw=0.8, ls="-.",
                    label="vanishing stability")  # fmt: skip
    axes[2].axhline(1.0, color="k", lw=0.5)
    axes[0].legend(fontsize=7)
    axes[1].legend(fontsize=7)
    axes[-1].set_xlabel("Fn" if key == "Fn" else "chi_c (deg)")
    axes[0].set_title(f"{doc['vessel']}: overtaken-by-waves cycle ({doc['status']})")
    fig.tight_layout()
    write_atomic(path, lambda p: fig.savefig(p, dpi=120, format="png"))
    plt.close(fig)


def write_files(out: Path, doc: dict[str, Any], cb: Any) -> list[Path]:
    """CSV, JSON and PNG of the branch into ``out``, each atomically."""
    key = doc["vary"]
    scale = 1.0 if key == "Fn" else 180.0 / math.pi
    rows = _rows(cb, key, scale)
    stem = "cycles_fn" if key == "Fn" else "cycles_chi_c"
    meta = {k: doc[k] for k in ("vessel", "Fn", "chi_c_deg", "status")}
    branch = {k: v.tolist() for k, v in rows.items()}
    paths = [
        write_text(out / f"{stem}.csv", csv_text(rows, meta)),
        write_json(out / f"{stem}.json", {**doc, "branch": branch}),
    ]
    _plot(out / f"{stem}.png", rows, key, doc)
    paths.append(out / f"{stem}.png")
    return paths


def run(args: argparse.Namespace) -> int:
    """Continue the cycle; 0 if the branch ended completely and never rolls past the angle
    of vanishing stability, else 1."""
    check_args(args)
    out = prepare_out(args.out)
    model, params = ship_from_args(args)  # checks --fn against the vessel's range
    if args.vary == "fn":
        check_fn(model, "--fn-max", args.Fn_max)
    doc, cb = compute(model, params, args)
    if out is not None:
        doc["files"] = [str(p) for p in write_files(out, doc, cb)]
    ok = doc["status"] in COMPLETE and not doc["rolls_past_vanishing_angle"]
    if args.compare:
        ok = ok and doc["Fn_bvp_status"] == "SUCCESS"
    emit(args, doc, _text)
    return 0 if ok else 1


def _fmt(v: float, unit: str = "") -> str:
    return "none" if v is None or not math.isfinite(v) else f"{v:.7g}{unit}"


def _text(doc: dict[str, Any]) -> str:
    key = doc["vary"]
    unit = "" if key == "Fn" else " deg"
    name = "Fn" if key == "Fn" else "chi_c"
    lo, hi = doc.get(f"{key}_range") or (doc[f"{key}_first"], doc[f"{key}_last"])
    limit = doc[f"{key}_limit_fit"]
    lost = doc[f"{key}_lost_stability"]
    lines = [
        f"{doc['vessel']}, cycle from Fn = {doc['Fn']:g}, chi_c = {doc['chi_c_deg']:g} deg, "
        f"continued in {name}: {doc['rows']} cycles, {name} in [{_fmt(lo, unit)}, "
        f"{_fmt(hi, unit)}], last period {doc['T_last']:.4g} s",
        f"  end: {doc['status']}: {doc['message']}",
    ]
    if limit is not None and math.isfinite(limit):
        lines.append(
            f"  period blow-up at {name}* = {_fmt(limit, unit)} (T = a - b ln|p* - p|; "
            f"saddle-focus law {_fmt(doc[f'{key}_limit_saddle_focus'], unit)})"
        )
    else:
        lines.append(f"  no period blow-up: the branch ended by {doc['status']}")
    if "Fn_bvp" in doc:
        lines.append(
            f"  connection solver: critical Fn = {_fmt(doc['Fn_bvp'])} ({doc['Fn_bvp_status']}); "
            f"fit - connection = {_fmt(doc['difference_fit_minus_bvp'])}"
        )
    if lost is not None and math.isfinite(lost):
        lines.append(f"  stability lost at {name} = {_fmt(lost, unit)}")
    else:
        lines.append("  stable throughout (no Floquet multiplier outside the unit circle)")
    lines.append(roll_verdict(doc))
    return "\n".join(lines)
