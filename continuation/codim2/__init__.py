"""Two-parameter continuation of fold and Hopf curves of equilibria.

:class:`FoldProblem` (Moore-Spence) and :class:`HopfProblem` (Roose-Hlavacek with a
normalisation that stays regular through Bogdanov-Takens points) are
:class:`~continuation.problem.ContinuationProblem` s with exact CasADi Jacobians;
:func:`continue_codim2` continues a located fold or Hopf point of a branch in a
second parameter and detects cusp, Bogdanov-Takens, zero-Hopf, double-Hopf and
generalised-Hopf points on the way.
"""

from .curves import RENORMALISE_BELOW, codim2_events, continue_codim2, relabel_codim2
from .fold import FoldProblem
from .hopf import HopfProblem, normalisation

__all__ = [
    "RENORMALISE_BELOW",
    "FoldProblem",
    "HopfProblem",
    "codim2_events",
    "continue_codim2",
    "normalisation",
    "relabel_codim2",
]
