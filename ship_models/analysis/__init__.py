"""Ship-level analysis of Umeda (1999): fixed points, eigen-structure, manifolds, critical Fn.

Reusable capabilities built on the generic engine (:mod:`continuation`) and the ship
model (:mod:`ship_models`); the figure scripts in ``studies/`` and the command line
(``broachkit fixed-points``, ``manifold``, ``critical``) call these.
"""

from __future__ import annotations

from .eigen import EigenStructure, eigen_structure, paper_scales
from .events import capsize_event, vanishing_angle
from .fixed_points import (
    FixedPoint,
    find_fixed_point,
    fixed_points,
    surge_roots,
    trace_in_chi_c,
    trace_in_fn,
)

__all__ = [
    "EigenStructure",
    "FixedPoint",
    "capsize_event",
    "eigen_structure",
    "find_fixed_point",
    "fixed_points",
    "paper_scales",
    "surge_roots",
    "trace_in_chi_c",
    "trace_in_fn",
    "vanishing_angle",
]
