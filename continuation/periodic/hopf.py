r"""Starting a branch of cycles at a Hopf point of an equilibrium branch.

Near a Hopf point :math:`(x_H, p_H)` with critical eigenvalues :math:`\pm i\omega`,
eigenvectors :math:`A q = i\omega q`, :math:`A^T \bar p = -i\omega \bar p`,
:math:`\bar q^T q = \bar p^T q = 1`, the centre-manifold coordinate
:math:`x \approx x_0(p) + z q + \bar z \bar q` obeys the normal form
:math:`\dot z = (\alpha(p) + i\omega) z + c_1 z |z|^2` with
:math:`\mathrm{Re}\, c_1 = \omega l_1` (Kuznetsov 2004, *Elements of Applied Bifurcation
Theory*, 3rd ed., Sec. 3.5, eq. (3.20)). Its cycle has
:math:`|z|^2 = -\alpha(p) / (\omega l_1)`, :math:`\alpha(p) \approx \alpha'(p_H)
(p - p_H)`: the cycles exist for :math:`\mathrm{sign}(p - p_H) = -\mathrm{sign}(\alpha'
l_1)` (:math:`l_1 < 0`: supercritical, on the side where the equilibrium is unstable),
and the first-order cycle is

.. math:: x(\tau) = x_0(p) + 2\,\mathrm{Re}(|z| q e^{2\pi i \tau}), \qquad T = 2\pi/\omega .
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from ..branch import Branch, SpecialKind, SpecialPoint
from ..bvp.collocation import CollocationMesh
from ..params import Params
from ..settings import NewtonSettings
from ..typing import FloatArray
from .orbit import PeriodicOrbit
from .solve import solve_orbit


def _multilinear(system: Any) -> tuple[Any, Any]:
    """``B(x, P, u, v)`` and ``C(x, P, u, v, w)``, from the CasADi trace or differences.

    The second and third derivatives of ``f`` applied to real directions, from the CasADi
    trace, or by central differences.
    """
    cache = system.__dict__.setdefault("_periodic_multilinear", {})
    if "B" in cache:
        return cache["B"], cache["C"]
    n, m = system.n_states, system.n_params
    if getattr(system, "has_casadi", False):
        x, P = ca.SX.sym("x", n), ca.SX.sym("P", max(m, 0))
        u, v, w = ca.SX.sym("u", n), ca.SX.sym("v", n), ca.SX.sym("w", n)
        f = system.symbolic(x, P)
        d1 = ca.jtimes(f, x, u)
        d2 = ca.jtimes(d1, x, v)
        d3 = ca.jtimes(d2, x, w)
        Bf = ca.Function("B", [x, P, u, v], [d2])
        Cf = ca.Function("C", [x, P, u, v, w], [d3])

        def B(x0: FloatArray, p0: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
            return np.asarray(Bf(x0, p0, a, b), dtype=float).reshape(-1)

        def C(x0: Any, p0: Any, a: Any, b: Any, c: Any) -> FloatArray:
            return np.asarray(Cf(x0, p0, a, b, c), dtype=float).reshape(-1)

    else:
        h = 1e-4

        def B(x0: FloatArray, p0: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
            f = system.f
            return (f(x0 + h * (a + b), p0) - f(x0 + h * (a - b), p0)
                    - f(x0 - h * (a - b), p0) + f(x0 - h * (a + b), p0)) / (4 * h * h)  # fmt: skip

        def C(x0: Any, p0: Any, a: Any, b: Any, c: Any) -> FloatArray:
            return (B(x0 + h * c, p0, a, b) - B(x0 - h * c, p0, a, b)) / (2 * h)

    cache["B"], cache["C"] = B, C
    return B, C


def _critical(J: FloatArray, omega: float | None) -> tuple[float, np.ndarray, np.ndarray]:
    eigs, V = np.linalg.eig(J)
    cand = np.flatnonzero(eigs.imag > 1e-12 * max(1.0, float(np.max(np.abs(eigs)))))
    if cand.size == 0:
        raise ValueError("the Jacobian at the Hopf point has no complex eigenvalue pair")
    if omega is not None:
        k = int(cand[np.argmin(np.abs(eigs[cand] - 1j * omega))])
    else:
        k = int(cand[np.argmin(np.abs(eigs[cand].real))])
    om = float(eigs[k].imag)
    q = V[:, k] / np.linalg.norm(V[:, k])
    el, W = np.linalg.eig(J.T)
    j = int(np.argmin(np.abs(el + 1j * om)))
    pv = W[:, j]
    pv = pv / np.conj(np.vdot(pv, q))  # conj(p)^T q = 1
    return om, q, pv


def first_lyapunov_coefficient(
    system: Any, x: Any, params: Any, omega: float | None = None
) -> float:
    r"""First Lyapunov coefficient :math:`l_1` at a Hopf point (Kuznetsov eq. (3.20)).

    .. math::

        l_1 = \frac{1}{2\omega}\mathrm{Re}\big[\langle p, C(q,q,\bar q)\rangle
        - 2\langle p, B(q, A^{-1} B(q,\bar q))\rangle
        + \langle p, B(\bar q, (2i\omega - A)^{-1} B(q,q))\rangle\big]

    with ``<q, q> = <p, q> = 1``. Negative: supercritical (stable small cycles).
    """
    x = system.check_state(x, "x")
    P = system.check_params(params, "params")
    J = np.asarray(system.jacobian(x, P), dtype=float)
    om, q, pv = _critical(J, omega)
    B, C = _multilinear(system)
    a, b = q.real, q.imag

    def Bc(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        ur, ui, vr, vi = u.real, u.imag, v.real, v.imag
        return (B(x, P, ur, vr) - B(x, P, ui, vi)) + 1j * (B(x, P, ur, vi) + B(x, P, ui, vr))

    Cqqqb = C(x, P, a, a, a) + C(x, P, a, b, b) + 1j * (C(x, P, a, a, b) + C(x, P, b, b, b))
    h11 = np.linalg.solve(J, Bc(q, q.conj()).real)
    h20 = np.linalg.solve(2j * om * np.eye(J.shape[0]) - J, Bc(q, q))
    val = np.vdot(pv, Cqqqb) - 2 * np.vdot(pv, Bc(q, h11.astype(complex)))
    val = val + np.vdot(pv, Bc(q.conj(), h20))
    return float(val.real / (2 * om))


def _hopf_point(branch: Branch, which: Any) -> SpecialPoint:
    if isinstance(which, SpecialPoint):
        return which
    hopfs = branch.find(SpecialKind.HOPF)
    if isinstance(which, str):
        for sp in hopfs:
            if sp.label == which:
                return sp
        raise ValueError(f"no Hopf point {which!r} on the branch; it has "
                         f"{[s.label for s in hopfs]}")  # fmt: skip
    if isinstance(which, int) and 0 <= which < len(hopfs):
        return hopfs[which]
    raise ValueError(f"`which` must be a Hopf label, index or SpecialPoint, got {which!r}")


def periodic_orbit_from_hopf(
    branch: Branch,
    which: str | int | SpecialPoint = 0,
    *,
    amplitude: float = 1e-2,
    mesh: CollocationMesh | None = None,
    correct: bool = True,
    newton: NewtonSettings | None = None,
) -> PeriodicOrbit:
    """A small cycle born at a located Hopf point of an equilibrium branch.

    Parameters
    ----------
    branch : Branch
        An equilibrium branch (its ``problem`` has ``system``, ``params``, ``free``).
    which : str, int or SpecialPoint
        The Hopf point: its label (``"H1"``), its index among the Hopf points, or the
        point itself.
    amplitude : float
        Largest Euclidean distance of the first-order cycle from the equilibrium; the
        parameter offset follows from the normal form (module doc).
    mesh : CollocationMesh, optional
        Default 40 intervals of degree 4.
    correct : bool
        Correct the guess by Newton's method (:func:`solve_orbit`).
    newton : NewtonSettings, optional

    Returns
    -------
    PeriodicOrbit
        Its ``params`` hold the free parameter at ``p_H + delta p``.

    Raises
    ------
    ValueError
        Bad arguments, a Hopf point that was not located, or a degenerate one
        (``l_1 = 0`` or no transversal crossing): the side of the cycles is unknown.
    """
    if not (isinstance(amplitude, int | float) and math.isfinite(amplitude) and amplitude > 0):
        raise ValueError(f"`amplitude` must be a positive number, got {amplitude!r}")
    sp = _hopf_point(branch, which)
    if not sp.located:
        raise ValueError(f"the Hopf point {sp.label!r} was bracketed, not located")
    prob = branch.problem
    if prob is None or not hasattr(prob, "system") or not hasattr(prob, "param_vector"):
        raise ValueError(
            "`branch` must be an equilibrium branch with its problem (a loaded branch has "
            "none: pass problem= to Branch.load)"
        )
    system, free = prob.system, branch.free
    x_h = np.asarray(sp.x, dtype=float)
    P_h = np.array(prob.param_vector(sp.p), dtype=float)
    ip = system.param_names.index(free)
    omega0 = float(sp.data.get("omega", math.nan))
    J = np.asarray(system.jacobian(x_h, P_h), dtype=float)
    om, q, _ = _critical(J, omega0 if math.isfinite(omega0) else None)
    l1 = first_lyapunov_coefficient(system, x_h, P_h, om)
    # alpha'(p_H) and dx/dp along the equilibrium branch (tangent at the point)
    tan = sp.tangent
    if tan is None or abs(float(tan[-1])) < 1e-12:
        raise ValueError(f"the Hopf point {sp.label!r} has no usable branch tangent")
    dxdp = np.asarray(tan[:-1], dtype=float) / float(tan[-1])
    dp = 1e-5 * max(1.0, abs(sp.p))

    def alpha(s: float) -> float:
        P = P_h.copy()
        P[ip] += s
        ev = np.linalg.eigvals(np.asarray(system.jacobian(x_h + s * dxdp, P), dtype=float))
        return float(ev[np.argmin(np.abs(ev - 1j * om))].real)

    dalpha = (alpha(dp) - alpha(-dp)) / (2 * dp)
    if not (abs(l1) > 1e-12 and abs(dalpha) > 1e-12):
        raise ValueError(
            f"degenerate Hopf point {sp.label!r} (l1={l1:.3g}, dRe(lambda)/dp={dalpha:.3g}): "
            "the side of the cycles is not determined"
        )
    s = np.linspace(0.0, 2 * np.pi, 64, endpoint=False)
    peak = float(np.max(np.linalg.norm(2 * np.real(q[None, :] * np.exp(1j * s)[:, None]),
                                       axis=1)))  # fmt: skip
    zabs = amplitude / peak
    delta = -om * l1 * zabs**2 / dalpha
    mesh = mesh if mesh is not None else CollocationMesh(40, 4, 1.0)
    tau = mesh.tau
    x0 = x_h + delta * dxdp
    X = x0[None, :] + 2 * np.real(zabs * q[None, :] * np.exp(2j * np.pi * tau)[:, None])
    P = P_h.copy()
    P[ip] += delta
    orb = PeriodicOrbit(system, Params(system.param_names, P), mesh, X, 2 * np.pi / om)
    return solve_orbit(orb, free, newton) if correct else orb


__all__ = ["first_lyapunov_coefficient", "periodic_orbit_from_hopf"]
