"""``broachkit vessels``: list the vessel models, show a vessel's coefficients, validate a file.

.. code-block:: text

    broachkit vessels list [--json]
    broachkit vessels show NAME [--json] [--no-estimate]
    broachkit vessels validate FILE [--schema-only]
    broachkit vessels hydrostatics NAME [--json]

``NAME`` is a registered model name (``broachkit vessels list``) or the path to a
vessel ``.toml`` file. ``show`` prints every coefficient with its value, unit,
status and source, including those the estimation pipeline fills (status
``estimated``/``assumed``); ``--no-estimate`` shows only what the file gives.
``validate`` exits with 0 and prints ``valid`` for a good file; for a bad one it
exits with 1 and prints the error, which names the offending field.
``hydrostatics`` prints the hull's upright hydrostatics (volume, LCB, KB, BM,
waterplane area and moments, from its offsets when the file names a
``[vessel] hull_offsets`` table, from its closed mesh when it names a ``[vessel]
hull_mesh`` instead, else from the form-parameter hull), the GZ curve by
direct integration at heel, and the wave-force amplitudes of the vessel's wave-force
model at its design wave for courses 0-60 deg.
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
    p = sub.add_parser(
        "hydrostatics", help="hull hydrostatics, GZ curve and wave-force amplitudes of a vessel"
    )
    p.add_argument("name", metavar="NAME", help="registered model name or path to a .toml file")
    p.add_argument("--json", action="store_true", help="print JSON")
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


def hydrostatics_report(name: str) -> dict[str, Any]:
    """Hydrostatics, GZ and wave-force amplitudes of a vessel (JSON-ready)."""
    import numpy as np

    from ship_models.contracts import SeaState, wave_model_name
    from ship_models.estimation import hull_mesh_path, mesh_is_hull, offsets_path
    from ship_models.hydro.upright import hydrostatics
    from ship_models.registry import get_vessel_data

    data = get_vessel_data(name)
    v = data.vessel
    hs = hydrostatics(data.hull)
    rho = v.get("environment.rho")
    gz = data.gz
    phi_deg = np.arange(0.0, math.degrees(gz.phi[-1]) + 1e-9, 5.0)
    F = data.forces
    Hl, lL = v.get("waves.H_over_lambda"), v.get("waves.lambda_over_L")
    c = float(F.celerity(lL))
    xi = np.linspace(0.0, 1.0, 64, endpoint=False)
    amps = {}
    for deg in range(0, 61, 10):
        chi = math.radians(deg)
        f = np.array([F.waves.forces(s, c, chi, SeaState(Hl, lL)) for s in xi], dtype=float)
        amps[str(deg)] = dict(
            zip(("X_w", "Y_w", "N_w", "K_w"), np.abs(f).max(axis=0).tolist(), strict=True)
        )
    off = offsets_path(v)
    mesh = hull_mesh_path(v) if mesh_is_hull(v) else None
    if off is not None:
        hull = str(off)
    elif mesh is not None:
        hull = f"{mesh} (closed mesh)"
    else:
        hull = "form-parameter hull of the particulars"
    return {
        "vessel": v.name,
        "hull": hull,
        "hydrostatics": hs.as_dict()
        | {"displacement_t": hs.volume * rho / 1000.0, "KM": hs.KB + hs.BM},
        "gz": {
            "phi_deg": phi_deg.tolist(),
            "gz_m": np.interp(np.radians(phi_deg), gz.phi, gz.gz).tolist(),
            "max_gz_m": gz.max_gz[1],
            "phi_max_gz_deg": math.degrees(gz.max_gz[0]),
            "phi_vanishing_deg": math.degrees(gz.vanishing_angle),
            "GM_m": v.get("loading.GM"),
            "topside_height_m": data.info["topside_height"],
        },
        "wave_forces": {
            "model": wave_model_name(data),
            "H_over_lambda": Hl,
            "lambda_over_L": lL,
            "amplitude_by_chi_deg": amps,
        },
    }


def _run_hydrostatics(args: argparse.Namespace) -> int:
    doc = hydrostatics_report(args.name)
    if args.json:
        sys.stdout.write(json.dumps(doc, indent=2) + "\n")
        return 0
    out = sys.stdout
    h = doc["hydrostatics"]
    out.write(f"vessel {doc['vessel']}: hull {doc['hull']}\n")
    out.write(
        f"  volume {h['volume']:.4g} m^3 ({h['displacement_t']:.4g} t), C_b {h['C_b']:.4f}, "
        f"LCB {h['lcb']:+.4g} m (from midship, + fwd)\n"
        f"  KB {h['KB']:.4g} m, BM {h['BM']:.4g} m, KM {h['KM']:.4g} m\n"
        f"  waterplane {h['A_wp']:.4g} m^2, LCF {h['lcf']:+.4g} m, I_T {h['I_T']:.4g} m^4, "
        f"I_L {h['I_L']:.4g} m^4\n"
    )
    g = doc["gz"]
    out.write(
        f"GZ (GM {g['GM_m']:g} m): max {g['max_gz_m']:.4g} m at {g['phi_max_gz_deg']:.1f} deg, "
        f"vanishing at {g['phi_vanishing_deg']:.1f} deg\n"
    )
    out.write("  " + "  ".join(f"{p:.0f}:{z:.3f}" for p, z in zip(g["phi_deg"], g["gz_m"],
                                                                  strict=True)) + "\n")  # fmt: skip
    w = doc["wave_forces"]
    out.write(
        f"wave forces ({w['model']}), H/lambda = {w['H_over_lambda']:.4g}, lambda/L = "
        f"{w['lambda_over_L']:.4g}: amplitudes X_w, Y_w (kN), N_w, K_w (kN m)\n"
    )
    for deg, a in w["amplitude_by_chi_deg"].items():
        out.write(
            f"  chi {deg:>2} deg: {a['X_w'] / 1e3:9.1f} {a['Y_w'] / 1e3:9.1f} "
            f"{a['N_w'] / 1e3:9.1f} {a['K_w'] / 1e3:9.1f}\n"
        )
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
    if action == "hydrostatics":
        return _run_hydrostatics(args)
    return _run_validate(args)
