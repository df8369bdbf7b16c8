"""``broachkit assess``: IMO second-generation surf-riding/broaching criteria, Level 1 and 2.

Level 1 and Level 2 of the MSC.1/Circ.1627 surf-riding/broaching criterion for one
vessel at its service Froude number, Level 2 both with Melnikov's threshold (the
criterion's method) and with the exact threshold of the same surge equation (a
connecting orbit continued over the wave cases), the operational limit Fn where C
reaches R_SR, and with ``--out DIR`` the figures and the JSON
(:mod:`ship_models.assessment`). The exact threshold runs as tasks of the sweep
engine, on local processes (default), a Dask ``LocalCluster`` (``--workers N``) or a
running scheduler (``--scheduler``), as ``broachkit sweep``.
The scatter table ``W2`` (IACS Rec. 34, North Atlantic) is not shipped: give it with
``--scatter FILE`` (``docs/imo_assessment.md``); without it, C is given per sea state.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ..options import (
    add_backend,
    add_json,
    add_out,
    add_vessel,
    finite,
    load_model,
    prepare_out,
    print_json,
)
from ..progress import StatusLine

NAME = "assess"
HELP = "IMO second-generation surf-riding/broaching criteria (Level 1 and 2)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit assess``."""
    add_vessel(parser)
    parser.add_argument(
        "--fn-service", dest="Fn", type=float, required=True, help="service Froude number"
    )
    parser.add_argument(
        "--scatter",
        type=Path,
        default=None,
        help="wave scatter table CSV (Hs rows, Tz columns; e.g. IACS Rec. 34 North Atlantic)",
    )
    parser.add_argument(
        "--standard",
        type=Path,
        default=None,
        help="file of the criterion's numbers (default: the shipped one, see its sources)",
    )
    parser.add_argument(
        "--no-exact",
        dest="exact",
        action="store_false",
        help="skip the exact threshold (Melnikov's only; under a second)",
    )
    parser.add_argument(
        "--broaching",
        action="store_true",
        help="beyond the standard: C from the 4-DOF capsizing threshold over courses (slow)",
    )
    parser.add_argument(
        "--chi-c",
        default="0,10,20",
        help="--broaching: autopilot courses in deg, comma-separated (default 0,10,20)",
    )
    parser.add_argument(
        "--broaching-lambda",
        default="1.25,1.75,2.5",
        help="--broaching: coarse wave cases, lambda/L values (default 1.25,1.75,2.5)",
    )
    parser.add_argument(
        "--broaching-steepness",
        default="0.05,0.09,0.13",
        help="--broaching: coarse wave cases, H/lambda values (default 0.05,0.09,0.13)",
    )
    parser.add_argument(
        "--sensitivity",
        action="store_true",
        help="dC/dtheta of the coefficients with a stated uncertainty (needs --scatter)",
    )
    add_backend(parser, "exact threshold")
    add_out(parser, None, "the figures and assessment.json")
    add_json(parser)


def _verdict(doc: dict[str, Any] | None) -> str:
    if doc is None:
        return "not computed"
    if doc["C"] is None:
        at = doc["C_sea_state_max_at"]
        return (
            f"C per sea state up to {doc['C_sea_state_max']:.3g} "
            f"(Hs {at['Hs']:g} m, Tz {at['Tz']:g} s); no scatter table: no verdict"
        )
    lim = doc["Fn_limit"]
    lim_txt = (
        f"; C <= R_SR up to Fn = {lim:.4f}" if lim is not None else f"; {doc['Fn_limit_note']}"
    )
    return f"C = {doc['C']:.4g} (R_SR {doc['R_SR']:g}): {doc['verdict']}{lim_txt}"


def _floats(name: str, text: str, low: float, high: float) -> list[float]:
    """Comma-separated numbers in ``(low, high]``, else ValueError naming ``name``."""
    parts = [t for t in str(text).split(",") if t.strip()]
    if not parts:
        raise ValueError(f"{name} needs at least one value")
    return [finite(name, t, low=low, high=high) for t in parts]


def _sweep_options(args: argparse.Namespace, out: Path | None) -> dict[str, Any]:
    """Where the exact threshold's tasks run (as ``broachkit sweep``); checkpoints in
    ``OUT/checkpoints`` with ``--out`` (a rerun resumes)."""
    from ..options import backend_options

    opts: dict[str, Any] = {"vessel": args.vessel, "progress": False if args.json else None}
    if out is not None:
        opts["store"] = out / "checkpoints"
    opts.update(backend_options(args))
    return opts


def run(args: argparse.Namespace) -> int:
    """Run the assessment; 0 when it completed."""
    from ship_models.assessment import assess, load_standard, read_scatter_table

    finite("--fn-service", args.Fn, low=0.0, high=1.0)
    if not args.Fn > 0:
        raise ValueError(f"--fn-service must be positive, got {args.Fn}")
    out = prepare_out(args.out)
    try:
        standard = load_standard(args.standard) if args.standard is not None else None
    except ValueError as exc:
        raise ValueError(f"--standard: {exc}") from None
    try:
        scatter = read_scatter_table(args.scatter) if args.scatter is not None else None
    except ValueError as exc:
        raise ValueError(f"--scatter: {exc}") from None
    from ship_models.surge import SurgeModel

    loaded = load_model(args.vessel)
    model = loaded if isinstance(loaded, SurgeModel) else SurgeModel(loaded.data)
    if args.sensitivity and scatter is None:
        raise ValueError("--sensitivity needs --scatter (dC/dtheta is of the aggregate C)")
    broaching = None
    if args.broaching:
        broaching = {
            "chi_c_deg": _floats("--chi-c", args.chi_c, -90.0, 90.0),
            "lambda_over_L": _floats("--broaching-lambda", args.broaching_lambda, 0.2, 10.0),
            "H_over_lambda": _floats("--broaching-steepness", args.broaching_steepness, 0.0, 1 / 7),
        }
    sweep = _sweep_options(args, out)  # checked also with --no-exact
    if not args.exact:
        sweep = None
    with StatusLine(enabled=not args.json) as status:
        a = assess(
            model, args.Fn, scatter=scatter, standard=standard, exact=args.exact,
            broaching=broaching, sensitivity=args.sensitivity, sweep=sweep,
            progress=status.show,
        )  # fmt: skip
    doc = a.to_json()
    if out is not None:
        doc["files"] = _write(a, doc, out)
    if args.json:
        print_json(doc)
        return 0
    lines = [
        f"{doc['vessel']} (L = {doc['L']:g} m) at Fn = {doc['Fn_service']:g}",
        f"  Level 1: {doc['level1']['verdict']} ({doc['level1']['reason']})",
        f"  Level 2, Melnikov threshold: {_verdict(doc['level2']['melnikov'])}",
        f"  Level 2, exact threshold:    {_verdict(doc['level2']['exact'])}",
    ]
    cmp_ = doc["threshold_comparison"]
    if cmp_.get("cells_compared"):
        lines.append(
            f"  Melnikov vs exact Fn_cr over {cmp_['cells_compared']} wave cases: max "
            f"{100 * cmp_['max_rel_difference']:.2f} % (at lambda/L "
            f"{cmp_['at_lambda_over_L']:.3f}, H/lambda {cmp_['at_H_over_lambda']:.4f}), below "
            f"exact in {100 * cmp_['fraction_melnikov_below_exact']:.0f} % of the cases"
        )
    eg = doc.get("exact_grid")
    if eg is not None:
        lines.append(
            f"  exact threshold: {eg['engine']}, {eg['continuation_steps']} continuation "
            f"steps, {doc['timings_s'].get('exact', float('nan')):.1f} s"
            + ("" if eg["complete"] else f"; incomplete: {len(eg['columns_not_ok'])} columns")
        )
    if doc["validity"]["outside_resistance_fit"]:
        lines.append(
            f"  note: {doc['validity']['outside_resistance_fit']} of "
            f"{doc['validity']['wave_cases']} {doc['validity']['note']}"
        )
    b = doc.get("broaching")
    if b is not None:
        for k, chi in enumerate(b["chi_c_deg"]):
            C = "no scatter table" if b["C"] is None else f"C = {b['C'][k]:.4g}"
            lines.append(
                f"  broaching (4-DOF, beyond the standard), chi_c = {chi:g} deg: {C} "
                f"(coarse wave cases; per sea state up to {b['C_sea_state_max'][k]:.3g})"
            )
        chk = b["rebinning_check"]
        if chk["C_surge_coarse"] is not None:
            lines.append(
                f"  coarse-case check: surf-riding C on the coarse cases "
                f"{chk['C_surge_coarse']:.4g} against {chk['C_surge_fine']:.4g} on the full grid"
            )
    sens = doc.get("sensitivity")
    if sens is not None:
        lines.append("  dC/dtheta (Melnikov's C), largest change per standard uncertainty first:")
        for r in sens["rows"][:8]:
            per = (
                ""
                if r["dC_sigma"] is None
                else f", sigma {r['sigma']:.3g}: dC = {r['dC_sigma']:+.3g}"
            )
            lines.append(
                f"    {r['key']} = {r['value']:.4g} {r['unit']}: {r['dC_dtheta']:+.3g}{per}"
            )
    if out is not None:
        lines.append(f"  written: {', '.join(doc['files'])}")
    sys.stdout.write("\n".join(lines) + "\n")
    return 0


def _write(a: Any, doc: dict[str, Any], out: Path) -> list[str]:
    """Figures and the JSON, each written atomically; returns their paths."""
    import numpy as np

    from ship_models.assessment.figures import sea_state_figure, threshold_figure

    from ..files import write_atomic, write_json

    files = []
    for name, make in (
        ("c_per_sea_state.png", sea_state_figure),
        ("threshold.png", threshold_figure),
    ):
        fig = make(a)
        files.append(str(write_atomic(out / name, lambda p, f=fig: f.savefig(p, dpi=120))))

    def grids(p: Path) -> None:
        arrays = {
            "lambda_over_L": a.melnikov.lambda_over_L,
            "H_over_lambda": a.melnikov.steepness,
            "Fn_cr_melnikov": a.melnikov.Fn_cr,
            "Hs": a.level2_melnikov.Hs,
            "Tz": a.level2_melnikov.Tz,
            "C_sea_state_melnikov": a.level2_melnikov.C_sea_state,
        }
        if a.exact is not None:
            arrays["Fn_cr_exact"] = a.exact.Fn_cr
            arrays["Fn_cr_exact_error"] = a.exact.error
            arrays["C_sea_state_exact"] = a.level2_exact.C_sea_state
        with open(p, "wb") as fh:
            np.savez(fh, **arrays)

    files.append(str(write_atomic(out / "assessment_grids.npz", grids)))
    files.append(str(out / "assessment.json"))
    write_json(out / "assessment.json", {**doc, "files": files})
    return files
