r"""Starting cycles: from a simulated trajectory, and the Hopf start with its side.

:func:`orbit_from_trajectory` cuts one period out of the end of a trajectory that has
settled on a cycle: the last sample :math:`x_e` defines the hyperplane
:math:`\langle f(x_e), x - x_e \rangle = 0`; the most recent earlier crossing of it in
the direction of the flow (with the periodic states shifted by the winding) that comes
back within ``tol`` of :math:`x_e` ends one period.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ..branch import Branch, SpecialPoint
from ..bvp.collocation import CollocationMesh
from ..settings import ContinuationSettings
from ..system import as_params
from .continuation import continue_periodic
from .hopf import _hopf_point, periodic_orbit_from_hopf
from .orbit import PeriodicOrbit, orbit_from_array, winding_vector
from .solve import adapt_mesh, solve_orbit


def orbit_from_trajectory(
    system: Any,
    params: Any,
    trajectory: Any,
    *,
    mesh: CollocationMesh | None = None,
    winding: Any = None,
    tol: float = 1e-2,
    correct: bool = True,
    adapt: bool = False,
) -> PeriodicOrbit:
    """One period cut from the end of a simulated trajectory, optionally corrected.

    Parameters
    ----------
    system : System
    params : Params, mapping or array
    trajectory : Trajectory or (t, x) pair
        Samples ``t (K,)``, ``x (K, n)`` (periodic states unwrapped), settled on the
        cycle at the end.
    mesh : CollocationMesh, optional
        Default 40 intervals of degree 4.
    winding : mapping of str to int, optional
        Rotation numbers of periodic states per period.
    tol : float
        Largest return distance, relative to the size ``1 + max |x|`` of the cycle.
    correct : bool
        Correct the cut by Newton's method on the collocation system.
    adapt : bool
        Place the nodes by equidistribution
        (:meth:`~continuation.bvp.collocation.CollocationMesh.equidistributed`) of the
        samples on a mesh four times finer before solving, then once more on the
        solution (:func:`~continuation.periodic.solve.adapt_mesh`); for cycles
        with fast and slow phases (relaxation oscillations).

    Raises
    ------
    ValueError
        If no return to the end point within ``tol`` is found.
    """
    if isinstance(trajectory, tuple):
        t, x = (np.asarray(a, dtype=float) for a in trajectory)
    else:
        t, x = np.asarray(trajectory.t, dtype=float), np.asarray(trajectory.x, dtype=float)
    if x.ndim != 2 or x.shape[0] != t.size or x.shape[1] != system.n_states:
        raise ValueError(f"`trajectory`: x must have shape ({t.size}, {system.n_states})")
    params = as_params(system, params)
    k = winding_vector(system, winding)
    shift = np.asarray(k, float) * np.asarray(getattr(system, "period", np.zeros(len(k))), float)
    xe = x[-1]
    fe = system.f(xe, params.values)
    g = (x + shift[None, :] - xe[None, :]) @ fe
    scale = 1.0 + float(np.max(np.abs(x[-max(2, t.size // 4) :])))
    cand = np.flatnonzero((g[:-1] < 0) & (g[1:] >= 0))[::-1]
    for i in cand:
        if i >= t.size - 3:
            continue
        s = float(-g[i] / (g[i + 1] - g[i]))
        xc = x[i] + s * (x[i + 1] - x[i])
        if np.linalg.norm(xc + shift - xe) <= tol * scale:
            tc = float(t[i] + s * (t[i + 1] - t[i]))
            tt = np.concatenate([[tc], t[i + 1 :]])
            xx = np.vstack([xc[None, :], x[i + 1 :]])
            xx[-1] = xx[0] + shift  # close exactly (the guess)
            mesh = mesh if mesh is not None else CollocationMesh(40, 4, 1.0)
            if adapt:
                fine = CollocationMesh(4 * mesh.n_intervals, mesh.degree, 1.0)
                g = orbit_from_array(system, params, tt, xx, mesh=fine, winding=winding)
                mesh = fine.equidistributed(g.X, mesh.n_intervals)
            orb = orbit_from_array(system, params, tt, xx, mesh=mesh, winding=winding)
            if not correct:
                return orb
            orb = solve_orbit(orb)
            return adapt_mesh(orb, rounds=1) if adapt else orb
    raise ValueError(
        f"`trajectory` does not return to its end point within tol={tol:g} (relative): "
        "simulate longer so that it settles on the cycle, or check `winding`"
    )


def continue_from_hopf(
    branch: Branch,
    which: str | int | SpecialPoint = 0,
    settings: ContinuationSettings | None = None,
    *,
    amplitude: float = 1e-2,
    mesh: CollocationMesh | None = None,
    **kwargs: Any,
) -> Branch:
    """The branch of cycles born at a Hopf point, continued away from it.

    :func:`~continuation.periodic.hopf.periodic_orbit_from_hopf` gives the first cycle;
    the sign of ``settings.ds`` is set so that the branch leaves the Hopf point
    (the side of the cycles from the first Lyapunov coefficient). Other keywords go
    to :func:`~continuation.periodic.continuation.continue_periodic`.
    """
    sp = _hopf_point(branch, which)
    orb = periodic_orbit_from_hopf(branch, sp, amplitude=amplitude, mesh=mesh)
    settings = settings if settings is not None else ContinuationSettings()
    side = 1.0 if orb.param(branch.free) > sp.p else -1.0
    settings = dataclasses.replace(settings, ds=side * abs(settings.ds))
    return continue_periodic(orb.system, orb, orb.params, branch.free, settings, **kwargs)


__all__ = ["continue_from_hopf", "orbit_from_trajectory"]
