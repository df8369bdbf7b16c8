r"""The published operating point of Umeda (1999), used as the vessel layer's defaults.

Umeda (1999, "Nonlinear dynamics of ship capsizing due to broaching in following and
quartering seas", J. Mar. Sci. Technol. 4:16-26) studies the purse seiner at the
nominal Froude number ``Fn = 0.3248`` and autopilot course ``chi_c = 10 deg``
(Figs. 2-15): at ``Fn = 0.3248`` the upslope branch of the crest saddle's unstable
manifold capsizes, at ``0.3247`` it tends to the periodic attractor (Figs. 10-15), so
the heteroclinic connection lies between them. The wave (``H/lambda``,
``lambda/L``) and the autopilot gains are vessel data (``ship_models/data/*.toml``),
not repeated here.

Every default ``Fn`` in the ship layer (the models' ``default_params``, the guess of
the critical-Fn solve, the command line) is :data:`PAPER_FN`.
"""

from __future__ import annotations

import math

#: Nominal Froude number of the paper's Figs. 2-15 (the upslope branch capsizes there).
PAPER_FN = 0.3248
#: The paper's bracket of the critical Fn at ``chi_c = 10 deg`` (periodic, capsize).
PAPER_FN_BRACKET = (0.3247, 0.3248)
#: Autopilot course of the paper's Figs. 6-15 (degrees).
PAPER_CHI_C_DEG = 10.0
#: The same course in radians (the library's unit).
PAPER_CHI_C = math.radians(PAPER_CHI_C_DEG)

__all__ = ["PAPER_CHI_C", "PAPER_CHI_C_DEG", "PAPER_FN", "PAPER_FN_BRACKET"]
