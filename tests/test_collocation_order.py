"""Convergence order of the Gauss-Legendre collocation of connecting orbits.

Reference: the pendulum separatrix ``theta'' + sin(theta) = 0`` connecting the saddle
``(-pi, 0)`` to itself shifted by the period ``2 pi``,
``theta(t) = 4 atan(exp(t)) - pi``, ``omega(t) = 2 sech(t)`` (exact). The declared orders
(de Boor & Swartz 1973, SIAM J. Numer. Anal. 10:582-606): ``2 m`` at the mesh nodes
and ``m + 1`` uniformly (max over mesh and collocation points). ``T = 40`` keeps the
truncation error (about ``exp(-T)``) far below the smallest mesh error measured.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import linregress

from continuation.bvp.accuracy import ConnectionAccuracy
from continuation.bvp.collocation import CollocationMesh
from continuation.bvp.connection import HeteroclinicProblem, PinPhase
from continuation.bvp.solve import solve_connection
from continuation.system import System

T = 40.0

PLAIN = ConnectionAccuracy(estimate=False)  # the plain solve on a fixed mesh


def pendulum() -> System:
    """theta'' + gamma theta' + sin(theta) = F as a first-order system; theta has period 2 pi."""

    def rhs(x, p, ops):
        return ops.stack([x[1], p[1] - p[0] * x[1] - ops.sin(x[0])])

    return System(rhs, ("theta", "omega"), ("gamma", "F"), periodic={"theta": 2 * np.pi})


SYS = pendulum()


def exact(t: np.ndarray) -> np.ndarray:
    """Separatrix centred at t = 0, shape (len(t), 2)."""
    return np.column_stack([4 * np.arctan(np.exp(t)) - np.pi, 2 / np.cosh(t)])


def perturbed_guess() -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(-T / 2, T / 2, 400)
    x = exact(t)
    x[:, 0] += 0.1 * np.sin(x[:, 0])  # not the solution: Newton has work to do
    x[:, 1] *= 1.1
    return t, x


def solve(n_intervals: int, degree: int, phase="pin"):
    """Separatrix (F solved for, gamma = 0) on a uniform mesh; returns the result."""
    ph = PinPhase("theta", 0.0) if phase == "pin" else "integral"
    prob = HeteroclinicProblem(
        SYS,
        SYS.params(gamma=0.0, F=0.01),
        "F",
        saddle_from=[-np.pi, 0.0],
        shift={"theta": 2 * np.pi},
        mesh=CollocationMesh(n_intervals, degree, T),
        phase=ph,
    )
    if phase == "pin":
        res = solve_connection(prob, perturbed_guess(), accuracy=PLAIN)
    else:
        # integral phase condition against the exact orbit as reference
        tt = np.linspace(-T / 2, T / 2, 4001)
        ref = prob.mesh.t - T / 2
        prob = prob.replace(reference=exact(ref))
        res = solve_connection(prob, (tt, exact(tt) * 1.02), accuracy=PLAIN)
    assert res.success, res.message
    return res


def errors(res) -> tuple[float, float]:
    """(max error at mesh nodes, max error at all mesh and collocation points)."""
    err = np.max(np.abs(res.x - exact(res.t - T / 2)), axis=1)
    return float(err[res.mesh.mesh_mask].max()), float(err.max())


def test_gauss_tableau_is_exact_for_polynomials():
    """Quadrature exact to degree 2m-1; D differentiates and e evaluates degree-m polynomials."""
    for m in range(1, 7):
        mesh = CollocationMesh(1, m, 1.0)
        c, b, D, e = mesh.c, mesh.b, mesh.D, mesh.e
        nodes = np.concatenate(([0.0], c))
        for j in range(2 * m):
            assert b @ c**j == pytest.approx(1.0 / (j + 1), rel=1e-13, abs=1e-14)
        for j in range(m + 1):
            assert np.allclose(D @ nodes**j, j * c ** max(j - 1, 0) if j else 0.0, atol=1e-11)
            assert e @ nodes**j == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize(
    ("degree", "ns_mesh", "ns_all"),
    [
        (1, (40, 80, 160), (40, 80, 160)),
        (2, (40, 80, 160), (80, 160, 320)),
        (3, (40, 80, 160), (80, 160, 320)),
        (4, (80, 160, 320), (80, 160, 320)),
    ],
)
def test_collocation_order(degree, ns_mesh, ns_all):
    """log(error) vs log(h): slope 2m at mesh nodes, m+1 over all points (within 0.5)."""
    cache = {n: errors(solve(n, degree)) for n in sorted(set(ns_mesh) | set(ns_all))}
    h_mesh = [T / n for n in ns_mesh]
    h_all = [T / n for n in ns_all]
    e_mesh = [cache[n][0] for n in ns_mesh]
    e_all = [cache[n][1] for n in ns_all]
    mesh = CollocationMesh(10, degree, T)
    slope_mesh = linregress(np.log(h_mesh), np.log(e_mesh)).slope
    slope_all = linregress(np.log(h_all), np.log(e_all)).slope
    assert abs(slope_mesh - mesh.order) < 0.5, (slope_mesh, e_mesh)
    assert abs(slope_all - mesh.uniform_order) < 0.5, (slope_all, e_all)
    assert np.all(np.diff(e_mesh) < 0) and np.all(np.diff(e_all) < 0)
    assert min(e_mesh) > 1e-13  # above round-off: the slope measures the discretisation


def test_integral_phase_keeps_superconvergence():
    """With the integral phase condition the mesh-node order is still 2m (m = 3)."""
    ns = (40, 80, 160)
    e = [errors(solve(n, 3, phase="integral"))[0] for n in ns]
    slope = linregress(np.log([T / n for n in ns]), np.log(e)).slope
    assert abs(slope - 6) < 0.5, (slope, e)


def test_solved_parameter_is_exact_for_the_separatrix():
    """The undamped pendulum connects only at F = 0 (gamma = 0): F comes out as 0."""
    res = solve(40, 3)
    assert abs(res.value("F")) < 1e-12


def fisher() -> System:
    """Fisher-KPP travelling waves u'' + c u' + u (1 - u) = 0."""

    def rhs(x, p, ops):
        return ops.stack([x[1], -p[0] * x[1] - x[0] * (1 - x[0])])

    return System(rhs, ("u", "v"), ("c",))


def fisher_error(res) -> float:
    """Max error against u = (1 + C exp(t/sqrt6))^-2 with u = 1/4 at the pinned node."""
    i_node = res.problem.layout.pin[1]
    t_pin = res.t_mesh[i_node]
    C = np.exp(-t_pin / np.sqrt(6))
    tt = np.linspace(0, res.T, 4001)
    ue = (1 + C * np.exp(tt / np.sqrt(6))) ** -2
    return float(np.max(np.abs(res.interpolate(tt)[:, 0] - ue)))


def test_mesh_adaptation_reduces_error():
    """Equidistribution on the Fisher-KPP front (exact profile, Ablowitz & Zeppetella 1979).

    Same number of intervals (40, degree 3, T = 60): two adaptation rounds must cut
    the max error of the dense output against the exact profile at least tenfold.
    """
    s = fisher()
    c = 5 / np.sqrt(6)
    Tf = 60.0
    prob = HeteroclinicProblem(
        s,
        s.params(c=c),
        (),
        saddle_from=[1.0, 0.0],
        saddle_to=[0.0, 0.0],
        mesh=CollocationMesh(40, 3, Tf),
        phase=PinPhase("u", 0.25),
    )
    t = np.linspace(0, Tf, 300)
    u = 1 / (1 + np.exp((t - Tf / 3) / 2))
    guess = (t, np.column_stack([u, np.gradient(u, t)]))
    uniform = solve_connection(prob, guess, accuracy=PLAIN)
    adapted = solve_connection(prob, guess, accuracy=PLAIN, adapt=2)
    assert uniform.success and adapted.success
    assert adapted.mesh.n_intervals == 40
    assert not np.allclose(np.diff(adapted.mesh.nodes), 1 / 40)
    e_uni, e_ad = fisher_error(uniform), fisher_error(adapted)
    assert e_ad < 0.1 * e_uni, (e_uni, e_ad)
    assert e_uni < 1e-4


def test_mesh_validation():
    with pytest.raises(ValueError, match="degree"):
        CollocationMesh(10, 0, 1.0)
    with pytest.raises(ValueError, match="n_intervals"):
        CollocationMesh(0, 2, 1.0)
    with pytest.raises(ValueError, match="T"):
        CollocationMesh(10, 2, -1.0)
    with pytest.raises(ValueError, match="nodes"):
        CollocationMesh(2, 2, 1.0, nodes=[0.0, 0.7, 0.5])
    with pytest.raises(ValueError, match="nodes"):
        CollocationMesh(2, 2, 1.0, nodes=[0.0, 1.0])


def test_refined_and_interpolation():
    """Halving keeps the old nodes; interpolation reproduces a degree-m polynomial exactly."""
    mesh = CollocationMesh(
        7, 3, 2.0, nodes=np.sort(np.r_[0, np.random.default_rng(1).random(6), 1])
    )
    fine = mesh.refined()
    assert fine.n_intervals == 14
    assert np.allclose(fine.nodes[::2], mesh.nodes)
    poly = lambda s: 1 + 2 * s - 3 * s**2 + 0.5 * s**3  # noqa: E731
    X = poly(mesh.tau)[:, None]
    s = np.linspace(0, 1, 57)
    assert np.allclose(mesh.interpolate(X, s)[:, 0], poly(s), atol=1e-12)
    assert np.allclose(
        mesh.derivative(X)[:, 0], (2 - 6 * mesh.tau + 1.5 * mesh.tau**2)[mesh.stage_mask]
    )
