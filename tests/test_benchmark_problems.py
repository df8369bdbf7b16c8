"""Correctness of the continuation-benchmark problems and of the SciPy PALC baseline.

No timing here: ``benchmarks/run_continuation.py`` measures; these tests check that what
it measures is right.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.optimize as opt
import scipy.sparse as sp

# ``benchmarks`` is a folder of the repository, not an installed package
_ROOT = str(Path(__file__).resolve().parents[1])
if _ROOT not in sys.path:
    sys.path.insert(0, _ROOT)

from benchmarks.problems import (  # noqa: E402
    BRATU_CONTINUOUS_FOLD,
    BRUSSELATOR_A,
    all_problems,
    bratu,
    bratu_fold,
    brusselator,
    cubic8,
    cubic8_equilibrium,
)
from benchmarks.scipy_palc import palc, palc_problem  # noqa: E402
from continuation.differentiation import fd_jacobian  # noqa: E402

PROBLEMS = all_problems()


def _dense(a):
    return a.toarray() if sp.issparse(a) else np.asarray(a)


@pytest.fixture(scope="module")
def systems():
    return {k: p.system() for k, p in PROBLEMS.items()}


# ----------------------------------------------------------------- problem definitions
@pytest.mark.parametrize("name", list(PROBLEMS))
def test_numpy_and_casadi_forms_agree(name, systems):
    """The vectorised NumPy f/jac/dfdp equal the CasADi trace of the same rhs."""
    prob, s = PROBLEMS[name], systems[name]
    rng = np.random.default_rng(1)
    pv = prob.param_vector()
    for _ in range(3):
        x = prob.x0 + 0.3 * rng.standard_normal(prob.n)
        scale = 1.0 + np.max(np.abs(prob.f(x, pv)))
        np.testing.assert_allclose(prob.f(x, pv), s.f(x, pv), rtol=1e-13, atol=1e-13 * scale)
        np.testing.assert_allclose(
            _dense(prob.jac(x, pv)), s.jacobian(x, pv), rtol=1e-13, atol=1e-13 * scale
        )
        np.testing.assert_allclose(
            prob.dfdp(x, pv), s.dfdp(x, pv)[:, prob.free_index], rtol=1e-13, atol=1e-15
        )


@pytest.mark.parametrize("name", list(PROBLEMS))
def test_jacobians_against_central_differences(name):
    prob = PROBLEMS[name]
    rng = np.random.default_rng(2)
    pv = prob.param_vector()
    x = prob.x0 + 0.2 * rng.standard_normal(prob.n)
    J = _dense(prob.jac(x, pv))
    Jfd = fd_jacobian(lambda y: prob.f(y, pv), x)
    assert np.max(np.abs(J - Jfd)) <= 1e-6 * max(1.0, np.max(np.abs(J)))

    def f_of_p(q):
        v = pv.copy()
        v[prob.free_index] = q[0]
        return prob.f(x, v)

    dp_fd = fd_jacobian(f_of_p, np.array([prob.p0]))[:, 0]
    np.testing.assert_allclose(prob.dfdp(x, pv), dp_fd, rtol=1e-6, atol=1e-8)


@pytest.mark.parametrize("name", list(PROBLEMS))
def test_start_point_is_an_equilibrium(name):
    prob = PROBLEMS[name]
    assert np.max(np.abs(prob.f(prob.x0, prob.param_vector()))) < 1e-12
    assert prob.p_min < prob.p0 < prob.p_max


def test_bratu200_trace_is_sparse(systems):
    """CasADi keeps the tridiagonal structure: 3N - 2 structural non-zeros."""
    prob = PROBLEMS["bratu200"]
    assert prob.sparse and sp.issparse(prob.jac(prob.x0, prob.param_vector()))
    J = systems["bratu200"].jacobian_sparse(prob.x0 + 0.1, prob.param_vector())
    assert J.nnz == 3 * 200 - 2


def test_continuous_bratu_fold_closed_form():
    """lambda_c = 8 t^2 / cosh^2 t with t tanh t = 1 (Gelfand 1963)."""
    t = opt.brentq(lambda s: s * math.tanh(s) - 1.0, 0.5, 2.0, xtol=1e-16)
    assert 8 * t * t / math.cosh(t) ** 2 == pytest.approx(BRATU_CONTINUOUS_FOLD, abs=1e-14)


def test_discrete_bratu_fold_converges_at_second_order():
    """The extended-system fold of the discrete problem tends to lambda_c as O(h^2)."""
    ns = np.array([20, 40, 80, 160])
    h = 1.0 / (ns + 1)
    err = np.array([abs(bratu_fold(int(n))[0] - BRATU_CONTINUOUS_FOLD) for n in ns])
    slope = np.polyfit(np.log(h), np.log(err), 1)[0]
    assert slope == pytest.approx(2.0, abs=0.05)
    # the discrete folds lie below the continuous one and increase with N
    lams = BRATU_CONTINUOUS_FOLD - err
    assert np.all(np.diff(lams) > 0)


def test_bratu_fold_is_singular_point():
    """At the computed fold, f = 0 and the Jacobian is singular (smallest |eigenvalue|)."""
    prob = bratu(20)
    lam, u = bratu_fold(20)
    pv = np.array([lam])
    assert np.max(np.abs(prob.f(u, pv))) < 1e-8
    ev = np.linalg.eigvalsh(_dense(prob.jac(u, pv)))
    assert np.min(np.abs(ev)) < 1e-8 * np.max(np.abs(ev))


def test_bratu_fold_rejects_tiny_grid():
    with pytest.raises(ValueError, match="n"):
        bratu_fold(1)


def test_brusselator_hopf_closed_form():
    """At B = 1 + A^2 the Jacobian at (A, B/A) has eigenvalues +-iA."""
    prob = brusselator()
    a = BRUSSELATOR_A
    b = 1.0 + a * a
    x = np.array([a, b / a])
    pv = np.array([a, b])
    assert np.max(np.abs(prob.f(x, pv))) < 1e-14
    ev = np.sort_complex(np.linalg.eigvals(prob.jac(x, pv)))
    np.testing.assert_allclose(ev, [-1j * a, 1j * a], atol=1e-14)
    assert prob.expected[0].p == b


@pytest.mark.parametrize("x0", [-1.0, 1.0])
def test_cubic8_folds_exact(x0):
    """At x0 = -+1 the explicit equilibrium is exact and the Jacobian singular."""
    prob = cubic8()
    p, x = cubic8_equilibrium(x0)
    assert p == pytest.approx(-2.0 * x0, abs=1e-15)
    pv = prob.param_vector(p)
    assert np.max(np.abs(prob.f(x, pv))) < 1e-15
    J = prob.jac(x, pv)
    assert abs(np.linalg.det(J)) < 1e-12
    # lower bidiagonal: eigenvalues 3 - 3 x0^2 = 0 and -1..-7
    np.testing.assert_allclose(
        np.sort(np.linalg.eigvals(J).real), [-7, -6, -5, -4, -3, -2, -1, 0], atol=1e-12
    )


# ----------------------------------------------------------------- SciPy baseline
def _residuals_small(prob, res):
    for p, x in zip(res.p, res.x, strict=True):
        assert np.max(np.abs(prob.f(x, prob.param_vector(p)))) < 1e-7 * (
            1.0 + np.max(np.abs(_dense(prob.jac(x, prob.param_vector(p)))))
        )


def test_baseline_brusselator_hopf():
    prob = brusselator()
    res = palc_problem(prob)
    hopf = res.find("hopf")
    assert len(hopf) == 1 and hopf[0].located
    assert hopf[0].p == pytest.approx(1.0 + BRUSSELATOR_A**2, abs=1e-9)
    assert hopf[0].omega == pytest.approx(BRUSSELATOR_A, abs=1e-9)
    assert res.find("fold") == ()
    assert res.status == "param_bound" and res.p[-1] > prob.p_max
    # stable before the Hopf point, one unstable pair after it
    k = hopf[0].index
    assert np.all(res.n_unstable[: k + 1] == 0) and np.all(res.n_unstable[k + 1 :] == 2)
    _residuals_small(prob, res)


def test_baseline_bratu_fold_and_norm_stop():
    prob = bratu(20)
    res = palc_problem(prob)
    folds = res.find("fold")
    assert len(folds) == 1 and folds[0].located
    assert folds[0].p == pytest.approx(bratu_fold(20)[0], abs=1e-10)
    assert res.status == "norm_bound"
    assert np.linalg.norm(res.x[-1]) > prob.norm_max >= np.linalg.norm(res.x[-2])
    # lower branch stable, upper branch has exactly one unstable eigenvalue
    k = folds[0].index
    assert np.all(res.n_unstable[: k + 1] == 0) and np.all(res.n_unstable[k + 1 :] == 1)
    _residuals_small(prob, res)


def test_baseline_sparse_path_matches_dense():
    """splu + eigs(sigma=0) give the same branch as the dense path."""
    prob = bratu(20)
    dense = palc_problem(prob, sparse=False)
    sparse_ = palc_problem(prob, sparse=True)
    assert sparse_.steps == dense.steps
    np.testing.assert_allclose(sparse_.p, dense.p, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(sparse_.n_unstable, dense.n_unstable)
    assert sparse_.find("fold")[0].p == pytest.approx(dense.find("fold")[0].p, abs=1e-11)


def test_baseline_cubic8_two_exact_folds():
    prob = cubic8()
    res = palc_problem(prob)
    folds = res.find("fold")
    assert [round(f.p, 6) for f in folds] == [2.0, -2.0]
    for f, x0 in zip(folds, (-1.0, 1.0), strict=True):
        assert f.p == pytest.approx(-2.0 * x0, abs=1e-10)
        np.testing.assert_allclose(f.x, cubic8_equilibrium(x0)[1], atol=1e-7)
    assert res.find("hopf") == ()
    assert res.status == "param_bound"
    # stable, then one unstable eigenvalue on the middle sheet, then stable again
    k1, k2 = folds[0].index, folds[1].index
    assert np.all(res.n_unstable[: k1 + 1] == 0)
    assert np.all(res.n_unstable[k1 + 1 : k2 + 1] == 1)
    assert np.all(res.n_unstable[k2 + 1 :] == 0)


def test_baseline_backward_direction():
    """A negative ds goes down in p and stops at p_min."""
    prob = brusselator()
    res = palc_problem(prob, ds=-0.01, p_min=0.5)
    assert res.status == "param_bound" and res.p[-1] < 0.5 and np.all(np.diff(res.p) < 0)
    assert res.find("hopf") == ()


def test_baseline_bad_input():
    prob = brusselator()
    args = (prob.f, prob.jac, prob.dfdp, prob.x0, prob.param_vector(), prob.free_index)
    with pytest.raises(ValueError, match="ds"):
        palc(*args, ds=1.0, ds_max=0.1)
    with pytest.raises(ValueError, match="max_steps"):
        palc(*args, max_steps=0)
    with pytest.raises(ValueError, match="free_index"):
        palc(*args[:-1], 5)
    with pytest.raises(ValueError, match="x0"):
        palc(prob.f, prob.jac, prob.dfdp, prob.x0 + 1.0, prob.param_vector(), prob.free_index)
