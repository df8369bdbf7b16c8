"""pycont-lite 0.6.0 (import name ``pycont``; "Lightweight matrix-free arclength
continuation with bifurcation detection and branch switching") on the benchmark problems.

pycont-lite takes only ``G(u, p)``: it is matrix-free (Newton-Krylov corrector
``scipy.optimize.newton_krylov``, tangents by L-GMRES, Jacobian-vector products by finite
differences), so the problem's exact Jacobian is not used. Settings:
``pseudoArclengthContinuation(G, x0, p0, ds_min, ds_max, ds, n_steps, sp)`` with the
shared ``ds, ds_min, ds_max, max_steps``, ``tolerance = 1e-10``,
``initial_directions = "increase_p"``, ``param_min/param_max`` = the parameter window,
``hopf_detection = True`` (tracks the 6 rightmost eigenvalues by Jacobi-Davidson),
``limit_cycle_continuation = False``, bifurcation (branch-point) detection left on; fold
detection is always on. pycont checks its detectors every 5th step and computes the
rightmost eigenvalue only once per branch, not at every point. At a fold it ends the
branch and starts a new one from the fold, so ``steps`` adds up all branches.

pycont has no norm cap. For the Bratu problems the adapter replaces pycont's
``ParamMaxDetectionModule`` (only inside this call) by a subclass that also fires when
``||u||_2`` exceeds ``norm_max``, so pycont stops where the other tools stop.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .common import PeerResult, PeerUnavailable

_KIND = {"LP": "fold", "HB": "hopf", "BP": "bp"}


def _pycont() -> Any:
    try:
        import pycont
        import pycont.continuation as pc_cont
    except Exception as exc:
        raise PeerUnavailable(f"pycont-lite not importable: {type(exc).__name__}: {exc}") from exc
    return pycont, pc_cont


def _norm_cap_module(base: type, norm_max: float) -> type:
    class ParamMaxOrNormCap(base):  # type: ignore[misc, valid-type]
        def update(self, F: Any, x_new: Any, tangent_new: Any) -> bool:
            if super().update(F, x_new, tangent_new):
                self._norm_hit = False
                return True
            if np.linalg.norm(x_new[: self.M]) > norm_max:
                self._norm_hit = True
                return True
            return False

        def localize(self) -> Any:
            if getattr(self, "_norm_hit", False):
                return (
                    np.array(self.u_new.tolist() + [self.p_new]) if hasattr(self, "u_new") else None
                )
            return super().localize()

    return ParamMaxOrNormCap


def run(problem: Any) -> PeerResult:
    """One pycont-lite continuation of ``problem`` (see module docstring)."""
    pycont, pc_cont = _pycont()
    pv = problem.param_vector()
    fi = problem.free_index
    f = problem.f

    def G(u: Any, p: float) -> Any:
        q = pv.copy()
        q[fi] = p
        return f(u, q)

    sp = {
        "tolerance": 1e-10,
        "initial_directions": "increase_p",
        "param_min": problem.p_min,
        "param_max": problem.p_max,
        "hopf_detection": True,
        "limit_cycle_continuation": False,
    }
    original = pc_cont.ParamMaxDetectionModule
    if math.isfinite(problem.norm_max):
        pc_cont.ParamMaxDetectionModule = _norm_cap_module(original, problem.norm_max)
    try:
        res = pycont.arclengthContinuation(
            G,
            np.array(problem.x0, dtype=float),
            problem.p0,
            problem.ds_min,
            problem.ds_max,
            problem.ds,
            problem.max_steps,
            solver_parameters=sp,
            verbosity=pycont.Verbosity.OFF,
        )
    finally:
        pc_cont.ParamMaxDetectionModule = original
    steps = sum(len(b.p_path) - 1 for b in res.branches)
    special = [(_KIND[e.kind], float(e.p)) for e in res.events if e.kind in _KIND]
    last = res.events[-1]
    return PeerResult(
        steps=steps,
        special=special,
        p_end=float(res.branches[-1].p_path[-1]),
        status=last.kind,
        extra={"branches": len(res.branches)},
    )


__all__ = ["run"]
