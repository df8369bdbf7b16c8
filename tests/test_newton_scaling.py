"""The continuation corrector's acceptance tests are scale-aware.

* the step test is componentwise, ``|du_i| <= step_tol (|u_i| + min(1, ||u||_inf))``:
  a state of size ``1e-7`` is converged to ``step_tol`` relative accuracy, not to an
  absolute ``step_tol`` (which would be 1 % of it), and a parameter of size ``1e6`` does
  not loosen the test of an O(1) state;
* a stalled iteration with a residual above ``tol`` is accepted only at the round-off
  floor of the terms of ``G`` (normwise backward error ``<= 64 eps``), never at any
  residual;
* consequently one problem written in units that differ by powers of ten gives the
  same fold to ``rel 1e-9`` and rows that solve the equations.
"""

from __future__ import annotations

import numpy as np
import pytest

from continuation.algorithms.corrector import ROUNDOFF_FLOOR, _backward_error, correct
from continuation.api import continue_equilibria
from continuation.problem import EquilibriumProblem
from continuation.settings import NewtonSettings
from continuation.system import System


def _fold_normal_form() -> System:
    """f = mu S - x^2 / S: equilibria x = +-S sqrt(mu) for mu >= 0, none for mu < 0."""

    def rhs(x, p, ops):  # noqa: ANN001, ANN202
        return ops.stack([p[0] * p[1] - x[0] ** 2 / p[1]])

    return System(rhs, ("x",), ("mu", "S"))


class _Protocol:
    """The same problem through the protocol methods only (the corrector's generic path)."""

    def __init__(self, prob: EquilibriumProblem) -> None:
        self._p = prob
        self.free = prob.free
        self.n_unknowns = prob.n_unknowns

    def residual(self, z, p):  # noqa: ANN001, ANN201
        return self._p.residual(z, p)

    def jacobian(self, z, p):  # noqa: ANN001, ANN201
        return self._p.jacobian(z, p)

    def dp(self, z, p):  # noqa: ANN001, ANN201
        return self._p.dp(z, p)


def _problems(S: float) -> list:
    sys = _fold_normal_form()
    prob = EquilibriumProblem(sys, sys.params(mu=0.25, S=S), "mu")
    assert prob.bordered_evaluator() is not None
    return [prob, _Protocol(prob)]


@pytest.mark.parametrize("S", [1e-6, 1e-3, 1.0, 1e3])
def test_tiny_and_large_states_converge_to_relative_accuracy(S):
    """Natural constraint mu = 1/4, start 20 % off x = S / 2: the corrected state has
    relative error below step_tol whatever the unit of x, on both corrector paths (the
    scaled test must not cost convergence where the residual is O(S) or O(1 / S))."""
    e_p = np.array([0.0, 1.0])
    u0 = np.array([0.6 * S, 0.25])
    for problem in _problems(S):
        for exact in (True, False):
            res = correct(problem, u0, u0, e_p, 0.0, NewtonSettings(), exact=exact)
            assert res.converged
            assert res.p == 0.25
            assert res.z[0] == pytest.approx(0.5 * S, rel=1e-9)


@pytest.mark.parametrize("mu", [-5e-5, -1e-9])
def test_no_point_accepted_where_no_equilibrium_exists(mu):
    """f = mu S - x^2 / S with S = 1e-6 at mu < 0 (natural constraint): |f| <= 1e-10 holds
    for every x near 0, but there is no equilibrium; the corrector must fail, not return a
    row (with the absolute step test, corrections below 1e-8 were accepted)."""
    S = 1e-6
    e_p = np.array([0.0, 1.0])
    for problem in _problems(S):
        for x0 in (1e-9, -3e-9, 2e-11):
            u0 = np.array([x0, mu])
            res = correct(problem, u0, u0, e_p, 0.0, NewtonSettings(), exact=False)
            assert not res.converged


class _Quantised:
    """G(z, p) = round(z, 7) - p with the Jacobian 1: Newton stalls with |G| ~ 1e-8, far
    above round-off (1e-17), as a residual with an evaluation error or noise would."""

    free = "p"
    n_unknowns = 1

    def residual(self, z, p):  # noqa: ANN001, ANN201
        return np.array([np.round(z[0], 7) - p])

    def jacobian(self, z, p):  # noqa: ANN001, ANN201
        return np.array([[1.0]])

    def dp(self, z, p):  # noqa: ANN001, ANN201
        return np.array([-1.0])


def test_stalled_residual_above_round_off_is_not_accepted():
    """The stall ("the residual did not halve after a step below step_tol") was accepted
    at any residual; now only at the round-off floor of G's terms."""
    p = 0.123456789
    u0 = np.array([0.12, p])
    for exact in (True, False):
        res = correct(_Quantised(), u0, u0, np.array([0.0, 1.0]), 0.0, NewtonSettings(),
                      exact=exact)  # fmt: skip
        assert not res.converged
        assert res.residual_norm > 1e-9


def test_backward_error_is_relative_to_the_terms():
    """omega = max(||G|| / || |G_z| |z| + |G_p| |p| ||, |c.u - h| / (|c| . |u|)): the
    scale of a large parameter's term does not enter the floor of the other equations."""
    Gz = np.array([[2.0, 0.0], [0.0, 1e-6]])
    Gp = np.array([1e-6, 0.0])
    c = np.array([0.5, 0.5, 0.5])
    u = np.array([1.0, 3.0, 1e6])  # terms of row 1: 2 and 1 (not ||Gz|| ||u|| = 2e6)
    M = np.block([[Gz, Gp[:, None]], [c[None, :]]])
    r = np.array([3e-15, 0.0, 0.0])
    w = _backward_error(M, r, u)
    assert w == pytest.approx(3e-15 / 3.0, rel=1e-12)
    assert _backward_error(Gz, r, u, Gp, c) == pytest.approx(w, rel=1e-12)
    assert w <= ROUNDOFF_FLOOR
    assert _backward_error(M, np.array([1e-10, 0.0, 0.0]), u) > ROUNDOFF_FLOOR


@pytest.mark.parametrize("P", [1e-6, 1e-3, 1.0, 1e3, 1e6])
def test_fold_invariant_under_parameter_units(P):
    """f = mu / P - 1 - x^2 (fold at mu = P, x = 0), default steps when mu is the smaller
    unknown and steps scaled to mu when it is the larger one: for every unit P the fold
    is located at P to rel 1e-9 and every row solves f = 0 (with the former absolute
    step test, P = 1e6 gave rows with |f| = 7e-5 and no fold)."""
    s = System(lambda x, p, ops: ops.stack([p[0] / p[1] - 1 - x[0] ** 2]), ("x",), ("mu", "P"))
    steps = {"ds": P / 10, "ds_max": P} if P > 1 else {}
    br = continue_equilibria(
        s, [1.0], {"mu": 2 * P, "P": P}, "mu", p_min=-10 * P, p_max=10 * P, **steps
    )
    assert br.status.ok
    folds = [sp for sp in br.find("fold")]
    assert len(folds) == 1 and folds[0].located
    assert folds[0].p == pytest.approx(P, rel=1e-9)
    assert abs(folds[0].x[0]) <= 1e-4
    assert np.max(np.abs(br.p / P - 1 - br.x[:, 0] ** 2)) <= 1e-9
    # both sheets x = +-sqrt(mu/P - 1) are followed to the bound
    assert br.x[:, 0].min() < -2.9 and br.x[:, 0].max() > 0.99
