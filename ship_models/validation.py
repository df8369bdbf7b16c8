r"""Physical plausibility of a vessel file, beyond the schema's ranges.

The schema (:mod:`ship_models.vessel`) checks each number against wide bounds; these
checks relate numbers to each other, so that a file every command would refuse, or a
ship that cannot steer, is refused when it is read (``broachkit vessels validate`` and
every model built from a file), with a one-line message naming the field:

- the file's size (:data:`MAX_VESSEL_FILE_BYTES`);
- the natural roll period ``loading.T_phi`` against the estimate of the IMO 2008 IS
  Code (Part A, 2.3.4, weather criterion):

  .. math:: T_\phi \approx \frac{2 C B}{\sqrt{GM}}, \qquad
            C = 0.373 + 0.023\,\frac{B}{d} - 0.043\,\frac{L}{100},

  accepted within a factor :data:`ROLL_PERIOD_FACTOR` of it (a radius of gyration
  outside the range of real hulls otherwise);
- the rudder limit ``rudder.delta_max`` at least :data:`MIN_RUDDER_LIMIT_DEG` (steering
  gear reaches 35 deg, SOLAS II-1/29; a few degrees cannot hold a course in waves);
- the rudder area ``rudder.A_R`` at least :data:`MIN_RUDDER_AREA_FRACTION` of the
  classification minimum :math:`A_R = \frac{L d}{100}\,(1 + 25 (B/L)^2)` (DNV rules
  for ships, Pt. 3 Ch. 14);
- the autopilot gain ``autopilot.K_R`` positive: with ``K_R = 0`` the rudder never
  answers a heading error, so there is no course to hold and no course-dependent
  threshold.

Both packaged vessels pass with margin (purse seiner: roll period 1.15 of the IMO
estimate, rudder area 1.7 of the minimum; KVLCC2: 1.34 and 0.93).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .vessel_schema import VesselFileError, _si_factor

#: Largest vessel file read (bytes); real files are a few kB.
MAX_VESSEL_FILE_BYTES = 1_000_000
#: The natural roll period must be within this factor of the IMO estimate.
ROLL_PERIOD_FACTOR = 2.5
#: Smallest rudder limit of a ship that can hold a course in waves (deg).
MIN_RUDDER_LIMIT_DEG = 10.0
#: Smallest rudder area, as a fraction of the classification minimum.
MIN_RUDDER_AREA_FRACTION = 0.25


def check_file_size(path: str | os.PathLike[str]) -> None:
    """Refuse a vessel file larger than :data:`MAX_VESSEL_FILE_BYTES`.

    Raises
    ------
    ValueError
        Naming the file and its size.
    """
    size = Path(path).stat().st_size
    if size > MAX_VESSEL_FILE_BYTES:
        raise ValueError(
            f"{path}: {size / 1e6:.1f} MB is too large for a vessel file "
            f"(at most {MAX_VESSEL_FILE_BYTES / 1e6:g} MB; real ones are a few kB)"
        )


def _si(coeffs: Mapping[str, Any], key: str) -> float | None:

    c = coeffs.get(key)
    if c is None:
        return None
    return float(c.value) * _si_factor(key, c.unit)


def imo_roll_period(B: float, d: float, L: float, GM: float) -> float:
    """Natural roll period estimate of the IMO 2008 IS Code, Part A 2.3.4 (s)."""
    C = 0.373 + 0.023 * (B / d) - 0.043 * (L / 100.0)
    return 2.0 * C * B / math.sqrt(GM)


def rudder_area_minimum(L: float, d: float, B: float) -> float:
    """Classification minimum rudder area ``L d / 100 (1 + 25 (B/L)^2)`` (m^2)."""
    return L * d / 100.0 * (1.0 + 25.0 * (B / L) ** 2)


def plausibility_problems(coeffs: Mapping[str, Any]) -> list[str]:
    """Every failed plausibility check of a coefficient set (dotted keys), in words.

    Checks whose inputs are absent are skipped (the estimation pipeline fills them).
    """
    problems: list[str] = []
    L, B = _si(coeffs, "particulars.L_pp"), _si(coeffs, "particulars.B")
    d = _si(coeffs, "particulars.d_m")
    if d is None:
        d_f, d_a = _si(coeffs, "particulars.d_f"), _si(coeffs, "particulars.d_a")
        d = None if d_f is None or d_a is None else 0.5 * (d_f + d_a)
    GM, T = _si(coeffs, "loading.GM"), _si(coeffs, "loading.T_phi")
    if None not in (L, B, d, GM, T) and GM > 0 and d > 0:
        est = imo_roll_period(B, d, L, GM)
        if est > 0 and not est / ROLL_PERIOD_FACTOR <= T <= est * ROLL_PERIOD_FACTOR:
            problems.append(
                f"`loading.T_phi` = {T:g} s is not a natural roll period of this hull: the "
                f"IMO estimate 2 C B / sqrt(GM) is {est:.3g} s (IS Code 2008, A 2.3.4); "
                f"accepted within a factor {ROLL_PERIOD_FACTOR:g}"
            )
    delta = _si(coeffs, "rudder.delta_max")
    if delta is not None and math.degrees(delta) < MIN_RUDDER_LIMIT_DEG:
        problems.append(
            f"`rudder.delta_max` = {math.degrees(delta):g} deg cannot hold a course in waves: "
            f"at least {MIN_RUDDER_LIMIT_DEG:g} deg (steering gear reaches 35 deg, "
            "SOLAS II-1/29)"
        )
    A_R = _si(coeffs, "rudder.A_R")
    if None not in (A_R, L, B, d):
        a_min = rudder_area_minimum(L, d, B)
        if A_R < MIN_RUDDER_AREA_FRACTION * a_min:
            problems.append(
                f"`rudder.A_R` = {A_R:g} m^2 is too small to steer: the classification "
                f"minimum L d/100 (1 + 25 (B/L)^2) is {a_min:.3g} m^2; at least "
                f"{MIN_RUDDER_AREA_FRACTION:g} of it"
            )
    K_R = _si(coeffs, "autopilot.K_R")
    if K_R is not None and not K_R > 0:
        problems.append(
            f"`autopilot.K_R` = {K_R:g}: with no rudder gain the ship holds no course, so "
            "there is no course-dependent capsizing threshold; give K_R > 0"
        )
    return problems


def check_plausible(coeffs: Mapping[str, Any]) -> None:
    """Raise on the first failed plausibility check (:func:`plausibility_problems`).

    Raises
    ------
    VesselFileError
        A ``ValueError`` naming the field.
    """
    problems = plausibility_problems(coeffs)
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise VesselFileError(problems[0] + more)


__all__ = [
    "MAX_VESSEL_FILE_BYTES",
    "MIN_RUDDER_AREA_FRACTION",
    "MIN_RUDDER_LIMIT_DEG",
    "ROLL_PERIOD_FACTOR",
    "check_file_size",
    "check_plausible",
    "imo_roll_period",
    "plausibility_problems",
    "rudder_area_minimum",
]
