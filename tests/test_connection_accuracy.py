"""Accuracy claims of connecting orbits: find_connection, the adaptive mesh, the estimates.

Every case of :mod:`tests.connection_problems` is found from its saddle alone
(:func:`find_connection`) and checked against its reference (closed form, shooting or
published digits). The property tests check the claim behind ``SUCCESS``: the result
is within its own error estimate (discretisation + truncation) of the reference, plus
the reference's own uncertainty, at the defaults and at deliberately coarse settings;
a result that is not SUCCESS must say which estimate failed.
"""

from __future__ import annotations

import numpy as np
import pytest

from continuation.bvp import (
    CollocationMesh,
    ConnectionAccuracy,
    HeteroclinicProblem,
    check_convergence,
    continue_connection,
    find_connection,
    solve_connection,
)
from continuation.bvp.find import cut_at_closest_approach
from continuation.dynamics.manifolds import unstable_manifold
from continuation.settings import ContinuationSettings
from continuation.status import Status
from tests.connection_problems import ConnectionCase, cases, cir

CASES = {c.name: c for c in cases()}
PUBLISHED = ("cir", "kpr", "lorenz", "she")

#: Deliberately coarse: few intervals of low degree, ends far from the saddles, loose
#: tolerances, few refinements.
COARSE = {
    "n_intervals": 6,
    "degree": 2,
    "end_distance": 1e-2,
    "accuracy": ConnectionAccuracy(
        rtol=1e-3, atol=1e-5, adapt_rounds=1, max_refinements=2, max_extensions=1
    ),
}
#: Coarser still, degree 1 (order 2) and a single adaptation round.
CRUDE = {
    "n_intervals": 8,
    "degree": 1,
    "end_distance": 3e-2,
    "accuracy": ConnectionAccuracy(
        rtol=1e-2, atol=1e-4, adapt_rounds=1, max_refinements=3, max_extensions=1
    ),
}
SETTINGS = {"defaults": {}, "coarse": COARSE, "crude": CRUDE}


def _find(case: ConnectionCase, **kw):
    return find_connection(case.system, case.system.params(**case.params), case.free,
                           **case.kwargs(), **kw)  # fmt: skip


@pytest.mark.parametrize("name", list(CASES))
def test_find_connection_reaches_the_reference_from_the_saddle_alone(name):
    """Defaults: SUCCESS, and the value within max(estimate, 1e-6 |p| + 1e-8) of the reference."""
    case = CASES[name]
    res = _find(case)
    assert res.success, res.message
    err = abs(res.value(case.free) - case.reference)
    assert err <= res.error(case.free) + case.reference_uncertainty, (err, res.errors)
    # the defaults' tolerances hold for the estimates
    tol = 1e-8 + 1e-6 * abs(res.value(case.free))
    assert res.errors.discretisation[case.free] <= tol
    assert res.errors.truncation[case.free] <= tol
    # both ends near the saddles
    assert np.linalg.norm(res.x[0] - res.x_from) < 1e-2
    assert np.linalg.norm(res.x[-1] - res.x_to) < 1e-2


@pytest.mark.parametrize("name", PUBLISHED)
def test_published_digits(name):
    """Rounded to the published digits, the value is the published one."""
    case = CASES[name]
    res = _find(case)
    digits = {"cir": 7, "kpr": 5, "lorenz": 7, "she": 6}[name]
    assert round(res.value(case.free), digits) == pytest.approx(case.reference, abs=1e-12)


@pytest.mark.parametrize("setting", list(SETTINGS))
@pytest.mark.parametrize("name", list(CASES))
def test_success_is_within_its_error_estimate(name, setting):
    """The claim of SUCCESS: |p - p_ref| <= discretisation + truncation estimate."""
    case = CASES[name]
    res = _find(case, **SETTINGS[setting])
    if res.success:
        err = abs(res.value(case.free) - case.reference)
        assert err <= res.error(case.free) + case.reference_uncertainty, (
            name, setting, err, res.errors,
        )  # fmt: skip
    else:
        assert res.status in (
            Status.DISCRETISATION_ERROR, Status.TRUNCATION_ERROR, Status.NEWTON_FAILED,
            Status.NONFINITE, Status.SINGULAR,
        ), res.message  # fmt: skip
        if res.status is Status.DISCRETISATION_ERROR:
            assert "discretisation" in res.message
        if res.status is Status.TRUNCATION_ERROR:
            assert "truncation" in res.message and "T" in res.message


def _manifold_guess(case: ConnectionCase, t_max: float):
    s = case.system
    par = s.params(**case.params)
    wu = unstable_manifold(s, par, case.source, eps=1e-6, t_max=t_max, branches=(case.branch,))
    t, x = wu.branch(case.branch).as_guess()
    target = wu.x_saddle if case.shift == 0 else wu.x_saddle + np.array([2 * np.pi, 0.0])
    k, _ = cut_at_closest_approach(t, x, wu.x_saddle, target)
    return par, wu.x_saddle, (t[: k + 1], x[: k + 1])


@pytest.mark.parametrize(
    ("name", "T", "old_error"),
    [("lorenz", 30.0, 1e-2), ("pendulum_cylinder", 20.0, 1e-7)],
)
def test_the_old_default_mesh_no_longer_gives_a_wrong_success(name, T, old_error):
    """The issue's cases on the old default mesh (40 uniform intervals x degree 4).

    Lorenz: the fast excursion (about 3.5 time units) takes ~12 % of T = 30; the plain
    solve on that mesh is more than 1 % off (the old default said SUCCESS). The
    cylinder: the saddle-to-shifted-saddle orbit of the damped pendulum at T = 20.
    Now: SUCCESS within the estimate of the reference, or a status saying why not.
    """
    case = CASES[name]
    par, xs, guess = _manifold_guess(case, t_max=5.0 if name == "lorenz" else 40.0)
    kw = {"shift": case.shift}
    prob = HeteroclinicProblem(case.system, par, case.free, saddle_from=xs, T=T, **kw)
    assert prob.mesh.n_intervals == 40
    plain = solve_connection(prob, guess, accuracy=ConnectionAccuracy(estimate=False))
    assert plain.success and plain.errors is None
    assert abs(plain.value(case.free) - case.reference) > old_error  # the old defect
    res = solve_connection(prob, guess)
    if res.success:
        err = abs(res.value(case.free) - case.reference)
        assert err <= res.error(case.free) + case.reference_uncertainty, (err, res.errors)
        assert err < 1e-6 * abs(case.reference) + 1e-8 + case.reference_uncertainty
    else:
        assert res.status in (Status.DISCRETISATION_ERROR, Status.TRUNCATION_ERROR)


def test_check_convergence_lengthens_T_at_the_same_resolution():
    """delta_T is the truncation error alone: the adapted mesh is kept, not re-made uniform."""
    case = CASES["cir"]
    res = _find(case)
    ck = check_convergence(res)
    assert ck.ok
    # interior nodes of the base mesh (in t) are nodes of the extended mesh
    off = 0.5 * (ck.extended.T - res.T)
    t_base = res.mesh.nodes * res.T + off
    t_ext = ck.extended.mesh.nodes * ck.extended.T
    assert np.min(np.abs(t_base[:, None] - t_ext[None, :]), axis=1).max() < 1e-9
    # a saddle-focus homoclinic at T ~ 50: the change with T is tiny, and so is the
    # discretisation change of the adapted mesh
    assert ck.delta_T["nu"] < 1e-9
    assert ck.delta_mesh["nu"] < 1e-8


def test_cir_curve_in_beta_against_auto():
    """Continued in beta, the cir saddle-focus homoclinic passes AUTO-07p's published points.

    AUTO-07p manual, HomCont demo cir, runs 2 and 3: (beta, nu) = (0.4535645,
    -0.7256925) and (0.5912315, -0.7204001) (7 digits). The branch rows are
    corrected at those beta by the solver with its estimates.
    """
    res = _find(CASES["cir"])
    br = continue_connection(
        res, "beta", ContinuationSettings(ds=-0.02, ds_max=0.05, p_min=0.44, p_max=0.62),
        direction="both",
    )  # fmt: skip
    assert br.status is Status.PARAM_BOUND, br.message
    for beta, nu in ((0.4535645, -0.7256925), (0.5912315, -0.7204001)):
        order = np.argsort(br.p)
        nu_b = float(np.interp(beta, np.asarray(br.p)[order], np.asarray(br.records["nu"])[order]))
        assert nu_b == pytest.approx(nu, abs=1e-3)  # linear interpolation between rows
        s = cir()
        par = dict(res.params.items())
        par.update(beta=beta, nu=float(nu_b))
        at = find_connection(s, s.params(**par), "nu", source=[0, 0, 0], shift=0)
        assert at.success, at.message
        assert at.value("nu") == pytest.approx(nu, abs=5e-8 + at.error("nu"))


def test_names_and_layouts():
    """free = solved, vary = continuation parameter; T= keyword; shift=0; (n, K) guesses."""
    case = CASES["kdv"]
    s = case.system
    with pytest.raises(ValueError, match="T="):
        HeteroclinicProblem(s, s.params(mu=0.05), "mu", saddle_from=[0, 0], shift=0)
    with pytest.raises(ValueError, match="scalar `shift` must be 0"):
        HeteroclinicProblem(s, s.params(mu=0.05), "mu", saddle_from=[0, 0], shift=1.0, T=20.0)
    with pytest.raises(ValueError, match="disagrees"):
        HeteroclinicProblem(s, s.params(mu=0.05), "mu", saddle_from=[0, 0], shift=0,
                            T=20.0, mesh=CollocationMesh(10, 4, 30.0))  # fmt: skip
    prob = HeteroclinicProblem(s, s.params(mu=0.05), "mu", saddle_from=[0, 0], shift=0, T=30.0)
    assert prob.free == ("mu",) and prob.vary is None and prob.T == 30.0
    assert prob.replace(T=40.0).mesh.T == 40.0
    t = np.linspace(-15, 15, 301)
    u = 1.6 / np.cosh(t / 2.2) ** 2
    x_kn = np.column_stack([u, np.gradient(u, t)])
    a = solve_connection(prob, (t, x_kn))
    b = solve_connection(prob, (t, x_kn.T))  # SciPy's layout
    assert a.success and b.success
    assert b.value("mu") == a.value("mu")
    sol_t = type("S", (), {"t": t, "y": x_kn.T})()  # an object with t and SciPy's y (n, K)
    assert solve_connection(prob, sol_t, accuracy=ConnectionAccuracy(estimate=False)).success
    with pytest.raises(ValueError, match="ambiguous"):
        solve_connection(prob, np.ones((2, 2)))
    with pytest.raises(ValueError, match="`vary`"):
        prob.replace(vary="mu")
    with pytest.raises(ValueError, match="exactly one of `target` and `shift`"):
        find_connection(s, s.params(mu=0.05), "mu", source=[0, 0])
    with pytest.raises(ValueError, match="unstable manifold"):
        find_connection(CASES["nagumo"].system, CASES["nagumo"].system.params(a=0.25, c=0.3),
                        "c", source=[0.25, 0.0], target=[0.0, 0.0])  # fmt: skip


def test_failed_estimate_is_a_distinct_status_with_advice():
    """Too few refinements for a tight tolerance: DISCRETISATION_ERROR naming the fix."""
    case = CASES["kpr"]
    acc = ConnectionAccuracy(rtol=1e-13, atol=0.0, max_refinements=0, adapt_rounds=0)
    res = _find(case, n_intervals=10, degree=2, accuracy=acc)
    assert res.status is Status.DISCRETISATION_ERROR
    assert "max_refinements" in res.message and "lam" in res.message
    assert not res.success and res.errors is not None
    acc_T = ConnectionAccuracy(rtol=1e-14, atol=0.0, max_extensions=0, safety=1.0)
    res_T = _find(CASES["nagumo"], end_distance=0.3, accuracy=acc_T)
    assert res_T.status in (Status.TRUNCATION_ERROR, Status.DISCRETISATION_ERROR)
    if res_T.status is Status.TRUNCATION_ERROR:
        assert "longer T" in res_T.message


def test_estimates_survive_save_and_load(tmp_path):
    case = CASES["san"]
    res = _find(case)
    back = type(res).load(res.save(tmp_path / "san"))
    assert back.errors == res.errors
    assert back.error("mut") == res.error("mut") and "+-" in repr(res)
    with pytest.raises(ValueError, match="not a solved parameter"):
        res.error("a")


def test_wrong_branch_says_so():
    """The other branch of the Nagumo saddle runs off: no SUCCESS, and the message says why."""
    case = CASES["nagumo"]
    s = case.system
    kw = {**case.kwargs(), "branch": -case.branch}
    res = find_connection(s, s.params(**case.params), case.free, **kw)
    assert not res.success
    assert "other `branch`" in res.message


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_manifold_stopped_at_the_window_end_gives_the_cut_of_the_full_run(name):
    """find_connection integrates W^u only until the cut's window closes; the cut (time
    and state of the closest approach) is that of the integration to the full t_max on
    the same sample grid (independent: one run, cut afterwards)."""
    from continuation.bvp.connection import _refine_equilibrium
    from continuation.bvp.find import _manifold_to_return

    case = CASES[name]
    s = case.system
    p = np.array(s.params(**case.params).values, dtype=float)
    x_m = _refine_equilibrium(s, np.asarray(case.source, dtype=float), p, "source")
    if case.target is not None:
        x_p = _refine_equilibrium(s, np.asarray(case.target, dtype=float), p, "target")
    elif isinstance(case.shift, dict):
        x_p = x_m + np.array([2 * np.pi, 0.0])
    else:
        x_p = x_m.copy()
    lam_u = float(np.max(np.linalg.eigvals(s.jacobian(x_m, p)).real))
    t_max = 200.0 + 40.0 / lam_u
    t, x, complete = _manifold_to_return(s, p, x_m, x_p, case.branch, 1e-4, t_max)
    assert complete
    k, d = cut_at_closest_approach(t, x, x_m, x_p)
    wu = unstable_manifold(s, p, x_m, eps=1e-4, t_max=t_max, dt=t_max / 1000.0,
                           branches=(case.branch,), refine=False)  # fmt: skip
    tf = np.asarray(wu.branch(case.branch).trajectory.t)
    xf = np.asarray(wu.branch(case.branch).trajectory.x)
    kf, df = cut_at_closest_approach(tf, xf, x_m, x_p)
    assert t[-1] <= tf[-1] + 1e-9
    if name in ("cir", "kpr", "san"):  # homoclinic: stopped well before t_max
        assert t[-1] < 0.5 * t_max, (name, t[-1], t_max)
    assert t[k] == pytest.approx(tf[kf], abs=1e-9 * t_max), (name, t[k], tf[kf])
    np.testing.assert_allclose(x[k], xf[kf], rtol=1e-5, atol=1e-7 * (1 + df))


def test_expanded_functions_equal_the_mx_graph(monkeypatch):
    """The SX expansion of a small system's collocation functions (casadi_backend)
    gives the residual and both Jacobians of the MX graph, at a solved orbit."""
    import continuation.bvp.casadi_backend as cb

    case = CASES["cir"]
    res = _find(case, accuracy=ConnectionAccuracy(estimate=False))
    prob = res.problem
    args = prob._args(res.z, None)
    sx = cb.ConnectionFunctions(case.system, prob.layout)
    monkeypatch.setattr(cb, "MAX_EXPANDED_POINT_INSTRUCTIONS", 0)
    mx = cb.ConnectionFunctions(case.system, prob.layout)
    assert sx._expand and not mx._expand
    for a, b in zip(sx.linearize(args), mx.linearize(args), strict=True):
        a = a.toarray() if hasattr(a, "toarray") else a
        b = b.toarray() if hasattr(b, "toarray") else b
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(sx.residual(args), mx.residual(args), rtol=1e-12, atol=1e-12)


def _nagumo_with_a_fast_direction():
    """The Nagumo front (u, v) with a slaved direction y' = -k (y - u^2): the front's
    speed is the closed form c = sqrt(2) (1/2 - a) whatever k, and k sets the
    stiffness of the flow (eigenvalue -k at both saddles)."""
    from continuation import System

    def rhs(x, p, ops):
        a, c, k = p[0], p[1], p[2]
        return ops.stack(
            [x[1], -c * x[1] - x[0] * (1 - x[0]) * (x[0] - a), -k * (x[2] - x[0] ** 2)]
        )

    return System(rhs, ("u", "v", "y"), ("a", "c", "k"))


@pytest.mark.parametrize(("k", "integrator"), [(2.0, "cvodes_adams"), (1e5, None)])
def test_the_manifold_integrator_follows_the_stiffness(k, integrator):
    """find_connection integrates W^u by CVODES's Adams method where the saddles'
    spectra are non-stiff and by BDF where they are stiff; both give the closed form
    within the result's own estimate."""
    import math

    from continuation.bvp import find as F

    s = _nagumo_with_a_fast_direction()
    a = 0.3
    p = s.params(a=a, c=0.2, k=k)
    pv = np.array(p.values, dtype=float)
    src, dst = np.array([1.0, 0.0, 1.0]), np.zeros(3)
    lam = [np.linalg.eigvals(np.asarray(s.jacobian(x, pv))) for x in (src, dst)]
    assert F._manifold_method(s, *lam) == integrator
    res = find_connection(s, p, "c", source=src, target=dst, branch=-1)
    assert res.status == Status.SUCCESS, res.message
    exact = math.sqrt(2.0) * (0.5 - a)
    assert abs(res.value("c") - exact) <= res.error("c") + 1e-12, (
        res.value("c") - exact,
        res.errors,
    )


def test_an_adams_run_that_fails_early_is_redone_with_bdf(monkeypatch):
    """Where the Adams integration of the manifold stops before the return (here made
    to), the manifold is integrated again by BDF, and the connection is found."""
    from continuation.bvp import find as F

    real = F._manifold_to_return
    used: list[str | None] = []

    def flaky(*args, **kw):
        t, x, complete = real(*args, **kw)
        ode = args[7] if len(args) > 7 else kw.get("method")
        used.append(ode)
        return (t[:3], x[:3], False) if ode is not None else (t, x, complete)

    monkeypatch.setattr(F, "_manifold_to_return", flaky)
    case = CASES["san"]
    res = _find(case)
    assert used == ["cvodes_adams", None]
    assert res.status == Status.SUCCESS, res.message
    assert abs(res.value(case.free) - case.reference) <= res.error(case.free) + 1e-12
