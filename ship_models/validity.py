"""Validity ranges of the regressions and measured curves, reported once when left.

Every estimate of the surge balance (resistance, thrust) holds on a range of its
argument: Holtrop & Mennen's (1982) resistance regression on the Froude numbers of
its database for the hull type, a measured table on its speeds, a K_T(J) fit or
polynomial on its advance ratios. :class:`ValidityRange` records one such range;
:func:`check_speed_range` evaluates an analysis' speeds against them and logs a
WARNING, once per (vessel, coefficient, side), naming the coefficient, the range and
the speed that leaves it.

An analysis of surf-riding at nominal Froude number ``Fn`` in a wave of celerity
``c`` visits surge speeds from below ``u_0 = Fn sqrt(g L)`` up to ``c`` (the orbit
that sets the threshold runs from about 0.2 c to c), so both ends are checked:
the nominal speed (where ``n(Fn)`` is set) and the celerity.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

log = logging.getLogger(__name__)

_REPORTED: set[tuple[str, str, str]] = set()


@dataclass(frozen=True)
class ValidityRange:
    """Range of the argument over which an estimate or a curve holds.

    Attributes
    ----------
    coefficient : str
        What is estimated (e.g. ``"resistance (Holtrop & Mennen 1982)"``).
    variable : str
        ``"Fn"`` (Froude number of the surge speed), ``"u"`` (m/s) or ``"J"``
        (advance ratio at the speed and the commanded revolution).
    low, high : float
        Closed interval.
    source : str
        Where the range comes from.
    """

    coefficient: str
    variable: str
    low: float
    high: float
    source: str


def report(vessel: str, rng: ValidityRange, value: float, where: str) -> bool:
    """Log (once per vessel, coefficient and side) that ``value`` leaves ``rng``.

    Returns
    -------
    bool
        True if ``value`` is outside the range (whether or not it was logged now).
    """
    if rng.low <= value <= rng.high:
        return False
    side = "above" if value > rng.high else "below"
    key = (vessel, rng.coefficient, side)
    if key not in _REPORTED:
        _REPORTED.add(key)
        log.warning(
            "%s: %s is used outside its validity range: %s = %.4g at %s, valid %.4g..%.4g (%s)",
            vessel, rng.coefficient, rng.variable, value, where, rng.low, rng.high, rng.source,
        )  # fmt: skip
    return True


def reset_reports() -> None:
    """Forget what was reported (for tests)."""
    _REPORTED.clear()


__all__ = ["ValidityRange", "report", "reset_reports"]
