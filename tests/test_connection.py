"""One-shot connecting-orbit solves against closed forms, published values and shooting.

References
----------
* Nagumo / Huxley front ``u'' + c u' + u (1 - u)(u - a) = 0`` from ``u = 1`` to
  ``u = 0``: ``c = sqrt(2) (1/2 - a)``, ``u = 1 / (1 + exp(t / sqrt 2))`` (McKean 1970,
  "Nagumo's equation", Adv. Math. 4:209-223; used as test by Beyn 1990, IMA J. Numer.
  Anal. 10:379-405).
* Fisher-KPP front ``u'' + c u' + u (1 - u) = 0`` at ``c = 5 / sqrt 6``:
  ``u = (1 + C exp(t / sqrt 6))^-2`` (Ablowitz & Zeppetella 1979, Bull. Math. Biol.
  41:835-840). The speed is not isolated here (``W^s`` of the node is 2-D), so the
  connection needs no free parameter: the count ``1 + 2 = n + 1 - 0`` closes with
  ``q = 0``.
* Homoclinic orbit of ``u'' = u - u^2 + mu u'``: the KdV solitary wave
  ``u = (3/2) sech^2(t/2)`` at ``mu = 0`` (Korteweg & de Vries 1895; Drazin & Johnson
  1989, "Solitons: an introduction", ch. 2); ``mu`` is a regular unfolding parameter
  (the Melnikov integral ``int u'^2 dt`` is nonzero), so it is solved for.
* Damped driven pendulum / Josephson junction ``theta'' + gamma theta' + sin theta = F``:
  the saddle connects to itself shifted by ``2 pi`` on a curve ``F(gamma)`` with
  ``F = 4 gamma / pi + O(gamma^3)`` (Melnikov / energy balance along the separatrix
  ``theta' = 2 sech t``; Guckenheimer & Holmes 1983, "Nonlinear Oscillations, Dynamical
  Systems, and Bifurcations of Vector Fields", sec. 4.5; Levi, Hoppensteadt & Miranker
  1978, Quart. Appl. Math. 36:167-198), and against shooting written here.
"""

from __future__ import annotations

import json

import matplotlib
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from continuation.bvp.accuracy import ConnectionAccuracy
from continuation.bvp.collocation import CollocationMesh
from continuation.bvp.connection import HeteroclinicProblem, PinPhase
from continuation.bvp.result import ConnectionResult
from continuation.bvp.solve import check_convergence, solve_connection
from continuation.differentiation import fd_jacobian
from continuation.errors import ConvergenceError
from continuation.settings import NewtonSettings
from continuation.status import Status
from continuation.system import System
from tests.connection_problems import nagumo, nagumo4, pendulum, shooting_F

matplotlib.use("Agg")

PLAIN = ConnectionAccuracy(estimate=False)  # a plain solve on the given mesh

SQ2 = np.sqrt(2.0)


# ---------------------------------------------------------------------------- models
def fisher() -> System:
    def rhs(x, p, ops):
        return ops.stack([x[1], -p[0] * x[1] - x[0] * (1 - x[0])])

    return System(rhs, ("u", "v"), ("c",))


def front_guess(T: float, width: float = 1.5, n: int = 200) -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0, T, n)
    u = 1 / (1 + np.exp((t - T / 2) / width))
    return t, np.column_stack([u, np.gradient(u, t)])


def nagumo_problem(a: float, N: int = 80, T: float = 40.0, **kw) -> HeteroclinicProblem:
    s = nagumo()
    return HeteroclinicProblem(
        s,
        s.params(a=a, c=0.2),
        "c",
        saddle_from=[1.0, 0.0],
        saddle_to=[0.0, 0.0],
        mesh=CollocationMesh(N, 4, T),
        **kw,
    )


def pendulum_problem(gamma: float, N: int = 120, T: float = 40.0) -> HeteroclinicProblem:
    s = pendulum()
    return HeteroclinicProblem(
        s,
        s.params(gamma=gamma, F=4 * gamma / np.pi),
        "F",
        saddle_from=[-np.pi, 0.0],
        shift={"theta": 2 * np.pi},
        mesh=CollocationMesh(N, 4, T),
    )


def separatrix_guess(T: float = 40.0) -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(-T / 2, T / 2, 400)
    return t, np.column_stack([4 * np.arctan(np.exp(t)) - np.pi, 2 / np.cosh(t)])


# ---------------------------------------------------------------------------- shooting
# ---------------------------------------------------------------------------- tests
@pytest.mark.parametrize("a", [0.1, 0.25, 0.4])
def test_nagumo_speed_closed_form(a):
    """c = sqrt2 (1/2 - a) (McKean 1970) to 1e-10; starting from c = 0.2."""
    res = solve_connection(nagumo_problem(a), front_guess(40.0))
    assert res.success, res.message
    assert res.value("c") == pytest.approx(SQ2 * (0.5 - a), abs=1e-10)
    assert res.residual_norm < 1e-10
    assert np.allclose(res.x_from, [1, 0], atol=1e-12)
    assert np.allclose(res.x_to, [0, 0], atol=1e-12)
    assert res.params["a"] == a


def test_nagumo_profile_with_pinned_phase():
    """u(t) = 1/(1 + exp((t - t_pin)/sqrt2)) with u(t_pin) = 1/2 pinned at the mid node."""
    res = solve_connection(nagumo_problem(0.3, phase=PinPhase("u", 0.5)), front_guess(40.0))
    assert res.success
    t_pin = res.T / 2
    assert res.t_mesh[res.mesh.n_intervals // 2] == pytest.approx(t_pin)
    ue = 1 / (1 + np.exp((res.t - t_pin) / SQ2))
    ve = -ue * (1 - ue) / SQ2
    err = np.abs(res.x - np.column_stack([ue, ve])).max(axis=1)
    assert err[res.mesh.mesh_mask].max() < 1e-10  # O(h^8) at the mesh nodes
    assert err.max() < 1e-7  # O(h^5) at the collocation points


def test_guess_from_simulated_unstable_manifold():
    """A typical workflow: the guess is the unstable manifold simulated at a wrong speed."""
    a, c_wrong = 0.25, 0.30
    s = nagumo()
    J = s.jacobian(np.array([1.0, 0.0]), np.array([a, c_wrong]))
    ev, V = np.linalg.eig(J)
    v = V[:, np.argmax(ev.real)].real
    v *= -np.sign(v[0])  # towards u < 1
    sol = solve_ivp(
        lambda t, x: s.f(x, np.array([a, c_wrong])),
        (0, 60),
        np.array([1.0, 0.0]) + 1e-6 * v,
        rtol=1e-9,
        atol=1e-12,
        dense_output=True,
    )
    t = np.linspace(0, sol.t[-1], 2000)
    x = sol.sol(t).T
    stop = int(np.argmin(np.linalg.norm(x, axis=1)))  # closest approach to (0, 0)
    # keep it up to there, then rest at the target saddle for 20 time units
    tail = t[stop] + np.linspace(0.5, 20.0, 40)
    guess = (np.r_[t[: stop + 1], tail], np.r_[x[: stop + 1], np.zeros((tail.size, 2))])
    prob = HeteroclinicProblem(
        s,
        s.params(a=a, c=c_wrong),
        "c",
        saddle_from=[1, 0],
        saddle_to=[0, 0],
        mesh=CollocationMesh(80, 4, float(tail[-1])),
    )
    res = solve_connection(prob, guess)
    assert res.success, res.message
    assert res.value("c") == pytest.approx(SQ2 * (0.5 - a), abs=1e-9)


def test_fisher_kpp_exact_profile_without_free_parameter():
    """Ablowitz & Zeppetella (1979) profile at c = 5/sqrt6, no unknown parameter (q = 0)."""
    s = fisher()
    T = 60.0
    prob = HeteroclinicProblem(
        s,
        s.params(c=5 / np.sqrt(6)),
        (),
        saddle_from=[1.0, 0.0],
        saddle_to=[0.0, 0.0],
        mesh=CollocationMesh(160, 4, T),
        phase=PinPhase("u", 0.25),
    )
    assert prob.dims == {"n": 2, "unstable_from": 1, "stable_to": 2, "free": 0}
    res = solve_connection(prob, front_guess(T, width=2.0))
    assert res.success, res.message
    t_pin = res.t_mesh[80]
    # u(t_pin) = (1 + 1)^-2 = 1/4 fixes C = exp(-t_pin / sqrt6)
    ue = (1 + np.exp((res.t - t_pin) / np.sqrt(6))) ** -2
    assert np.max(np.abs(res.state("u") - ue)) < 1e-8


def test_damped_pendulum_against_shooting():
    """F(gamma = 0.3) from the BVP equals shooting + bracketing to 1e-9."""
    gamma = 0.3
    res = solve_connection(pendulum_problem(gamma), separatrix_guess())
    assert res.success, res.message
    F_shoot = shooting_F(gamma)
    assert res.value("F") == pytest.approx(F_shoot, abs=1e-9)
    # the saddle moves with F: theta_u - 2 pi = -pi - asin(F)
    assert res.x_from[0] == pytest.approx(-np.pi - np.arcsin(res.value("F")), abs=1e-12)
    assert res.x_to[0] - res.x_from[0] == pytest.approx(2 * np.pi)
    # the orbit increases monotonically in theta from one saddle to the next
    assert np.all(np.diff(res.state("theta")) > 0)


def test_damped_pendulum_melnikov_asymptotics():
    """F = (4 gamma / pi)(1 + k gamma^2 + ...): relative deviation small and ~ gamma^2."""
    dev = []
    for gamma in (0.01, 0.02):
        res = solve_connection(pendulum_problem(gamma, N=60), separatrix_guess())
        assert res.success
        dev.append(res.value("F") / (4 * gamma / np.pi) - 1)
    assert abs(dev[0]) < 1e-4
    assert dev[1] / dev[0] == pytest.approx(4.0, rel=0.01)  # O(gamma^2), no O(gamma) term


def test_four_dimensional_complex_spectrum_and_exact_jacobian():
    """n = 4 with complex saddle eigenvalues: c exact; dG/dz and dG/dp match differences."""
    s = nagumo4()
    a, om = 0.3, 2.0
    A = np.array([[-1.0, om], [-om, -1.0]])

    def eq(u):
        return np.r_[u, 0.0, np.linalg.solve(A, -np.array([u**2, np.sin(u)]))]

    prob = HeteroclinicProblem(
        s,
        s.params(a=a, c=0.1, om=om),
        "c",
        saddle_from=eq(1.0),
        saddle_to=eq(0.0),
        mesh=CollocationMesh(60, 4, 40.0),
    )
    assert prob.layout.k_minus == 3 and prob.layout.k_plus == 1  # Riccati blocks 1x3, 3x1
    t, x2 = front_guess(40.0)
    res = solve_connection(prob, (t, np.column_stack([x2, np.zeros((t.size, 2))])))
    assert res.success, res.message
    assert res.value("c") == pytest.approx(SQ2 * (0.5 - a), abs=1e-9)
    assert np.allclose(res.x_from, eq(1.0), atol=1e-12)
    # exact Jacobians, away from the solution so that the Riccati unknowns are nonzero
    small = prob.replace(mesh=CollocationMesh(8, 3, 40.0), reference=None)
    sres = solve_connection(small, res, accuracy=PLAIN)  # coarse: the difference Jacobian is cheap
    pr = sres.problem.with_vary("a")
    z = sres.z + 1e-3 * np.random.default_rng(0).standard_normal(sres.z.size)
    J = pr.jacobian(z, a).toarray()
    Jfd = fd_jacobian(lambda zz: pr.residual(zz, a), z)
    assert np.max(np.abs(J - Jfd)) < 1e-6 * max(1.0, np.max(np.abs(J)))
    dp = pr.dp(z, a)
    dpfd = fd_jacobian(lambda q: pr.residual(z, q[0]), np.array([a]))[:, 0]
    assert np.max(np.abs(dp - dpfd)) < 1e-6
    G, Jz, Gp = pr.linearize(z, a)
    assert np.allclose(G, pr.residual(z, a)) and np.allclose(Gp, dp)
    assert np.allclose(Jz.toarray(), J)


def test_convergence_check_estimates_the_error():
    """Halving the mesh: |delta c| matches the true error (order 8: ratio 1 - 2^-8)."""
    res = solve_connection(nagumo_problem(0.25, N=40), front_guess(40.0), accuracy=PLAIN)
    ck = check_convergence(res, T_factor=1.5)
    assert ck.ok
    err = abs(res.value("c") - SQ2 * 0.25)
    assert ck.delta_mesh["c"] == pytest.approx(err, rel=0.05)
    assert ck.delta_T["c"] < 1e-11  # truncation error, exponentially small in T
    assert ck.extended.T == pytest.approx(60.0)
    assert ck.refined.mesh.n_intervals == 80
    assert ck.converged(1e-8) and not ck.converged(1e-12)


def test_save_load_and_plot(tmp_path):
    res = solve_connection(nagumo_problem(0.25, N=20), front_guess(40.0))
    path = res.save(tmp_path / "front")
    assert path.suffix == ".npz"
    meta = json.loads(path.with_suffix(".json").read_text())
    assert meta["free"] == ["c"] and meta["status"] == "SUCCESS"
    back = ConnectionResult.load(path)
    assert back.problem is None
    assert back.status is Status.SUCCESS and back.value("c") == res.value("c")
    assert np.array_equal(back.x, res.x) and np.array_equal(back.t, res.t)
    assert np.array_equal(back.mesh.nodes, res.mesh.nodes)
    # a loaded result is a valid guess: one Newton step at most
    again = solve_connection(nagumo_problem(0.25, N=20), back)
    assert again.success and again.value("c") == pytest.approx(res.value("c"), abs=1e-12)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    res.plot(ax, x="u", y="v")
    assert len(ax.lines) == 2  # orbit + saddles
    assert np.allclose(ax.lines[0].get_xdata(), res.state("u"))
    res.plot(ax)  # all states against t
    assert len(ax.lines) == 4
    plt.close(fig)


def test_failure_is_a_status_or_raises():
    prob = nagumo_problem(0.25, N=20)
    bad = NewtonSettings(max_iter=1)
    res = solve_connection(prob, front_guess(40.0, width=5.0), newton=bad)
    assert res.status is Status.NEWTON_FAILED and not res.success
    assert res.residual_norm > 1e-10
    with pytest.raises(ConvergenceError):
        solve_connection(prob, front_guess(40.0, width=5.0), newton=bad, throw=True)


def test_bad_input_raises_value_error_naming_the_argument():
    s = nagumo()
    kw = dict(saddle_from=[1.0, 0.0], saddle_to=[0.0, 0.0], mesh=CollocationMesh(10, 2, 20.0))
    params = s.params(a=0.25, c=0.2)
    with pytest.raises(ValueError, match="free"):
        HeteroclinicProblem(s, params, "speed", **kw)
    with pytest.raises(ValueError, match=r"count does not close.*1 \+ 1 = 2.*n \+ 1 - q = 3"):
        HeteroclinicProblem(s, params, (), **kw)
    with pytest.raises(ValueError, match="count does not close"):
        HeteroclinicProblem(s, params, ("a", "c"), **kw)
    with pytest.raises(ValueError, match="saddle_from"):
        HeteroclinicProblem(
            s, params, "c", saddle_from=[np.nan, 0.0], saddle_to=[0, 0], mesh=kw["mesh"]
        )
    with pytest.raises(ValueError, match="saddle_from"):
        HeteroclinicProblem(s, params, "c", saddle_from=[1.0, 0.0, 0.0], saddle_to=[0, 0])
    with pytest.raises(ValueError, match="saddle_to.*shift"):
        HeteroclinicProblem(s, params, "c", saddle_from=[1.0, 0.0])
    with pytest.raises(ValueError, match="shift"):  # u is not periodic
        HeteroclinicProblem(s, params, "c", saddle_from=[1.0, 0.0], shift={"u": 1.0})
    with pytest.raises(ValueError, match="vary"):
        HeteroclinicProblem(s, params, "c", vary="c", **kw)
    with pytest.raises(ValueError, match="vary"):
        HeteroclinicProblem(s, params, "c", vary="b", **kw)
    with pytest.raises(ValueError, match="phase"):
        HeteroclinicProblem(s, params, "c", phase="midpoint", **kw)
    with pytest.raises(ValueError, match="unknown state"):
        HeteroclinicProblem(s, params, "c", phase=PinPhase("w"), **kw)
    with pytest.raises(ValueError, match="degree"):
        CollocationMesh(10, 0, 20.0)
    # non-hyperbolic start: a = 0 makes u = 0 a non-hyperbolic equilibrium
    with pytest.raises(ValueError, match="not hyperbolic"):
        HeteroclinicProblem(
            s, s.params(a=0.0, c=0.2), "c", saddle_from=[0.0, 0.0], saddle_to=[1.0, 0.0]
        )
    # periodic shift that is not a whole period
    sp_ = pendulum()
    with pytest.raises(ValueError, match="whole"):
        HeteroclinicProblem(
            sp_, sp_.params(gamma=0.1, F=0.1), "F", saddle_from=[-np.pi, 0], shift={"theta": np.pi}
        )
    # NumPy-only system: no CasADi trace
    s_np = System(lambda x, p: np.array([x[1], -x[0]]), ("u", "v"), ("a",))
    with pytest.raises(ValueError, match="system"):
        HeteroclinicProblem(s_np, s_np.params(a=0.0), "a", saddle_from=[0, 0], saddle_to=[1, 0])
    # guesses
    prob = HeteroclinicProblem(s, params, "c", **kw)
    with pytest.raises(ValueError, match="guess"):
        solve_connection(prob, (np.linspace(0, 1, 5), np.zeros((5, 3))))
    with pytest.raises(ValueError, match="guess"):
        solve_connection(prob, (np.linspace(1, 0, 5), np.zeros((5, 2))))
    with pytest.raises(ValueError, match="guess"):
        solve_connection(prob, "front")
    with pytest.raises(ValueError, match="newton"):
        solve_connection(prob, front_guess(20.0), newton={"tol": 1e-8})
    with pytest.raises(ValueError, match="adapt"):
        solve_connection(prob, front_guess(20.0), adapt=-1)
    with pytest.raises(ValueError, match="problem"):
        solve_connection("not a problem", front_guess(20.0))


def test_interrupt_during_adaptation_keeps_the_last_solution():
    calls = []

    def progress(res):
        calls.append(res)
        if len(calls) == 2:  # after the first adaptation round
            raise KeyboardInterrupt

    res = solve_connection(
        nagumo_problem(0.25, N=40), front_guess(40.0), adapt=3, progress=progress
    )
    assert res.status is Status.INTERRUPTED and not res.success
    assert len(calls) == 2
    assert res.value("c") == calls[1].value("c")
    assert res.value("c") == pytest.approx(SQ2 * 0.25, abs=1e-8)


def test_homoclinic_kdv_solitary_wave():
    """shift = 0: homoclinic to the saddle (0, 0); mu = 0 and u = (3/2) sech^2(t/2)."""

    def rhs(x, p, ops):
        return ops.stack([x[1], x[0] - x[0] ** 2 + p[0] * x[1]])

    s = System(rhs, ("u", "v"), ("mu",))
    T = 40.0
    prob = HeteroclinicProblem(
        s,
        s.params(mu=0.05),
        "mu",
        saddle_from=[0.0, 0.0],
        shift=[0.0, 0.0],
        mesh=CollocationMesh(80, 4, T),
        phase=PinPhase("v", 0.0),  # the crest at the middle node
    )
    t = np.linspace(-T / 2, T / 2, 300)
    u = 1.6 / np.cosh(t / 2.2) ** 2  # a sloppy soliton
    res = solve_connection(prob, (t, np.column_stack([u, np.gradient(u, t)])))
    assert res.success, res.message
    assert abs(res.value("mu")) < 1e-12
    assert np.array_equal(res.x_from, res.x_to)
    ue = 1.5 / np.cosh((res.t - T / 2) / 2) ** 2
    err = np.abs(res.state("u") - ue)
    assert err[res.mesh.mesh_mask].max() < 1e-8
    assert res.state("u").max() == pytest.approx(1.5, abs=1e-8)


# ---------------------------------------------------------------- simplified Newton methods
@pytest.mark.parametrize("method", ["broyden", "chord"])
def test_simplified_methods_reach_the_closed_form(method):
    """Nagumo front speed c = sqrt2 (1/2 - a) (McKean 1970) to 1e-10 with the
    Jacobian-saving methods, from the same guess as Newton, same solution to 1e-12."""
    a = 0.25
    ref = solve_connection(nagumo_problem(a), front_guess(40.0))
    res = solve_connection(nagumo_problem(a), front_guess(40.0), method=method)
    assert res.success, res.message
    assert res.residual_norm < 1e-10
    assert res.value("c") == pytest.approx(SQ2 * (0.5 - a), abs=1e-10)
    # both stop at max |G| <= 1e-10: the same solution to that level
    assert res.value("c") == pytest.approx(ref.value("c"), abs=1e-10)
    assert {"broyden": "Newton-Broyden", "chord": "chord-Newton"}[method] in res.message


def test_simplified_method_on_the_pendulum_against_shooting():
    """Damped pendulum F(gamma = 0.3): Broyden solve equals shooting to 1e-9."""
    res = solve_connection(pendulum_problem(0.3), separatrix_guess(), method="broyden")
    assert res.success, res.message
    assert res.value("F") == pytest.approx(shooting_F(0.3), abs=1e-9)


def test_simplified_newton_counts_and_rates():
    """On G(z) = A z + z^3 / 3 - b (root known by construction) Broyden converges to tol
    with one Jacobian and fewer residuals than the chord method; Newton's quadratic
    convergence needs a Jacobian per step."""
    from continuation.bvp.simplified import simplified_newton
    from continuation.newton import newton
    from continuation.settings import NewtonSettings

    rng = np.random.default_rng(7)
    n = 12
    A = np.eye(n) * 4 + rng.standard_normal((n, n)) * 0.3
    z_star = rng.standard_normal(n) * 0.5
    b = A @ z_star + z_star**3 / 3
    n_res = {"k": 0}
    n_jac = {"k": 0}

    def G(z):
        n_res["k"] += 1
        return A @ z + z**3 / 3 - b

    def J(z):
        n_jac["k"] += 1
        return A + np.diag(z**2)

    st = NewtonSettings(tol=1e-12, max_iter=60)
    counts = {}
    z0 = z_star + 0.2 * rng.standard_normal(n)
    for name, fn in (
        ("broyden", lambda z0: simplified_newton(G, J, z0, st, broyden=True, refresh=0.5)),
        ("chord", lambda z0: simplified_newton(G, J, z0, st, broyden=False, refresh=0.5)),
        ("newton", lambda z0: newton(G, J, z0, st)),
    ):
        n_res["k"] = n_jac["k"] = 0
        r = fn(z0)
        assert r.converged, (name, r.message)
        np.testing.assert_allclose(r.z, z_star, atol=1e-11)
        counts[name] = (n_res["k"], n_jac["k"])
    assert counts["broyden"][1] == 1 and counts["chord"][1] == 1
    # superlinear (Broyden) against linear (chord) convergence from the same Jacobian
    assert counts["broyden"][0] < counts["chord"][0] - 2
    assert counts["newton"][1] >= 3


def test_simplified_newton_failures_and_bad_input():
    from continuation.bvp.simplified import simplified_newton
    from continuation.errors import ConvergenceError
    from continuation.status import Status

    def G(z):
        return z**2 + 1.0  # no real root

    def J(z):
        return np.diag(2 * z)

    r = simplified_newton(G, J, np.array([0.5]), NewtonSettings(max_iter=20))
    assert not r.converged and r.status in (Status.NEWTON_FAILED, Status.SINGULAR)
    with pytest.raises(ConvergenceError):
        simplified_newton(G, J, np.array([0.5]), NewtonSettings(max_iter=20), throw=True)
    with pytest.raises(ValueError, match="refresh"):
        simplified_newton(G, J, np.array([0.5]), refresh=1.5)
    with pytest.raises(ValueError, match="z0"):
        simplified_newton(G, J, np.array([np.nan]))
    with pytest.raises(ValueError, match="method"):
        solve_connection(nagumo_problem(0.25, N=20), front_guess(20.0), method="secant")


def test_jacobian_cache_serves_a_sequence_of_nearby_solves():
    """Roots of A z + z^3/3 = b(mu) (known by construction) along mu: one factorisation
    serves neighbouring solves; a far jump refreshes it; every root to 1e-11."""
    from continuation.bvp.simplified import JacobianCache, simplified_newton

    rng = np.random.default_rng(11)
    n = 10
    A = np.eye(n) * 4 + rng.standard_normal((n, n)) * 0.3
    z_a, z_b = rng.standard_normal(n) * 0.5, rng.standard_normal(n) * 0.5
    cache = JacobianCache()
    st = NewtonSettings(tol=1e-12, max_iter=40)
    z_prev = z_a
    for mu in np.linspace(0.0, 0.1, 6):
        z_star = (1 - mu) * z_a + mu * z_b
        b = A @ z_star + z_star**3 / 3
        r = simplified_newton(
            lambda z, b=b: A @ z + z**3 / 3 - b, lambda z: A + np.diag(z**2), z_prev, st,
            cache=cache,
        )  # fmt: skip
        assert r.converged, r.message
        np.testing.assert_allclose(r.z, z_star, atol=1e-11)
        z_prev = r.z
    assert cache.n_factorisations == 1
    z_star = 3.0 * z_b  # far away: the old Jacobian stalls and is refreshed
    b = A @ z_star + z_star**3 / 3
    r = simplified_newton(
        lambda z: A @ z + z**3 / 3 - b, lambda z: A + np.diag(z**2), z_prev, st, cache=cache
    )
    assert r.converged and cache.n_factorisations > 1
    np.testing.assert_allclose(r.z, z_star, atol=1e-10)
    with pytest.raises(ValueError, match="cache"):
        simplified_newton(lambda z: z, lambda z: np.eye(1), np.zeros(1), cache=object())
