"""Checks of a vessel file's entries: the form of each table, each value against its
schema range, and the relations between fields (drafts below the depth, L/B, B/d,
KG > 0, ...); every refusal a :class:`~ship_models.vessel_schema.VesselFileError`
naming the field by its dotted path.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from .vessel_schema import (
    SCHEMA,
    STATUSES,
    UNCERTAINTY_TYPES,
    Coefficient,
    Uncertainty,
    VesselFileError,
    _si_factor,
)


def check_uncertainty(key: str, raw: Any) -> Uncertainty:
    where = f"uncertainties.{key}"
    sec, _, name = key.partition(".")
    if sec not in SCHEMA or name not in SCHEMA[sec]:
        raise VesselFileError(f"`{where}`: no coefficient {key!r} in the schema")
    if not isinstance(raw, Mapping):
        raise VesselFileError(f"`{where}` must be a table {{ value, type, source[, unit] }}")
    missing = [k for k in ("value", "type", "source") if k not in raw]
    if missing:
        raise VesselFileError(f"`{where}` is missing {', '.join(missing)}")
    extra = sorted(set(raw) - {"value", "type", "source", "unit"})
    if extra:
        raise VesselFileError(f"`{where}` has unknown key(s) {extra}")
    value = raw["value"]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise VesselFileError(f"`{where}.value` must be a number, got {value!r}")
    if not (math.isfinite(value) and value >= 0):
        raise VesselFileError(f"`{where}.value` must be finite and >= 0, got {value!r}")
    kind = raw["type"]
    if kind not in UNCERTAINTY_TYPES:
        raise VesselFileError(f"`{where}.type` must be one of {UNCERTAINTY_TYPES}, got {kind!r}")
    src = raw["source"]
    if not isinstance(src, str) or not src.strip():
        raise VesselFileError(f"`{where}.source` must be a non-empty string")
    unit = raw.get("unit", "-")
    if kind == "absolute":
        if "unit" not in raw:
            raise VesselFileError(f"`{where}` is absolute and needs a `unit`")
        _si_factor(key, unit)  # refuses a unit of the wrong dimension
    elif unit != "-":
        raise VesselFileError(f"`{where}` is relative; its unit must be '-', got {unit!r}")
    return Uncertainty(float(value), kind, src, unit)


def check_table(key: str, raw: Any) -> Coefficient:
    if not isinstance(raw, Mapping):
        raise VesselFileError(
            f"`{key}` must be a table {{ value, unit, source, status }}, got {type(raw).__name__}"
        )
    need = ("value", "unit", "source", "status")
    missing = [k for k in need if k not in raw]
    if missing:
        raise VesselFileError(f"`{key}` is missing {', '.join(missing)}")
    extra = sorted(set(raw) - set(need))
    if extra:
        raise VesselFileError(f"`{key}` has unknown key(s) {extra}; allowed are {list(need)}")
    value = raw["value"]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise VesselFileError(f"`{key}.value` must be a number, got {value!r}")
    for k in ("unit", "source", "status"):
        if not isinstance(raw[k], str):
            raise VesselFileError(f"`{key}.{k}` must be a string, got {raw[k]!r}")
    if not raw["source"].strip():
        raise VesselFileError(f"`{key}.source` must not be empty")
    if raw["status"] not in STATUSES:
        raise VesselFileError(f"`{key}.status` must be one of {STATUSES}, got {raw['status']!r}")
    return Coefficient(float(value), raw["unit"], raw["source"], raw["status"])


def _check_value(key: str, c: Coefficient) -> None:
    sec, name = key.split(".", 1)
    spec = SCHEMA[sec][name]
    if not math.isfinite(c.value):
        raise VesselFileError(f"`{key}` must be finite, got {c.value}")
    v = c.value * _si_factor(key, c.unit)
    if spec.integer and v != int(v):
        raise VesselFileError(f"`{key}` must be an integer, got {c.value}")
    too_low = v <= spec.low if spec.low_open else v < spec.low
    if too_low or v > spec.high:
        lo = "(" if spec.low_open else "["
        raise VesselFileError(
            f"`{key}` = {c.value} {c.unit} is outside the allowed range "
            f"{lo}{spec.low}, {spec.high}] ({spec.doc})"
        )


def _check_consistency(coeffs: Mapping[str, Coefficient]) -> None:
    def si(k: str) -> float:
        c = coeffs[k]
        return c.value * _si_factor(k, c.unit)

    d_f, d_a, depth = si("particulars.d_f"), si("particulars.d_a"), si("particulars.D")
    for k, d in (("particulars.d_f", d_f), ("particulars.d_a", d_a)):
        if d >= depth:
            raise VesselFileError(
                f"`{k}` = {d} m must be below the depth `particulars.D` = {depth} m"
            )
    if "particulars.d_m" in coeffs:
        d_m = si("particulars.d_m")
        if abs(d_m - 0.5 * (d_f + d_a)) > 0.01 * d_m:
            raise VesselFileError(
                f"`particulars.d_m` = {d_m} m differs from (d_f + d_a)/2 = "
                f"{0.5 * (d_f + d_a):.4f} m by more than 1 %"
            )
    L = si("particulars.L_pp")
    B = si("particulars.B")
    if not 1.5 <= L / B <= 20.0:
        raise VesselFileError(
            f"`particulars.B` = {B} m gives L_pp/B = {L / B:.3g}; a ship has 1.5 <= L_pp/B <= 20"
        )
    d_mean = 0.5 * (d_f + d_a)
    if not 0.5 <= B / d_mean <= 15.0:
        raise VesselFileError(
            f"`particulars.d_f`/`particulars.d_a` give B/d_m = {B / d_mean:.3g}; a ship has "
            "0.5 <= B/d_m <= 15"
        )
    # KG = KM - GM must be positive: KM = KB + BM <= d_m + B^2 / (12 C_b d_m) (KB <= d_m;
    # the waterplane's transverse inertia <= L B^3 / 12, the volume = C_b L B d_m).
    km_max = d_mean + B**2 / (12.0 * si("particulars.C_b") * d_mean)
    if si("loading.GM") >= km_max:
        raise VesselFileError(
            f"`loading.GM` = {si('loading.GM')} m would put G below the keel (KG = KM - GM < 0; "
            f"KM <= {km_max:.3g} m for these particulars)"
        )
    if abs(si("particulars.lcb_aft")) >= 0.5 * L:
        raise VesselFileError("`particulars.lcb_aft` must lie within the ship (|lcb| < L_pp/2)")
    if "loading.mass" in coeffs:
        vol = si("particulars.C_b") * L * si("particulars.B") * 0.5 * (d_f + d_a)
        m_hull = si("environment.rho") * vol
        m = si("loading.mass")
        if abs(m - m_hull) > 0.02 * m_hull:
            raise VesselFileError(
                f"`loading.mass` = {m:.6g} kg differs from rho C_b L B d_m = {m_hull:.6g} kg "
                "by more than 2 %"
            )
    lo, hi = si("hull.beta_min"), si("hull.beta_max")
    if not lo < hi:
        raise VesselFileError("`hull.beta_min` must be smaller than `hull.beta_max`")
    if lo < 0.5:
        raise VesselFileError("`hull.beta_min` must be >= 0.5 (convex sections)")
    if si("hull.n_stations") % 2:
        raise VesselFileError("`hull.n_stations` must be even")
    kt = [k for k in ("propulsion.K_T0", "propulsion.K_T1", "propulsion.K_T2") if k in coeffs]
    if 0 < len(kt) < 3:
        raise VesselFileError(
            "`propulsion.K_T0`, `propulsion.K_T1`, `propulsion.K_T2` must be given together"
        )
    # an added mass given both dimensionally and as a prime must agree
    half_rho_L2d = 0.5 * si("environment.rho") * L**2 * 0.5 * (d_f + d_a)
    for name, scale in (
        ("m_x", half_rho_L2d),
        ("m_y", half_rho_L2d),
        ("J_zz", half_rho_L2d * L**2),
    ):
        dim_key, prime_key = f"hydrodynamics.{name}", f"hydrodynamics.{name}_prime"
        if dim_key in coeffs and prime_key in coeffs:
            a, b = si(dim_key), si(prime_key) * scale
            if abs(a - b) > 1e-6 * max(abs(a), abs(b)):
                raise VesselFileError(
                    f"`{dim_key}` = {a:.6g} disagrees with `{prime_key}` x rho/2 L^n d_m = "
                    f"{b:.6g}; give only one of them"
                )


def validate(coeffs: Mapping[str, Coefficient]) -> None:
    """Check a full set of coefficients (dotted keys); raise VesselFileError naming the field."""
    for key in coeffs:
        sec, _, name = key.partition(".")
        if sec not in SCHEMA:
            raise VesselFileError(f"`{key}`: unknown section {sec!r}; sections are {list(SCHEMA)}")
        if name not in SCHEMA[sec]:
            raise VesselFileError(
                f"`{key}`: unknown key {name!r} in [{sec}]; allowed are {list(SCHEMA[sec])}"
            )
    for sec, fields in SCHEMA.items():
        for name, spec in fields.items():
            key = f"{sec}.{name}"
            if spec.required and key not in coeffs:
                if spec.required_unless and spec.required_unless in coeffs:
                    continue
                alt = f" or give `{spec.required_unless}`" if spec.required_unless else ""
                raise VesselFileError(f"missing required field `{key}` ({spec.doc}){alt}")
    for key, c in coeffs.items():
        if c.status not in STATUSES:
            raise VesselFileError(f"`{key}.status` must be one of {STATUSES}, got {c.status!r}")
        _check_value(key, c)
    _check_consistency(coeffs)
