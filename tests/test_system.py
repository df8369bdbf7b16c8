"""Systems: exact (CasADi) derivatives against finite differences, linearisation, periods."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import TOY_SYSTEMS, bratu, fold_normal_form, periodic_sine

from continuation.api import continue_equilibria
from continuation.differentiation import fd_jacobian
from continuation.problem import EquilibriumProblem
from continuation.system import System, check_jacobian


def _sample(system, seed):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.1, 0.9, system.n_states)
    p = rng.uniform(0.2, 1.5, system.n_params)
    return x, p


@pytest.mark.parametrize("name", sorted(TOY_SYSTEMS))
def test_jacobians_match_finite_differences(name):
    system = TOY_SYSTEMS[name]()
    assert system.has_casadi
    for seed in range(3):
        x, p = _sample(system, seed)
        ex, ep = check_jacobian(system, x, p, rtol=1e-6)
        assert ex <= 1.0 and ep <= 1.0, (ex, ep)


@pytest.mark.parametrize("name", sorted(TOY_SYSTEMS))
def test_linearize_is_consistent(name):
    system = TOY_SYSTEMS[name]()
    x, p = _sample(system, 7)
    f, J, Jp = system.linearize(x, p)
    np.testing.assert_array_equal(f, system.f(x, p))
    np.testing.assert_allclose(J, system.jacobian(x, p), rtol=1e-15, atol=0)
    np.testing.assert_allclose(Jp, system.dfdp(x, p), rtol=1e-15, atol=0)
    f2, Js, Jp2 = system.linearize(x, p, sparse=True)
    np.testing.assert_allclose(Js.toarray(), J, rtol=1e-15, atol=0)
    np.testing.assert_allclose(system.jacobian_sparse(x, p).toarray(), J, rtol=1e-15, atol=0)
    # repeated calls do not share output memory
    f3 = system.linearize(x + 0.1, p)[0]
    assert not np.array_equal(f3, f)


def test_equilibrium_problem_derivatives():
    system = TOY_SYSTEMS["cstr"]()
    prob = EquilibriumProblem(system, system.params(Da=0.1), "Da")
    x, p = np.array([0.3, 1.2]), 0.12
    G, Gz, Gp = prob.linearize(x, p)
    np.testing.assert_array_equal(G, prob.residual(x, p))
    np.testing.assert_allclose(Gz, prob.jacobian(x, p), rtol=1e-15)
    fd_p = fd_jacobian(lambda q: prob.residual(x, q[0]), np.array([p]))[:, 0]
    np.testing.assert_allclose(Gp, fd_p, rtol=1e-8)
    np.testing.assert_allclose(prob.dp(x, p), Gp, rtol=1e-15)
    big = EquilibriumProblem(bratu(120), bratu(120).params(lam=1.0), "lam")
    assert big.sparse and big.linearize(np.zeros(120), 1.0)[1].format == "csc"


def test_numpy_only_system_uses_finite_differences():
    def rhs(x, p):
        return np.array([p[0] - x[0] ** 2])

    system = System(rhs, ("x",), ("mu",))
    assert not system.has_casadi
    ex, ep = check_jacobian(system, np.array([0.7]), np.array([0.2]))
    assert ex <= 1 and ep <= 1
    br = continue_equilibria(system, [1.0], {"mu": 1.0}, "mu", p_max=2.0)
    (f,) = br.find("fold")
    assert abs(f.p) < 1e-8


def test_periodic_difference():
    system = periodic_sine()
    two_pi = 2 * np.pi
    assert system.same_point(np.array([0.1]), np.array([0.1 + 3 * two_pi]))
    np.testing.assert_allclose(system.difference(np.array([0.1]), np.array([two_pi - 0.1])), 0.2)
    np.testing.assert_allclose(system.wrap(np.array([-0.1])), two_pi - 0.1)
    prob = EquilibriumProblem(system, system.params(mu=0.0), "mu")
    np.testing.assert_allclose(prob.difference(np.array([0.0]), np.array([two_pi])), 0.0)


def test_params_from_mapping_and_defaults():
    system = TOY_SYSTEMS["brusselator"]()
    np.testing.assert_array_equal(system.check_params({"B": 3.0}), [1.0, 3.0])
    with pytest.raises(ValueError, match="unknown parameter"):
        system.params(C=1.0)
    nodefault = fold_normal_form()
    with pytest.raises(ValueError, match="missing"):
        nodefault.params()


@pytest.mark.parametrize("name", sorted(TOY_SYSTEMS))
def test_fast_evaluators_match_linearize(name):
    """System.linearizer (per free parameter, dense and sparse) and
    System.bordered_evaluator give exactly the values of System.linearize."""
    system = TOY_SYSTEMS[name]()
    x, p = _sample(system, 3)
    n = system.n_states
    f, J, Jp = system.linearize(x, p)
    rng = np.random.default_rng(5)
    for k in range(system.n_params):
        q = p.copy()
        q[k] = 0.61
        f_q, J_q, Jp_q = system.linearize(x, q)
        for sparse in (False, True):
            lin = system.linearizer(k, p, sparse=sparse)
            g, Gz, Gp = lin(x, 0.61)
            Gz = Gz.toarray() if sparse else Gz
            np.testing.assert_array_equal(g, f_q)
            np.testing.assert_array_equal(Gz, J_q)
            np.testing.assert_array_equal(Gp, Jp_q[:, k])
            g2 = lin(x + 0.1, 0.61)[0]  # fresh output arrays at every call
            assert not np.array_equal(g2, g)
        ev = system.bordered_evaluator(k, p)
        c, h = rng.standard_normal(n + 1), 0.37
        ev.set_border(c, h)
        ev.u[:n], ev.u[n] = x, 0.61
        ev()
        u = np.append(x, 0.61)
        np.testing.assert_allclose(ev.r, np.append(f_q, c @ u - h), rtol=1e-15, atol=1e-15)
        np.testing.assert_array_equal(ev.M, np.block([[J_q, Jp_q[:, k : k + 1]], [c[None, :]]]))
        g, Gz, Gp = ev.lin()
        np.testing.assert_array_equal(Gz, J_q)
        np.testing.assert_array_equal(Gp, Jp_q[:, k])
    with pytest.raises(ValueError, match="index"):
        system.linearizer(system.n_params, p)


def test_fast_evaluators_absent_without_casadi():
    system = System(lambda x, p: np.array([p[0] - x[0] ** 2]), ("x",), ("mu",))
    prob = EquilibriumProblem(system, system.params(mu=1.0), "mu")
    assert prob.linearizer() is None and prob.bordered_evaluator() is None
    sparse = EquilibriumProblem(bratu(120), bratu(120).params(lam=1.0), "lam")
    assert sparse.bordered_evaluator() is None  # sparse problems: linearizer + SuperLU
    assert sparse.linearizer()(np.zeros(120), 1.0)[1].format == "csc"


def test_point_evaluations_agree_with_the_closed_form_in_concurrent_threads():
    # f, df/dx, df/dp at one point go through per-thread buffered evaluators: each
    # thread must get its own point's values (closed form), whatever the others do
    import threading

    def rhs(x, p, ops):
        return [p[0] * x[0] - x[0] ** 3 + x[1], ops.sin(x[0]) - p[1] * x[1]]

    s = System(rhs, ["x", "y"], ["a", "b"])
    errors: list[str] = []

    def work(seed: int) -> None:
        rng = np.random.default_rng(seed)
        for _ in range(300):
            x, p = rng.standard_normal(2), rng.standard_normal(2)
            f = [p[0] * x[0] - x[0] ** 3 + x[1], np.sin(x[0]) - p[1] * x[1]]
            J = [[p[0] - 3 * x[0] ** 2, 1.0], [np.cos(x[0]), -p[1]]]
            Jp = [[x[0], 0.0], [0.0, -x[1]]]
            for got, want in ((s.f(x, p), f), (s.jacobian(x, p), J), (s.dfdp(x, p), Jp)):
                if not np.allclose(got, want, rtol=1e-14, atol=1e-14):
                    errors.append(f"thread {seed}: {got} != {want}")

    import sys

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # switch threads as often as possible
    try:
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(old)
    assert not errors, errors[:3]
    with pytest.raises(RuntimeError):  # a wrong size is still CasADi's error
        s.f(np.zeros(3), np.zeros(2))
