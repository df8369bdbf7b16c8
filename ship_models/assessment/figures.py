"""Figures of the surf-riding assessment (matplotlib, Agg backend).

* :func:`sea_state_figure`: ``C(Hs, Tz)`` as heat maps, Melnikov's threshold beside
  the exact one.
* :func:`threshold_figure`: the threshold surfaces ``Fn_cr(lambda/L, H/lambda)`` with
  the service ``Fn`` contour (the surf-riding cases lie where ``Fn_cr < Fn``), and
  their difference.

Each returns a :class:`matplotlib.figure.Figure`; the caller saves it (atomically).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .assess import Assessment


def _figure(ncols: int, width: float = 5.2, height: float = 4.3) -> tuple[Any, Any]:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width * ncols, height), layout="constrained")
    axes = fig.subplots(1, ncols, squeeze=False)[0]
    return fig, axes


def sea_state_figure(a: Assessment) -> Any:
    """Heat maps of ``C(Hs, Tz)`` (log colour scale over six decades, white below)."""
    import matplotlib
    from matplotlib.colors import LogNorm

    panels = [("Melnikov threshold (the criterion)", a.level2_melnikov)]
    if a.level2_exact is not None:
        panels.append(("exact threshold (connecting orbit)", a.level2_exact))
    fig, axes = _figure(len(panels))
    vals = np.concatenate([r.C_sea_state[r.C_sea_state > 0].ravel() for _, r in panels] or [[]])
    vmax = float(vals.max()) if vals.size else 1.0
    vmin = max(vmax * 1e-6, float(vals.min()) if vals.size else 1e-12)
    im = None
    for ax, (title, r) in zip(axes, panels, strict=True):
        C = np.ma.masked_less_equal(r.C_sea_state, 0.0)
        cmap = matplotlib.colormaps["viridis"].with_extremes(under="white", bad="white")
        im = ax.pcolormesh(r.Tz, r.Hs, C, norm=LogNorm(vmin, vmax), cmap=cmap, shading="nearest")
        head = title if r.C is None else f"{title}\nC = {r.C:.3g} (R_SR = {a.standard.R_SR:g})"
        ax.set_title(head, fontsize=10)
        ax.set_xlabel("Tz (s)")
        ax.set_ylabel("Hs (m)")
    if im is not None:
        fig.colorbar(
            im, ax=list(axes), label="C(Hs, Tz): probability of surf-riding waves (white: below)"
        )
    fig.suptitle(f"{a.vessel}, Fn = {a.Fn:g}: C per sea state", fontsize=11)
    return fig


def threshold_figure(a: Assessment) -> Any:
    """Threshold surfaces with the service-Fn contour; the difference if exact is given."""
    m = a.melnikov
    panels: list[tuple[str, np.ndarray]] = [("Melnikov Fn_cr", m.Fn_cr)]
    if a.exact is not None:
        panels.append(("exact Fn_cr", a.exact.Fn_cr))
    fig, axes = _figure(len(panels) + (1 if a.exact is not None else 0))
    X, Y = m.steepness, m.lambda_over_L
    finite = np.concatenate([p[np.isfinite(p)].ravel() for _, p in panels])
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    for ax, (title, Z) in zip(axes, panels, strict=False):
        im = ax.pcolormesh(X, Y, Z, vmin=lo, vmax=hi, cmap="magma", shading="nearest")
        if np.nanmin(Z) < a.Fn < np.nanmax(Z):
            cs = ax.contour(X, Y, Z, levels=[a.Fn], colors="cyan", linewidths=1.5)
            ax.clabel(cs, fmt={a.Fn: f"Fn = {a.Fn:g}"}, fontsize=8)
        if (~m.in_range).any():
            ax.contour(X, Y, m.in_range.astype(float), levels=[0.5], colors="white",
                       linestyles="dashed", linewidths=1.0)  # fmt: skip
        ax.set_title(f"{title} (surf-riding where Fn_cr < {a.Fn:g})", fontsize=10)
        ax.set_xlabel("H / lambda")
        ax.set_ylabel("lambda / L")
        fig.colorbar(im, ax=ax, label="critical Fn")
    if a.exact is not None:
        ax = axes[-1]
        d = m.Fn_cr - a.exact.Fn_cr
        v = float(np.nanmax(np.abs(d))) if np.isfinite(d).any() else 1.0
        im = ax.pcolormesh(X, Y, d, vmin=-v, vmax=v, cmap="RdBu_r", shading="nearest")
        ax.set_title("Melnikov - exact", fontsize=10)
        ax.set_xlabel("H / lambda")
        ax.set_ylabel("lambda / L")
        fig.colorbar(im, ax=ax, label="difference in critical Fn")
    note = " (dashed: resistance fit left)" if (~m.in_range).any() else ""
    fig.suptitle(
        f"{a.vessel}: surf-riding threshold over the Level 2 wave cases{note}", fontsize=11
    )
    return fig


__all__ = ["sea_state_figure", "threshold_figure"]
