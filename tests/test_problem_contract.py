"""Every problem class of the engine keeps the contract of continuation.problem.

:func:`continuation.check.check_problem` runs over one instance of each class the
driver continues (equilibria dense and sparse, codim-2 fold and Hopf curves with
exact and finite-difference derivatives, periodic orbits, connecting orbits,
landing orbits), at a point on (or next to) its branch: shapes, ``G_z`` and ``G_p``
against central differences within their error bound, the fast paths against the
plain methods, and the hooks. The negative tests show the check fails where the
contract is broken (a wrong Jacobian entry, a wrong shape, a stale fast path).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from helpers import brusselator_rd, cstr, hopf_normal_form

from continuation.bvp import CollocationMesh, solve_connection
from continuation.bvp.connection import HeteroclinicProblem
from continuation.bvp.landing import LandingProblem
from continuation.bvp.landing_solve import ContinuedLanding, solve_landing
from continuation.bvp.solve import ContinuedConnection
from continuation.check import check_problem
from continuation.codim2 import FoldProblem, HopfProblem
from continuation.periodic import orbit_from_array
from continuation.periodic.problem import PeriodicOrbitProblem
from continuation.problem import EquilibriumProblem
from continuation.system import System


def _cusp(x, p, ops):
    return ops.stack([p[0] + p[1] * x[0] - x[0] ** 3])


def _brusselator(x, p, ops):
    A, B = p[0], p[1]
    return ops.stack([A - (B + 1) * x[0] + x[0] ** 2 * x[1], B * x[0] - x[0] ** 2 * x[1]])


def _equilibria() -> tuple[Any, np.ndarray, float]:
    s = cstr()
    return EquilibriumProblem(s, s.params(Da=0.1), "Da"), np.array([0.3, 1.2]), 0.1


def _equilibria_sparse() -> tuple[Any, np.ndarray, float]:
    s = brusselator_rd(6, 0.02, 0.04)
    z = np.concatenate([np.full(6, 2.0), np.full(6, 2.4)]) + 0.01 * np.arange(12)
    return EquilibriumProblem(s, s.params(A=2.0, B=4.8), "B", sparse=True), z, 4.8


def _fold(exact: bool) -> tuple[Any, np.ndarray, float]:
    if exact:
        s = System(_cusp, ("x",), ("b1", "b2"))
    else:
        s = System(lambda x, p: np.array([p[0] + p[1] * x[0] - x[0] ** 3]), ("x",), ("b1", "b2"))
    x = 0.8
    prob = FoldProblem.from_state(s, s.params(b1=-2 * x**3 + 0.02, b2=3 * x**2), "b1", "b2",
                                  [x + 0.02])  # fmt: skip
    return prob, np.asarray(prob.z0), float(prob.p0)


def _hopf() -> tuple[Any, np.ndarray, float]:
    s = System(_brusselator, ("x", "y"), ("A", "B"))
    A, B = 1.0, 2.03
    prob = HopfProblem.from_state(s, s.params(A=A, B=B), "B", "A", [A, B / A])
    return prob, np.asarray(prob.z0), float(prob.p0)


def _periodic() -> tuple[Any, np.ndarray, float]:
    s = hopf_normal_form()
    mu = 0.25
    t = np.linspace(0.0, 2 * np.pi, 60)
    r = np.sqrt(mu)
    X = np.column_stack([r * np.cos(t), r * np.sin(t)])
    orb = orbit_from_array(s, {"mu": mu}, t, X, mesh=CollocationMesh(8, 3, 1.0))
    prob = PeriodicOrbitProblem.from_orbit(orb, "mu")
    z = np.array(prob.reference, dtype=float)
    z[:-1] *= 1.0 + 0.01 * np.sin(np.arange(z.size - 1))  # off the branch: G != 0
    return prob, z, mu


def _connection() -> tuple[Any, np.ndarray, float]:
    def rhs(x, p, ops):
        a, c = p[0], p[1]
        return ops.stack([x[1], -c * x[1] - x[0] * (1 - x[0]) * (x[0] - a)])

    s = System(rhs, ("u", "v"), ("a", "c"))
    T = 30.0
    prob = HeteroclinicProblem(s, s.params(a=0.25, c=0.3), "c", saddle_from=[1.0, 0.0],
                               saddle_to=[0.0, 0.0], mesh=CollocationMesh(20, 3, T))  # fmt: skip
    t = np.linspace(0, T, 100)
    u = 1 / (1 + np.exp((t - T / 2) / 1.5))
    res = solve_connection(prob, (t, np.column_stack([u, np.gradient(u, t)])))
    assert res.success
    cont = ContinuedConnection(res.problem.with_vary("a"))
    return cont, np.asarray(res.z), 0.25


def _landing() -> tuple[Any, np.ndarray, float]:
    def rhs(x, p, ops):
        return ops.stack([x[0] - p[0] + x[1] ** 2, -x[1]])

    s = System(rhs, ("u", "y"), ("p",))
    T = 2.0
    prob = LandingProblem(s, {"p": 0.3}, "p", start=lambda v: [v, 1.0], saddle=[0.3, 0.0],
                          T=T, s=0.1, start_name="s")  # fmt: skip
    t = np.linspace(0.0, T, 40)
    from continuation.bvp import ConnectionAccuracy

    r = solve_landing(prob, (t, np.column_stack([0 * t, np.exp(-t)])),
                      accuracy=ConnectionAccuracy(estimate=False))  # fmt: skip
    assert r.success
    return ContinuedLanding(r.problem), np.asarray(r.z), 0.1


CASES: dict[str, Callable[[], tuple[Any, np.ndarray, float]]] = {
    "equilibria": _equilibria,
    "equilibria-sparse": _equilibria_sparse,
    "fold-curve": lambda: _fold(True),
    "fold-curve-fd": lambda: _fold(False),
    "hopf-curve": _hopf,
    "periodic-orbit": _periodic,
    "connection": _connection,
    "landing": _landing,
}


@pytest.mark.parametrize("name", list(CASES))
def test_every_problem_keeps_the_contract(name):
    problem, z, p = CASES[name]()
    rep = check_problem(problem, z, p)
    assert rep.ok, rep.failures
    assert rep.jacobian_ratio <= 10.0 and rep.dp_ratio <= 10.0


def test_check_finds_a_wrong_derivative_and_a_wrong_shape():
    """The check can fail: a Jacobian entry off by 1e-4 relative, dG/dp with an entry
    too many, and a linearize fast path that disagrees with the plain methods."""
    prob, z, p = _equilibria()

    @dataclasses.dataclass(frozen=True)
    class WrongJacobian(EquilibriumProblem):
        def jacobian(self, z, p):
            J = np.array(super().jacobian(z, p), dtype=float)
            J[1, 0] *= 1.0 + 1e-4
            return J

        def linearize(self, z, p):
            return self.residual(z, p), self.jacobian(z, p), self.dp(z, p)

        def linearizer(self):
            return None

        def bordered_evaluator(self):
            return None

    @dataclasses.dataclass(frozen=True)
    class WrongShape(EquilibriumProblem):
        def dp(self, z, p):
            return np.append(super().dp(z, p), 0.0)

    @dataclasses.dataclass(frozen=True)
    class StaleFastPath(EquilibriumProblem):
        def linearize(self, z, p):
            G, J, Gp = super().linearize(z, p)
            return G, J, 2.0 * Gp

    base = dict(system=prob.system, params=prob.params, free="Da")
    bad = check_problem(WrongJacobian(**base), z, p)
    assert not bad.ok and bad.jacobian_ratio > 10.0 and "jacobian" in bad.failures[0]
    assert bad.dp_ratio <= 10.0
    bad = check_problem(WrongShape(**base), z, p)
    assert not bad.ok and "dp has shape (3,)" in bad.failures[0]
    bad = check_problem(StaleFastPath(**base), z, p)
    assert bad.failures == ("linearize differs from (residual, jacobian, dp)",)


def test_driver_runs_the_life_cycle_hooks():
    """``accept(z, p)`` once per accepted row (start included, in order, before
    ``progress``) and ``relabel`` once on the finished branch's special points."""
    from helpers import fold_normal_form

    from continuation.driver import continue_branch
    from continuation.settings import ContinuationSettings

    calls: list[tuple[str, float]] = []

    @dataclasses.dataclass(frozen=True)
    class Hooked(EquilibriumProblem):
        def accept(self, z, p):
            calls.append(("accept", float(p)))

        def relabel(self, specials):
            calls.append(("relabel", float(len(specials))))
            return tuple(dataclasses.replace(s, label=f"my{s.label}") for s in specials)

    s = fold_normal_form()
    prob = Hooked(s, s.params(mu=1.0), "mu")
    seen: list[float] = []
    br = continue_branch(prob, [1.0], 1.0, settings=ContinuationSettings(ds=-0.1, max_steps=30),
                         progress=lambda bp: seen.append(float(bp.p)))  # fmt: skip
    accepted = [p for k, p in calls if k == "accept"]
    np.testing.assert_array_equal(accepted, br.p)
    assert seen == accepted
    assert [k for k, _ in calls].count("relabel") == 1 and calls[-1][0] == "relabel"
    (fold,) = br.find("fold")
    assert fold.label == "myF1" and fold.p == pytest.approx(0.0, abs=1e-8)
