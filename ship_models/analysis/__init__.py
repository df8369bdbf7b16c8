"""Ship-level analysis of Umeda (1999): fixed points, eigen-structure, manifolds, critical Fn.

Reusable capabilities built on the generic engine (:mod:`continuation`) and the ship
model (:mod:`ship_models`); the figure scripts in ``studies/`` and the command line
(``broachkit fixed-points``, ``manifold``, ``critical``) call these.

- :mod:`.fixed_points` -- surge roots at chi_c = 0, traced in chi_c and Fn; all fixed
  points at one (Fn, chi_c) with eigen-data (Figs. 2-5)
- :mod:`.eigen` -- eigenvalues, saddle index, unstable eigenvector in the paper's
  nondimensional units (Figs. 6-9)
- :mod:`.events` -- the capsize event (roll beyond the vanishing angle of GZ)
- :mod:`.manifold` -- unstable manifolds of a saddle and their fates (Figs. 10-15)
- :mod:`.global_picture` -- fixed points, attractors and manifolds as a graph
- :mod:`.critical` -- critical Fn of the heteroclinic bifurcation by bisection
- :mod:`.connection` -- the same as a connecting orbit by collocation, and its
  continuation in chi_c (the critical curve, Fig. 23)
- :mod:`.sudden_change` -- the paper's "sudden change" experiments: start on the periodic
  orbit of one control setting, switch the controls, classify the transient (Figs. 16-22)

The simulation-based names are imported lazily (on first use).
"""

from __future__ import annotations

import importlib
from typing import Any

from .eigen import EigenStructure, eigen_structure, paper_scales
from .events import capsize_angle, capsize_event, vanishing_angle
from .fixed_points import (
    FixedPoint,
    find_fixed_point,
    fixed_points,
    surge_roots,
    trace_in_chi_c,
    trace_in_fn,
)

_LAZY = {
    "ShipFate": ".manifold",
    "ShipManifold": ".manifold",
    "classify_ship_fate": ".manifold",
    "unstable_manifold": ".manifold",
    "CriticalResult": ".critical",
    "critical_fn": ".critical",
    "first_passage": ".critical",
    "CRITERIA": ".critical",
    "RETURNED": ".critical",
    "PictureDiff": ".global_picture",
    "compare_pictures": ".global_picture",
    "build_global_picture": ".global_picture",
    "CriticalConnection": ".connection",
    "CriticalCurve": ".connection",
    "critical_curve": ".connection",
    "critical_fn_bisection": ".connection",
    "critical_fn_bvp": ".connection",
    "periodic_orbit": ".sudden_change",
    "follow_orbit": ".sudden_change",
    "sudden_change": ".sudden_change",
    "sudden_change_boundary": ".sudden_change",
    "sudden_change_map": ".sudden_change",
    "PeriodicOrbit": ".sudden_change",
    "SuddenChange": ".sudden_change",
    "SuddenChangeBoundary": ".sudden_change",
    "SuddenChangeMap": ".sudden_change",
}


def __getattr__(name: str) -> Any:
    mod = _LAZY.get(name)
    if mod is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(mod, __name__), name)


__all__ = [
    "periodic_orbit",
    "follow_orbit",
    "sudden_change",
    "sudden_change_boundary",
    "sudden_change_map",
    "PeriodicOrbit",
    "SuddenChange",
    "SuddenChangeBoundary",
    "SuddenChangeMap",
    "CRITERIA",
    "RETURNED",
    "first_passage",
    "CriticalConnection",
    "CriticalCurve",
    "critical_curve",
    "critical_fn_bisection",
    "critical_fn_bvp",
    "CriticalResult",
    "EigenStructure",
    "FixedPoint",
    "PictureDiff",
    "ShipFate",
    "ShipManifold",
    "capsize_angle",
    "capsize_event",
    "classify_ship_fate",
    "compare_pictures",
    "critical_fn",
    "eigen_structure",
    "find_fixed_point",
    "fixed_points",
    "build_global_picture",
    "paper_scales",
    "surge_roots",
    "trace_in_chi_c",
    "trace_in_fn",
    "unstable_manifold",
    "vanishing_angle",
]
