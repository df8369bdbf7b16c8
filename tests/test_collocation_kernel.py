"""One compiled kernel of the collocation and continuity rows of every collocated orbit.

The kernel is :mod:`continuation.bvp._collocation_jit`: connections, landings and
cycles fill their collocation and continuity rows, and the Jacobian of those rows, by
the same compiled functions. References: central finite differences of the residual,
with the tolerance from their own error (the Richardson estimate of the truncation
error plus the rounding error of the residual over the step), and the identity of the
compiled function objects.
"""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from continuation.bvp.collocation import CollocationMesh
from continuation.periodic.problem import PeriodicOrbitProblem
from tests.connection_problems import CIR_START, cir, cir_connection

SHARED = "continuation.bvp._collocation_jit"


@pytest.fixture(scope="module")
def connection():
    res = cir_connection()
    prob = res.problem.with_vary("beta")
    # off the solution (an arbitrary point: the Jacobian is checked, not the orbit)
    rng = np.random.default_rng(11)
    z = res.z + 1e-2 * rng.standard_normal(res.z.size) * (1.0 + np.abs(res.z))
    return prob, z


def _central(fun, x, v, delta):
    return (fun(x + delta * v) - fun(x - delta * v)) / (2 * delta)


def _fd_tolerance(fun, x, v, delta, scale, m):
    """Error bound of the central difference at ``delta``: its truncation error
    (Richardson: about ``|D(2 delta) - D(delta)| / 3``, taken whole) plus the rounding
    of the residual's ``m + 2``-term sums, ``eps * scale`` per term, over ``delta``."""
    d1 = _central(fun, x, v, delta)
    d2 = _central(fun, x, v, 2 * delta)
    eps = np.finfo(float).eps
    return d1, np.abs(d2 - d1) + 4 * (m + 2) * eps * scale / delta


def test_connection_collocation_jacobian_against_finite_differences(connection):
    prob, z = connection
    lay = prob.layout
    rows = slice(0, lay.boundary_row)  # the kernel's rows: collocation and continuity
    p = 0.6
    G, Jz, Gp = prob.linearize(z, p)
    Jabs = abs(Jz)
    # rounding scale of each row: the sum of its terms' magnitudes
    scale = (Jabs @ np.abs(z) + np.abs(G))[rows]
    rng = np.random.default_rng(3)
    delta = 1e-5
    directions = [rng.standard_normal(z.size) for _ in range(3)]
    # the solved parameter's column (dG/dnu, from f_p into dG/dz) on its own
    e_nu = np.zeros(z.size)
    e_nu[lay.slices()["params"]] = 1.0
    for v in [*directions, e_nu]:
        fd, tol = _fd_tolerance(lambda w: prob.residual(w, p)[rows], z, v, delta, scale,
                                lay.degree)  # fmt: skip
        Jv = (Jz @ v)[rows]
        err = np.abs(Jv - fd)
        tol = tol + 4 * (lay.degree + 2) * np.finfo(float).eps * (Jabs @ np.abs(v))[rows]
        assert np.all(err <= tol), (float(np.max(err / tol)), float(np.max(np.abs(Jv))))
        # the bound is far below the entries (a 0.1 % error in the f_x or f_p terms of
        # the kernel fails this test)
        assert np.max(tol) < 1e-6 * np.max(np.abs(Jv))
    # dG/dp of the continuation parameter beta (f_p into dG/dP)
    fd, tol = _fd_tolerance(lambda q: prob.residual(z, q[0])[rows], np.array([p]),
                            np.ones(1), delta, np.abs(Gp[rows]) + scale, lay.degree)  # fmt: skip
    assert np.all(np.abs(Gp[rows] - fd) <= tol)
    assert np.max(np.abs(Gp[rows])) > 1e3 * np.max(tol)  # not a trivially zero column


def test_connection_and_cycle_use_the_same_kernel(connection, monkeypatch):
    shared = importlib.import_module(SHARED)
    backend = importlib.import_module("continuation.bvp.casadi_backend")
    cycle = importlib.import_module("continuation.periodic.problem")
    # both load the one kernel module; the cycle's compiled residual and Jacobian call
    # its collocation_residual and collocation_values inside it
    assert backend.KERNELS == cycle.KERNELS == SHARED
    # the connection's residual and Jacobian go through them (spied)
    calls = []
    for name in ("collocation_residual", "linearize"):
        fn = getattr(shared, name)
        monkeypatch.setattr(shared, name,
                            lambda *a, _fn=fn, _n=name: (calls.append(_n), _fn(*a))[1])  # fmt: skip
    prob, z = connection
    prob.residual(z, 0.6)
    prob.linearize(z, 0.6)
    assert calls == ["collocation_residual", "linearize"]
    monkeypatch.undo()
    # and a cycle's rows are those of the shared function, bit for bit
    s = cir()
    N, m = 6, 3
    mesh = CollocationMesh(N, m, 1.0)
    rng = np.random.default_rng(2)
    X = rng.standard_normal((mesh.n_points, 3))
    T = 2.5
    cyc = PeriodicOrbitProblem(s, s.params(**CIR_START), "beta", mesh, (0, 0, 0),
                               np.concatenate([X.ravel(), [T]]))  # fmt: skip
    z_c = np.concatenate([X.ravel(), [T]])
    G_c = cyc.residual(z_c, 0.6)
    Xs = X[cyc.layout.stage_points]
    F = np.array([s.f(x, cyc.param_vector(0.6)) for x in Xs])
    G = np.empty(cyc.n_unknowns)
    shared.collocation_residual(X, F, T, mesh.D, mesh.e, mesh.h, G)
    b = cyc.layout.orbit.boundary_row
    np.testing.assert_array_equal(G[:b], G_c[:b])


def test_jacobian_alone_equals_the_one_with_the_residual(connection):
    """``dG/dz`` without the residual (Newton's Jacobian call) is the linearisation's, bit
    for bit, on the same pattern, at a point off the solution."""
    prob, z = connection
    F = prob.functions
    args = prob._args(z, 0.6)
    J_alone = F.jacobian(args)
    g, J_with = F.residual_jacobian(args)
    assert J_alone.shape == J_with.shape
    np.testing.assert_array_equal(J_alone.indptr, J_with.indptr)
    np.testing.assert_array_equal(J_alone.indices, J_with.indices)
    np.testing.assert_array_equal(J_alone.data, J_with.data)
    np.testing.assert_array_equal(g, F.residual(args))


def test_parameter_jacobian_alone_equals_the_linearisation(connection):
    """``dG/dP`` alone (the sensitivity's exact columns) is the linearisation's, bit for
    bit, on the same pattern, at a point off the solution."""
    prob, z = connection
    F = prob.functions
    args = prob._args(z, 0.6)
    P_alone = F.param_jacobian(args)
    P_with = F.linearize(args)[2]
    assert P_alone.shape == P_with.shape
    np.testing.assert_array_equal(P_alone.indptr, P_with.indptr)
    np.testing.assert_array_equal(P_alone.indices, P_with.indices)
    np.testing.assert_array_equal(P_alone.data, P_with.data)
