"""The options and output shared by the three cycle commands.

``broachkit periodic`` (one cycle), ``broachkit cycles`` (the cycle continued in Fn or
chi_c, ``--vary``) and ``broachkit periodic-branch`` (the same with a range instead of
``--vary``) take their branch options (``--period-max``, ``--max-steps``,
``--compare``), their checks, the verdict on the largest roll and the JSON-or-text
output from here, so that the three say the same thing the same way.
"""

from __future__ import annotations

import argparse
from typing import Any

from .options import emit, finite

#: Fn of the start cycle when ``--fn`` is not given (simulation settles there).
START_FN = 0.1
#: Defaults of the branch options.
PERIOD_MAX_S, MAX_STEPS = 60.0, 400


def add_branch_options(parser: argparse.ArgumentParser, compare_help: str) -> None:
    """``--period-max`` (s), ``--max-steps`` and ``--compare`` of a cycle branch."""
    parser.add_argument(
        "--period-max",
        dest="period_max",
        type=float,
        default=PERIOD_MAX_S,
        help=f"end the branch where the period exceeds this many seconds ({PERIOD_MAX_S:g})",
    )
    parser.add_argument(
        "--max-steps",
        dest="max_steps",
        type=int,
        default=MAX_STEPS,
        help=f"most continuation steps ({MAX_STEPS})",
    )
    parser.add_argument("--compare", action="store_true", help=compare_help)


def check_branch_options(args: argparse.Namespace) -> None:
    """ValueError naming ``--period-max`` or ``--max-steps`` when out of range."""
    finite("--period-max", args.period_max, low=0.0, high=1e4, unit="s")
    if not isinstance(args.max_steps, int) or not 1 <= args.max_steps <= 100_000:
        raise ValueError(f"--max-steps must be an integer in [1, 100000], got {args.max_steps}")


def roll_verdict(doc: dict[str, Any]) -> str:
    """The line comparing the cycle's largest roll with the angle of vanishing stability."""
    past = doc["rolls_past_vanishing_angle"]
    verdict = "ROLLS PAST it: a capsize, not a cycle" if past else "below it"
    return (
        f"  max roll {doc['max_roll_deg']:.3g} deg vs vanishing stability "
        f"{doc['vanishing_angle_deg']:.3g} deg: {verdict}"
    )


__all__ = [
    "MAX_STEPS",
    "PERIOD_MAX_S",
    "START_FN",
    "add_branch_options",
    "check_branch_options",
    "emit",
    "roll_verdict",
]
