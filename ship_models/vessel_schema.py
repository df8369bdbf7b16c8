"""The schema of a vessel file: its sections and keys (:data:`SCHEMA`), the units each
accepts, the statuses and method choices, and the value types of an entry
(:class:`Coefficient`, :class:`Uncertainty`). Read and checked by
:mod:`ship_models.vessel` and :mod:`ship_models.vessel_checks`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

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


def _si_factor(key: str, unit: str) -> float:
    sec, name = key.split(".", 1)
    spec = SCHEMA[sec][name]
    units = _UNITS[spec.dim]
    if unit not in units:
        raise VesselFileError(f"`{key}`: unit {unit!r} not accepted; use one of {sorted(units)}")
    return units[unit]


#: The method choices of a ``[vessel]`` section and what each may be (the first is
#: the default).
METHOD_CHOICES: dict[str, tuple[str, ...]] = {
    "wave_surge_model": WAVE_SURGE_MODELS,
    "resistance_method": RESISTANCE_METHODS,
    "propeller_method": PROPELLER_METHODS,
    "heel_derivatives_method": HEEL_METHODS,
}
