r"""The lowest parameter value at which a fate occurs: a scan, then bisection.

:func:`~continuation.dynamics.fate_bisection.bisect_fate` locates *a* switch of a fate
inside a bracket whose ends differ. When the fate is not monotone in the parameter
(windows of one fate inside the other, as near a crisis or a period-doubling cascade),
the switch it finds need not be the first one, and the connection it was designed for
need not be where the fate first occurs at all. :func:`lowest_fate` answers the other
question: the smallest :math:`p` in ``[lo, hi]`` at which ``fate(p)`` is the target
(e.g. escape, capsize),

.. math::  p_c = \min\{p \in [lo, hi] : \mathrm{fate}(p) \in T\},

to a stated resolution:

1. a grid of spacing ``coarse_step``; an interval whose two ends are not both
   *plain* (``is_plain``, e.g. the ordinary periodic attractor, decided quickly and far
   from any boundary) is scanned again at ``step``; the first target point ends the
   scan;
2. bisection between the last non-target point below it and it, to ``tol``.

Claims: a target window narrower than ``step`` (than ``coarse_step`` between two
plain points) below ``p_c`` is not resolved; an undecided fate (``None``) below ``p_c``
makes the result ``UNDECIDED`` (a lower ``p_c`` cannot be excluded). The cost is about
``(hi - lo) / coarse_step`` plus the refined intervals plus ``log2(step / tol)`` fate
evaluations.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field

from ..status import Status


@dataclass(frozen=True)
class LowestFate:
    """Result of :func:`lowest_fate`.

    Attributes
    ----------
    p : float
        Midpoint of the final bracket (NaN if no target point was found).
    error : float
        Half the bracket width (NaN if none).
    bracket : (float, float) or None
        ``(last non-target, first target)``.
    samples : dict
        ``p -> label`` of every evaluation (``None`` for undecided).
    undecided_below : tuple of float
        Undecided points below ``p``.
    status : Status
        ``SUCCESS``; ``NO_BRACKET`` (no target in ``[lo, hi]``, or already at ``lo``);
        ``UNDECIDED`` (undecided points below ``p``, or inside the final bracket).
    message : str
    """

    p: float
    error: float
    bracket: tuple[float, float] | None
    samples: dict[float, Hashable | None] = field(repr=False)
    undecided_below: tuple[float, ...]
    status: Status
    message: str


def _grid(lo: float, hi: float, h: float) -> list[float]:
    n = max(1, int(math.ceil((hi - lo) / h - 1e-9)))
    return [lo + (hi - lo) * k / n for k in range(n + 1)]


def lowest_fate(
    fate: Callable[[float], Hashable | None],
    lo: float,
    hi: float,
    *,
    is_target: Callable[[Hashable], bool],
    is_plain: Callable[[Hashable], bool] = lambda label: False,
    step: float,
    coarse_step: float | None = None,
    tol: float,
) -> LowestFate:
    """Smallest ``p`` in ``[lo, hi]`` with a target fate (module notes).

    Parameters
    ----------
    fate : callable
        ``fate(p)`` -> a hashable label, or ``None`` when undecided. Called once per
        point (results are memoised here).
    lo, hi : float
        The range searched, ``lo < hi``.
    is_target : callable
        ``label -> bool``: the fate sought (e.g. ``label == "capsize"``).
    is_plain : callable, optional
        ``label -> bool``: a fate far from any boundary; intervals with plain fates at
        both ends are not refined (default: none is, so the whole range is scanned at
        ``step``).
    step : float
        Resolution of the scan.
    coarse_step : float, optional
        Spacing of the first grid (default ``step``).
    tol : float
        Final bracket width, ``0 < tol < step``.

    Returns
    -------
    LowestFate

    Raises
    ------
    ValueError
        For ``lo >= hi`` or step sizes that are not ``0 < tol < step <= coarse_step``.
    """
    coarse = step if coarse_step is None else coarse_step
    for name, v in (("lo", lo), ("hi", hi), ("step", step), ("coarse_step", coarse),
                    ("tol", tol)):  # fmt: skip
        if not (isinstance(v, (int, float)) and math.isfinite(v)):
            raise ValueError(f"`{name}` must be a finite number, got {v!r}")
    if not lo < hi:
        raise ValueError(f"`lo` must be below `hi`, got {lo!r}, {hi!r}")
    if not 0 < tol < step <= coarse:
        raise ValueError(f"need 0 < tol < step <= coarse_step, got {tol}, {step}, {coarse}")
    seen: dict[float, Hashable | None] = {}

    def at(p: float) -> Hashable | None:
        key = round(float(p), 14)
        if key not in seen:
            seen[key] = fate(key)
        return seen[key]

    def target(label: Hashable | None) -> bool:
        return label is not None and bool(is_target(label))

    def plain(label: Hashable | None) -> bool:
        return label is not None and bool(is_plain(label))

    first: float | None = None
    prev: float | None = None
    for g in _grid(lo, hi, coarse):
        cur = at(g)
        if prev is not None and not (plain(at(prev)) and plain(cur)):
            for f in _grid(prev, g, step)[1:-1]:
                if target(at(f)):
                    first = f
                    break
        if first is None and target(cur):
            first = g
        if first is not None:
            break
        prev = g
    if first is None:
        return LowestFate(math.nan, math.nan, None, seen, (), Status.NO_BRACKET,
                          f"no target fate in [{lo:.6g}, {hi:.6g}]")  # fmt: skip
    ok_below = [p for p, lab in sorted(seen.items()) if p < first and lab is not None
                and not target(lab)]  # fmt: skip
    if not ok_below:
        return LowestFate(math.nan, math.nan, None, seen, (), Status.NO_BRACKET,
                          f"the target fate already occurs at the start of the range, "
                          f"{first:.6g}")  # fmt: skip
    a, b = ok_below[-1], first
    stuck = False
    while b - a > tol:
        mid = 0.5 * (a + b)
        lab = at(mid)
        if lab is None:
            stuck = True
            break
        if target(lab):
            b = mid
        else:
            a = mid
    p = 0.5 * (a + b)
    undecided = tuple(q for q, lab in sorted(seen.items()) if lab is None and q < a)
    msg = f"lowest target fate at {p:.8g} +- {0.5 * (b - a):.1e}"
    status = Status.SUCCESS
    if stuck:
        status = Status.UNDECIDED
        msg += f"; bisection stopped at an undecided fate inside [{a:.8g}, {b:.8g}]"
    if undecided:
        status = Status.UNDECIDED
        msg += "; undecided below it at " + ", ".join(f"{q:.6g}" for q in undecided)
    return LowestFate(p, 0.5 * (b - a), (a, b), seen, undecided, status, msg)


__all__ = ["LowestFate", "lowest_fate"]
