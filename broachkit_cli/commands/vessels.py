"""``broachkit vessels``: list the vessel models, show a vessel's coefficients, validate a file.

.. code-block:: text

    broachkit vessels list [--json]
    broachkit vessels show NAME [--json] [--no-estimate]
    broachkit vessels validate FILE [--schema-only]

``NAME`` is a registered model name (``broachkit vessels list``) or the path to a
vessel ``.toml`` file. ``show`` prints every coefficient with its value, unit,
status and source, including those the estimation pipeline fills (status
``estimated``/``assumed``); ``--no-estimate`` shows only what the file gives.
``validate`` exits with 0 and prints ``valid`` for a good file; for a bad one it
exits with 1 and prints the error, which names the offending field.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections import Counter
from typing import Any

from ..options import add_verbose

NAME = "vessels"
HELP = "list vessel models, show a vessel's coefficients with their sources, validate a file"

STATUS_ORDER = ("given", "measured", "estimated", "assumed")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Sub-commands ``list``, ``show`` and ``validate``."""
    sub = parser.add_subparsers(dest="action", metavar="ACTION")
    p = sub.add_parser("list", help="list the registered vessel models")
    p.add_argument("--json", action="store_true", help="print JSON")
    p = sub.add_parser("show", help="every coefficient of a vessel with value, unit, source")
    p.add_argument("name", metavar="NAME", help="registered model name or path to a .toml file")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument(
        "--no-estimate",
        action="store_true",
        help="show only the coefficients of the file (skip the estimation pipeline)",
    )
    p = sub.add_parser("validate", help="check a vessel file; exit status 0 if valid")
    p.add_argument("file", metavar="FILE", help="vessel .toml file (or packaged vessel name)")
    p.add_argument(
        "--schema-only",
        action="store_true",
        help="check the file format and values only (do not run the estimation pipeline)",
    )
    for action in sub.choices.values():
        add_verbose(action)


def _finite_or_none(x: Any) -> Any:
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def _status_counts(coeffs: dict[str, Any]) -> dict[str, int]:
    c = Counter(co.status for co in coeffs.values())
    return {s: c.get(s, 0) for s in STATUS_ORDER}


def _run_list(args: argparse.Namespace) -> int:
    from ship_models.registry import list_models, model_info

    entries = [model_info(n) for n in list_models()]
    if args.json:
        sys.stdout.write(json.dumps([e.as_dict() for e in entries], indent=2) + "\n")
        return 0
    w = max(len(e.name) for e in entries) if entries else 4
    sys.stdout.write(f"{'NAME':<{w}}  {'KIND':<6}  {'ORIGIN':<11}  DESCRIPTION\n")
    for e in entries:
        sys.stdout.write(f"{e.name:<{w}}  {e.kind:<6}  {e.origin:<11}  {e.description}\n")
    return 0


def _vessel_for_show(name: str, estimate: bool) -> tuple[Any, dict[str, float]]:
    from ship_models.registry import get_vessel_data, model_info
    from ship_models.vessel import load_vessel

    if estimate:
        data = get_vessel_data(name)
        return data.vessel, dict(data.info)
    if "/" in name or name.endswith(".toml"):
        return load_vessel(name), {}
    entry = model_info(name)
    if entry.vessel is None:  # plugin or custom factory: needs the full pipeline
        data = get_vessel_data(name)
        return data.vessel, dict(data.info)
    return load_vessel(entry.vessel), {}


def _run_show(args: argparse.Namespace) -> int:
    vessel, info = _vessel_for_show(args.name, not args.no_estimate)
    coeffs = dict(sorted(vessel.coefficients.items()))
    counts = _status_counts(coeffs)
    if args.json:
        doc = {
            "name": vessel.name,
            "model": args.name,
            "file": vessel.path,
            "meta": dict(vessel.meta),
            "coefficients": {k: c.as_dict() for k, c in coeffs.items()},
            "status_counts": counts,
            "derived": {k: _finite_or_none(float(v)) for k, v in sorted(info.items())},
        }
        sys.stdout.write(json.dumps(doc, indent=2) + "\n")
        return 0
    out = sys.stdout
    out.write(f"vessel {vessel.name}  ({vessel.path})\n")
    for k, v in vessel.meta.items():
        out.write(f"  {k}: {v}\n")
    kw = max(len(k) for k in coeffs)
    section = ""
    for key, c in coeffs.items():
        sec = key.split(".", 1)[0]
        if sec != section:
            section = sec
            out.write(f"[{sec}]\n")
        val = f"{c.value:.6g} {c.unit}"
        out.write(f"  {key:<{kw}}  {val:<22}  {c.status:<9}  {c.source}\n")
    summary = ", ".join(f"{n} {s}" for s, n in counts.items())
    out.write(f"{len(coeffs)} coefficients: {summary}\n")
    if info:
        out.write("derived: " + ", ".join(f"{k}={v:.6g}" for k, v in sorted(info.items())) + "\n")
    return 0


def _run_validate(args: argparse.Namespace) -> int:
    from ship_models.estimation import resolve_vessel
    from ship_models.vessel import load_vessel

    try:
        vessel = load_vessel(args.file)
    except ValueError as exc:
        sys.stderr.write(f"{args.file}: invalid: {exc}\n")
        return 1
    counts = _status_counts(dict(vessel.coefficients))
    n_est = 0
    if not args.schema_only:
        try:
            data = resolve_vessel(vessel)
        except ValueError as exc:
            sys.stderr.write(f"{args.file}: invalid: the estimation pipeline failed: {exc}\n")
            return 1
        n_est = len(data.vessel) - len(vessel)
    summary = ", ".join(f"{n} {s}" for s, n in counts.items())
    tail = "" if args.schema_only else f"; {n_est} more filled by the estimation pipeline"
    sys.stdout.write(
        f"{args.file}: valid: vessel {vessel.name!r}, {len(vessel)} coefficients "
        f"({summary}){tail}\n"
    )
    return 0


def run(args: argparse.Namespace) -> int:
    """Run ``broachkit vessels ACTION``."""
    action = getattr(args, "action", None) or "list"
    if action == "list":
        if not hasattr(args, "json"):
            args.json = False
        return _run_list(args)
    if action == "show":
        from ship_models.registry import PluginError

        try:
            return _run_show(args)
        except PluginError as exc:
            sys.stderr.write(f"broachkit vessels show: error: {exc}\n")
            return 1
    return _run_validate(args)
