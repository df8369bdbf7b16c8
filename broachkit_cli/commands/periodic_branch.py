"""``broachkit periodic-branch``: the overtaken-by-waves cycle continued over a range.

``--fn A:B`` with one ``--chi-c``: the cycle at ``Fn = A`` continued in ``Fn`` towards
``B``; ``--chi-c A:B`` with one ``--fn``: the cycle at ``chi_c = A`` continued in the
course over ``[A, B]`` (degrees). The branch ends where its period exceeds
``--period-max`` (``PERIOD_UNBOUNDED``: the cycle approaches the heteroclinic
connection, whose parameter is fitted from ``T = a - b ln|p* - p|``), at the end of the
range, or where the continuation fails, and says which. Everything else (Floquet
multipliers along the branch, where the cycle loses stability, the largest roll
against the angle of vanishing stability, ``--compare`` with the connection solver,
files) is as in ``broachkit cycles``, which this command drives with a range instead of
``--vary``.
"""

from __future__ import annotations

import argparse
from typing import Any

from ..cycle_options import add_branch_options
from ..options import (
    add_json,
    add_out,
    add_vessel,
    add_wave,
    check_chi_c_deg,
    finite,
)
from . import cycles

NAME = "periodic-branch"
HELP = "the overtaken-by-waves cycle continued over an Fn or chi_c range to where it ends"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit periodic-branch``."""
    add_vessel(parser)
    parser.add_argument(
        "--fn", dest="Fn", default="0.1:0.4",
        help="Fn range START:END (continued in Fn), or one Fn with a --chi-c range "
        "(default 0.1:0.4)",
    )  # fmt: skip
    parser.add_argument(
        "--chi-c", dest="chi_c", default="10",
        help="course in degrees, or a range START:END (continued in chi_c) with one --fn "
        "(default 10)",
    )  # fmt: skip
    add_wave(parser)
    add_json(parser)
    add_branch_options(
        parser, "with an Fn range: also solve the heteroclinic connection for its critical Fn"
    )
    add_out(parser, None, "cycles_fn or cycles_chi_c .csv/.json/.png")


def _range(name: str, text: Any) -> tuple[float, float | None]:
    """``"A:B"`` -> ``(A, B)``; ``"A"`` -> ``(A, None)``; ValueError naming ``name``."""
    parts = str(text).split(":")
    if len(parts) not in (1, 2) or not all(p.strip() for p in parts):
        raise ValueError(f"{name} must be a number or a range START:END, got {text!r}")
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        raise ValueError(f"{name} must be a number or a range START:END, got {text!r}") from None
    return vals[0], (vals[1] if len(vals) == 2 else None)


def cycles_args(args: argparse.Namespace) -> argparse.Namespace:
    """The ``broachkit cycles`` options of this command's ranges (checked)."""
    fn0, fn1 = _range("--fn", args.Fn)
    chi0, chi1 = _range("--chi-c", args.chi_c)
    if (fn1 is None) == (chi1 is None):
        raise ValueError(
            "give exactly one range: --fn START:END with one --chi-c, or --chi-c START:END "
            f"with one --fn (got --fn {args.Fn!r}, --chi-c {args.chi_c!r})"
        )
    out = argparse.Namespace(**vars(args))
    out.Fn = finite("--fn", fn0, low=0.0)
    out.chi_c = check_chi_c_deg("--chi-c", chi0)
    if fn1 is not None:
        finite("--fn", fn1, low=0.0)
        if not fn1 > fn0:
            raise ValueError(f"--fn range must increase (START < END), got {args.Fn!r}")
        out.vary, out.Fn_max = "fn", fn1
        out.chi_c_min = out.chi_c_max = out.chi_c
    else:
        check_chi_c_deg("--chi-c", chi1)
        if chi1 == chi0:
            raise ValueError(f"--chi-c range must not be empty, got {args.chi_c!r}")
        out.vary, out.Fn_max = "chi-c", None
        out.chi_c_min, out.chi_c_max = min(chi0, chi1), max(chi0, chi1)
    cycles.check_args(out)
    return out


def run(args: argparse.Namespace) -> int:
    """Continue the cycle over the range; exit codes as ``broachkit cycles``."""
    return cycles.run(cycles_args(args))
