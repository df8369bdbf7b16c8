"""What every estimation stage shares: the particulars read once and the record of the
build (:class:`Build`: its estimates and validity ranges)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

from ..validity import ValidityRange
from ..vessel import Coefficient, VesselData


def estimated(value: float, unit: str, source: str, status: str = "estimated") -> Coefficient:
    """A :class:`~ship_models.vessel.Coefficient` filled by a method (``source``) or, with
    ``status="assumed"``, by a stated assumption."""
    return Coefficient(float(value), unit, source, status)


class Particulars(NamedTuple):
    """The environment, principal particulars and loading of a vessel file, in SI units.

    Attributes
    ----------
    rho, g, nu : float
        Water density, gravity, kinematic viscosity (``environment.*``).
    L, B : float
        ``particulars.L_pp``, ``particulars.B``.
    d_f, d_a, d_m : float
        Drafts fore and aft and their mean :math:`d_m = (d_f + d_a)/2`.
    C_b, lcb_aft : float
        Block coefficient; longitudinal centre of buoyancy, aft of midship +.
    GM, T_phi : float
        Metacentric height and natural roll period (``loading.*``).
    """

    rho: float
    g: float
    nu: float
    L: float
    B: float
    d_f: float
    d_a: float
    d_m: float
    C_b: float
    lcb_aft: float
    GM: float
    T_phi: float

    @classmethod
    def of(cls, v: VesselData) -> Particulars:
        """The particulars of the vessel ``v``."""
        d_f, d_a = v.get("particulars.d_f"), v.get("particulars.d_a")
        return cls(
            rho=v.get("environment.rho"),
            g=v.get("environment.g"),
            nu=v.get("environment.nu"),
            L=v.get("particulars.L_pp"),
            B=v.get("particulars.B"),
            d_f=d_f,
            d_a=d_a,
            d_m=0.5 * (d_f + d_a),
            C_b=v.get("particulars.C_b"),
            lcb_aft=v.get("particulars.lcb_aft"),
            GM=v.get("loading.GM"),
            T_phi=v.get("loading.T_phi"),
        )


@dataclass
class Build:
    """One run of the estimation pipeline: what every stage reads and records.

    Attributes
    ----------
    vessel : VesselData
        The vessel file's data.
    p : Particulars
        Its particulars, read once.
    estimates : dict of str to Coefficient
        The coefficients the stages estimated, by dotted key, in the order estimated.
    validity : list of ValidityRange
        The validity ranges of the methods used.
    """

    vessel: VesselData
    p: Particulars
    estimates: dict[str, Coefficient] = field(default_factory=dict)
    validity: list[ValidityRange] = field(default_factory=list)

    @classmethod
    def of(cls, vessel: VesselData) -> Build:
        """A new build of ``vessel`` (nothing estimated yet)."""
        return cls(vessel, Particulars.of(vessel))
