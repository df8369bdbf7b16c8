"""The ship's outcomes: one enumeration for every fate and outcome of the ship layer.

A trajectory of the ship (a manifold branch, a sudden-change transient) ends in one of
the outcomes of Umeda (1999): it capsizes (roll past the angle of vanishing stability),
settles on the periodic surging motion (overtaken by the waves), surf-rides on a stable
equilibrium, or converges onto a saddle; next to the heteroclinic connection the
surging motion may be *recurrent* without a settled period. The bisections of the
critical Fn compare coarser outcomes: the upslope branch of the crest saddle either
passes the next crest (``PERIODIC``) or is ``CAPTURED`` by the wave (capsize, turned
back down the slope); on its first passage it may also have ``RETURNED`` to a periodic
motion.

:class:`ShipOutcome` is a :class:`enum.StrEnum`: its members compare equal to, print
and serialise as their values (``"capsize"``, ...), the strings the ship layer has
always reported. Where a meaning coincides with the engine's
:class:`continuation.dynamics.fates.FateKind` the value is the same (``"periodic"``,
``"equilibrium"``, ``"saddle"``, ``"undecided"``) and :meth:`ShipOutcome.fate_kind`
gives it; ``CAPSIZE`` is the engine's ``FateKind.EVENT`` for the ship's capsize event.
"""

from __future__ import annotations

import enum

from continuation.dynamics import FateKind


class ShipOutcome(enum.StrEnum):
    """Outcome of a ship trajectory (see the module docstring)."""

    CAPSIZE = "capsize"
    PERIODIC = "periodic"
    RECURRENT = "recurrent"
    EQUILIBRIUM = "equilibrium"
    SURF_RIDING = "surf-riding"
    SADDLE = "saddle"
    CAPTURED = "captured"
    RETURNED = "returned"
    UNDECIDED = "undecided"

    @property
    def fate_kind(self) -> FateKind | None:
        """The engine's :class:`FateKind` of the same meaning (None where there is none)."""
        return _FATE_KIND.get(self)

    @property
    def captured(self) -> bool:
        """Captured by the wave: capsize, surf-riding, a saddle reached, or ``CAPTURED``."""
        return self in CAPTURED_BY_WAVE or self is ShipOutcome.CAPTURED


_FATE_KIND = {
    ShipOutcome.CAPSIZE: FateKind.EVENT,
    ShipOutcome.PERIODIC: FateKind.PERIODIC,
    ShipOutcome.EQUILIBRIUM: FateKind.EQUILIBRIUM,
    ShipOutcome.SURF_RIDING: FateKind.EQUILIBRIUM,
    ShipOutcome.SADDLE: FateKind.SADDLE,
    ShipOutcome.UNDECIDED: FateKind.UNDECIDED,
}

#: The fates of :class:`~ship_models.analysis.manifold.ShipFate` (``kind``), in the order
#: of :mod:`ship_models.analysis.manifold`'s documentation.
FATE_KINDS = (
    ShipOutcome.CAPSIZE,
    ShipOutcome.PERIODIC,
    ShipOutcome.RECURRENT,
    ShipOutcome.EQUILIBRIUM,
    ShipOutcome.SADDLE,
    ShipOutcome.UNDECIDED,
)
#: Outcomes of a sudden-change run (Umeda 1999, Figs. 16, 22).
SUDDEN_CHANGE_OUTCOMES = (
    ShipOutcome.CAPSIZE,
    ShipOutcome.PERIODIC,
    ShipOutcome.SURF_RIDING,
    ShipOutcome.SADDLE,
    ShipOutcome.UNDECIDED,
)
#: Outcomes counted as "captured by the wave" (the upper side of a sudden-change boundary).
CAPTURED_BY_WAVE = frozenset({ShipOutcome.CAPSIZE, ShipOutcome.SURF_RIDING, ShipOutcome.SADDLE})

__all__ = ["CAPTURED_BY_WAVE", "FATE_KINDS", "SUDDEN_CHANGE_OUTCOMES", "ShipOutcome"]
