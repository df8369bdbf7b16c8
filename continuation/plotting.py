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


# ------------------------------------------------------------------ legibility
#: Width (CSS px) at which a report shows a figure; a wider PNG is scaled down to it.
REPORT_FIGURE_PX = 1080
#: Smallest legible text height on screen (CSS px) of a figure shown at that width.
MIN_FONT_PX = 8.0
#: PNG text key under which :func:`legibility_metadata` stores the smallest font size.
FONT_KEY = "broachkit:min_font_pt"


def smallest_font_pt(fig: Any) -> float:
    """Smallest font size (pt) of the visible, non-empty text of a matplotlib figure."""
    from matplotlib.text import Text

    sizes = [
        float(t.get_fontsize())
        for t in fig.findobj(Text)
        if t.get_visible() and t.get_text().strip()
    ]
    return min(sizes) if sizes else float("inf")


def displayed_font_px(
    font_pt: float, width_px: float, dpi: float, shown_px: float = REPORT_FIGURE_PX
) -> float:
    r"""Height on screen (CSS px) of ``font_pt`` text in a PNG shown at most ``shown_px`` wide.

    .. math:: h = f \frac{\mathrm{dpi}}{72} \min\!\left(1, \frac{W_\mathrm{shown}}{W}\right)

    with :math:`W` the PNG's width in pixels (a wider image is scaled down to the
    column; a narrower one is shown at its size).
    """
    return font_pt * dpi / 72.0 * min(1.0, shown_px / width_px)


def legibility_metadata(fig: Any) -> dict[str, str]:
    """PNG metadata recording the figure's smallest font size (for :func:`png_font_px`)."""
    return {FONT_KEY: f"{smallest_font_pt(fig):.3g}"}


def png_font_px(path: Any, shown_px: float = REPORT_FIGURE_PX) -> float | None:
    """Smallest text height (CSS px) of a PNG written with :func:`legibility_metadata`.

    ``None`` when the PNG does not record its font size or DPI.
    """
    from PIL import Image

    with Image.open(path) as im:
        dpi = im.info.get("dpi", (None,))[0]
        font = im.info.get(FONT_KEY)
        width = im.size[0]
    if dpi is None or font is None:
        return None
    return displayed_font_px(float(font), width, float(dpi), shown_px)
