"""``report.html``: the paper's statements beside this run's figures, numbers and verdicts.

Written by ``broachkit reproduce`` at the top of its output folder from the run's own
step summaries, with the Jinja2 template ``templates/report.html.j2`` (which holds no
numbers: every number comes from the run or from :mod:`studies.paper`). Figures are
linked relatively (``fig10_15/fig10_position_above.png``), so the folder can be moved
or opened offline.
"""

from __future__ import annotations

import datetime as _dt
import logging
import math
from collections import Counter
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .files import write_text

log = logging.getLogger(__name__)

#: File name of the report inside the output folder.
REPORT_NAME = "report.html"


def _fmt(v: Any, spec: str = ".8g") -> str:
    if isinstance(v, float):
        return "n/a" if not math.isfinite(v) else format(v, spec)
    if v is None:
        return "n/a"
    return str(v)


def claims_context(out: Path, results: Mapping[str, Any]) -> list[dict[str, Any]]:
    """Each claim of :data:`studies.paper.CLAIMS` with this run's finding and figures."""
    from studies.paper import CLAIMS

    rows = []
    for c in CLAIMS:
        try:
            f = c.check(results)
            numbers, verdict, reason = f.numbers, f.verdict, f.reason
        except (KeyError, TypeError, ValueError, IndexError, ZeroDivisionError) as exc:
            # a summary of an unexpected shape: say so instead of guessing
            numbers, verdict, reason = (), "not run", f"cannot read this run's summary ({exc!r})"
        rows.append(
            {
                "key": c.key,
                "figure": c.figure,
                "statement": c.statement,
                "paper_numbers": c.paper_numbers,
                "numbers": numbers,
                "verdict": verdict,
                "reason": reason,
                "figures": [{"href": p, "exists": (out / p).is_file()} for p in c.figures],
            }
        )
    return rows


#: Relative IS-Code margin below which a condition is "at the limit" rather than failing:
#: the topside height is fitted to the limit with a 1 mm tolerance
#: (:func:`ship_models.hydro.hydrostatics.marginal_topside_height`), which moves the
#: tightest criterion by about this much.
AT_LIMIT_MARGIN = 1e-3


def is_code_sentence(margin: float) -> str:
    """What the computed IMO IS-Code margin says, in words that agree with its sign.

    ``margin`` is the smallest ``value/required - 1`` over the general criteria
    (:func:`ship_models.hydro.hydrostatics.is_code_margin`).
    """
    if margin >= 0.0:
        return (
            f"IMO IS Code general criteria: met (smallest relative margin {margin:+.1e}); "
            "the paper's loading condition 'marginally complies'."
        )
    if margin > -AT_LIMIT_MARGIN:
        return (
            f"IMO IS Code general criteria: at the limit; the tightest criterion is missed "
            f"by a relative {margin:+.1e}, within the tolerance of the topside-height fit "
            "that puts the condition on the limit (the paper: 'marginally complies')."
        )
    return (
        f"IMO IS Code general criteria: NOT met (smallest relative margin {margin:+.1e}); "
        "the paper's condition 'marginally complies'."
    )


def vessel_context(name: str = "purse_seiner") -> dict[str, Any]:
    """The vessel's Table 1, every coefficient (value, unit, status, source), derived numbers."""
    from ship_models.registry import get_vessel_data

    data = get_vessel_data(name)
    v = data.vessel
    coeffs = sorted(v.coefficients.items())
    rows = [
        {"key": k, "value": _fmt(c.value), "unit": c.unit, "status": c.status, "source": c.source}
        for k, c in coeffs
    ]
    table1 = [r for r in rows if r["status"] == "given" and "Table 1" in r["source"]]
    info = dict(data.info)
    margin = info.get("is_code_margin")
    meta = dict(v.meta)
    if margin is None:
        is_code = ""
    else:
        is_code = is_code_sentence(float(margin))
    return {
        "name": v.name,
        "description": meta.get("description", ""),
        "is_code": is_code,
        "table1": table1,
        "coefficients": rows,
        "derived": [derived_row(k, float(val)) for k, val in sorted(info.items())],
    }


#: Units of the estimation pipeline's derived numbers (``VesselModelData.info``);
#: angles (radians there) are shown in degrees.
DERIVED_UNITS: dict[str, str] = {
    "volume": "m^3", "mass": "kg", "wetted_surface_hull": "m^2",
    "wetted_surface_used": "m^2", "zeta_G": "m (centre of gravity above the waterline)",
    "KG": "m", "KM": "m", "gz_fit_error": "m", "phi_gz_max": "deg", "gz_max": "m",
    "phi_vanishing": "deg", "topside_height": "m",
    "is_code_margin": "- (fraction of the tightest IS Code criterion)",
    "resistance_fit_error": "- (relative)", "kt_fit_error": "- (relative)", "z_H": "m",
    "z_R": "m", "eta_rudder": "- (rudder span in the propeller race / rudder span)",
    "x_G": "m", "I_zz": "kg m^2",
}  # fmt: skip
_DERIVED_ANGLES = ("phi_gz_max", "phi_vanishing")


def derived_row(key: str, value: float) -> tuple[str, str, str]:
    """``(key, value, unit)`` of a derived number; angles in degrees, unknown units named."""
    if key in _DERIVED_ANGLES:
        value = math.degrees(value)
    return key, _fmt(value), DERIVED_UNITS.get(key, "unit not recorded")


def _vessel_figure(out: Path, name: str = "purse_seiner") -> str | None:
    """The one-page vessel figure (``studies.vessel_report``) in ``out/vessel``; its href."""
    from studies.vessel_report import build_report

    files = build_report(name, out / "vessel")
    return str(Path(files.png).relative_to(out))


def key_number_rows(numbers: Mapping[str, Any]) -> list[tuple[str, str]]:
    """The headline numbers as (label, formatted value) rows."""
    rows = []
    chi = numbers.get("chi_c_deg")
    where = f" at chi_c = {chi:g} deg" if isinstance(chi, int | float) else ""
    th = numbers.get("threshold") or {}
    for c, fn, err, mech in zip(th.get("chi_c_deg", []), th.get("Fn", []), th.get("error", []),
                                th.get("mechanism", []), strict=False):  # fmt: skip
        rows.append((f"capsizing threshold at chi_c = {c:g} deg ({mech})",
                     f"{_fmt(fn)} +- {_fmt(err)}"))  # fmt: skip
    if th.get("parting_chi_c_deg"):
        a, b = th["parting_chi_c_deg"]
        rows.append(("threshold parts from the heteroclinic Fn", f"between {a:g} and {b:g} deg"))
    rows.append((f"heteroclinic Fn{where}, connecting orbit", _fmt(numbers.get("Fn_bvp"))))
    rows.append((f"heteroclinic Fn{where}, bisection", _fmt(numbers.get("Fn_bisection"))))
    br = numbers.get("Fn_bisection_bracket")
    if br:
        rows.append(("bisection bracket", f"[{_fmt(br[0])}, {_fmt(br[1])}]"))
    for end in numbers.get("critical_curve_ends") or []:
        rows.append((f"heteroclinic line at chi_c = {end['chi_c_deg']:g} deg", _fmt(end["Fn"])))
    hend = numbers.get("heteroclinic_end")
    if hend:
        rows.append(("heteroclinic line ends (fold in chi_c)",
                     f"chi_c = {hend['chi_c_deg']:.2f} deg, Fn = {_fmt(hend['Fn'])}"))  # fmt: skip
    return rows


def differentiated_text(s: Mapping[str, Any]) -> str:
    """How many of the vessel's coefficients the step differentiated, in words."""
    n = int(s["n_coefficients"])
    total = s.get("n_vessel_coefficients")
    of = f" of {int(total)}" if total else ""
    return (
        f"{n}{of}: those with an uncertainty in the vessel file, the factors and the "
        "system parameters (`broachkit sensitivity` differentiates every coefficient)"
    )


def sensitivity_context(results: Mapping[str, Any]) -> dict[str, Any] | None:
    """The report's sensitivity section from the ``sensitivity`` step's ``summary.json``.

    ``None`` when the step did not run. Every number comes from the step's summary.
    """
    s = results.get("sensitivity")
    if not s:
        return None
    lo, hi = s["band"]
    plo, phi = s["paper_Fn"]
    return {
        "figure": "sensitivity/tornado.png",
        "rows": [
            (f"critical Fn at chi_c = {s['chi_c_deg']:g} deg", _fmt(s["Fn"])),
            ("standard uncertainty (linear propagation)", _fmt(s["sigma_linear"])),
            (f"band (Fn -+ {s['coverage']:g} sigma)", f"[{_fmt(lo)}, {_fmt(hi)}]"),
            ("the paper's value", f"[{_fmt(plo)}, {_fmt(phi)}]"),
            ("the paper's value inside the band", "yes" if s["paper_inside_band"] else "no"),
            ("coefficients differentiated", differentiated_text(s)),
        ],
        "dominant": [
            (
                d["key"],
                _fmt(d["sigma_Fn"]),
                "n/a" if d["share"] is None else f"{100 * d['share']:.0f} %",
            )  # fmt: skip
            for d in s["dominant"]
        ],
        "elasticities": [
            (e["key"], e["status"], _fmt(e["elasticity"])) for e in s["elasticities"]
        ],  # fmt: skip
    }


def diffraction_context(results: Mapping[str, Any]) -> dict[str, Any] | None:
    """The report's wave-force section from the optional ``diffraction`` step (None if it
    did not run: ``broachkit reproduce --only diffraction``)."""
    d = results.get("diffraction")
    if not d:
        return None
    th = d.get("thresholds", {})
    names = {"froude_krylov_strips": "Froude-Krylov, strips (the paper's model, default)",
             "panel_fk": "Froude-Krylov, panel method",
             "panel_fk_diffraction": "Froude-Krylov + diffraction, panel method"}  # fmt: skip
    rows = [(names.get(k, k), _fmt(v.get("threshold_10deg"), ".5f"), v.get("mechanism_10deg", ""),
             _fmt(v.get("Fn_10deg"))) for k, v in th.items()]  # fmt: skip
    lo, hi = d.get("ratio_range_chi0", [None, None])
    return {
        "figure": "diffraction/diffraction.png",
        "ratio": f"{_fmt(lo, '.2f')}-{_fmt(hi, '.2f')}",
        "ratio_15": _fmt(d.get("ratio_at_1.5"), ".3f"),
        "speed": "-".join(_fmt(v, ".2f") for v in d.get("ratio_speed_range_chi0", [])),
        "rows": rows,
        "panels": d.get("panels"),
    }


def intact_stability_context(name: str = "purse_seiner") -> dict[str, Any] | None:
    """The IMO 2008 IS Code checks of the vessel by class, and the weather criterion.

    From :func:`ship_models.hydro.stability_criteria.vessel_intact_stability`; ``None``
    (section left out, with a log line) if the checks cannot be evaluated.
    """
    import math

    from ship_models.hydro.stability_criteria import vessel_intact_stability
    from ship_models.registry import get_vessel_data

    try:
        r = vessel_intact_stability(get_vessel_data(name))
    except ValueError as exc:
        log.warning("intact stability section left out of the report: %s", exc)
        return None

    def show(c: Any) -> tuple[str, str, str, str, str]:
        deg = c.unit == "rad"
        val = math.degrees(c.value) if deg else c.value
        req = math.degrees(c.required) if deg else c.required
        unit = "deg" if deg else c.unit
        return (c.name, f"{_fmt(val)} {unit}", f">= {_fmt(req)} {unit}", c.verdict, c.clause)

    w = r["weather"]
    return {
        "vessel_class": r["vessel_class"],
        "general": [show(c) for c in r["general"]],
        "weather": [show(c) for c in w.checks],
        "weather_numbers": [
            ("windage area A (hull and topside only, a lower bound)", f"{_fmt(r['A_wind'])} m^2"),
            ("windage lever Z", f"{_fmt(r['Z_wind'])} m"),
            ("steady wind lever lw1 / gust lever lw2", f"{_fmt(w.lw1)} / {_fmt(w.lw2)} m"),
            (
                "steady heel phi0 (limit)",
                f"{_fmt(math.degrees(w.phi0))} ({_fmt(math.degrees(w.phi0_limit))}) deg",
            ),
            (
                "roll to windward phi1 (T by the Code's formula)",
                f"{_fmt(math.degrees(w.phi1))} deg (T = {_fmt(w.T_roll)} s)",
            ),
            ("areas a, b", f"{_fmt(w.area_a)}, {_fmt(w.area_b)} m rad"),
            ("largest windage area that passes (same Z)", f"{_fmt(r['A_wind_limit'])} m^2"),
        ],  # fmt: skip
        "assumptions": r["assumptions"],
    }


def write_report(out: Path, results: Mapping[str, Any], doc: Mapping[str, Any]) -> Path:
    """Render ``out/report.html`` from the step summaries and the job's document.

    Parameters
    ----------
    out : Path
        The output folder of the job (figures below it, linked relatively).
    results : mapping
        ``{step: summary}`` of the steps of this run (done now or earlier).
    doc : mapping
        The job's ``reproduce.json`` document (``key_numbers``, ``figures``,
        ``seconds``, ``total_seconds``, ``versions``, ``settings``).

    Returns
    -------
    Path
        The report's path.
    """
    import jinja2

    env = jinja2.Environment(
        loader=jinja2.PackageLoader("broachkit_cli", "templates"),
        autoescape=jinja2.select_autoescape(["html", "j2"]),
        undefined=jinja2.StrictUndefined,
    )
    claims = claims_context(out, results)
    counts = Counter(c["verdict"] for c in claims)
    try:
        vessel = vessel_context()
        vessel["figure"] = _vessel_figure(out)
    except ValueError as exc:  # the vessel file became invalid since the run: say so
        log.warning("vessel table left out of the report: %s", exc)
        vessel = {"name": "purse_seiner", "description": str(exc), "is_code": "",
                  "table1": [], "coefficients": [], "derived": [], "figure": None}  # fmt: skip
    html = env.get_template("report.html.j2").render(
        title="broachkit: Umeda (1999) reproduced with the default vessel",
        subtitle=(
            "Each statement of the paper beside this run's figure, numbers and verdict. "
            "The paper's hydrodynamic coefficients were measured; ours are estimated from "
            "its Table 1, so thresholds move while the structure is the paper's."
        ),
        verdict_counts={v: counts.get(v, 0) for v in ("agrees", "differs", "not run")},
        key_numbers=key_number_rows(doc.get("key_numbers", {})),
        claims=claims,
        all_figures=list(doc.get("figures", [])),
        vessel=vessel,
        sensitivity=sensitivity_context(results),
        diffraction=diffraction_context(results),
        stability=intact_stability_context(),
        run={
            "started": doc.get("started", _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")),
            "total_seconds": doc.get("total_seconds"),
            "out": str(out),
            "seconds": sorted((doc.get("seconds") or {}).items()),
            "versions": sorted((doc.get("versions") or {}).items()),
            "settings": sorted((doc.get("settings") or {}).items()),
        },
    )
    return write_text(out / REPORT_NAME, html)


__all__ = ["REPORT_NAME", "claims_context", "key_number_rows", "vessel_context", "write_report"]
