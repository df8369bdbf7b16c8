"""How far to trust the critical Fn at chi_c = 10 deg: sensitivities, band, tornado figure.

Differentiates the connecting orbit at the critical Fn with respect to every
coefficient of the default vessel (:func:`ship_models.analysis.sensitivity.critical_fn_sensitivity`:
one adjoint solve, ``G_theta`` by central differences of the residual with the model
rebuilt at ``theta +- h``) and propagates the vessel file's standard uncertainties
linearly (:func:`~ship_models.analysis.sensitivity.uncertainty_band`, no sampled
re-solves here: ``broachkit sensitivity --samples N`` confirms the band by sampling).
States whether the paper's 0.3247-0.3248 lies inside the band and which coefficients
dominate its width.

Writes to ``--out`` (default ``out/sensitivity``): ``tornado.png`` (the elasticities
and each coefficient's contribution to the band), ``sensitivity.json`` (every entry
and the band) and ``summary.json`` (the numbers the report reads).

Run: ``python studies/sensitivity.py [--out DIR]``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from continuation.atomic import atomic_path
from ship_models.paper import PAPER_FN_BRACKET
from studies._common import write_results, write_summary

CHI_C_DEG = 10.0
#: Rows of the tornado figure and of the summary's elasticity list.
TOP = 25
#: Coefficients named as dominating the band's width.
N_DOMINANT = 3


def summarise(sens: Any, band: Any, *, top: int = TOP) -> dict[str, Any]:
    """The report's numbers from a :class:`Sensitivity` and its :class:`UncertaintyBand`.

    Returns
    -------
    dict
        ``chi_c_deg``, ``Fn``, ``sigma_linear``, ``coverage``, ``band`` ([lo, hi]),
        ``paper_Fn`` ([lo, hi]), ``paper_inside_band`` (both ends of the paper's
        bracket inside), ``dominant`` (the ``N_DOMINANT`` largest contributions, each
        ``{key, sigma_Fn, share}`` with ``share`` its fraction of ``sigma^2``),
        ``elasticities`` (the ``top`` largest ``{key, status, value, unit,
        elasticity}``, numerical fit settings left out), ``n_coefficients``.
    """
    lo, hi = band.band
    var = band.sigma_linear**2
    dom = [
        {"key": k, "sigma_Fn": v, "share": (v * v / var) if var > 0 else None}
        for k, v in band.contributions[:N_DOMINANT]
    ]
    rows = [e for e in sens.entries if e.elasticity is not None and e.kind != "numerical"]
    return {
        "chi_c_deg": math.degrees(sens.chi_c),
        "Fn": sens.Fn,
        "sigma_linear": band.sigma_linear,
        "coverage": band.coverage,
        "band": [lo, hi],
        "paper_Fn": list(PAPER_FN_BRACKET),
        "paper_inside_band": bool(
            band.contains(PAPER_FN_BRACKET[0]) and band.contains(PAPER_FN_BRACKET[1])
        ),  # fmt: skip
        "dominant": dom,
        "elasticities": [
            {
                "key": e.key,
                "status": e.status,
                "value": e.value,
                "unit": e.unit,
                "elasticity": e.elasticity,
            }  # fmt: skip
            for e in rows[:top]
        ],
        "n_coefficients": len(sens.entries),
        "n_vessel_coefficients": n_vessel_coefficients(),
    }


def write_outputs(out: Path, sens: Any, band: Any, *, seconds: float) -> dict[str, Any]:
    """Write ``tornado.png``, ``sensitivity.json`` and ``summary.json`` (atomically)."""
    from ship_models.analysis.sensitivity import tornado_figure

    out.mkdir(parents=True, exist_ok=True)
    with atomic_path(out / "tornado.png") as tmp:
        tornado_figure(sens, tmp, top=TOP, band=band)
    write_results(out / "sensitivity.json", {"sensitivity": sens.to_json(), "band": band.to_json()})
    summary = summarise(sens, band)
    summary["keys"] = [e.key for e in sens.entries]
    summary["elapsed_s"] = seconds
    summary["files"] = ["tornado.png", "sensitivity.json"]
    write_summary(out, summary)
    return summary


def n_vessel_coefficients() -> int:
    """How many keys ``broachkit sensitivity`` differentiates by default (all of them)."""
    from ship_models.analysis.sensitivity import default_keys
    from ship_models.estimation import build_vessel_model
    from ship_models.vessel import load_vessel

    return len(default_keys(build_vessel_model(load_vessel("purse_seiner")).vessel))


def main_job_keys(vessel: Any) -> list[str]:
    """The coefficients the main job differentiates (the band's and the tornado's).

    Every coefficient that carries an uncertainty in the vessel file (all the band
    needs), the factors on intermediate force quantities (wave surge amplitude's
    neighbours: resistance, thrust, lateral wave forces) and the parameters of the
    dynamical system. The given hull dimensions are left to ``broachkit sensitivity``
    (each re-runs the hydrostatics, ~2.5 s, more than all the others together).
    """
    from ship_models.analysis.sensitivity import FACTORS, SYSTEM_PARAMS
    from ship_models.estimation import build_vessel_model

    resolved = build_vessel_model(vessel).vessel
    unc = [k for k in resolved.uncertainties if k in resolved.coefficients]
    sys_p = [k for k in SYSTEM_PARAMS if k in resolved.coefficients and k not in unc]
    return unc + sys_p + list(FACTORS)


def compute(
    out: Path,
    progress: Callable[[str], None] | None = None,
    *,
    keys: Iterable[str] | None = None,
    every_coefficient: bool = False,
) -> dict[str, Any]:
    """Sensitivities of the critical Fn at 10 deg, the linear band, the tornado figure.

    ``keys``: the coefficients (default :func:`main_job_keys`, or all of them with
    ``every_coefficient``; the band needs every coefficient that carries an
    uncertainty).
    """
    from ship_models.analysis.sensitivity import critical_fn_sensitivity, uncertainty_band
    from ship_models.vessel import load_vessel
    from studies._model import default_model, heteroclinic

    say = progress or (lambda msg: None)
    t0 = time.perf_counter()
    vessel = load_vessel("purse_seiner")
    if keys is None and not every_coefficient:
        keys = main_job_keys(vessel)
    say(f"critical Fn at chi_c = {CHI_C_DEG:g} deg and its derivative in every coefficient")
    # the default vessel's model and its connection, shared with the other steps of
    # this process (studies._model); the rebuilt models start from the same file
    sens = critical_fn_sensitivity(
        math.radians(CHI_C_DEG), vessel=vessel, keys=keys, model=default_model(),
        connection=heteroclinic(CHI_C_DEG), progress=lambda k: say(f"  d Fn*/d {k}"),
    )  # fmt: skip
    band = uncertainty_band(sens, vessel)
    lo, hi = band.band
    say(f"  Fn = {sens.Fn:.6f}, sigma = {band.sigma_linear:.4f}, band [{lo:.4f}, {hi:.4f}]")
    return write_outputs(out, sens, band, seconds=time.perf_counter() - t0)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: ``python studies/sensitivity.py [--out DIR]``."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out") / "sensitivity")
    ap.add_argument("--all", action="store_true", help="differentiate every coefficient")
    args = ap.parse_args(argv)
    s = compute(args.out, progress=lambda m: sys.stderr.write(m + "\n"),
                every_coefficient=args.all)  # fmt: skip
    sys.stdout.write(f"band [{s['band'][0]:.5f}, {s['band'][1]:.5f}]; "
                     f"paper inside: {s['paper_inside_band']}\n")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
