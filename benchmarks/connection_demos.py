r"""Three of AUTO-07p/HomCont's homoclinic demos, defined once for both tools.

Each :class:`Demo` holds the equations twice, written for this benchmark from the
published models (no AUTO-07p file is copied): ``rhs(x, p, ops)`` for broachkit and a
Fortran equation file for AUTO-07p (``FUNC`` with its Jacobian, ``STPNT`` with the
demo's parameter values), plus the AUTO constants of the demo's runs.

* ``kpr`` -- Koper's extended van der Pol model (Koper 1995, "Bifurcations of mixed-mode
  oscillations in a three-variable autonomous Van der Pol-Duffing model with a
  cross-shaped phase diagram", Physica D 80:72-94)::

      x' = (kappa y - x^3 + 3 x - lambda) / eps1,   y' = x - 2 y + z,   z' = y - z

  ``1/eps1 = 10``, ``kappa = -0.15``; homoclinic orbit to the saddle
  ``x = y = z = x*`` (``x*^3 - (3 + kappa) x* + lambda = 0``), solved for ``lambda``;
  continued in ``kappa``. AUTO's route (demo runs 1-2): the homotopy of ``ISTART=3``
  from the saddle (Doedel, Friedman & Monteiro 1994) grows ``T`` and then locates the
  orbit by continuation in ``(T, lambda)`` up to ``T = 60``.
* ``cir`` -- the electronic circuit of Freire, Rodriguez-Luis, Gamero & Ponce (1993, "A
  case study for homoclinic chaos in an autonomous electronic circuit", Physica D
  62:230-253)::

      x' = (-(beta + nu) x + beta y - a3 x^3 + b3 (y - x)^3) / r
      y' = beta x - (beta + gamma) y - z - b3 (y - x)^3,        z' = y

  ``beta = 0.6, gamma = 0, r = 0.6, a3 = 0.328578, b3 = 0.933578``: a homoclinic orbit
  to the saddle-focus at the origin (one real unstable eigenvalue, a stable complex
  pair), solved for ``nu`` (about -0.7213); continued in ``beta``. AUTO's route (demo
  run 1): continuation in ``(T, nu)`` from starting data at ``T = 36.13`` to
  ``T = 100``; the starting data here are this benchmark's own (a simulated unstable
  manifold, :func:`manifold_guess`), not the demo's data file.
* ``san`` -- Sandstede's test model (Sandstede 1997, "Constructing dynamical systems
  having homoclinic bifurcation points of codimension two", J. Dyn. Diff. Eq.
  9:269-288) with ``b = 1, c = -2, beta = 1`` and ``alpha = gamma = mu = 0``::

      x' = a x + b y - a x^2 + (mu~ - alpha z) x (2 - 3 x)
      y' = b x + a y - 3/2 b x^2 - 3/2 a x y - 2 (mu~ - alpha z) y
      z' = c z + mu x + gamma x z + alpha beta (x^2 (1 - x) - y^2)

  homoclinic to the origin; at ``a = 0`` the orbit is known in closed form with
  ``mu~ = 0``. AUTO's route (demo run 1): continuation from that orbit in ``(a, mu~)``
  to ``a = 0.25`` (``T = 20``); the connection solved is ``mu~`` at ``a = 0.25``;
  continued in ``alpha`` from 0 to 1.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from benchmarks.peers.auto_native import EMPTY_ROUTINES, FUNC_HEAD, STPNT_HEAD

_STUBS = "\n" + EMPTY_ROUTINES  # a blank line before the stubs, as the files had

# Settings every demo run shares (HomCont's IPS = 9; the demos' own values).
AUTO_BASE: dict[str, Any] = {
    "NDIM": 3,
    "IPS": 9,
    "ILP": 0,
    "NCOL": 4,
    "ISP": 0,
    "ISW": 1,
    "IPLT": 0,
    "NBC": 0,
    "NINT": 0,
    "MXBF": 0,
    "IID": 0,
    "ITMX": 10,
    "ITNW": 7,
    "NWTN": 3,
    "EPSL": 1e-7,
    "EPSU": 1e-7,
    "EPSS": 1e-5,
    "IADS": 1,
    "NPR": 1000,
}


@dataclasses.dataclass(frozen=True)
class Demo:
    """One HomCont demo.

    Attributes
    ----------
    key : str
    params : dict of str to float
        broachkit's parameter names and the values of the solve (the solved one: a guess).
    auto_index : dict of str to int
        AUTO's ``PAR`` index of each parameter.
    solved, second : str
        The parameter solved for, and the one the connection is continued in.
    saddle : callable
        ``saddle(pvec) -> x_-`` (n,), the equilibrium the orbit is homoclinic to.
    fortran : str
        AUTO-07p equation file.
    auto_solve : list of dict
        AUTO constants of the run(s) that lead to the connection at the demo's
        parameters; ``("UZ", k)`` as ``IRS`` restarts from the k-th UZ of the previous run.
    auto_continue : dict
        Constants of the continuation in ``second`` (restarts from the solve's last UZ).
    T : float
        The truncation interval at the solve.
    """

    key: str
    title: str
    state_names: tuple[str, ...]
    params: dict[str, float]
    auto_index: dict[str, int]
    solved: str
    second: str
    rhs: Callable[[Any, Any, Any], Any]
    saddle: Callable[[np.ndarray], np.ndarray]
    fortran: str
    auto_solve: list[dict[str, Any]]
    auto_continue: dict[str, Any]
    T: float
    branch: int = 1  # side of the unstable manifold that makes the orbit
    auto_files: Callable[[Demo], dict[str, str]] | None = None

    def system(self) -> Any:
        from continuation.system import System

        return System(self.rhs, self.state_names, tuple(self.params))

    def pvec(self, **changes: float) -> np.ndarray:
        vals = {**self.params, **changes}
        return np.array([vals[k] for k in self.params], dtype=float)


# ------------------------------------------------------------------------------- kpr
def _kpr_rhs(x: Any, p: Any, ops: Any) -> Any:
    lam, kappa, inv_eps = p[0], p[1], p[2]
    return ops.stack(
        [
            inv_eps * (kappa * x[1] - x[0] ** 3 + 3.0 * x[0] - lam),
            x[0] - 2.0 * x[1] + x[2],
            x[1] - x[2],
        ]
    )


def _kpr_saddle(p: np.ndarray) -> np.ndarray:
    lam, kappa = p[0], p[1]
    r = np.roots([1.0, 0.0, -(3.0 + kappa), lam])
    r = np.sort(r[np.abs(r.imag) < 1e-12].real)
    return np.full(3, r[1])  # the middle root (AUTO's -0.9591): the saddle


_KPR_F90 = (
    FUNC_HEAD
    + """  f(1) = par(3) * (par(2) * u(2) - u(1)**3 + 3d0 * u(1) - par(1))
  f(2) = u(1) - 2d0 * u(2) + u(3)
  f(3) = u(2) - u(3)
  if (ijac == 0) return
  dfdu(1, :) = (/ par(3) * (3d0 - 3d0 * u(1)**2), par(3) * par(2), 0d0 /)
  dfdu(2, :) = (/ 1d0, -2d0, 1d0 /)
  dfdu(3, :) = (/ 0d0, 1d0, -1d0 /)
  if (ijac == 1) return
  dfdp(:, 1) = (/ -par(3), 0d0, 0d0 /)
  dfdp(:, 2) = (/ par(3) * u(2), 0d0, 0d0 /)
  dfdp(:, 3) = (/ par(2) * u(2) - u(1)**3 + 3d0 * u(1) - par(1), 0d0, 0d0 /)
end subroutine func
"""
    + STPNT_HEAD
    + """  par(1) = -1.851185124d0
  par(2) = -0.15d0
  par(3) = 10d0
  par(11) = 0.1d0
  par(12:14) = -0.9591016d0
  par(15) = -1d-5
end subroutine stpnt
"""
    + _STUBS
)

_KPR_BASE = {
    **AUTO_BASE,
    "NTST": 15,
    "IAD": 1,
    "JAC": 1,
    "DS": 0.1,
    "DSMIN": 0.001,
    "DSMAX": 2.0,
    "NPAR": 15,
    "IEQUIB": 1,
}

KPR = Demo(
    key="kpr",
    title="Koper's van der Pol model: lambda at kappa = -0.15",
    state_names=("x", "y", "z"),
    params={"lam": -1.851185124, "kappa": -0.15, "inv_eps": 10.0},
    auto_index={"lam": 1, "kappa": 2, "inv_eps": 3},
    solved="lam",
    second="kappa",
    rhs=_kpr_rhs,
    saddle=_kpr_saddle,
    fortran=_KPR_F90,
    auto_solve=[
        {**_KPR_BASE, "IRS": 0, "ICP": [11, 17], "NMX": 35, "UZR": {17: 0.0}, "ISTART": 3},
        {
            **_KPR_BASE,
            "IRS": ("UZ", 1),
            "ICP": [11, 1],
            "NMX": 50,
            "UZSTOP": {11: 60.0},
            "ISTART": 3,
        },
    ],
    auto_continue={
        **_KPR_BASE,
        "ICP": [1, 2],
        "NTST": 25,
        "NMX": 50,
        "DS": 0.1,
        "DSMIN": 0.01,
        "DSMAX": 0.2,
        "ISTART": 1,
        "ITWIST": 0,
    },
    T=60.0,
    branch=-1,
)


# ------------------------------------------------------------------------------- cir
def _cir_rhs(x: Any, p: Any, ops: Any) -> Any:
    nu, be, ga, r, a3, b3 = (p[i] for i in range(6))
    d3 = (x[1] - x[0]) ** 3
    return ops.stack(
        [
            (-(be + nu) * x[0] + be * x[1] - a3 * x[0] ** 3 + b3 * d3) / r,
            be * x[0] - (be + ga) * x[1] - x[2] - b3 * d3,
            x[1],
        ]
    )


_CIR_F90 = (
    FUNC_HEAD
    + """  double precision :: nu, be, ga, r, a3, b3, d2, d3
  nu = par(1); be = par(2); ga = par(3); r = par(4); a3 = par(5); b3 = par(6)
  d2 = (u(2) - u(1))**2
  d3 = (u(2) - u(1))**3
  f(1) = (-(be + nu) * u(1) + be * u(2) - a3 * u(1)**3 + b3 * d3) / r
  f(2) = be * u(1) - (be + ga) * u(2) - u(3) - b3 * d3
  f(3) = u(2)
  if (ijac == 0) return
  dfdu(1, :) = (/ (-(be + nu) - 3d0 * a3 * u(1)**2 - 3d0 * b3 * d2) / r, &
                  (be + 3d0 * b3 * d2) / r, 0d0 /)
  dfdu(2, :) = (/ be + 3d0 * b3 * d2, -(be + ga) - 3d0 * b3 * d2, -1d0 /)
  dfdu(3, :) = (/ 0d0, 1d0, 0d0 /)
  if (ijac == 1) return
  dfdp(:, 1) = (/ -u(1) / r, 0d0, 0d0 /)
  dfdp(:, 2) = (/ (u(2) - u(1)) / r, u(1) - u(2), 0d0 /)
  dfdp(:, 3) = (/ 0d0, -u(2), 0d0 /)
  dfdp(:, 4) = (/ -f(1) / r, 0d0, 0d0 /)
  dfdp(:, 5) = (/ -u(1)**3 / r, 0d0, 0d0 /)
  dfdp(:, 6) = (/ d3 / r, -d3, 0d0 /)
end subroutine func
"""
    + STPNT_HEAD
    + """  par(1) = NU0
  par(2) = 0.6d0
  par(3) = 0d0
  par(4) = 0.6d0
  par(5) = 0.328578d0
  par(6) = 0.933578d0
  par(11) = T0
  par(12:14) = 0d0
end subroutine stpnt
"""
    + _STUBS
)

_CIR_BASE = {**AUTO_BASE, "NTST": 35, "IAD": 1, "JAC": 1, "NPAR": 14, "IEQUIB": 0}


def _cir_files(demo: Demo) -> dict[str, str]:
    t, X = manifold_guess(demo)
    T = float(t[-1] - t[0])
    rows = np.column_stack([(t - t[0]) / T, X])
    return {"guess.dat": "".join(" ".join(f"{v: .15e}" for v in r) + "\n" for r in rows)}


CIR = Demo(
    key="cir",
    title="Freire et al. circuit: nu of the saddle-focus homoclinic orbit",
    state_names=("x", "y", "z"),
    params={"nu": -0.721309, "beta": 0.6, "gamma": 0.0, "r": 0.6, "a3": 0.328578, "b3": 0.933578},
    auto_index={"nu": 1, "beta": 2, "gamma": 3, "r": 4, "a3": 5, "b3": 6},
    solved="nu",
    second="beta",
    rhs=_cir_rhs,
    saddle=lambda p: np.zeros(3),
    fortran=_CIR_F90,  # NU0, T0 filled in from the guess by the benchmark
    auto_solve=[
        {
            **_CIR_BASE,
            "dat": "guess.dat",
            "IRS": 0,
            "ICP": [11, 1],
            "NMX": 50,
            "DS": 1.0,
            "DSMIN": 1e-4,
            "DSMAX": 5.0,
            "UZSTOP": {11: 100.0},
        },
    ],
    auto_continue={
        **_CIR_BASE,
        "ICP": [1, 2],
        "NMX": 100,
        "DS": 0.01,
        "DSMIN": 1e-4,
        "DSMAX": 0.01,
    },
    T=100.0,
    auto_files=_cir_files,
)


# ------------------------------------------------------------------------------- san
def _san_rhs(x: Any, p: Any, ops: Any) -> Any:
    a, b, c, al, be, ga, mu, mt = (p[i] for i in range(8))
    w = mt - al * x[2]
    return ops.stack(
        [
            a * x[0] + b * x[1] - a * x[0] ** 2 + w * x[0] * (2.0 - 3.0 * x[0]),
            b * x[0] + a * x[1] - 1.5 * b * x[0] ** 2 - 1.5 * a * x[0] * x[1] - 2.0 * w * x[1],
            c * x[2]
            + mu * x[0]
            + ga * x[0] * x[2]
            + al * be * (x[0] ** 2 * (1.0 - x[0]) - x[1] ** 2),
        ]
    )


_SAN_F90 = (
    FUNC_HEAD
    + """  double precision :: w
  w = par(8) - par(4) * u(3)
  f(1) = par(1) * u(1) + par(2) * u(2) - par(1) * u(1)**2 + w * u(1) * (2d0 - 3d0 * u(1))
  f(2) = par(2) * u(1) + par(1) * u(2) - 1.5d0 * par(2) * u(1)**2 &
         - 1.5d0 * par(1) * u(1) * u(2) - 2d0 * w * u(2)
  f(3) = par(3) * u(3) + par(7) * u(1) + par(6) * u(1) * u(3) &
         + par(4) * par(5) * (u(1)**2 * (1d0 - u(1)) - u(2)**2)
  if (ijac == 0) return
  dfdu(1, :) = (/ par(1) - 2d0 * par(1) * u(1) + w * (2d0 - 6d0 * u(1)), par(2), &
                  -par(4) * u(1) * (2d0 - 3d0 * u(1)) /)
  dfdu(2, :) = (/ par(2) - 3d0 * par(2) * u(1) - 1.5d0 * par(1) * u(2), &
                  par(1) - 1.5d0 * par(1) * u(1) - 2d0 * w, 2d0 * par(4) * u(2) /)
  dfdu(3, :) = (/ par(7) + par(6) * u(3) + par(4) * par(5) * u(1) * (2d0 - 3d0 * u(1)), &
                  -2d0 * par(4) * par(5) * u(2), par(3) + par(6) * u(1) /)
end subroutine func
"""
    + STPNT_HEAD
    + """  double precision :: s, e
  par(1:8) = (/ 0d0, 1d0, -2d0, 0d0, 1d0, 0d0, 0d0, 0d0 /)
  par(11) = 20d0
  par(12:14) = 0d0
  ! the closed-form orbit at a = 0, b = 1: x = 1 - tanh(s/2)^2, y = x'
  s = (t - 0.5d0) * par(11)
  e = exp(s)
  u(1) = 1d0 - ((1d0 - e) / (1d0 + e))**2
  u(2) = 4d0 * e * (1d0 - e) / (1d0 + e)**3
  u(3) = 0d0
end subroutine stpnt
"""
    + _STUBS
)

_SAN_BASE = {
    **AUTO_BASE,
    "NTST": 35,
    "IAD": 3,
    "JAC": -1,
    "ITMX": 9,
    "NPAR": 14,
    "IEQUIB": 0,
    "DS": 0.05,
    "DSMIN": 0.005,
    "DSMAX": 0.1,
}

SAN = Demo(
    key="san",
    title="Sandstede's model: mu~ at a = 0.25",
    state_names=("x", "y", "z"),
    params={
        "a": 0.25,
        "b": 1.0,
        "c": -2.0,
        "alpha": 0.0,
        "beta": 1.0,
        "gamma": 0.0,
        "mu": 0.0,
        "mu_t": 0.0,
    },
    auto_index={"a": 1, "b": 2, "c": 3, "alpha": 4, "beta": 5, "gamma": 6, "mu": 7, "mu_t": 8},
    solved="mu_t",
    second="alpha",
    rhs=_san_rhs,
    saddle=lambda p: np.zeros(3),
    fortran=_SAN_F90,
    auto_solve=[
        {**_SAN_BASE, "IRS": 0, "ICP": [1, 8], "NMX": 99999, "UZSTOP": {1: 0.25}},
    ],
    auto_continue={**_SAN_BASE, "ICP": [4, 8], "NMX": 50, "UZSTOP": {4: 1.0}},
    T=20.0,
)

DEMOS = {d.key: d for d in (KPR, CIR, SAN)}


def manifold_guess(
    demo: Demo,
    params: dict[str, float] | None = None,
    eps: float = 1e-6,
    t_max: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The saddle's 1-D unstable manifold, simulated and cut at its closest return.

    Starts at ``x_- + eps v_u`` (``v_u`` the unstable eigenvector, on the side
    ``demo.branch``), integrates (DOP853, ``rtol = 1e-10``, up to ``t_max``, default ``2 T``, or
    until the orbit is 10 away) and cuts at the closest return: the smallest distance to
    the saddle while the orbit, after its excursion, stays within 0.2 times the
    excursion's first maximum distance (beyond, it leaves again when the parameter is
    not exact). Returns ``(t, x)`` with ``t`` from 0, shapes (K,) and (K, 3).
    """
    vals = {**demo.params, **(params or {})}
    p = np.array([vals[k] for k in demo.params], dtype=float)
    s = demo.system()
    xs = demo.saddle(p)
    w, V = np.linalg.eig(np.asarray(s.jacobian(xs, p), dtype=float))
    v = np.real(V[:, int(np.argmax(w.real))])
    v = v / np.linalg.norm(v)
    if v[0] != 0:
        v = v * np.sign(v[0])
    x0 = xs + demo.branch * eps * v

    def escape(t: float, x: np.ndarray) -> float:
        return float(np.linalg.norm(x - xs)) - 10.0

    escape.terminal = True  # type: ignore[attr-defined]
    t_end = 2.0 * demo.T if t_max is None else t_max
    from continuation.ops import NUMPY_OPS

    def f(t: float, x: np.ndarray) -> np.ndarray:
        return np.asarray(demo.rhs(x, p, NUMPY_OPS), dtype=float)

    sol = solve_ivp(
        f,
        (0.0, t_end),
        x0,
        method="DOP853",
        rtol=1e-10,
        atol=1e-13,
        dense_output=True,
        events=escape,
    )
    t = np.linspace(0.0, sol.t[-1], 20001)
    X = sol.sol(t).T
    d = np.linalg.norm(X - xs, axis=1)
    up = np.flatnonzero((d[1:] < d[:-1]) & (d[:-1] > 100 * eps))
    if up.size == 0:
        raise ValueError(f"{demo.key}: the unstable manifold (side {demo.branch}) never turns back")
    k0 = int(up[0])  # the excursion's first maximum distance
    inside = d[k0:] < 0.2 * d[k0]
    if not inside.any():
        raise ValueError(f"{demo.key}: the unstable manifold (side {demo.branch}) does not return")
    k1 = k0 + int(np.argmax(inside))  # back within 0.2 x the first maximum distance
    out = np.flatnonzero(~inside[k1 - k0 :])
    k2 = k1 + (int(out[0]) if out.size else len(d) - k1)  # leaves that ball again
    k = k1 + int(np.argmin(d[k1:k2]))  # closest return in between
    return t[: k + 1], X[: k + 1]


def guess_on(
    t: np.ndarray, X: np.ndarray, T: float, K: int = 2001
) -> tuple[np.ndarray, np.ndarray]:
    """Place the orbit ``(t, X)`` on ``[0, T]``: its last ``T`` time units if longer,
    else padded at both ends with its end values (the saddle is approached there)."""
    d = float(t[-1] - t[0])
    tt = np.linspace(0.0, T, K)
    if d >= T:
        src = t[-1] - T + tt
    else:
        src = np.clip(tt - 0.5 * (T - d), 0.0, d) + t[0]
    Y = np.column_stack([np.interp(src, t, X[:, i]) for i in range(X.shape[1])])
    return tt, Y
