"""Vessel data files: every number with its unit, source and status.

A vessel is described by one TOML file (read with :mod:`tomllib`) in which every
number is a table::

    GM = { value = 1.0, unit = "m", source = "Umeda (1999) Table 1", status = "given" }

``status`` is one of ``given`` (from the reference paper's table), ``measured``
(from a cited test report), ``estimated`` (a named method computed it),
``assumed`` (a stated engineering assumption) or ``calibrated`` (solved so that the
model reproduces a stated target, e.g. a published critical Froude number; the
source names the target and where it came from). Free-text metadata (strings) are
allowed only in the ``[vessel]`` section; there ``wave_surge_model`` selects the
wave surge-force model (one of :data:`WAVE_SURGE_MODELS`, default
``"froude_krylov"``).

Uncertainties (optional) live in an ``[uncertainties]`` section keyed by the dotted
name of any schema coefficient, given in the file or filled by the estimation
pipeline::

    [uncertainties]
    "hydrodynamics.m_x" = { value = 0.3, type = "relative", source = "..." }
    "rudder.x_H_over_L" = { value = 0.05, type = "absolute", unit = "-", source = "..." }

``value`` is a *standard* uncertainty (one standard deviation, as in the ISO Guide
to the Expression of Uncertainty in Measurement), relative to the coefficient's
value or absolute in ``unit``; ``source`` states where it comes from (a method's
published accuracy, or an assumption stated as one). See :class:`Uncertainty`.

:func:`load_vessel` parses and validates a file and returns an immutable
:class:`VesselData`. Validation refuses, with a :class:`VesselFileError` naming the
field by its dotted path (e.g. ``loading.GM``): a missing required field; a table
without ``value``/``unit``/``source``/``status`` or with extra keys; an unknown
status, unit, section or key (no silent typos); a non-finite value; non-positive
lengths, breadth, drafts, mass or periods, or beyond any ship's (``L_pp`` > 500 m,
``L_pp/B`` outside [1.5, 20], ``B/d_m`` outside [0.5, 15]); ``GM <= 0`` or so large
that G lies below the keel (``KG = KM - GM < 0``); a wave steeper than the
breaking limit ``H/lambda = 1/7`` (Michell, J.H. 1893, "The highest waves in water",
Phil. Mag. 36:430-437).

Nothing is silently defaulted: coefficients that the file does not give are
filled by the estimation pipeline (:func:`ship_models.estimation.resolve_vessel`),
which records them with status ``estimated`` and the method in ``source``.
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .vessel_curves import CurveData, CurveError, curves_to_toml, parse_curves

STATUSES = ("given", "measured", "estimated", "assumed", "calibrated")

#: Kinds of uncertainty in the ``[uncertainties]`` section.
UNCERTAINTY_TYPES = ("relative", "absolute")

#: Wave surge-force models selectable by ``[vessel] wave_surge_model``:
#: ``"froude_krylov"`` (default) -- the Froude-Krylov integral over the hull, as in
#: Umeda (1999); ``"froude_krylov_taylor"`` -- plus G.I. Taylor's (1928) long-wave
#: diffraction part ``X_D = (m_x / rho V) X_FK`` (:mod:`ship_models.hydro.diffraction`;
#: valid for wavelengths long against the hull, so not the default at lambda/L ~ 1).
#: A measured ratio to the selected model can be given as
#: ``hydrodynamics.wave_surge_scale``.
WAVE_SURGE_MODELS = ("froude_krylov", "froude_krylov_taylor")

#: Resistance methods selectable by ``[vessel] resistance_method``: ``"holtrop"``
#: (default; ITTC-1957 + Holtrop 1984, or the MMG R0' when ``resistance.R0_prime`` is
#: given) or ``"table"`` (the measured ``[curves] resistance``).
RESISTANCE_METHODS = ("holtrop", "table")

#: Open-water propeller models selectable by ``[vessel] propeller_method``:
#: ``"bseries_quadratic"`` (default; quadratic fit of the Wageningen B-series on
#: ``[0, J_max_fit]``, or the given K_T0..K_T2), ``"bseries"`` (the full B-series
#: polynomial, cubic in J) or ``"curve"`` (the ``[curves] K_T`` table or polynomial).
PROPELLER_METHODS = ("bseries_quadratic", "bseries", "curve")

#: Heel-derivative estimates selectable by ``[vessel] heel_derivatives_method``:
#: ``"none"`` (default; Y_phi = N_phi = K_phi = 0 unless given) or
#: ``"son_nomoto_ratio"`` (the ratios of Son & Nomoto's 1981 captive-tested container
#: ship applied to the hull's drift derivatives, an analogy:
#: :mod:`ship_models.hydro.heel`).
HEEL_METHODS = ("none", "son_nomoto_ratio")

#: Hull types known to ``[vessel] hull_type`` (sets the validity range of the
#: regressions, e.g. Holtrop & Mennen's Fn range for trawlers).
HULL_TYPES = ("fishing_vessel", "merchant")

#: Breaking limit of the wave steepness (Michell 1893: H/lambda = 0.142 ~ 1/7).
BREAKING_STEEPNESS = 1.0 / 7.0

DATA_DIR = Path(__file__).resolve().parent / "data"

# accepted units per physical dimension, with the factor to SI
_UNITS: dict[str, dict[str, float]] = {
    "length": {"m": 1.0},
    "area": {"m^2": 1.0},
    "volume": {"m^3": 1.0},
    "mass": {"kg": 1.0, "t": 1000.0},
    "time": {"s": 1.0},
    "angle": {"rad": 1.0, "deg": math.pi / 180.0},
    "density": {"kg/m^3": 1.0},
    "acceleration": {"m/s^2": 1.0},
    "viscosity": {"m^2/s": 1.0},
    "inertia": {"kg m^2": 1.0, "t m^2": 1000.0},
    "none": {"-": 1.0},
    "count": {"-": 1.0},
    "force": {"N": 1.0, "kN": 1000.0},
}


class VesselFileError(ValueError):
    """A vessel file (or an override) is malformed or non-physical.

    The message always names the offending field by its dotted path.
    """


@dataclass(frozen=True)
class Field:
    """Schema entry of one coefficient.

    Attributes
    ----------
    dim : str
        Physical dimension (a key of the unit table), e.g. ``"length"``.
    required : bool
        The file must give it (otherwise it is optional: estimated when absent,
        or, for switches, simply unused).
    low, high : float
        Allowed closed interval (after conversion to SI).
    low_open : bool
        If True the lower bound is exclusive (``value > low``).
    integer : bool
        The value must be an integer.
    doc : str
        One-line description.
    required_unless : str
        Dotted key of a field that makes this one unnecessary when it is given
        (e.g. the Holtrop fit range is not needed when ``resistance.R0_prime`` gives
        the resistance directly). Only meaningful with ``required=True``.
    """

    dim: str
    required: bool = True
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    integer: bool = False
    doc: str = ""
    required_unless: str = ""


def _pos(dim: str, doc: str, required: bool = True, high: float = math.inf) -> Field:
    return Field(dim, required, 0.0, high, True, False, doc)


def _frac(doc: str, required: bool = True, low: float = 0.0, high: float = 1.0) -> Field:
    return Field("none", required, low, high, True, False, doc)


def _opt(dim: str, doc: str, low: float = -math.inf, high: float = math.inf) -> Field:
    return Field(dim, False, low, high, False, False, doc)


#: The schema: section -> key -> Field. Keys not listed here are refused.
SCHEMA: dict[str, dict[str, Field]] = {
    "particulars": {
        "L_pp": Field("length", True, 1.0, 500.0, doc="length between perpendiculars"),
        "L_OA": _pos("length", "length overall", required=False, high=550.0),
        "B": _pos("length", "moulded breadth", high=100.0),
        "D": _pos("length", "moulded depth (keel to deck at side)", high=60.0),
        "d_f": _pos("length", "draft at the fore perpendicular", high=40.0),
        "d_m": _pos("length", "mean draft", required=False, high=40.0),
        "d_a": _pos("length", "draft at the aft perpendicular", high=40.0),
        "C_b": _frac("block coefficient"),
        "lcb_aft": Field("length", True, doc="longitudinal centre of buoyancy aft of midship"),
        "S_f": _pos("area", "wetted surface area", required=False),
        "kappa_yy_over_L": _frac("gyro radius in pitch / L_pp", required=False),
        "kappa_zz_over_L": _frac("gyro radius in yaw / L_pp"),
    },
    "loading": {
        "GM": _pos("length", "metacentric height"),
        "T_phi": _pos("time", "natural roll period", high=120.0),
        "mass": _pos("mass", "displacement mass (within 2 % of rho C_b L B d_m)", False),
    },
    "environment": {
        "rho": _pos("density", "water density"),
        "g": _pos("acceleration", "gravitational acceleration"),
        "nu": _pos("viscosity", "kinematic viscosity of water"),
    },
    "waves": {
        "H_over_lambda": Field("none", True, 0.0, BREAKING_STEEPNESS, doc="wave steepness"),
        "lambda_over_L": _pos("none", "wavelength / L_pp"),
    },
    "hull": {
        "C_M": _frac("midship section coefficient"),
        "C_wp": _frac("waterplane area coefficient", required=False),
        "n_stations": Field("count", True, 8, 400, integer=True, doc="strips (even)"),
        "n_depth": Field("count", True, 2, 64, integer=True, doc="depth nodes per strip"),
        "beta_min": _frac("smallest section area coefficient (convex sections need >= 0.5)"),
        "beta_max": _frac("largest section area coefficient"),
    },
    "propulsion": {
        "D_p": _pos("length", "propeller diameter"),
        "n_blades": Field("count", True, 2, 7, integer=True, doc="number of blades"),
        "P_over_D": Field("none", True, 0.5, 1.4, doc="pitch ratio (B-series range)"),
        "AE_over_A0": Field("none", True, 0.3, 1.05, doc="blade area ratio (B-series range)"),
        "J_max_fit": Field(
            "none",
            True,
            0.0,
            low_open=True,
            doc="upper end of the J range of the quadratic K_T fit",
            required_unless="propulsion.K_T0",
        ),
        "w_P": _opt("none", "effective wake fraction", 0.0, 0.9),
        "t_P": _opt("none", "thrust deduction fraction", 0.0, 0.9),
        "K_T0": _opt("none", "K_T(J) = K_T0 + K_T1 J + K_T2 J^2"),
        "K_T1": _opt("none", "K_T(J) = K_T0 + K_T1 J + K_T2 J^2"),
        "K_T2": _opt("none", "K_T(J) = K_T0 + K_T1 J + K_T2 J^2"),
    },
    "resistance": {
        "C_stern": Field("none", True, -25.0, 10.0, doc="Holtrop stern-shape parameter"),
        "Fn_max_fit": Field(
            "none",
            True,
            0.0,
            low_open=True,
            doc="upper end of the Froude-number range of the R(u) fit",
            required_unless="resistance.R0_prime",
        ),
        "knot_spacing_Fn": Field(
            "none",
            True,
            0.005,
            0.2,
            doc="R(u) spline knot spacing in Fn",
            required_unless="resistance.R0_prime",
        ),
        "form_factor": _opt("none", "1 + k", 1.0, 3.0),
        "C_A": _opt("none", "correlation allowance", -0.01, 0.01),
        "R0_prime": Field(
            "none",
            False,
            0.0,
            1.0,
            True,
            doc="straight-running resistance R0' = R / (rho/2 L_pp d_m u^2) of the MMG "
            "standard method; if given, R(u) = R0' rho/2 L_pp d_m u^2 replaces the Holtrop "
            "estimate",
        ),
    },
    "rudder": {
        "A_R": _pos("area", "rudder area"),
        "aspect_ratio": _pos("none", "rudder aspect ratio Lambda"),
        "delta_max": _pos("angle", "maximum rudder angle", high=math.pi / 2),
        "a_H": _frac("rudder-hull interaction factor a_H", low=-1.0),
        "x_H_over_L": Field("none", True, -1.0, 0.0, doc="x_H / L_pp of the hull-induced force"),
        "gamma_R": _frac("flow-straightening coefficient gamma_R", high=2.0),
        "l_R_over_L": Field("none", True, -2.0, 0.0, doc="effective longitudinal rudder lever"),
        "epsilon": _pos("none", "(1 - w_R) / (1 - w_P)", high=3.0),
        "kappa": _frac("propeller-race factor kappa", high=2.0),
        "f_alpha": _opt("none", "rudder normal-force lift slope per rad", 0.0, 10.0),
        "H_R": Field(
            "length", False, 0.0, low_open=True, doc="rudder span; default sqrt(aspect_ratio A_R)"
        ),
    },
    "autopilot": {
        "K_R": Field("none", True, 0.0, doc="rudder gain"),
        "T_D": Field("time", True, 0.0, doc="differential-control time constant"),
        "T_E": _pos("time", "steering-gear time constant"),
    },
    "roll": {
        "zeta_0": Field("none", True, 0.0, 1.0, doc="roll damping ratio at zero speed"),
        "z_H_over_d": Field("none", True, 0.0, 1.0, doc="depth of lateral force / d_m"),
    },
    "stability": {
        "n_gz_terms": Field("count", True, 4, 80, integer=True, doc="sine terms of GZ fit"),
        "heel_step": _pos("angle", "heel step of the hydrostatic GZ computation", high=0.2),
        "topside_height": _opt("length", "watertight extension above the deck counted in GZ", 0.0),
    },
    "hydrodynamics": {
        "m_x": _opt("mass", "surge added mass", 0.0),
        "m_y": _opt("mass", "sway added mass", 0.0),
        "J_zz": _opt("inertia", "yaw added moment of inertia", 0.0),
        "m_x_prime": _opt("none", "m_x / (rho/2 L_pp^2 d_m) (alternative to m_x)", 0.0),
        "m_y_prime": _opt("none", "m_y / (rho/2 L_pp^2 d_m) (alternative to m_y)", 0.0),
        "J_zz_prime": _opt("none", "J_zz / (rho/2 L_pp^4 d_m) (alternative to J_zz)", 0.0),
        "x_ref": _opt(
            "length",
            "x (from midship, + forward) of the origin to which the hull derivatives "
            "Y_v'..N_r' and J_zz refer (e.g. 0 for the MMG standard method); absent: "
            "they are used as referred to G",
        ),
        "I_xx_plus_J_xx": _opt("inertia", "roll moment of inertia incl. added", 0.0),
        "Y_v_prime": _opt("none", "Y_v / (rho/2 L d U)"),
        "Y_r_prime": _opt("none", "Y_r / (rho/2 L^2 d U)"),
        "N_v_prime": _opt("none", "N_v / (rho/2 L^2 d U)"),
        "N_r_prime": _opt("none", "N_r / (rho/2 L^3 d U)"),
        "Y_phi_prime": _opt("none", "Y_phi / (rho/2 L d U^2)"),
        "N_phi_prime": _opt("none", "N_phi / (rho/2 L^2 d U^2)"),
        "K_phi_prime": _opt("none", "K_phi / (rho/2 L d^2 U^2)"),
        "K_p0": _opt("none", "-K_p(0) / (I_xx + J_xx) (1/s, >= 0)", 0.0),
        "K_p_lift_prime": _opt("none", "roll lift damping / (rho/2 L d^3 U)", 0.0),
        "wave_surge_scale": Field(
            "none",
            False,
            0.0,
            10.0,
            True,
            doc="factor on the wave surge force X_w of the selected wave_surge_model "
            "(absent: 1, the model's own amplitude)",
        ),
        "wave_surge_diffraction": _opt(
            "none",
            "diffraction-to-Froude-Krylov ratio X_D/X_FK of wave_surge_model "
            "'froude_krylov_taylor' (absent: m_x/(rho V), Taylor 1928)",
            0.0,
            10.0,
        ),
    },
}


@dataclass(frozen=True)
class Coefficient:
    """One number of a vessel file.

    Attributes
    ----------
    value : float
        The value in ``unit``.
    unit : str
        Unit as written (converted to SI by :meth:`si`).
    source : str
        Where the number comes from (author, year, title, table), or the method.
    status : str
        ``given``, ``measured``, ``estimated`` or ``assumed``.
    """

    value: float
    unit: str
    source: str
    status: str

    def as_dict(self) -> dict[str, Any]:
        """Plain dictionary of the four fields (for JSON)."""
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Uncertainty:
    """Standard uncertainty (one standard deviation) of one coefficient.

    Attributes
    ----------
    value : float
        ``>= 0``; a fraction of the coefficient's value (``type="relative"``) or an
        amount in ``unit`` (``type="absolute"``).
    type : str
        ``"relative"`` or ``"absolute"``.
    source : str
        Where it comes from: a method's published accuracy, or an assumption stated
        as one.
    unit : str
        Unit of an absolute uncertainty (``"-"`` for relative ones).
    """

    value: float
    type: str
    source: str
    unit: str = "-"

    def as_dict(self) -> dict[str, Any]:
        """Plain dictionary (for JSON and TOML)."""
        d: dict[str, Any] = {"value": self.value, "type": self.type, "source": self.source}
        if self.type == "absolute":
            d["unit"] = self.unit
        return d

    def sigma(self, key: str, coefficient: Coefficient) -> float:
        """Standard uncertainty of the coefficient at dotted ``key``, in its own unit."""
        if self.type == "relative":
            return abs(self.value * coefficient.value)
        return self.value * _si_factor(key, self.unit) / _si_factor(key, coefficient.unit)


def _check_uncertainty(key: str, raw: Any) -> Uncertainty:
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


def _si_factor(key: str, unit: str) -> float:
    sec, name = key.split(".", 1)
    spec = SCHEMA[sec][name]
    units = _UNITS[spec.dim]
    if unit not in units:
        raise VesselFileError(f"`{key}`: unit {unit!r} not accepted; use one of {sorted(units)}")
    return units[unit]


def _check_table(key: str, raw: Any) -> Coefficient:
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


#: The method choices of a ``[vessel]`` section and what each may be (the first is
#: the default).
METHOD_CHOICES: dict[str, tuple[str, ...]] = {
    "wave_surge_model": WAVE_SURGE_MODELS,
    "resistance_method": RESISTANCE_METHODS,
    "propeller_method": PROPELLER_METHODS,
    "heel_derivatives_method": HEEL_METHODS,
}


class _MethodChoice:
    """A method choice of :class:`VesselData` (read-only attribute of the same name):
    ``[vessel] <name>``, or the first of :data:`METHOD_CHOICES` ``[name]`` when the
    file names none."""

    def __init__(self, doc: str) -> None:
        self.__doc__ = doc

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name
        self.__doc__ = f"{self.__doc__[:-1]} (``[vessel] {name}``)."

    def __get__(self, obj: Any, objtype: type | None = None) -> Any:
        if obj is None:
            return self
        return str(obj.meta.get(self.name, METHOD_CHOICES[self.name][0]))


@dataclass(frozen=True)
class VesselData(Mapping[str, Coefficient]):
    """An immutable, validated vessel description.

    It is a read-only mapping from dotted keys (``"loading.GM"``) to
    :class:`Coefficient`.

    Attributes
    ----------
    name : str
        Short identifier (``[vessel] name``).
    meta : mapping of str to str
        Free-text metadata of the ``[vessel]`` section.
    coefficients : mapping of str to Coefficient
        All numbers, by dotted key.
    path : str
        File it was read from ("" when built in code).
    uncertainties : mapping of str to Uncertainty
        Standard uncertainties by dotted key (section ``[uncertainties]``); a key may
        name a coefficient that only the estimation pipeline fills.
    """

    name: str
    meta: Mapping[str, str]
    coefficients: Mapping[str, Coefficient] = field(repr=False)
    path: str = ""
    uncertainties: Mapping[str, Uncertainty] = field(default_factory=dict, repr=False)
    curves: Mapping[str, CurveData] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        coeffs = dict(self.coefficients)
        validate(coeffs)
        from .validation import check_plausible  # relations between fields (plausibility)

        check_plausible(coeffs)
        meta = dict(self.meta)
        for key, allowed in (*METHOD_CHOICES.items(), ("hull_type", HULL_TYPES)):
            if key in meta and meta[key] not in allowed:
                raise VesselFileError(f"`vessel.{key}` must be one of {allowed}, got {meta[key]!r}")
        curves = dict(self.curves)
        if meta.get("resistance_method") == "table" and "resistance" not in curves:
            raise VesselFileError(
                "`vessel.resistance_method` = 'table' needs a `curves.resistance` table"
            )
        if meta.get("propeller_method") == "curve" and "K_T" not in curves:
            raise VesselFileError("`vessel.propeller_method` = 'curve' needs a `curves.K_T` entry")
        object.__setattr__(self, "curves", curves)
        unc = dict(self.uncertainties)
        for k, u in unc.items():
            if not isinstance(u, Uncertainty):
                unc[k] = _check_uncertainty(k, u)
            else:
                _check_uncertainty(k, u.as_dict() | {"unit": u.unit})
        object.__setattr__(self, "coefficients", coeffs)
        object.__setattr__(self, "meta", meta)
        object.__setattr__(self, "uncertainties", unc)

    resistance_method = _MethodChoice("The selected resistance method.")
    propeller_method = _MethodChoice("The selected open-water propeller model.")
    heel_derivatives_method = _MethodChoice("The selected heel-derivative estimate.")
    wave_surge_model = _MethodChoice("The selected wave surge-force model.")

    def sigma(self, key: str) -> float | None:
        """Standard uncertainty of ``key`` in the coefficient's unit (None if none given)."""
        k = self._resolve_key(key)
        u = self.uncertainties.get(k)
        return None if u is None else u.sigma(k, self.coefficients[k])

    # Mapping protocol
    def __getitem__(self, key: str) -> Coefficient:
        return self.coefficient(key)

    def __iter__(self) -> Iterator[str]:
        return iter(self.coefficients)

    def __len__(self) -> int:
        return len(self.coefficients)

    def __hash__(self) -> int:
        return hash(
            (
                self.name,
                tuple(sorted(self.coefficients.items())),
                tuple(sorted(self.meta.items())),
                tuple(sorted(self.curves.items())),
            )
        )

    def _resolve_key(self, key: str) -> str:
        if key in self.coefficients:
            return key
        if "." not in key:
            hits = [k for k in self.coefficients if k.split(".", 1)[1] == key]
            if len(hits) == 1:
                return hits[0]
            if len(hits) > 1:
                raise KeyError(f"key {key!r} is ambiguous: {hits}; use the dotted path")
        raise KeyError(f"no coefficient {key!r} in vessel {self.name!r}")

    def coefficient(self, key: str) -> Coefficient:
        """The :class:`Coefficient` at dotted ``key`` (or a unique bare name)."""
        return self.coefficients[self._resolve_key(key)]

    def get(self, key: str, default: Any = None) -> Any:  # type: ignore[override]
        """Value of ``key`` in SI units (``default`` if absent, else KeyError if no default)."""
        try:
            k = self._resolve_key(key)
        except KeyError:
            if default is not None:
                return default
            raise
        c = self.coefficients[k]
        return c.value * _si_factor(k, c.unit)

    def has(self, key: str) -> bool:
        """True if the coefficient is present."""
        try:
            self._resolve_key(key)
        except KeyError:
            return False
        return True

    def to_dict(self) -> dict[str, Any]:
        """Nested plain dictionary (JSON-serialisable), sections as in the file."""
        out: dict[str, Any] = {"vessel": {"name": self.name, **self.meta}}
        for k, c in self.coefficients.items():
            sec, name = k.split(".", 1)
            out.setdefault(sec, {})[name] = c.as_dict()
        if self.uncertainties:
            out["uncertainties"] = {k: u.as_dict() for k, u in self.uncertainties.items()}
        if self.curves:
            out["curves"] = {k: c.as_dict() for k, c in self.curves.items()}
        return out

    def with_overrides(self, overrides: Mapping[str, float | Coefficient]) -> VesselData:
        """A copy with some coefficients replaced (validated again).

        Parameters
        ----------
        overrides : mapping
            ``{dotted_key: Coefficient}``, or ``{dotted_key: float}``: a bare number
            keeps the unit of the existing entry (SI unit of the schema if absent) and
            is recorded with ``source="user override"`` and ``status="measured"``.

        Raises
        ------
        VesselFileError
            For unknown keys or values that fail validation.
        """
        coeffs = dict(self.coefficients)
        for key, val in overrides.items():
            sec, _, name = key.partition(".")
            if sec not in SCHEMA or name not in SCHEMA[sec]:
                raise VesselFileError(f"`{key}`: unknown coefficient; use a dotted schema key")
            if isinstance(val, Coefficient):
                coeffs[key] = val
            else:
                default_unit = next(iter(_UNITS[SCHEMA[sec][name].dim]))
                unit = coeffs[key].unit if key in coeffs else default_unit
                coeffs[key] = Coefficient(float(val), unit, "user override", "measured")
        return VesselData(self.name, self.meta, coeffs, self.path, self.uncertainties, self.curves)

    def with_estimates(self, estimates: Mapping[str, Coefficient]) -> VesselData:
        """A copy with estimated coefficients added (existing keys are kept)."""
        coeffs = dict(self.coefficients)
        for key, c in estimates.items():
            coeffs.setdefault(key, c)
        return VesselData(self.name, self.meta, coeffs, self.path, self.uncertainties, self.curves)

    def summary(self) -> list[tuple[str, float, str, str, str]]:
        """Rows ``(key, value, unit, status, source)`` sorted by key."""
        return [
            (k, c.value, c.unit, c.status, c.source) for k, c in sorted(self.coefficients.items())
        ]


def parse_vessel(doc: Mapping[str, Any], path: str = "") -> VesselData:
    """Build a :class:`VesselData` from a parsed TOML document (nested dictionaries).

    Raises
    ------
    VesselFileError
        Naming the offending field.
    """
    meta_raw = doc.get("vessel", {})
    if not isinstance(meta_raw, Mapping):
        raise VesselFileError("`vessel` must be a table of strings")
    meta: dict[str, str] = {}
    for k, v in meta_raw.items():
        if not isinstance(v, str):
            raise VesselFileError(f"`vessel.{k}` must be a string (numbers go in other sections)")
        meta[k] = v
    name = meta.pop("name", "") or (Path(path).stem if path else "vessel")
    coeffs: dict[str, Coefficient] = {}
    unc_raw = doc.get("uncertainties", {})
    if not isinstance(unc_raw, Mapping):
        raise VesselFileError("`uncertainties` must be a table keyed by dotted coefficient names")
    uncertainties = {str(k): _check_uncertainty(str(k), u) for k, u in unc_raw.items()}
    try:
        curves = parse_curves(doc.get("curves", {}))
    except CurveError as exc:
        raise VesselFileError(str(exc)) from None
    for sec, body in doc.items():
        if sec in ("vessel", "uncertainties", "curves"):
            continue
        if sec not in SCHEMA:
            raise VesselFileError(
                f"`{sec}`: unknown section; sections are "
                f"{['vessel', *SCHEMA, 'curves', 'uncertainties']}"
            )
        if not isinstance(body, Mapping):
            raise VesselFileError(f"`{sec}` must be a table")
        for key, raw in body.items():
            dotted = f"{sec}.{key}"
            if key not in SCHEMA[sec]:
                raise VesselFileError(
                    f"`{dotted}`: unknown key {key!r} in [{sec}]; allowed are {list(SCHEMA[sec])}"
                )
            coeffs[dotted] = _check_table(dotted, raw)
    return VesselData(name, meta, coeffs, path, uncertainties, curves)


def _toml_str(s: str) -> str:
    return json.dumps(s, ensure_ascii=True)  # a JSON string is a valid TOML basic string


def _toml_num(x: float) -> str:
    return repr(float(x))  # shortest repr: reads back to the same float


def vessel_to_toml(vessel: VesselData, header: str = "") -> str:
    """The vessel as the text of a vessel file (:func:`load_vessel` reads it back).

    Parameters
    ----------
    vessel : VesselData
    header : str
        Comment lines put at the top (each prefixed with ``# ``).
    """
    lines = [f"# {h}" if h else "#" for h in header.splitlines()] if header else []
    lines += ["", "[vessel]", f"name = {_toml_str(vessel.name)}"]
    lines += [f"{k} = {_toml_str(v)}" for k, v in vessel.meta.items()]
    by_sec: dict[str, list[tuple[str, Coefficient]]] = {}
    for k, c in vessel.coefficients.items():
        sec, name = k.split(".", 1)
        by_sec.setdefault(sec, []).append((name, c))
    for sec in SCHEMA:
        if sec not in by_sec:
            continue
        lines += ["", f"[{sec}]"]
        for name, c in by_sec[sec]:
            lines.append(
                f"{name} = {{ value = {_toml_num(c.value)}, unit = {_toml_str(c.unit)}, "
                f"source = {_toml_str(c.source)}, status = {_toml_str(c.status)} }}"
            )
    lines += curves_to_toml(vessel.curves)
    if vessel.uncertainties:
        lines += ["", "[uncertainties]"]
        for k, u in vessel.uncertainties.items():
            unit = f", unit = {_toml_str(u.unit)}" if u.type == "absolute" else ""
            lines.append(
                f"{_toml_str(k)} = {{ value = {_toml_num(u.value)}, type = {_toml_str(u.type)}"
                f"{unit}, source = {_toml_str(u.source)} }}"
            )
    return "\n".join(lines) + "\n"


def dump_vessel(vessel: VesselData, path: str | Path, header: str = "") -> Path:
    """Write :func:`vessel_to_toml` to ``path``; return the path."""
    p = Path(path)
    p.write_text(vessel_to_toml(vessel, header))
    return p


def available_vessels() -> list[str]:
    """Names of the vessel files packaged in ``ship_models/data``."""
    return sorted(p.stem for p in DATA_DIR.glob("*.toml"))


def load_vessel(path_or_name: str | Path) -> VesselData:
    """Read and validate a vessel file.

    Parameters
    ----------
    path_or_name : str or Path
        A path to a ``.toml`` file, or the name of a packaged vessel
        (see :func:`available_vessels`), e.g. ``"purse_seiner"``.

    Returns
    -------
    VesselData

    Raises
    ------
    ValueError
        If the file does not exist (message lists the packaged vessels).
    VesselFileError
        If the file is malformed or non-physical (message names the field).
    """
    p = Path(path_or_name)
    if not p.suffix and not p.exists():
        p = DATA_DIR / f"{p.name}.toml"
    if not p.is_file():
        raise ValueError(
            f"no vessel file {str(path_or_name)!r}; packaged vessels are {available_vessels()}"
        )
    from .validation import check_file_size

    check_file_size(p)
    try:
        with p.open("rb") as fh:
            doc = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise VesselFileError(f"{p}: not valid TOML: {exc}") from exc
    return parse_vessel(doc, str(p))


__all__ = [
    "BREAKING_STEEPNESS",
    "Coefficient",
    "HEEL_METHODS",
    "HULL_TYPES",
    "PROPELLER_METHODS",
    "RESISTANCE_METHODS",
    "UNCERTAINTY_TYPES",
    "Uncertainty",
    "WAVE_SURGE_MODELS",
    "dump_vessel",
    "vessel_to_toml",
    "Field",
    "SCHEMA",
    "STATUSES",
    "VesselData",
    "VesselFileError",
    "available_vessels",
    "load_vessel",
    "parse_vessel",
    "validate",
]
