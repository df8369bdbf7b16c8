"""Pseudo-arclength and natural continuation: geometry, step control, stopping rules."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from helpers import (
    assert_invariants,
    bratu,
    bratu_branch,
    brusselator,
    circle,
    fold_normal_form,
    hopf_normal_form,
)

import continuation.algorithms.base as base
import continuation.algorithms.corrector as corrector
import continuation.linalg as linalg
from continuation.algorithms import PALC, Natural, StepOutcome, adapt_ds
from continuation.api import continue_equilibria
from continuation.driver import continue_branch
from continuation.errors import ContinuationError
from continuation.problem import EquilibriumProblem
from continuation.settings import ContinuationSettings
from continuation.status import Status


def test_circle_closes_with_two_folds():
    """x^2 + mu^2 = 1 is a closed curve: folds at mu = +-1 (x = 0), loop closes."""
    br = continue_equilibria(circle(), [1.0], {"mu": 0.0}, "mu", direction="forward")
    assert br.status is Status.CLOSED_LOOP
    folds = br.find("fold")
    assert sorted(round(f.p, 12) for f in folds) == [-1.0, 1.0]
    for f in folds:
        assert abs(f.x[0]) < 1e-5 and f.located
    np.testing.assert_allclose(br.x[:, 0] ** 2 + br.p**2, 1.0, atol=1e-10)
    # circumference in the theta-norm (theta = 1/2, N = 1): 2 pi sqrt(1/2)
    circ = 2 * math.pi * math.sqrt(0.5)
    assert 0.99 * circ < br.arclength[-1] < circ + 0.1
    assert_invariants(br)


@pytest.mark.parametrize("theta", [0.1, 0.5, 0.9])
def test_theta_does_not_change_the_fold(theta):
    sys = fold_normal_form()
    prob = EquilibriumProblem(sys, sys.params(mu=1.0), "mu")
    st = ContinuationSettings(ds=-0.05, theta=theta, p_min=-1.0, p_max=1.5)
    br = continue_branch(prob, [1.0], 1.0, PALC(), st)
    (f,) = br.find("fold")
    assert abs(f.p) < 1e-8
    assert br.p[-1] == pytest.approx(1.5, abs=1e-12)
    assert br.x[-1, 0] == pytest.approx(-math.sqrt(1.5), abs=1e-10)


def test_natural_stops_before_fold():
    sys = fold_normal_form()
    prob = EquilibriumProblem(sys, sys.params(mu=1.0), "mu")
    st = ContinuationSettings(ds=-0.05, ds_min=1e-6, ds_max=0.05)
    br = continue_branch(prob, [1.0], 1.0, Natural(), st)
    assert br.status is Status.DS_MIN
    assert np.all(br.x[:, 0] > 0)
    np.testing.assert_allclose(br.x[:, 0] ** 2 - br.p, 0.0, atol=st.newton.tol)
    assert 0 < br.p[-1] < 1e-2  # reached close to the fold, not past it
    # parameter steps are exactly ds while easy (Natural steps the parameter)
    assert br.p[1] == pytest.approx(0.95, abs=1e-14)
    with pytest.raises(ContinuationError):
        continue_branch(prob, [1.0], 1.0, Natural(), st, throw=True)


def test_natural_matches_palc_on_monotone_branch():
    sys = brusselator()
    prob = EquilibriumProblem(sys, sys.params(A=1.0, B=0.5), "B")
    st = ContinuationSettings(ds=0.05, ds_max=0.05, p_max=3.0)
    nat = continue_branch(prob, [1.0, 0.5], 0.5, Natural(), st)
    pal = continue_branch(prob, [1.0, 0.5], 0.5, PALC(), st)
    assert nat.status is pal.status is Status.PARAM_BOUND
    (hn,), (hp,) = nat.find("hopf"), pal.find("hopf")
    assert hn.p == pytest.approx(2.0, abs=1e-9) and hp.p == pytest.approx(2.0, abs=1e-9)
    np.testing.assert_allclose(np.interp(nat.p, pal.p, pal.x[:, 1]), nat.x[:, 1], atol=1e-12)


def _brusselator_in_B(**options):
    """The Brusselator's equilibria continued in ``B`` from ``(x, y) = (1, 0.5)`` at
    ``A = 1, B = 0.5``."""
    return continue_equilibria(brusselator(), [1.0, 0.5], {"A": 1.0, "B": 0.5}, "B", **options)


def test_step_grows_to_ds_max_and_bounds_are_exact():
    br = _brusselator_in_B(p_min=0.2, p_max=3.0, ds=1e-3, ds_max=0.08)
    assert br.status is Status.PARAM_BOUND
    assert br.p[0] == pytest.approx(0.2, abs=1e-12) and br.p[-1] == pytest.approx(3.0, abs=1e-12)
    assert np.all(np.diff(br.p) > 0)  # ordered from the backward end
    assert br.ds.max() == pytest.approx(0.08, rel=1e-12)
    assert br.ds[0] == 0.0 and np.all(br.ds[1:] > 0)
    assert br.newton_iters.mean() < 4


def test_adapt_ds_rules():
    st = ContinuationSettings(ds=0.1, ds_max=0.2, grow=1.5, shrink=0.5)
    assert adapt_ds(0.1, StepOutcome(True, 2, 0.0), st) == pytest.approx(0.15)
    assert adapt_ds(0.19, StepOutcome(True, 1, 0.0), st) == pytest.approx(0.2)
    assert adapt_ds(0.1, StepOutcome(True, 5, 0.0), st) == pytest.approx(0.1)
    assert adapt_ds(0.1, StepOutcome(False, 20, 1.0), st) == pytest.approx(0.05)


def test_max_steps_and_progress():
    seen = []
    br = continue_equilibria(
        hopf_normal_form(),
        [0.0, 0.0],
        {"mu": -1.0},
        "mu",
        max_steps=7,
        direction="forward",
        progress=seen.append,
    )
    assert br.status is Status.MAX_STEPS
    assert len(br) == 8 == len(seen)
    assert [bp.index for bp in seen] == list(range(8))
    np.testing.assert_array_equal([bp.p for bp in seen], br.p)
    assert seen[3].n_unstable == br.n_unstable[3]


def test_keyboard_interrupt_returns_partial_branch():
    calls = []

    def progress(bp):
        calls.append(bp)
        if len(calls) == 5:
            raise KeyboardInterrupt

    br = _brusselator_in_B(p_max=3.0, progress=progress, throw=True)
    assert br.status is Status.INTERRUPTED
    assert len(br) == 5  # backward direction interrupted: forward never started
    assert np.all(np.diff(br.p) > 0)


def test_both_directions_single_ordered_branch():
    sys = fold_normal_form()
    fwd = continue_equilibria(sys, [1.0], {"mu": 1.0}, "mu", p_max=2.0, direction="forward")
    bwd = continue_equilibria(sys, [1.0], {"mu": 1.0}, "mu", p_max=2.0, direction="backward")
    both = continue_equilibria(sys, [1.0], {"mu": 1.0}, "mu", p_max=2.0, direction="both")
    assert len(both) == len(fwd) + len(bwd) - 1
    k0 = len(bwd) - 1
    np.testing.assert_array_equal(both.x[k0], fwd.x[0])
    np.testing.assert_array_equal(both.p[: k0 + 1], bwd.p[::-1])
    np.testing.assert_array_equal(both.p[k0:], fwd.p)
    (f,) = both.find("fold")
    (fb,) = bwd.find("fold")
    assert f.index == k0 - fb.index - 1
    assert f.bracket == (both.p[f.index], both.p[f.index + 1])
    assert f.delta_unstable == (-fb.delta_unstable[0], -fb.delta_unstable[1])
    assert both.p[0] == pytest.approx(2.0) and both.x[0, 0] < 0 < both.x[-1, 0]
    assert both.x[-1, 0] == pytest.approx(math.sqrt(2.0), abs=1e-12)
    assert_invariants(both)


def test_bratu_200_uses_sparse_lu_and_shift_invert(monkeypatch):
    n = 200
    calls = {"splu": 0, "getrf": 0}
    real_splu, real_getrf = linalg.spla.splu, linalg._getrf

    def splu(*a, **k):
        calls["splu"] += 1
        return real_splu(*a, **k)

    def getrf(*a, **k):
        calls["getrf"] += 1
        return real_getrf(*a, **k)

    monkeypatch.setattr(linalg.spla, "splu", splu)
    monkeypatch.setattr(linalg, "_getrf", getrf)
    br = bratu_branch(
        n,
        ds=0.1,
        ds_max=0.5,
        max_steps=6,
        direction="forward",
    )
    assert br.problem.sparse
    assert calls["splu"] > 6 and calls["getrf"] == 0
    # only n_eigs = 6 eigenvalues (nearest 0) are computed; the rest are NaN
    assert br.eigenvalues.shape == (len(br), n)
    assert np.all(np.isfinite(br.eigenvalues[:, :6])) and np.all(np.isnan(br.eigenvalues[:, 6:]))
    # at lam = 0 the Jacobian is the 3-point Laplacian: lambda_k = -4/h^2 sin^2(k pi h / 2)
    h = 1.0 / (n + 1)
    exact = -4 / h**2 * np.sin(np.arange(1, 7) * np.pi * h / 2) ** 2
    np.testing.assert_allclose(br.eigenvalues[0, :6].real, exact, rtol=1e-10)
    assert np.all(br.n_unstable == 0)


class _PlainFold:
    """Protocol-only problem (no linearize, no eigenvalues): x^2 - mu = 0 on a parabola."""

    free = "mu"
    n_unknowns = 1

    def residual(self, z, p):
        return np.array([z[0] ** 2 - p])

    def jacobian(self, z, p):
        return np.array([[2 * z[0]]])

    def dp(self, z, p):
        return np.array([-1.0])

    def stability(self, z, p):
        return None

    def record(self, z, p):
        return {"x2": z[0] ** 2}


def test_generic_problem_without_stability():
    br = continue_branch(
        _PlainFold(), [1.0], 1.0, settings=ContinuationSettings(ds=-0.1, p_max=2.0)
    )
    assert br.status is Status.PARAM_BOUND
    (f,) = br.find("fold")
    assert abs(f.p) < 1e-8
    assert br.eigenvalues.shape == (len(br), 0)
    assert np.all(br.n_unstable == -1)
    np.testing.assert_allclose(br.records["x2"], br.p, atol=1e-12)
    assert br.state_names == ("z0",)


# ------------------------------------------------------------------ corrector safeguards
def test_codim2_fold_curve_does_not_jump_to_a_distant_family():
    """Regression (issue 2): the fold curve of the CSTR (Uppal, Ray & Poore 1974, B = 14)
    continued in beta from the second fold of the Da branch used to jump, in one step
    whose corrector "converged" in 10 iterations, from beta = 2.42 to a spurious family
    at beta = -1 (x2 = -4.87), and kept that row below p_min = -0.99.

    Reference: on the fold curve x2 = 1 / (1 - x1) and beta = B x1 (1 - x1) - 1 (the
    closed form derived in tests/test_codim2.py::TestCSTR); the curve passes the cusp at
    beta = B/4 - 1 = 2.5, turns, and reaches p_min = -0.99 as x1 -> 0.
    """
    from helpers import cstr

    from continuation.codim2 import continue_codim2

    B = 14.0
    br = continue_equilibria(
        cstr(),
        [0.0, 0.0],
        {"Da": 0.0, "B": B, "beta": 2.0},
        "Da",
        p_min=0.0,
        p_max=0.3,
        ds=0.01,
    )
    st = ContinuationSettings(ds=0.05, ds_max=0.2, p_min=-0.99, p_max=8)
    curve = continue_codim2(br, br.find("fold")[1], "beta", st, direction="forward")
    x1, x2, beta = curve.x[:, 0], curve.x[:, 1], curve.p
    np.testing.assert_allclose(x2, 1 / (1 - x1), atol=1e-8)
    np.testing.assert_allclose(beta, B * x1 * (1 - x1) - 1, atol=1e-8)
    assert curve.status is Status.PARAM_BOUND
    assert beta.min() == -0.99 and beta[-1] == -0.99  # on the bound, never beyond it
    (cp,) = curve.find("cusp")  # the curve turns at the cusp
    assert cp.located and cp.p == pytest.approx(B / 4 - 1, abs=1e-8)
    assert beta.max() < B / 4 - 1
    # no step longer than ds_max (theta-norm) between consecutive rows
    w = base.theta_weights(curve.x.shape[1], st.theta)
    u = np.column_stack((curve.x, curve.p))
    steps = np.sqrt((np.diff(u, axis=0) ** 2 * w).sum(axis=1))
    assert steps.max() < 1.5 * st.ds_max


def test_corrector_contraction_safeguard():
    """Newton on arctan(x) = 0 from x0 = 1.3 (natural constraint p = 0): the iterates
    1.3 -> -1.16 -> 0.86 -> ... contract by only 0.82 in the second step, i.e. outside
    the region of quadratic convergence (it still converges, slowly). With the
    Allgower-Georg contraction test at 0.8 the corrector gives up instead."""

    class Atan:
        free = "p"
        n_unknowns = 1

        def residual(self, z, p):
            return np.array([math.atan(z[0]) + p])

        def jacobian(self, z, p):
            return np.array([[1.0 / (1.0 + z[0] ** 2)]])

        def dp(self, z, p):
            return np.array([1.0])

    e_p = np.array([0.0, 1.0])
    u0 = np.array([1.3, 0.0])
    newton = ContinuationSettings().newton
    free = corrector.correct(Atan(), u0, np.zeros(2), e_p, 0.0, newton)
    assert free.converged and abs(free.z[0]) < 1e-12
    guarded = corrector.correct(Atan(), u0, np.zeros(2), e_p, 0.0, newton, max_contraction=0.8)
    assert not guarded.converged and "contracts too slowly" in guarded.message
    assert guarded.iters == 2
    # from a good predictor the guard never triggers (quadratic convergence)
    near = corrector.correct(
        Atan(), np.array([0.3, 0.0]), np.zeros(2), e_p, 0.0, newton, max_contraction=0.8
    )
    assert near.converged and abs(near.z[0]) < 1e-12


def test_palc_distance_safeguard_rejects_far_corrections(monkeypatch):
    """A corrected point farther than max_distance * ds from the predictor is rejected
    (the Python step, whose corrector is replaced here; the compiled step's own
    safeguards: tests/test_step_kernel.py)."""
    sys = fold_normal_form()
    prob = EquilibriumProblem(sys, sys.params(mu=1.0), "mu")
    st = ContinuationSettings(ds=-0.1, ds_max=0.1, p_min=-1.0, p_max=2.0)
    alg = PALC(kernel=False)
    state = alg.init(prob, np.array([1.0]), 1.0, st)
    real = corrector.correct

    def far(*args, **kw):  # the corrector lands 3 ds away, on the same curve
        res = real(*args, **kw)
        x = -math.sqrt(0.4)
        return corrector.CorrectorResult(True, np.array([x]), 0.4, res.lin, res.iters, 0.0)

    monkeypatch.setattr("continuation.algorithms.step.correct", far)
    _, out = alg.step(prob, state, st)
    assert not out.converged and "away from the predictor" in out.message
    with pytest.raises(ValueError, match="max_distance"):
        PALC(max_distance=0.0)
    with pytest.raises(ValueError, match="max_contraction"):
        PALC(max_contraction=1.0)


def test_unlocatable_bound_never_leaves_a_row_outside():
    """Regression (issue 2): x = p on [0, 1] with a model that cannot be evaluated for
    0.95 < p < 1.1. The step 0.9 -> 1.2 crosses p_max = 1 but the bound cannot be
    located; the row at 1.2 used to be kept. Now the step is retried shorter, the
    retries fail inside the hole, and the branch ends (DS_MIN) inside its bounds."""

    class Hole:
        free = "p"
        n_unknowns = 1

        def residual(self, z, p):
            return np.array([z[0] - p]) if not 0.95 < p < 1.1 else np.array([math.nan])

        def jacobian(self, z, p):
            return np.array([[1.0]])

        def dp(self, z, p):
            return np.array([-1.0])

        def stability(self, z, p):
            return None

        def record(self, z, p):
            return {}

    st = ContinuationSettings(ds=0.3, ds_max=0.3, ds_min=1e-3, p_min=0.0, p_max=1.0, theta=0.5)
    br = continue_branch(Hole(), [0.0], 0.0, settings=st)
    assert br.p.max() <= 1.0
    assert br.status is Status.DS_MIN and br.p[-1] <= 0.95
    np.testing.assert_allclose(br.x[:, 0], br.p, atol=1e-12)
    # the same model with a reachable bound stops exactly on it
    st2 = dataclasses.replace(st, p_max=0.8)
    br2 = continue_branch(Hole(), [0.0], 0.0, settings=st2)
    assert br2.status is Status.PARAM_BOUND and br2.p[-1] == 0.8


# ---------------------------------------------------------------- sparse linear algebra reuse
def test_bordered_csc_pattern_cache_matches_dense_assembly():
    """assemble_bordered_csc (pattern built once, data overwritten) equals np.block, for
    repeated calls on one pattern, a second pattern, and a non-canonical matrix."""
    import scipy.sparse as sp

    rng = np.random.default_rng(3)
    for n, density in ((30, 0.2), (12, 0.5)):
        A = sp.random(n, n, density=density, format="csc", random_state=rng) + sp.eye(n)
        A = sp.csc_matrix(A)
        for _ in range(3):
            B = linalg.csc_with_data(A, rng.standard_normal(A.nnz))  # same pattern, new data
            gp, c = rng.standard_normal(n), rng.standard_normal(n + 1)
            M = linalg.assemble_bordered_csc(B, gp, c)
            ref = np.block([[B.toarray(), gp[:, None]], [c[None, :]]])
            np.testing.assert_array_equal(M.toarray(), ref)
            assert M.has_canonical_format
            # a factorisation of the assembled matrix solves the dense system
            lu = linalg.BorderedLU(B, gp, c)
            rhs = rng.standard_normal(n + 1)
            np.testing.assert_allclose(ref @ lu.solve(rhs), rhs, atol=1e-9)
            assert lu.sign == np.sign(np.linalg.det(ref))
    # duplicates (non-canonical): summed like SciPy does, the input left untouched
    D = sp.csc_matrix((np.array([1.0, 2.0, 3.0]), np.array([0, 0, 1]), np.array([0, 2, 3])),
                      shape=(2, 2))  # fmt: skip
    M = linalg.assemble_bordered_csc(D, np.array([1.0, 1.0]), np.array([0.0, 0.0, 1.0]))
    np.testing.assert_array_equal(M.toarray(), [[3.0, 0.0, 1.0], [0.0, 3.0, 1.0], [0, 0, 1]])
    assert D.nnz == 3


def test_sparse_eigs_reuse_the_corrector_factorisation():
    """Along a sparse Bratu branch the eigenvalues near 0 from ARPACK with the bordered
    factorisation as G_z^{-1} equal dense LAPACK eigenvalues of G_z."""
    import continuation.row_eigs as drv

    n = 150
    sys = bratu(n)
    prob = EquilibriumProblem(sys, sys.params(lam=0.0), "lam")
    st = ContinuationSettings(ds=0.3, ds_max=0.3, max_steps=8, p_max=3.0)
    used = []
    real_opinv = drv.SparseEigs._opinv

    def spy(self, pt):
        op = real_opinv(self, pt)
        used.append(op is not None)
        return op

    drv.SparseEigs._opinv = spy
    try:
        br = continue_branch(prob, np.zeros(n), 0.0, settings=st)
    finally:
        drv.SparseEigs._opinv = real_opinv
    assert len(br) == 9 and all(used) and len(used) >= 9
    for k in range(len(br)):
        J = prob.jacobian(br.x[k], br.p[k]).toarray()
        dense = np.sort(np.linalg.eigvals(J).real)[::-1][:6]  # symmetric: real spectrum
        # rows are within the corrector's step tolerance of the point the eigenvalues
        # were computed at: compare at that level
        np.testing.assert_allclose(br.eigenvalues[k, :6].real, dense, rtol=1e-8)
        np.testing.assert_allclose(br.eigenvalues[k, :6].imag, 0.0, atol=1e-8)
    # a pair near the shift cut at k: both members returned (conjugates), with vectors
    import scipy.sparse as sp

    from continuation.stability import sparse_eigs_near

    m = n // 2  # 2x2 blocks [[-j, j/2], [-j/2, -j]]: eigenvalues -j +- i j/2
    j = np.arange(1.0, m + 1)
    blocks = [np.array([[-a, a / 2], [-a / 2, -a]]) for a in j]
    T = sp.csc_matrix(sp.block_diag(blocks))
    vals, vecs = sparse_eigs_near(T, 5, 0.0, tol=1e-12, vectors=True)
    assert vals.size == 6  # the pair cut at k = 5 is completed by its conjugate
    ref = np.concatenate([-j[:3] + 0.5j * j[:3], -j[:3] - 0.5j * j[:3]])
    np.testing.assert_allclose(np.sort_complex(vals), np.sort_complex(ref), rtol=1e-10)
    np.testing.assert_allclose(T @ vecs, vecs * vals, atol=1e-9)


def test_hermite_predictor_same_branch_fewer_newton_iterations():
    """The cubic Hermite predictor (default) and the tangent predictor solve the same
    equations: the fold of the N = 20 Bratu problem agrees to 1e-12 (reference: the
    tangent-predictor run and the extended-system value 3.509682479821677, see
    benchmarks/problems.py), every row solves G = 0, and the better prediction needs
    fewer corrector iterations (O(ds^4) against O(ds^2) prediction error)."""
    runs = {}
    for predictor in ("tangent", "hermite"):
        br = bratu_branch(
            20,
            p_min=0.0,
            p_max=4.0,
            ds=0.01,
            ds_max=0.1,
            direction="forward",
            max_steps=50,
            algorithm=PALC(predictor=predictor),
        )
        (f,) = br.find("fold")
        assert f.located
        assert_invariants(br)
        runs[predictor] = (f.p, int(br.newton_iters[1:].sum()), len(br))
    assert runs["hermite"][0] == pytest.approx(runs["tangent"][0], abs=1e-12)
    assert runs["hermite"][0] == pytest.approx(3.509682479821677, abs=1e-11)
    assert runs["hermite"][2] == runs["tangent"][2]
    assert runs["hermite"][1] <= 0.8 * runs["tangent"][1]
    with pytest.raises(ValueError, match="predictor"):
        PALC(predictor="quadratic")


def test_bound_crossing_is_placed_exactly_on_the_bound():
    """A monotone crossing of p_max is placed by one solve at p = p_max: the last row is
    exactly on the bound and solves G = 0 there (fold normal form mu - x^2: x = sqrt(mu))."""
    sys = fold_normal_form()
    prob = EquilibriumProblem(sys, sys.params(mu=1.0), "mu")
    st = ContinuationSettings(ds=0.07, ds_max=0.3, p_min=0.0, p_max=2.345)
    br = continue_branch(prob, [1.0], 1.0, PALC(), st)
    assert br.status is Status.PARAM_BOUND
    assert br.p[-1] == 2.345
    assert br.x[-1, 0] == pytest.approx(math.sqrt(2.345), abs=1e-12)
    assert 0 < br.ds[-1] <= 0.3


def test_start_exactly_at_a_fold_both_directions_covers_both_halves(caplog):
    """mu - x^2 started at its fold (0, 0): dp/ds = 0 there, so the sign rule cannot
    orient the two runs; with direction="both" they must still leave in opposite
    directions and together cover x = -1..1 (closed form x = +-sqrt(mu)). A
    single-direction start there warns that the direction is arbitrary."""
    sys = fold_normal_form()
    br = continue_equilibria(sys, [0.0], {"mu": 0.0}, "mu", p_min=-1.0, p_max=1.0)
    assert br.x[:, 0].min() == pytest.approx(-1.0, abs=1e-12)
    assert br.x[:, 0].max() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(br.x[:, 0] ** 2, br.p, atol=1e-10)
    assert np.all(np.diff(br.x[:, 0]) > 0) or np.all(np.diff(br.x[:, 0]) < 0)
    assert len(br.find("fold")) == 0 or all(abs(f.p) < 1e-10 for f in br.find("fold"))
    with caplog.at_level("WARNING", logger="continuation.driver"):
        one = continue_equilibria(
            sys, [0.0], {"mu": 0.0}, "mu", p_min=-1.0, p_max=1.0, direction="forward"
        )
    assert one.status is Status.PARAM_BOUND
    assert any("is (numerically) a fold" in r.message for r in caplog.records)
