"""Connecting-orbit problems with reference values, shared by the connection tests.

Each :class:`ConnectionCase` names a system, the starting parameters, the solved
parameter, the source saddle, the target (a saddle or a shift), the branch of the
source's unstable manifold that leads to the connection, and a reference value with
its own uncertainty (0 for closed forms; half a unit of the last published digit for
published values). Sources:

* ``nagumo``: ``u'' + c u' + u(1-u)(u-a) = 0``, ``c = sqrt2 (1/2 - a)`` (McKean 1970).
* ``nagumo4``: the Nagumo front driving a damped rotation, n = 4 (same ``c``).
* ``nagumo3_coupled``: a heteroclinic orbit between two different saddles in 3-D, the
  Nagumo front with a slaved third state ``z' = -k z + u^2 + v``, written in the
  coupled coordinates ``w = z + u v`` so that every equation involves every state; the
  speed is still ``sqrt2 (1/2 - a)`` (a change of coordinates keeps the orbit).
* ``pendulum_cylinder``: ``theta'' + gamma theta' + sin theta = F`` on the cylinder,
  saddle to the saddle shifted by ``2 pi``; reference ``F`` by shooting
  (:func:`shooting_F`, 1e-12).
* ``pendulum_separatrix``: the undamped separatrix between (-pi, 0) and (pi, 0),
  ``gamma = 0`` (Guckenheimer & Holmes 1983, sec. 4.5).
* ``kdv``: ``u'' = u - u^2 + mu u'``, homoclinic only at ``mu = 0``.
* ``phi4_tilted``: ``u'' + c u' + u - u^3 - h = 0``, ``c = 3 r2 / sqrt2`` (McKean 1970).
* ``lorenz``: first homoclinic orbit of the origin, ``r = 13.9265574`` (Doedel,
  Krauskopf & Osinga 2006).
* ``cir``: the electronic circuit of Freire, Rodriguez-Luis, Gamero & Ponce (1993),
  AUTO-07p demo ``cir``, homoclinic to a saddle-focus: ``nu = -0.7213093`` at
  ``beta = 0.6`` (AUTO-07p manual, HomCont demo cir, run 1).
* ``kpr``: Koper's extended Van der Pol model (Koper 1995), AUTO-07p demo ``kpr``, a
  3-D homoclinic orbit with a fast excursion (``1/eps_1 = 10``): ``lambda =
  -1.85119`` at ``k = -0.15`` (AUTO-07p manual, demo kpr, run 2); the demo file's
  starting value is ``-1.851185124``.
* ``san``: Sandstede's model (1995), AUTO-07p demo ``san`` at ``a = 0.25``, ``b = 1``,
  ``c = -2``, ``alpha = mu = gamma = 0``: the curve ``y^2 = x^2 (1 - x)`` is invariant
  for every ``a`` when ``mu~ = 0`` (direct computation), so the homoclinic orbit has
  ``mu~ = 0`` (AUTO's run 1: ``-1.86e-11``).
* ``she``: the 5-D shearing-instability model of Rucklidge & Matthews (1995), AUTO-07p
  demo ``she``, a heteroclinic orbit from ``(sqrt mu, -mu, 0, 0, 0)`` to the origin at
  ``Q = 0``, ``zeta = 4``: ``mu = 0.163875`` at ``sigma = 0.5`` (AUTO-07p manual, demo
  she, run 1).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from continuation.bvp import ConnectionResult, find_connection
from continuation.system import System

SQ2 = np.sqrt(2.0)


@dataclass(frozen=True)
class ConnectionCase:
    name: str
    system: System
    params: dict[str, float]
    free: str
    source: Any
    reference: float
    reference_uncertainty: float
    target: Any = None
    shift: Any = None
    branch: int = 1
    extra: dict[str, Any] = field(default_factory=dict)

    def kwargs(self) -> dict[str, Any]:
        kw: dict[str, Any] = {"source": self.source, "branch": self.branch}
        if self.shift is not None:
            kw["shift"] = self.shift
        else:
            kw["target"] = self.target
        return kw


def nagumo() -> System:
    def rhs(x, p, ops):
        a, c = p[0], p[1]
        return ops.stack([x[1], -c * x[1] - x[0] * (1 - x[0]) * (x[0] - a)])

    return System(rhs, ("u", "v"), ("a", "c"))


def nagumo4() -> System:
    def rhs(x, p, ops):
        u, v, y, w = x[0], x[1], x[2], x[3]
        a, c, om = p[0], p[1], p[2]
        return ops.stack(
            [
                v,
                -c * v - u * (1 - u) * (u - a),
                -y + om * w + u**2 + 0.3 * v * y,
                -om * y - w + ops.sin(u),
            ]
        )

    return System(rhs, ("u", "v", "y", "w"), ("a", "c", "om"))


def nagumo3_coupled() -> System:
    """States (u, v, w), w = z + u v with z' = -k z + u^2 + v slaved to the front."""

    def rhs(x, p, ops):
        u, v, w = x[0], x[1], x[2]
        a, c, k = p[0], p[1], p[2]
        du = v
        dv = -c * v - u * (1 - u) * (u - a)
        z = w - u * v
        dz = -k * z + u**2 + v
        return ops.stack([du, dv, dz + du * v + u * dv])

    return System(rhs, ("u", "v", "w"), ("a", "c", "k"))


def pendulum() -> System:
    def rhs(x, p, ops):
        return ops.stack([x[1], p[1] - p[0] * x[1] - ops.sin(x[0])])

    return System(rhs, ("theta", "omega"), ("gamma", "F"), periodic={"theta": 2 * np.pi})


def pendulum_plane() -> System:
    def rhs(x, p, ops):
        return ops.stack([x[1], p[1] - p[0] * x[1] - ops.sin(x[0])])

    return System(rhs, ("theta", "omega"), ("gamma", "F"))


def kdv() -> System:
    def rhs(x, p, ops):
        return ops.stack([x[1], x[0] - x[0] ** 2 + p[0] * x[1]])

    return System(rhs, ("u", "v"), ("mu",))


def phi4() -> System:
    def rhs(x, p, ops):
        c, h = p[0], p[1]
        return ops.stack([x[1], -c * x[1] - x[0] + x[0] ** 3 + h])

    return System(rhs, ("u", "v"), ("c", "h"))


def lorenz() -> System:
    def rhs(x, p, ops):
        sigma, r, beta = p[0], p[1], p[2]
        return ops.stack(
            [sigma * (x[1] - x[0]), r * x[0] - x[1] - x[0] * x[2], x[0] * x[1] - beta * x[2]]
        )

    return System(rhs, ("x", "y", "z"), ("sigma", "r", "beta"))


def cir() -> System:
    """AUTO-07p demo cir (Freire et al. 1993), equations of cir.f90."""

    def rhs(u, p, ops):
        nu, be, ga, r, a3, b3 = (p[i] for i in range(6))
        x, y, z = u[0], u[1], u[2]
        return ops.stack(
            [
                (-(be + nu) * x + be * y - a3 * x**3 + b3 * (y - x) ** 3) / r,
                be * x - (be + ga) * y - z - b3 * (y - x) ** 3,
                y,
            ]
        )

    return System(rhs, ("x", "y", "z"), ("nu", "beta", "gamma", "r", "a3", "b3"))


#: The starting parameters of AUTO-07p's demo ``cir`` (cir.f90), ``nu`` solved for.
CIR_START = {"nu": -0.72, "beta": 0.6, "gamma": 0.0, "r": 0.6, "a3": 0.328578, "b3": 0.933578}


@functools.lru_cache(maxsize=1)
def cir_connection() -> ConnectionResult:
    """The homoclinic orbit of ``cir`` found from :data:`CIR_START` (``nu`` free), cached.

    Shared by the tests that need a converged connection to linearise; callers must not
    modify it.
    """
    s = cir()
    res = find_connection(s, s.params(**CIR_START), "nu", source=[0.0, 0.0, 0.0], shift=0)
    if not res.success:
        raise AssertionError(f"the cir connection did not converge: {res.status}")
    return res


def kpr() -> System:
    """AUTO-07p demo kpr (Koper 1995), equations of kpr.f90 (eps_2 = 1)."""

    def rhs(x, p, ops):
        lam, k, ie1 = p[0], p[1], p[2]
        return ops.stack(
            [ie1 * (k * x[1] - x[0] ** 3 + 3 * x[0] - lam), x[0] - 2 * x[1] + x[2], x[1] - x[2]]
        )

    return System(rhs, ("x", "y", "z"), ("lam", "k", "ie1"))


def san() -> System:
    """AUTO-07p demo san (Sandstede 1995), equations of the AUTO manual, ch. HomCont san."""

    def rhs(u, p, ops):
        a, b, c, alpha, beta, gamma, mu, mut = (p[i] for i in range(8))
        x, y, z = u[0], u[1], u[2]
        m = mut - alpha * z
        return ops.stack(
            [
                a * x + b * y - a * x**2 + m * x * (2 - 3 * x),
                b * x + a * y - 1.5 * b * x**2 - 1.5 * a * x * y - 2 * m * y,
                c * z + mu * x + gamma * x * y + alpha * beta * (x**2 * (1 - x) - y**2),
            ]
        )

    return System(rhs, ("x", "y", "z"), ("a", "b", "c", "alpha", "beta", "gamma", "mu", "mut"))


def she() -> System:
    """AUTO-07p demo she (Rucklidge & Matthews 1995), equations of she.f90."""
    pi2 = 3.141592654**2

    def rhs(x, p, ops):
        mu, Q, sigma, zeta = p[0], p[1], p[2], p[3]
        a, b, c, d, e = (x[i] for i in range(5))
        return ops.stack(
            [
                a * b + a * mu - c * d,
                -(a**2 + b),
                c * mu + a * d - 9 * sigma * c / (4 * (sigma + 1)),
                (-Q * sigma * e / pi2 - sigma * d + 3 * a * c * (1 + 1 / sigma)) / 4,
                zeta * (d - e) / 4,
            ]
        )

    return System(rhs, ("P11", "T02", "P12", "P01", "A01"), ("mu", "Q", "sigma", "zeta"))


def _phi4_reference(h: float) -> float:
    r2 = float(np.sort(np.roots([1.0, 0.0, -1.0, h]).real)[1])
    return 3 * r2 / SQ2


def _phi4_saddles(h: float) -> tuple[float, float]:
    r = np.sort(np.roots([1.0, 0.0, -1.0, h]).real)
    return float(r[0]), float(r[2])


def shooting_F(gamma: float) -> float:
    """F(gamma) by shooting along the unstable manifold and Brent's bracketing method.

    The manifold of the saddle theta_u - 2 pi (theta_u = pi - asin F) leaves with
    omega > 0. Its fate: it passes theta_u (F too large; g = omega^2 there) or turns
    back with omega = 0 first (F too small; g = -|cos theta_u| (theta_u - theta)^2).
    g is continuous with a simple zero at the connection. Independent of the BVP code.
    """

    def g(F: float) -> float:
        thu = np.pi - np.arcsin(F)
        th0 = thu - 2 * np.pi
        J = np.array([[0.0, 1.0], [-np.cos(th0), -gamma]])
        ev, V = np.linalg.eig(J)
        v = V[:, np.argmax(ev.real)].real
        v *= np.sign(v[1]) / np.linalg.norm(v)
        x0 = np.array([th0, 0.0]) + 1e-8 * v

        def over(t, x):
            return x[0] - thu

        def back(t, x):
            return x[1]

        over.terminal = True
        back.terminal, back.direction = True, -1
        sol = solve_ivp(
            lambda t, x: [x[1], F - gamma * x[1] - np.sin(x[0])],
            (0.0, 400.0),
            x0,
            events=(over, back),
            rtol=1e-12,
            atol=1e-14,
            method="DOP853",
        )
        if sol.t_events[0].size:
            return float(sol.y_events[0][0][1] ** 2)
        if sol.t_events[1].size:
            return float(-abs(np.cos(thu)) * (thu - sol.y_events[1][0][0]) ** 2)
        raise RuntimeError("unstable manifold met neither event")

    F_mel = 4 * gamma / np.pi
    return float(brentq(g, 0.5 * F_mel, min(0.95, 1.2 * F_mel), xtol=1e-14, rtol=1e-14))


def cases() -> list[ConnectionCase]:
    """Every connecting-orbit problem with a reference value (built fresh each call)."""

    gamma = 0.3
    F_ref = shooting_F(gamma)
    F0 = 4 * gamma / np.pi
    h = 0.1
    lo, hi = _phi4_saddles(h)
    mu_she = 0.163875
    return [
        ConnectionCase(
            "nagumo", nagumo(), {"a": 0.25, "c": 0.3}, "c", [1.0, 0.0], SQ2 * 0.25, 0.0,
            target=[0.0, 0.0], branch=-1,
        ),
        ConnectionCase(
            "nagumo4", nagumo4(), {"a": 0.25, "c": 0.3, "om": 2.0}, "c",
            [1.0, 0.0, 0.2, 0.4], SQ2 * 0.25, 0.0, target=[0.0, 0.0, 0.0, 0.0], branch=-1,
        ),
        ConnectionCase(
            "nagumo3_coupled", nagumo3_coupled(), {"a": 0.3, "c": 0.25, "k": 1.5}, "c",
            [1.0, 0.0, 1.0 / 1.5], SQ2 * 0.2, 0.0, target=[0.0, 0.0, 0.0], branch=-1,
        ),
        ConnectionCase(
            "pendulum_cylinder", pendulum(), {"gamma": gamma, "F": F0}, "F",
            [-np.pi - np.arcsin(F0), 0.0], F_ref, 1e-11, shift={"theta": 2 * np.pi},
        ),
        ConnectionCase(
            "pendulum_separatrix", pendulum_plane(), {"gamma": 0.2, "F": 0.0}, "gamma",
            [-np.pi, 0.0], 0.0, 0.0, target=[np.pi, 0.0],
        ),
        ConnectionCase("kdv", kdv(), {"mu": 0.05}, "mu", [0.0, 0.0], 0.0, 0.0, shift=0),
        ConnectionCase(
            "phi4_tilted", phi4(), {"c": 0.1, "h": h}, "c", [lo, 0.0], _phi4_reference(h),
            1e-14, target=[hi, 0.0],
        ),
        ConnectionCase(
            "lorenz", lorenz(), {"sigma": 10.0, "r": 14.0, "beta": 8.0 / 3.0}, "r",
            [0.0, 0.0, 0.0], 13.9265574, 5e-8, shift=0,
        ),
        ConnectionCase(
            "cir", cir(), dict(CIR_START), "nu", [0.0, 0.0, 0.0], -0.7213093, 5e-8, shift=0,
        ),
        ConnectionCase(
            "kpr", kpr(), {"lam": -1.8512, "k": -0.15, "ie1": 10.0}, "lam",
            [-0.9591016] * 3, -1.85119, 5e-6, shift=0, branch=-1,
        ),
        ConnectionCase(
            "san", san(),
            {"a": 0.25, "b": 1.0, "c": -2.0, "alpha": 0.0, "beta": 1.0, "gamma": 0.0,
             "mu": 0.0, "mut": 0.01},
            "mut", [0.0, 0.0, 0.0], 0.0, 0.0, shift=0,
        ),
        ConnectionCase(
            "she", she(), {"mu": 0.16, "Q": 0.0, "sigma": 0.5, "zeta": 4.0}, "mu",
            [np.sqrt(mu_she), -mu_she, 0.0, 0.0, 0.0], 0.163875, 5e-7,
            target=[0.0] * 5,
        ),
    ]  # fmt: skip
