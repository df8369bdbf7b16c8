r"""The end of a cycle branch at a Hopf point, where its cycles shrink onto an equilibrium.

A branch of cycles that reaches a Hopf point (e.g. one joining two Hopf points of an
equilibrium branch, as in AUTO-07p's demo ``plp``) does not stop there by itself: at
the Hopf point the cycles :math:`x(\tau) = \bar x + a\, v(\tau) + O(a^2)` pass through
zero amplitude and the collocation unknowns go on smoothly to :math:`a < 0`, the same
cycles again, half a period out of phase; the parameter,
:math:`p = p_H + c\, a^2 + O(a^3)`, turns there, which the fold test would report as a
fold of cycles (LPC) though none is there, and the branch retraces itself (Kuznetsov
2004, Sec. 10.3.2, on the Hopf start of a cycle branch). The passage shows between two
rows as deviations from the mean, :math:`D_k = x_k(\tau) - \bar x_k`, pointing in
opposite directions: their correlation is close to -1 (for consecutive cycles
aligned by the integral phase condition it is otherwise close to +1).
:func:`hopf_end` cuts the branch at the last row before the passage.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from typing import Any

import numpy as np

from ..branch import Branch, SpecialKind, SpecialPoint
from ..status import Status
from .rows import orbit_at, problem_at, truncated

log = logging.getLogger(__name__)

#: Consecutive rows whose deviations from their means correlate below this have passed
#: through zero amplitude (a Hopf point) between them.
PASSAGE_CORRELATION = -0.5

#: Samples per period for the correlation.
N_SAMPLES = 64


def _deviation(br: Branch, k: int) -> np.ndarray:
    """Deviation from its mean of the cycle of row ``k``, sampled at ``N_SAMPLES`` times."""
    o = orbit_at(br, k)
    x = o(np.arange(N_SAMPLES) * (o.T / N_SAMPLES))
    return x - x.mean(axis=0)


def _stage_deviation(br: Branch, k: int) -> tuple[Any, np.ndarray, np.ndarray]:
    """The deviation of row ``k`` at its collocation points, with its problem.

    Returns ``(problem, D, w)``, ``w`` the Gauss weights ``h_j b_l`` of the time average
    (no interpolation: rows on one mesh are compared point by point).
    """
    prob = problem_at(br, k)
    X, _ = prob.layout.split(np.asarray(br.x[k][: prob.n_unknowns], dtype=float))
    mesh = prob.mesh
    w = (mesh.h[:, None] * mesh.b[None, :]).reshape(-1)
    Xs = X[mesh.stage_mask]
    return prob, Xs - (w @ Xs) / w.sum(), w


def _correlation(
    br: Branch, k: int, here: tuple[Any, np.ndarray, np.ndarray]
) -> tuple[float, tuple[Any, np.ndarray, np.ndarray]]:
    """Correlation of the deviations of rows ``k`` and ``k + 1`` (NaN at zero amplitude).

    Also returns row ``k + 1``'s stage deviation. On one mesh the time average is the
    Gauss quadrature at the collocation points; across meshes both cycles are sampled.
    """
    nxt = _stage_deviation(br, k + 1)
    if nxt[0] is here[0]:
        (_, a, w), (_, b, _) = here, nxt
        num = float(np.sum(w[:, None] * a * b))
        na, nb = float(np.sum(w[:, None] * a * a)), float(np.sum(w[:, None] * b * b))
    else:
        a, b = _deviation(br, k), _deviation(br, k + 1)
        num, na, nb = float(np.sum(a * b)), float(np.sum(a * a)), float(np.sum(b * b))
    if na <= 0.0 or nb <= 0.0:
        return math.nan, nxt
    return num / math.sqrt(na * nb), nxt


def hopf_end(br: Branch, free: str, start: int = 0) -> Branch | None:
    """The branch cut before its cycles pass through zero amplitude, or None.

    Rows from ``start`` on are examined (earlier ones were). Where rows ``k`` and
    ``k + 1`` have deviations from their means with correlation below
    :data:`PASSAGE_CORRELATION`, the branch ends at row ``k`` with ``Status.EVENT``, a
    Hopf point ``"H"`` bracketed (not located) by the two rows, and no special point
    beyond row ``k`` (the fold the passage makes in the parameter is not an LPC). The
    Hopf point's parameter and period are estimates: the quadratics in the signed
    amplitude (``+|D|`` before the passage, ``-|D|`` after) through rows ``k - 1``,
    ``k`` and ``k + 1`` at zero amplitude.
    """
    n = len(br)
    if n < 2:
        return None
    k0 = max(start, 0)
    here = _stage_deviation(br, k0)
    for k in range(k0, n - 1):
        corr, here = _correlation(br, k, here)
        if corr < PASSAGE_CORRELATION:
            rows = [k, k + 1] if k == 0 else [k - 1, k, k + 1]
            amp = [float(np.linalg.norm(_deviation(br, j))) for j in rows]
            amp[-1] = -amp[-1]
            return _cut(br, free, k, rows, np.array(amp))
    return None


def _at_zero(a: np.ndarray, y: np.ndarray) -> float:
    """Value at ``a = 0`` of the polynomial of degree ``len(a) - 1`` through ``(a, y)``."""
    return float(np.polyval(np.polyfit(a, y, len(a) - 1), 0.0))


def _cut(br: Branch, free: str, k: int, rows: list[int], a: np.ndarray) -> Branch:
    p0, p1 = float(br.p[k]), float(br.p[k + 1])
    p_h = _at_zero(a, np.asarray(br.p[rows], dtype=float))
    T = _at_zero(a, np.asarray(br.records["T"][rows], dtype=float))
    msg = (
        f"{Status.EVENT.value} The cycles shrink onto an equilibrium at a Hopf point between "
        f"the rows at {free}={p0:.10g} and {free}={p1:.10g} (their amplitude passes through "
        f"zero; near {free}={p_h:.8g}, period {T:.6g}): the branch ends there; the "
        "equilibria's continuation locates the Hopf point."
    )
    log.info(msg)
    out = truncated(br, k, Status.EVENT, msg)
    s0, s1 = float(br.arclength[k]), float(br.arclength[k + 1])
    w = float(a[-2] / (a[-2] - a[-1]))
    hopf = SpecialPoint(
        kind=SpecialKind.HOPF,
        index=k,
        p=p_h,
        x=np.array(br.x[k]),
        located=False,
        bracket=(p0, p1),
        label="H",
        data={"omega": 2.0 * math.pi / T},
        s=s0 + w * (s1 - s0),
    )
    return dataclasses.replace(out, special_points=(*out.special_points, hopf))


__all__ = ["PASSAGE_CORRELATION", "hopf_end"]
