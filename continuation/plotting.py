"""Bifurcation diagrams: stable parts solid, unstable parts dashed, special points marked."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .branch import Branch, SpecialKind
from .typing import FloatArray

_MARKERS = {
    SpecialKind.FOLD: "o",
    SpecialKind.HOPF: "s",
    SpecialKind.BRANCH_POINT: "D",
    SpecialKind.PERIOD_DOUBLING: "v",
    SpecialKind.NEIMARK_SACKER: "p",
    SpecialKind.USER: "^",
}

Coordinate = str | Callable[[FloatArray, float], float] | None


def _values(branch: Branch, which: Coordinate, default: str) -> tuple[FloatArray, str]:
    if which is None:
        which = default
    if callable(which):
        vals = np.array([float(which(branch.x[k], float(branch.p[k]))) for k in range(len(branch))])
        return vals, getattr(which, "__name__", "f")
    if which == "norm":
        return np.linalg.norm(branch.x, axis=1), "|x|"
    if which == branch.free or which == "p":
        return np.array(branch.p), branch.free
    if which in branch.state_names:
        return branch.state(which), which
    if which in branch.records or which in branch.param_values:
        return branch.param(which), which
    valid = (branch.free, "norm", *branch.state_names, *branch.records)
    raise ValueError(f"unknown coordinate {which!r}; valid names are {valid} or a callable")


def _point_value(branch: Branch, which: Coordinate, default: str, x: FloatArray, p: float) -> float:
    if which is None:
        which = default
    if callable(which):
        return float(which(x, p))
    if which == "norm":
        return float(np.linalg.norm(x))
    if which == branch.free or which == "p":
        return float(p)
    if which in branch.state_names:
        return float(x[branch.state_names.index(which)])
    return float("nan")


def plot_branch(
    ax: Any,
    branch: Branch,
    y: Coordinate = "norm",
    x: Coordinate = None,
    *,
    color: Any = None,
    label: str | None = None,
    special: bool = True,
    **kwargs: Any,
) -> list[Any]:
    """Draw a branch on a Matplotlib ``ax``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    branch : Branch
    y, x : str or callable, optional
        A state name, the free parameter's name, ``"norm"`` (Euclidean norm of ``x``),
        a recorded quantity, or a callable ``f(x_row, p) -> float``. ``x`` defaults to
        the free parameter, ``y`` to ``"norm"``.
    color : optional
        Line colour (default: the next colour of the axes cycle).
    label : str, optional
        Legend label (put on the first segment).
    special : bool
        Mark and label special points (``label`` text, e.g. ``"F1"``, ``"H1"``).
    **kwargs
        Passed to ``ax.plot`` for the lines.

    Returns
    -------
    list
        The Matplotlib artists created.

    Notes
    -----
    Rows with ``n_unstable == 0`` are stable (solid); others dashed (rows without
    eigenvalues, ``n_unstable = -1``, are drawn dotted). Consecutive segments share
    their end row so the curve is continuous.
    """
    xv, xlabel = _values(branch, x, branch.free)
    yv, ylabel = _values(branch, y, "norm")
    artists: list[Any] = []
    if len(branch) == 0:
        return artists
    kind = np.where(branch.n_unstable < 0, 2, np.where(branch.n_unstable == 0, 0, 1))
    styles = {0: "-", 1: "--", 2: ":"}
    start = 0
    first = True
    N = len(branch)
    for k in range(1, N + 1):
        if k == N or kind[k] != kind[start]:
            stop = min(k + 1, N)
            (line,) = ax.plot(
                xv[start:stop],
                yv[start:stop],
                linestyle=styles[int(kind[start])],
                color=color,
                label=label if first else None,
                **kwargs,
            )
            color = line.get_color()  # the first segment picks the colour of the cycle
            artists.append(line)
            first = False
            start = k
    if special:
        for sp in branch.special_points:
            px = _point_value(branch, x, branch.free, sp.x, sp.p)
            py = _point_value(branch, y, "norm", sp.x, sp.p)
            if not np.isfinite(px) or not np.isfinite(py):
                px, py = xv[sp.index], yv[sp.index]
            marker = _MARKERS.get(sp.kind, "*")
            artists.append(
                ax.plot(
                    [px], [py], marker=marker, color=color, markerfacecolor="none", linestyle="none"
                )[0]
            )
            artists.append(
                ax.annotate(
                    sp.label or sp.kind.value,
                    (px, py),
                    textcoords="offset points",
                    xytext=(4, 4),
                    fontsize="small",
                )
            )
    if not ax.get_xlabel():
        ax.set_xlabel(xlabel)
    if not ax.get_ylabel():
        ax.set_ylabel(ylabel)
    return artists


__all__ = ["plot_branch"]
