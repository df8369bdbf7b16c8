r"""Ship sweeps on the generic sweep layer (:mod:`continuation.sweep`): Figs. 16/22/23, surface.

Every study here is many independent solves; each solve is one task ``run_task(key)``
with a JSON key that names everything it depends on (vessel, wave, controls,
tolerances), so tasks run on local processes, a Dask ``LocalCluster`` or a remote
scheduler, are checkpointed as they finish, and an interrupted sweep resumes
(:func:`continuation.sweep.run_sweep`). The context of every task is the content of
the vessel file (:func:`vessel_context`): editing it invalidates the checkpoints.

Tasks (``key["task"]``):

- ``"boundary"`` -- critical nominal Froude number of one sudden-change experiment by
  bisection of its outcome (:func:`~ship_models.analysis.sudden_change.sudden_change_boundary`)
  for one initial position :math:`(\xi_G/\lambda)_0` and new course ``chi_c``
  (Umeda 1999, Figs. 16, 22 boundaries; Fig. 23 squares).
- ``"outcome"`` -- the outcome of one sudden change at one ``(Fn, xi_0)`` (the maps
  of Figs. 16, 22; :func:`~ship_models.analysis.sudden_change.sudden_change`).
- ``"line"`` -- the critical Fn of the heteroclinic connection over wave steepness
  :math:`H/\lambda` at one wavelength :math:`\lambda/L` and course (:func:`critical_line`):
  one row of the critical surface :math:`Fn^*(H/\lambda, \lambda/L)`.
- ``"surge-line"`` -- the same for the uncoupled surge model (``chi_c = 0``,
  :func:`surge_threshold`): the surge-only threshold beside the surface.

Sweeps (the calling side): :func:`boundary_sweep`, :func:`courses_sweep`,
:func:`surface_sweep`. The IMO Level 2 exact surf-riding grid runs on the same engine
with its own task (:func:`ship_models.assessment.exact_sweep.exact_threshold_sweep`).

Notes
-----
The connection is the capture threshold only where the fate of the upslope branch
switches at it. For the purse seiner at ``chi_c = 10 deg``, ``lambda/L = 1.5`` this was
checked by bisection by simulation at ``H/lambda = 0.08, 0.1`` (agreement to 1e-7),
but at ``H/lambda = 0.06`` the connection (Fn = 0.358836, converged under mesh halving
and longer T; the simulated branch passes within 1e-3 of the shifted saddle there)
does not change the fate -- periodic on both sides -- and the fate switches at
Fn = 0.36030 instead, with the branch nowhere near the shifted saddle: another global
bifurcation takes over in gentler waves. :func:`surface_sweep` therefore re-checks a
sample of points by bisection (``check``) and reports ``agrees`` for each.

Ship functions called (for re-pointing after the reorganisation of
``ship_models.analysis``): ``sudden_change.periodic_orbit``,
``sudden_change.follow_orbit``, ``sudden_change.sudden_change``,
``sudden_change.sudden_change_boundary``, ``fixed_points.fixed_points``,
``critical_bvp.critical_fn_bvp``, ``critical_curve.critical_curve``,
``critical_bisection.upslope_bisection``,
``SurgeModel.fixed_points`` / ``surge_force``, ``registry.get_model`` /
``get_vessel_data``; engine: ``continuation.bvp.continue_connection``,
``continuation.newton.newton``, ``continuation.dynamics.simulate``.
"""

from __future__ import annotations

from .boundary import BoundarySweep, boundary_sweep
from .context import BRACKET_OFFSETS, MAP_OFFSETS, vessel_context
from .courses import CoursesSweep, courses_sweep
from .critical_line import CriticalLine, critical_line
from .surface import SurfaceSweep, surface_sweep
from .surge import SurgeThreshold, surf_riding_range, surge_threshold
from .tasks import run_task

__all__ = [
    "BRACKET_OFFSETS",
    "MAP_OFFSETS",
    "BoundarySweep",
    "CoursesSweep",
    "CriticalLine",
    "SurfaceSweep",
    "SurgeThreshold",
    "boundary_sweep",
    "courses_sweep",
    "critical_line",
    "run_task",
    "surf_riding_range",
    "surface_sweep",
    "surge_threshold",
    "vessel_context",
]
