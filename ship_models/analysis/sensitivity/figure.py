"""The tornado figure of the sorted elasticities."""

from __future__ import annotations

import math
from pathlib import Path

from .band import UncertaintyBand
from .result import Sensitivity


def tornado_figure(
    sens: Sensitivity,
    path: str | Path,
    *,
    top: int = 25,
    band: UncertaintyBand | None = None,
) -> Path:
    """Horizontal bars of the ``top`` largest elasticities (PNG), coloured by status.

    With ``band``, a second panel shows each coefficient's contribution to the
    standard uncertainty of Fn*.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    # numerical settings (fit ranges, knot spacing) are not properties of the ship:
    # their derivatives measure fit noise, not physics, and are left out of the figure
    rows = [e for e in sens.entries if e.elasticity is not None and e.kind != "numerical"]
    rows = rows[:top][::-1]
    colours = {"given": "#1f77b4", "assumed": "#ff7f0e", "estimated": "#2ca02c",
               "measured": "#9467bd", "calibrated": "#8c564b", "factor": "#7f7f7f"}  # fmt: skip
    ncol = 2 if band is not None else 1
    fig, axes = plt.subplots(1, ncol, figsize=(7.5 * ncol, 0.32 * len(rows) + 1.6), squeeze=False)
    ax = axes[0, 0]
    ax.barh(range(len(rows)), [e.elasticity for e in rows],
            color=[colours.get(e.status, "k") for e in rows])  # fmt: skip
    ax.set_yticks(range(len(rows)), [e.key for e in rows], fontsize=7)
    ax.axvline(0.0, color="k", lw=0.6)
    ax.set_xlabel(r"elasticity $(\theta/Fn^*)\,dFn^*/d\theta$")
    ax.set_title(f"critical Fn = {sens.Fn:.5f} at chi_c = {math.degrees(sens.chi_c):g} deg",
                 fontsize=9)  # fmt: skip
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in colours.values()]
    ax.legend(handles, list(colours), fontsize=7, loc="lower right")
    if band is not None:
        ax2 = axes[0, 1]
        cont = list(band.contributions[:top])[::-1]
        ax2.barh(range(len(cont)), [v for _, v in cont], color="#d62728")
        ax2.set_yticks(range(len(cont)), [k for k, _ in cont], fontsize=7)
        ax2.set_xlabel(r"$|dFn^*/d\theta|\,\sigma_\theta$")
        lo, hi = band.band
        ax2.set_title(f"sigma(Fn*) = {band.sigma_linear:.4f}; band [{lo:.4f}, {hi:.4f}]",
                      fontsize=9)  # fmt: skip
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path
