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
positive. The reference component is the state named by ``orient`` if given; otherwise
the first periodic state if its component is at least ``1e-3`` of the largest one
(for the ship: ``+v_u`` increases ``xi_G``); otherwise the largest component.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .fates import Fate, FateClassifier, refine_equilibrium
from .simulate import DEFAULT_ATOL, DEFAULT_RTOL, Simulator, Trajectory, _param_vector, _period
from .status import Status
from .typing import ComplexArray, FloatArray

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


def oriented_unstable_direction(
    system: Any,
    J: FloatArray,
    *,
    orient: str | int | None = None,
    scale: Any = None,
    eig_tol: float = 1e-9,
) -> tuple[float, FloatArray, ComplexArray]:
    """Unstable eigenvalue and oriented unit eigenvector of an index-1 saddle.

    Parameters
    ----------
    system : System
        Supplies state names and periods for the orientation.
    J : ndarray, shape (n, n)
        Jacobian at the saddle.
    orient : str or int, optional
        State whose component of ``v_u`` is made positive.
    scale : array_like (n,), optional
        ``v_u`` has unit norm in ``||v / scale||_2``.
    eig_tol : float
        Real parts within ``eig_tol * max(1, max|lambda|)`` of zero count as zero.

    Returns
    -------
    (lambda_u, v_u, eigenvalues)

    Raises
    ------
    ValueError
        If ``J`` has not exactly one eigenvalue with positive real part, or an
        eigenvalue on the imaginary axis (not hyperbolic), or ``orient`` names a
        state whose component vanishes.
    """
    n = J.shape[0]
    vals, vecs = np.linalg.eig(np.asarray(J, dtype=float))
    order = np.lexsort((-vals.imag, -vals.real))
    vals, vecs = np.asarray(vals, complex)[order], np.asarray(vecs, complex)[:, order]
    thr = eig_tol * max(1.0, float(np.max(np.abs(vals))))
    n_unst = int(np.sum(vals.real > thr))
    if n_unst != 1:
        raise ValueError(
            f"`x_saddle` must have exactly one unstable eigenvalue (saddle of index 1; only "
            f"1-D unstable manifolds are supported), got {n_unst}: eigenvalues {vals}"
        )
    if np.any(np.abs(vals.real) <= thr):
        raise ValueError(f"`x_saddle` is not hyperbolic (eigenvalue on the imaginary axis): {vals}")
    lam = float(vals[0].real)
    v = np.real(vecs[:, 0])
    s = np.ones(n) if scale is None else np.asarray(scale, dtype=float).reshape(n)
    v = v / np.linalg.norm(v / s)
    names = tuple(system.state_names)
    if orient is not None:
        i = names.index(orient) if isinstance(orient, str) and orient in names else orient
        if not isinstance(i, (int, np.integer)) or not 0 <= int(i) < n:
            raise ValueError(f"`orient` must be a state name or index, got {orient!r}")
        i = int(i)
        if abs(v[i]) <= 1e-9 * np.max(np.abs(v)):
            raise ValueError(f"`orient` state {names[i]!r} has no component along v_u")
    else:
        per = _period(system, n)
        big = float(np.max(np.abs(v)))
        cand = [k for k in np.flatnonzero(per > 0) if abs(v[k]) >= 1e-3 * big]
        i = int(cand[0]) if cand else int(np.argmax(np.abs(v)))
    if v[i] < 0:
        v = -v
    return lam, v, vals


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
        Sampling and integrator options (see :func:`~continuation.simulate.simulate`).
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
    p = _param_vector(system, params)
    n = len(system.state_names)
    if not (isinstance(eps, (int, float)) and math.isfinite(eps) and eps > 0):
        raise ValueError(f"`eps` must be a positive finite number, got {eps!r}")
    branches = tuple(int(b) for b in branches)
    if (
        not branches
        or any(b not in (1, -1) for b in branches)
        or len(set(branches)) != len(branches)
    ):
        raise ValueError(f"`branches` must be a non-empty subset of (+1, -1), got {branches}")
    if scale is not None:
        sc = np.asarray(scale, dtype=float).reshape(-1)
        if sc.shape != (n,) or np.any(~np.isfinite(sc)) or np.any(sc <= 0):
            raise ValueError(f"`scale` must be {n} positive finite numbers")
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
                period=_period(system, n),
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
    "oriented_unstable_direction",
    "unstable_manifold",
]
