r"""Switching from a period-doubling point onto the branch of doubled cycles.

At a PD point the cycle ``x`` (period ``T``) has a multiplier ``-1`` with eigenvector
``v``; the variational solution :math:`w(t) = Y(t) v` satisfies :math:`w(t + T) = -w(t)`
and is ``2T``-periodic. In the problem of cycles of period about ``2T`` (``x`` traversed
twice, on the doubled mesh) the PD point is a branch point whose new direction is
``w`` (with no component in ``T`` or ``p`` to first order). The first point of the
doubled branch is corrected by Newton's method on the collocation system bordered
by :math:`\langle w, u - u_{PD} \rangle = \varepsilon |w|^2` (Doedel, Keller & Kernevez
1991, "Numerical analysis and control of bifurcation problems (II)", Int. J. Bif.
Chaos 1:745-772, Sec. 6; Kuznetsov 2004, Sec. 10.3.2).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from ..algorithms.corrector import correct
from ..branch import Branch, SpecialKind, SpecialPoint
from ..bvp.collocation import CollocationMesh
from ..errors import ConvergenceError
from ..settings import ContinuationSettings, NewtonSettings
from .collocation import monodromy_factors
from .continuation import continue_periodic
from .floquet import monodromy
from .orbit import PeriodicOrbit
from .problem import PeriodicOrbitProblem
from .rows import special_problem


def _pd_point(branch: Branch, which: Any) -> SpecialPoint:
    if isinstance(which, SpecialPoint):
        return which
    pds = branch.find(SpecialKind.PERIOD_DOUBLING)
    if isinstance(which, int) and 0 <= which < len(pds):
        return pds[which]
    raise ValueError(f"`which` must be a PD point or its index among {len(pds)}, got {which!r}")


def doubled_orbit(orbit: PeriodicOrbit) -> PeriodicOrbit:
    """``orbit`` traversed twice: period ``2 T`` on the doubled mesh (``2 N`` intervals)."""
    nodes = orbit.mesh.nodes
    nodes2 = np.concatenate([nodes[:-1] / 2.0, 0.5 + nodes / 2.0])
    mesh2 = CollocationMesh(2 * orbit.mesh.n_intervals, orbit.mesh.degree, 1.0, nodes2)
    X2 = np.vstack([orbit.X[:-1], orbit.X + orbit.shift[None, :]])
    k2 = tuple(2 * k for k in orbit.winding)
    return PeriodicOrbit(orbit.system, orbit.params, mesh2, X2, 2.0 * orbit.T, k2)


def switch_period_doubling(
    branch: Branch,
    which: int | SpecialPoint = 0,
    *,
    amplitude: float = 1e-2,
    newton: NewtonSettings | None = None,
) -> tuple[PeriodicOrbit, float]:
    """The first cycle of the period-doubled branch at a located PD point.

    Parameters
    ----------
    branch : Branch
        A cycle branch of :func:`~continuation.periodic.continuation.continue_periodic`.
    which : int or SpecialPoint
        The PD point (index among ``branch.find("pd")`` or the point).
    amplitude : float
        ``epsilon``: size of the step along ``w`` (scaled to ``max |w| = 1``).
    newton : NewtonSettings, optional

    Returns
    -------
    (PeriodicOrbit, float)
        The doubled cycle (period about ``2 T``) and the side ``sign(p - p_PD)`` of the
        doubled branch (0.0 if ``p`` did not move measurably).

    Raises
    ------
    ValueError
        Not a cycle branch, no such PD point, or a PD point that was not located.
    ConvergenceError
        If the corrector fails.
    """
    if not (isinstance(amplitude, int | float) and math.isfinite(amplitude) and amplitude > 0):
        raise ValueError(f"`amplitude` must be a positive number, got {amplitude!r}")
    sp = _pd_point(branch, which)
    if not sp.located:
        raise ValueError("the PD point was bracketed, not located")
    prob = special_problem(branch, sp)
    orbit = prob.orbit(sp.x, sp.p)
    B, _ = prob._blocks(sp.x, sp.p)
    Phi, S = monodromy_factors(prob.layout, B, stages=True)
    mu, V = np.linalg.eig(monodromy(Phi))
    k = int(np.argmin(np.abs(mu + 1.0)))
    v = np.real(V[:, k])
    lay = prob.layout
    N, m, n = lay.N, lay.m, lay.n
    W = np.zeros((2 * N * (m + 1) + 1, n))
    q = 0
    for _ in range(2):
        for j in range(N):
            W[q] = v
            W[q + 1 : q + m + 1] = np.einsum("lab,b->la", S[j], v)
            v = Phi[j] @ v
            q += m + 1
    W[q] = v
    W /= float(np.max(np.abs(W)))
    orb2 = doubled_orbit(orbit)
    prob2 = PeriodicOrbitProblem.from_orbit(orb2, branch.free)
    wz = np.concatenate([W.reshape(-1), [0.0]])
    u_pd = np.append(prob2.reference, sp.p)
    c = np.append(wz, 0.0)
    sigma = amplitude * float(c @ c)
    res = correct(prob2, u_pd + amplitude * c, u_pd, c, sigma,
                  newton if newton is not None else NewtonSettings(max_iter=40))  # fmt: skip
    if not res.converged:
        raise ConvergenceError(f"no doubled cycle near the PD point: {res.message}")
    dp = res.p - sp.p
    side = 0.0 if abs(dp) <= 1e-12 * max(1.0, abs(sp.p)) else math.copysign(1.0, dp)
    return prob2.orbit(res.z, res.p), side


def continue_period_doubled(
    branch: Branch,
    which: int | SpecialPoint = 0,
    settings: ContinuationSettings | None = None,
    *,
    amplitude: float = 1e-2,
    **kwargs: Any,
) -> Branch:
    """The branch of doubled cycles from a PD point, continued away from it.

    The sign of ``settings.ds`` follows the side of :func:`switch_period_doubling`. Other
    keywords go to :func:`~continuation.periodic.continuation.continue_periodic`.
    """
    orb, side = switch_period_doubling(branch, which, amplitude=amplitude)
    settings = settings if settings is not None else ContinuationSettings()
    if side != 0.0:
        settings = dataclasses.replace(settings, ds=side * abs(settings.ds))
    return continue_periodic(orb.system, orb, orb.params, branch.free, settings, **kwargs)


__all__ = ["continue_period_doubled", "doubled_orbit", "switch_period_doubling"]
