"""Shared test helpers: toy systems with exactly known bifurcations, and the branch
invariants every run must satisfy.

Each factory returns a :class:`continuation.system.System` whose right-hand side is
written once against ``ops`` (so it has exact CasADi Jacobians). The known answers
are given in the docstrings; tests assert against them. Test modules import these
from here (``from helpers import ...``); ``conftest.py`` holds only the fixtures.
"""

from __future__ import annotations

import math

import numpy as np

from continuation.branch import SpecialKind
from continuation.system import System

#: The paper's 10 degree course (rad), where the ship tests place the heteroclinic Fn.
CHI10 = math.radians(10.0)


def fold_normal_form() -> System:
    """x' = mu - x**2: fold at (x, mu) = (0, 0); x = +sqrt(mu) stable."""
    return System(lambda x, p, ops: ops.stack([p[0] - x[0] ** 2]), ("x",), ("mu",), name="fold")


def hopf_normal_form() -> System:
    """Hopf normal form; equilibrium 0 with eigenvalues mu +- i: Hopf at mu=0, omega=1.

    x' = mu x - y - x (x^2 + y^2),  y' = x + mu y - y (x^2 + y^2).
    """

    def rhs(x, p, ops):
        r2 = x[0] ** 2 + x[1] ** 2
        return ops.stack([p[0] * x[0] - x[1] - x[0] * r2, x[0] + p[0] * x[1] - x[1] * r2])

    return System(rhs, ("x", "y"), ("mu",), name="hopf")


def transcritical() -> System:
    """x' = mu x - x**2: branches x=0 and x=mu cross at mu=0 (transcritical BP)."""
    return System(
        lambda x, p, ops: ops.stack([p[0] * x[0] - x[0] ** 2]), ("x",), ("mu",), name="tc"
    )


def pitchfork() -> System:
    """x' = mu x - x**3: supercritical pitchfork at mu=0 on the branch x=0."""
    return System(
        lambda x, p, ops: ops.stack([p[0] * x[0] - x[0] ** 3]), ("x",), ("mu",), name="pf"
    )


def pitchfork_2d() -> System:
    """Pitchfork in x plus a stable passive state: x' = mu x - x^3, y' = -y + x^2."""
    return System(
        lambda x, p, ops: ops.stack([p[0] * x[0] - x[0] ** 3, -x[1] + x[0] ** 2]),
        ("x", "y"),
        ("mu",),
        name="pf2",
    )


def brusselator() -> System:
    """Brusselator x' = A - (B+1) x + x^2 y, y' = B x - x^2 y.

    Equilibrium (A, B/A); Hopf at B = 1 + A^2 with omega = A
    (Lefever & Prigogine 1968; Nicolis & Prigogine 1977, Self-Organization in
    Nonequilibrium Systems, Wiley, Ch. 7).
    """

    def rhs(x, p, ops):
        A, B = p[0], p[1]
        return ops.stack([A - (B + 1) * x[0] + x[0] ** 2 * x[1], B * x[0] - x[0] ** 2 * x[1]])

    return System(rhs, ("x", "y"), ("A", "B"), defaults={"A": 1.0, "B": 1.0}, name="bruss")


def cstr() -> System:
    """Exothermic CSTR, A -> B (Uppal, Ray & Poore 1974; AUTO-07p demo ``ab``).

    u1' = -u1 + Da (1 - u1) exp(u2)
    u2' = -u2 + Da B (1 - u1) exp(u2) - beta u2
    """

    def rhs(x, p, ops):
        Da, B, beta = p[0], p[1], p[2]
        e = Da * (1 - x[0]) * ops.exp(x[1])
        return ops.stack([-x[0] + e, -x[1] + B * e - beta * x[1]])

    return System(
        rhs, ("u1", "u2"), ("Da", "B", "beta"), defaults={"Da": 0.0, "B": 14.0, "beta": 2.0}
    )


def selkov() -> System:
    """Sel'kov glycolysis model x' = -x + a y + x^2 y, y' = b - a y - x^2 y.

    Equilibrium (b, b / (a + b^2)); Hopf where the trace vanishes:
    b^2 = (1 - 2a +- sqrt(1 - 8a)) / 2 (Strogatz 2015, Nonlinear Dynamics and Chaos,
    2nd ed., Example 7.3.2).
    """

    def rhs(x, p, ops):
        a, b = p[0], p[1]
        return ops.stack([-x[0] + a * x[1] + x[0] ** 2 * x[1], b - a * x[1] - x[0] ** 2 * x[1]])

    return System(rhs, ("x", "y"), ("a", "b"), defaults={"a": 0.08, "b": 0.2})


def bratu(n: int) -> System:
    """Finite-difference Bratu problem -u'' = lam exp(u), u(0) = u(1) = 0, n interior nodes.

    ``f_i = (u_{i-1} - 2 u_i + u_{i+1}) / h^2 + lam exp(u_i)``, ``h = 1 / (n + 1)``.
    The discrete fold ``lam*_h`` converges at second order to the continuous
    ``lam* = 3.513830719125161``.
    """
    h2 = (1.0 / (n + 1)) ** 2

    def rhs(x, p, ops):
        out = []
        for i in range(n):
            left = x[i - 1] if i > 0 else 0.0
            right = x[i + 1] if i < n - 1 else 0.0
            out.append((left - 2 * x[i] + right) / h2 + p[0] * ops.exp(x[i]))
        return ops.stack(out)

    return System(rhs, tuple(f"u{i}" for i in range(n)), ("lam",), name=f"bratu{n}")


def bratu_branch(n: int, **options):
    """The Bratu equilibria (:func:`bratu`, ``n`` nodes) continued in ``lam`` from
    ``u = 0`` at ``lam = 0``; ``options`` go to ``continue_equilibria``."""
    from continuation.api import continue_equilibria

    return continue_equilibria(bratu(n), np.zeros(n), {"lam": 0.0}, "lam", **options)


def circle() -> System:
    """x' = x^2 + mu^2 - 1: the equilibria form the closed curve x^2 + mu^2 = 1."""
    return System(lambda x, p, ops: ops.stack([x[0] ** 2 + p[0] ** 2 - 1]), ("x",), ("mu",))


def periodic_sine() -> System:
    """theta' = mu - sin(theta), theta periodic (2 pi): a closed branch on the cylinder.

    Folds at (theta, mu) = (pi/2, 1) and (3 pi/2, -1).
    """
    return System(
        lambda x, p, ops: ops.stack([p[0] - ops.sin(x[0])]),
        ("theta",),
        ("mu",),
        periodic={"theta": 2 * np.pi},
    )


def lorenz84() -> System:
    """Lorenz-84 model (Lorenz 1984; Shil'nikov, Nicolis & Nicolis 1995).

    x' = -y^2 - z^2 - a x + a F, y' = x y - b x z - y + G, z' = b x y + x z - z.
    """

    def rhs(x, p, ops):
        a, b, F, G = p[0], p[1], p[2], p[3]
        X, Y, Z = x[0], x[1], x[2]
        return ops.stack(
            [-(Y**2) - Z**2 - a * X + a * F, X * Y - b * X * Z - Y + G, b * X * Y + X * Z - Z]
        )

    return System(
        rhs,
        ("X", "Y", "Z"),
        ("a", "b", "F", "G"),
        defaults={"a": 0.25, "b": 4.0, "F": 2.0, "G": 0.2},
    )


TOY_SYSTEMS = {
    "fold": fold_normal_form,
    "hopf": hopf_normal_form,
    "transcritical": transcritical,
    "pitchfork": pitchfork,
    "pitchfork_2d": pitchfork_2d,
    "brusselator": brusselator,
    "cstr": cstr,
    "selkov": selkov,
    "circle": circle,
    "periodic_sine": periodic_sine,
    "lorenz84": lorenz84,
    "bratu10": lambda: bratu(10),
}


def brusselator_rd(N: int, D1: float, D2: float) -> System:
    """Brusselator on [0, 1] with Dirichlet data (A, B/A), second-order differences."""
    h2 = (1.0 / (N + 1)) ** 2

    def rhs(x, p, ops):
        A, B = p[0], p[1]
        out = []
        for i in range(N):
            ul = x[i - 1] if i > 0 else A
            ur = x[i + 1] if i < N - 1 else A
            u, v = x[i], x[N + i]
            out.append(D1 * (ul - 2 * u + ur) / h2 + A - (B + 1) * u + u * u * v)
        for i in range(N):
            vl = x[N + i - 1] if i > 0 else B / A
            vr = x[N + i + 1] if i < N - 1 else B / A
            u, v = x[i], x[N + i]
            out.append(D2 * (vl - 2 * v + vr) / h2 + B * u - u * u * v)
        return ops.stack(out)

    names = tuple(f"u{i}" for i in range(N)) + tuple(f"v{i}" for i in range(N))
    return System(rhs, names, ("A", "B"))


def vdp_period(mu: float) -> float:
    """Period of the van der Pol cycle, an independent reference: the time between upward
    zero crossings of x by SciPy's DOP853 at rtol = atol = 1e-12, after the transient
    from (2, 0)."""
    from scipy.integrate import solve_ivp

    f = lambda t, x: [x[1], mu * (1 - x[0] ** 2) * x[1] - x[0]]  # noqa: E731
    up = lambda t, x: x[0]  # noqa: E731
    up.direction = 1
    r = solve_ivp(f, (0.0, 6 * (3 + 1.7 * mu)), [2.0, 0.0], method="DOP853", rtol=1e-12,
                  atol=1e-12, events=up)  # fmt: skip
    return float(np.diff(r.t_events[0])[-1])


def pendulum_loop_returns(I: float, gamma: float) -> float:
    """+1 if the saddle's unstable manifold of the driven pendulum
    ``theta'' + gamma theta' + sin(theta) = I`` passes the next saddle (theta + 2 pi),
    -1 if it falls back (v = 0 first): the sign whose change is the homoclinic orbit
    (an independent shooting computation, tight tolerances)."""
    import math

    from scipy.integrate import solve_ivp

    ths = math.pi - math.asin(I)
    J = np.array([[0.0, 1.0], [-math.cos(ths), -gamma]])
    w, V = np.linalg.eig(J)
    v = V[:, int(np.argmax(w.real))].real
    v = v if v[1] > 0 else -v
    ev1 = lambda t, x: x[0] - (ths + 2 * math.pi)  # noqa: E731
    ev1.terminal = True
    ev2 = lambda t, x: x[1]  # noqa: E731
    ev2.terminal, ev2.direction = True, -1
    r = solve_ivp(lambda t, x: [x[1], I - gamma * x[1] - math.sin(x[0])], (0, 200),
                  np.array([ths, 0.0]) + 1e-9 * v, events=[ev1, ev2], rtol=1e-12,
                  atol=1e-14, method="DOP853")  # fmt: skip
    return 1.0 if r.t_events[0].size else -1.0


def assert_invariants(br, tol=1e-9):
    """Branch invariants that must hold on every run."""
    prob = br.problem
    for k in range(len(br)):
        assert np.max(np.abs(prob.residual(br.x[k], br.p[k]))) < tol
    s = br.arclength
    sp_idx = {sp.index for sp in br.special_points}
    for k in range(len(br) - 1):
        if br.n_unstable[k] != br.n_unstable[k + 1]:
            assert k in sp_idx, f"saddle index changes at row {k} without a special point"
    for sp in br.special_points:
        if sp.located:
            assert s[sp.index] - 1e-12 <= sp.s <= s[sp.index + 1] + 1e-12
            assert np.max(np.abs(prob.residual(sp.x, sp.p))) < tol
            # (documented in continuation.branch: not for a fold, nor for any point in
            # a step that holds a fold, where p is not monotone)
            folds = {f.index for f in br.special_points if f.kind is SpecialKind.FOLD}
            if sp.kind is not SpecialKind.FOLD and sp.index not in folds:
                lo, hi = sorted(sp.bracket)
                assert lo - 1e-12 <= sp.p <= hi + 1e-12
        assert sp.bracket == (br.p[sp.index], br.p[sp.index + 1])


def chua_rhs(x, p, ops):
    r"""Chua's circuit with the smooth cubic-like nonlinearity of AUTO-07p's demo ``chu``
    (``demos/chu/chu.f90``; Khibnik, Roose & Chua 1993): parameters
    ``(alpha, beta, K, a0, a1)``,

    .. math::

        x' = \alpha (y - h(x)),\quad y' = x - y + z,\quad z' = -\beta y,\qquad
        h(x) = a_1 x + \tfrac12 (a_0 - a_1)(|x + 1|_K - |x - 1|_K),

    with the smooth absolute value :math:`|u|_K = (2/\pi)\, u \arctan(K u)`.
    """
    al, be, K, a0, a1 = p[0], p[1], p[2], p[3], p[4]

    def ab(u):
        return 2 * u * ops.arctan(K * u) / math.pi

    h = a1 * x[0] + 0.5 * (a0 - a1) * (ab(x[0] + 1) - ab(x[0] - 1))
    return ops.stack([al * (x[1] - h), x[0] - x[1] + x[2], -be * x[1]])
