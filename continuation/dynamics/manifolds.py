r"""One-dimensional unstable manifolds of saddle equilibria, by forward integration.

For a saddle :math:`x_s` of index 1 (exactly one eigenvalue :math:`\lambda_u > 0` of
:math:`J = \partial f / \partial x (x_s)`, all others with negative real part), the
unstable manifold :math:`W^u(x_s)` is a curve tangent to the eigenvector :math:`v_u`.
Its two branches are approximated by the trajectories from

.. math::  x_\pm(0) = x_s \pm \varepsilon\, v_u ,

integrated forward (Umeda 1999, "Nonlinear dynamics of ship capsizing due to broaching
in following and quartering seas", J. Mar. Sci. Technol. 4: the fixed point near the
wave crest, "with a small perturbation for the positive or negative direction of the
eigenvector of the eigenvalue having a positive real part"). The error of the linear
start is :math:`O(\varepsilon^2)` transverse to the manifold, which the flow then
contracts (the other directions are stable), so for small ``eps`` the computed branch
is the manifold up to the integration error and a time shift
:math:`\ln(\varepsilon_1/\varepsilon_2)/\lambda_u` between two choices of ``eps``.

Sign convention (so that "upslope/downslope" is reproducible): ``v_u`` has unit norm
(in the ``scale``-weighted 2-norm) and is oriented so that its *reference component* is
positive (:func:`~continuation.dynamics.saddles.oriented_unstable_direction`: the state
named by ``orient`` if given; otherwise the first periodic state if its component is at
least ``1e-3`` of the largest one, for the ship ``+v_u`` increases ``xi_G``; otherwise
the largest component).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..arguments import positive
from ..status import Status
from ..typing import ComplexArray, FloatArray
from ._common import check_scale, param_vector, state_period
from .classifier import FateClassifier
from .fates import Fate
from .integrators import DEFAULT_ATOL, DEFAULT_RTOL
from .saddles import oriented_unstable_direction, refine_equilibrium
from .simulate import Simulator
from .trajectory import Trajectory

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class ManifoldBranch:
    """One branch of an unstable manifold.

    Attributes
    ----------
    sign : int
        ``+1`` (start at ``x_s + eps v_u``) or ``-1``.
    x0 : ndarray, shape (n,)
        Start point.
    trajectory : Trajectory
        The integrated branch (``t`` from 0).
    fate : Fate or None
        Its classification, when a classifier was given (whatever a plain callable
        ``classify`` returned).
    """

    sign: int
    x0: FloatArray
    trajectory: Trajectory
    fate: Fate | Any = None

    @property
    def status(self) -> Status:
        """Status of the integration (or of the classification)."""
        return self.fate.status if isinstance(self.fate, Fate) else self.trajectory.status

    def as_guess(self, target: Any = None) -> tuple[FloatArray, FloatArray]:
        """``(t (M,), x (M, n))`` of the branch, e.g. as the initial guess of a BVP.

        Parameters
        ----------
        target : array_like, shape (n,), optional
            Cut the branch at its closest sample to ``target`` (Euclidean distance on
            the unwrapped states: give the target already shifted by whole periods).
        """
        t, x = np.array(self.trajectory.t), np.array(self.trajectory.x)
        if target is not None:
            xt = np.asarray(target, dtype=float).reshape(-1)
            if xt.shape != (x.shape[1],):
                raise ValueError(f"`target` must have shape ({x.shape[1]},), got {xt.shape}")
            k = int(np.argmin(np.linalg.norm(x - xt, axis=1)))
            t, x = t[: k + 1], x[: k + 1]
        return t, x


@dataclass(frozen=True, eq=False)
class ManifoldResult:
    """Both branches of the unstable manifold of an index-1 saddle.

    Attributes
    ----------
    x_saddle : ndarray, shape (n,)
        The saddle, refined by Newton.
    eigenvalue : float
        The unstable eigenvalue ``lambda_u > 0``.
    eigenvector : ndarray, shape (n,)
        The oriented unit eigenvector ``v_u`` (see the module docstring).
    eigenvalues : ndarray, shape (n,) complex
        All eigenvalues of ``J(x_saddle)``, by decreasing real part.
    eps : float
        Distance of the start points from the saddle along ``v_u``.
    params : ndarray, shape (m,)
        Parameter vector.
    plus, minus : ManifoldBranch or None
        The branches along ``+v_u`` and ``-v_u`` (``None`` if not requested, or not
        computed because of an interruption).
    status : Status
        ``SUCCESS`` if every computed branch ended normally, else the first failure
        (``INTERRUPTED``, ``INTEGRATION_FAILED``).
    """

    x_saddle: FloatArray
    eigenvalue: float
    eigenvector: FloatArray
    eigenvalues: ComplexArray
    eps: float
    params: FloatArray
    plus: ManifoldBranch | None
    minus: ManifoldBranch | None
    status: Status

    @property
    def branches(self) -> tuple[ManifoldBranch, ...]:
        """The computed branches, ``+`` first."""
        return tuple(b for b in (self.plus, self.minus) if b is not None)

    def branch(self, sign: int) -> ManifoldBranch:
        """The branch with ``sign`` = ``+1`` or ``-1``."""
        b = {1: self.plus, -1: self.minus}.get(int(sign))
        if b is None:
            raise ValueError(f"branch {sign:+d} was not computed")
        return b

    @property
    def fates(self) -> tuple[Fate | None, ...]:
        """Fates of the computed branches (``None`` where not classified)."""
        return tuple(b.fate for b in self.branches)


def unstable_manifold(
    system: Any,
    params: Any,
    x_saddle: Any,
    *,
    eps: float = 1e-6,
    t_max: float = 100.0,
    events: Sequence[Any] = (),
    classify: FateClassifier | Callable[[FloatArray], Fate] | None = None,
    branches: Sequence[int] = (1, -1),
    orient: str | int | None = None,
    scale: Any = None,
    dt: float | None = None,
    method: str | None = None,
    rtol: float = DEFAULT_RTOL,
    atol: float = DEFAULT_ATOL,
    refine: bool = True,
    dense: bool = False,
    progress: Callable[[float, FloatArray], None] | None = None,
) -> ManifoldResult:
    r"""Integrate the one-dimensional unstable manifold of a saddle equilibrium.

    Starts at ``x_saddle ± eps * v_u``, where ``v_u`` is the oriented unit eigenvector
    of the single positive eigenvalue of ``J(x_saddle)``, and integrates
    :math:`\dot x = f(x, p)` forward (see the module docstring for the convention).

    Parameters
    ----------
    system : System
        The dynamical system.
    params : Params, mapping or array_like, shape (m,)
        Parameter values.
    x_saddle : array_like, shape (n,)
        An equilibrium with exactly one unstable eigenvalue (refined by Newton first
        unless ``refine=False``).
    eps : float
        Initial distance from the saddle along ``v_u`` (``scale``-weighted norm).
    t_max : float
        Integration time of each branch when ``classify`` is None.
    events : sequence of SimEvent
        Events for the integration when ``classify`` is None (a terminal one stops
        the branch). With a classifier, its own events are used.
    classify : FateClassifier or callable, optional
        If given, each branch is integrated *and classified* by it
        (``FateClassifier.classify(x0, exclude_visit=...)``, or ``classify(x0)``):
        its ``t_max``, events and tolerances apply, and ``branch.fate`` is set.
    branches : sequence of {+1, -1}
        Which branches to compute.
    orient : str or int, optional
        State whose ``v_u`` component is made positive.
    scale : array_like (n,), optional
        State scales for the norm of ``v_u``.
    dt, method, rtol, atol
        Sampling and integrator options (see :func:`~continuation.dynamics.simulate.simulate`).
    refine : bool
        Newton-refine ``x_saddle`` first.
    dense : bool
        Store derivatives so that ``trajectory.at(t)`` interpolates (without a
        classifier).
    progress : callable, optional
        ``progress(t, x)`` during the integration of each branch.

    Returns
    -------
    ManifoldResult
        ``plus``/``minus`` branches, each with ``trajectory.t`` (M,) and
        ``trajectory.x`` (M, n), the eigen-data and a status.

    Raises
    ------
    ValueError
        If ``J(x_saddle)`` does not have exactly one eigenvalue with positive real
        part (or is not hyperbolic), if ``x_saddle`` is not near an equilibrium, or for
        bad ``eps``, ``branches``, ``orient``.
    """
    p = param_vector(system, params)
    n = len(system.state_names)
    positive("eps", eps)
    branches = tuple(int(b) for b in branches)
    if (
        not branches
        or any(b not in (1, -1) for b in branches)
        or len(set(branches)) != len(branches)
    ):
        raise ValueError(f"`branches` must be a non-empty subset of (+1, -1), got {branches}")
    if scale is not None:
        check_scale(n, scale)
    if refine:
        xs, _, _, _ = refine_equilibrium(system, x_saddle, p, name="x_saddle")
    else:
        xs = system.check_state(x_saddle, "x_saddle")
    lam, v, vals = oriented_unstable_direction(
        system, system.jacobian(xs, p), orient=orient, scale=scale
    )
    exclude = None
    if isinstance(classify, FateClassifier):
        for i, e in enumerate(classify.equilibria):
            if classify.distance(e.x, xs) <= classify.tol:
                exclude = i
    elif classify is not None and not callable(classify):
        raise ValueError("`classify` must be a FateClassifier, a callable or None")
    sim = (
        None if classify is not None else Simulator(system, p, method=method, rtol=rtol, atol=atol)
    )
    out: dict[int, ManifoldBranch | None] = {1: None, -1: None}
    status = Status.SUCCESS
    for sgn in branches:
        x0 = xs + sgn * eps * v
        try:
            if isinstance(classify, FateClassifier):
                fate = classify.classify(x0, progress=progress, exclude_visit=exclude)
                traj = fate.trajectory
            elif classify is not None:
                fate = classify(x0)
                traj = getattr(fate, "trajectory", None)
            else:
                assert sim is not None  # (built above when classify is None)
                fate = None
                traj = sim.run(
                    x0, (0.0, t_max), events=events, dt=dt, dense=dense, progress=progress
                )
        except KeyboardInterrupt:
            status = Status.INTERRUPTED
            break
        if traj is None:
            traj = Trajectory(
                np.array([0.0]),
                x0[None, :],
                state_names=tuple(system.state_names),
                period=state_period(system, n),
                params=p,
            )
        br = ManifoldBranch(sgn, x0, traj, fate)
        out[sgn] = br
        if not br.status.ok and status is Status.SUCCESS:
            status = br.status
        if br.status is Status.INTERRUPTED:
            break
    log.debug("unstable manifold: lambda_u=%.6g, branches %s", lam, branches)
    return ManifoldResult(xs, lam, v, vals, float(eps), p, out[1], out[-1], status)


__all__ = [
    "ManifoldBranch",
    "ManifoldResult",
    "unstable_manifold",
]
