"""Ship-level analysis of Umeda (1999): fixed points, eigen-structure, manifolds, critical Fn.

Reusable capabilities built on the generic engine (:mod:`continuation`) and the ship
model (:mod:`ship_models`); the figure scripts in ``studies/`` and the command line
(``broachkit fixed-points``, ``manifold``, ``critical``) call these.

- :mod:`.fixed_points` -- surge roots at chi_c = 0, traced in chi_c and Fn; all fixed
  points at one (Fn, chi_c) with eigen-data (Figs. 2-5)
- :mod:`.eigen` -- eigenvalues, saddle index, unstable eigenvector in the paper's
  nondimensional units (Figs. 6-9)
- :mod:`.events` -- the capsize event (roll beyond the vanishing angle of GZ)
- :mod:`.params` -- the one coercion of parameters and courses (``ship_params``)
- :mod:`.outcomes` -- the one enumeration of outcomes (``ShipOutcome``)
- :mod:`.manifold` -- unstable manifolds of a saddle and their fates (Figs. 10-15), on
  the engine's :func:`continuation.dynamics.manifolds.unstable_manifold`
- :mod:`.global_picture` -- fixed points, attractors and manifolds as a graph
- :mod:`.crest_saddle` -- the crest saddle followed from chi_c = 0 (a ``FixedPoint``)
- :mod:`.upslope` -- one run of the upslope branch, its fate, a connection guess
- :mod:`.critical` -- ``critical_fn(model, params, method="bvp"|"bisection")``, one
  result type ``CriticalFn`` (:mod:`.critical_result`)
- :mod:`.critical_bvp` -- the critical Fn as a connecting orbit by collocation
- :mod:`.critical_bisection` -- the critical Fn by bisection on simulated fates
- :mod:`.critical_curve` -- its continuation in chi_c (the critical curve, Fig. 23)
- :mod:`.sudden_change` -- the paper's "sudden change" experiments: start on the periodic
  orbit of one control setting (the engine's return-map solver,
  :mod:`continuation.dynamics.shooting`), switch the controls, classify the transient
  (Figs. 16-22)

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
from .outcomes import ShipOutcome
from .params import ship_params

_LAZY = {
    "ShipFate": ".manifold",
    "ShipManifold": ".manifold",
    "classify_ship_fate": ".manifold",
    "unstable_manifold": ".manifold",
    "BVPSettings": ".critical_bvp",
    "CriticalFn": ".critical_result",
    "critical_fn": ".critical",
    "critical_fn_bvp": ".critical_bvp",
    "first_passage_bisection": ".critical_bisection",
    "upslope_bisection": ".critical_bisection",
    "first_passage": ".critical_bisection",
    "CRITERIA": ".critical_bisection",
    "RETURNED": ".critical_bisection",
    "PictureDiff": ".global_picture",
    "compare_pictures": ".global_picture",
    "build_global_picture": ".global_picture",
    "CriticalCurve": ".critical_curve",
    "critical_curve": ".critical_curve",
    "crest_saddle": ".crest_saddle",
    "UpslopeRun": ".upslope",
    "upslope_branch": ".upslope",
    "periodic_orbit": ".sudden_change",
    "follow_orbit": ".sudden_change",
    "sudden_change": ".sudden_change",
    "sudden_change_boundary": ".sudden_change",
    "sudden_change_map": ".sudden_change",
    "ShootingOrbit": ".sudden_change",
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
    "BVPSettings",
    "CRITERIA",
    "CriticalCurve",
    "CriticalFn",
    "EigenStructure",
    "FixedPoint",
    "ShootingOrbit",
    "PictureDiff",
    "RETURNED",
    "ShipFate",
    "ShipManifold",
    "ShipOutcome",
    "SuddenChange",
    "SuddenChangeBoundary",
    "SuddenChangeMap",
    "UpslopeRun",
    "build_global_picture",
    "capsize_angle",
    "capsize_event",
    "classify_ship_fate",
    "compare_pictures",
    "crest_saddle",
    "critical_curve",
    "critical_fn",
    "critical_fn_bvp",
    "eigen_structure",
    "find_fixed_point",
    "first_passage",
    "first_passage_bisection",
    "fixed_points",
    "follow_orbit",
    "paper_scales",
    "periodic_orbit",
    "ship_params",
    "sudden_change",
    "sudden_change_boundary",
    "sudden_change_map",
    "surge_roots",
    "trace_in_chi_c",
    "trace_in_fn",
    "unstable_manifold",
    "upslope_bisection",
    "upslope_branch",
    "vanishing_angle",
]
