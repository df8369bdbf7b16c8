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
    # panels one above the other, 8 in wide: legible at a report's column width
    # (9-pt labels stay >= 8 px high when the PNG is shown 1080 px wide)
    height = 0.3 * len(rows) + 1.4
    fig, axes = plt.subplots(ncol, 1, figsize=(8.0, height * ncol), squeeze=False)
    ax = axes[0, 0]
    ax.barh(range(len(rows)), [e.elasticity for e in rows],
            color=[colours.get(e.status, "k") for e in rows])  # fmt: skip
    ax.set_yticks(range(len(rows)), [e.key for e in rows], fontsize=9)
    ax.axvline(0.0, color="k", lw=0.6)
    ax.set_xlabel(r"elasticity $(\theta/Fn^*)\,dFn^*/d\theta$")
    ax.set_title(f"critical Fn = {sens.Fn:.5f} at chi_c = {math.degrees(sens.chi_c):g} deg",
                 fontsize=9)  # fmt: skip
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in colours.values()]
    ax.legend(handles, list(colours), fontsize=9, loc="lower right")
    if band is not None:
        ax2 = axes[1, 0]
        cont = list(band.contributions[:top])[::-1]
        ax2.barh(range(len(cont)), [v for _, v in cont], color="#d62728")
        ax2.set_yticks(range(len(cont)), [k for k, _ in cont], fontsize=9)
        ax2.set_xlabel(r"$|dFn^*/d\theta|\,\sigma_\theta$")
        lo, hi = band.band
        ax2.set_title(f"sigma(Fn*) = {band.sigma_linear:.4f}; band [{lo:.4f}, {hi:.4f}]",
                      fontsize=9)  # fmt: skip
    fig.tight_layout()
    path = Path(path)
    from continuation.atomic import atomic_path
    from continuation.plotting import legibility_metadata

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=130, metadata=legibility_metadata(fig))
    plt.close(fig)
    return path
