"""Curves of connecting orbits through the pseudo-arclength driver ``continue_branch``.

References
----------
* Nagumo front speed ``c(a) = sqrt2 (1/2 - a)`` (McKean 1970, Adv. Math. 4:209-223;
  Beyn 1990, IMA J. Numer. Anal. 10:379-405), continued in ``a`` over [0.1, 0.4].
* Damped driven pendulum ``theta'' + gamma theta' + sin theta = F``: the curve
  ``F(gamma)`` of saddle-to-shifted-saddle connections, against shooting along the
  unstable manifold (independent method written in ``test_connection.py``'s style
  here) at ``gamma = 0.3`` and ``0.7``, located on the branch by user events.
"""

from __future__ import annotations

import numpy as np
import pytest

from continuation.bvp.collocation import CollocationMesh
from continuation.bvp.connection import HeteroclinicProblem
from continuation.bvp.solve import connection_at, continue_connection, solve_connection
from continuation.events import Event
from continuation.settings import ContinuationSettings, NewtonSettings
from continuation.status import Status
from tests.connection_problems import nagumo, pendulum, shooting_F

SQ2 = np.sqrt(2.0)


@pytest.fixture(scope="module")
def nagumo_start():
    s = nagumo()
    T = 40.0
    prob = HeteroclinicProblem(
        s,
        s.params(a=0.25, c=0.2),
        "c",
        saddle_from=[1.0, 0.0],
        saddle_to=[0.0, 0.0],
        mesh=CollocationMesh(80, 4, T),
    )
    t = np.linspace(0, T, 200)
    u = 1 / (1 + np.exp((t - T / 2) / 1.5))
    res = solve_connection(prob, (t, np.column_stack([u, np.gradient(u, t)])))
    assert res.success
    return res


def test_nagumo_speed_curve(nagumo_start):
    """c(a) = sqrt2 (1/2 - a) at every point of the branch over a in [0.1, 0.4]."""
    seen = []
    settings = ContinuationSettings(ds=0.02, ds_max=0.05, p_min=0.1, p_max=0.4)
    br = continue_connection(
        nagumo_start, "a", settings, direction="both", progress=lambda pt: seen.append(pt.p)
    )
    assert br.status is Status.PARAM_BOUND, br.message
    assert br.free == "a"
    assert br.p.min() == pytest.approx(0.1, abs=1e-10)
    assert br.p.max() == pytest.approx(0.4, abs=1e-10)
    assert len(br) >= 7
    assert np.all(np.diff(br.p) > 0)  # ordered from the backward to the forward end
    c = br.records["c"]
    assert np.max(np.abs(c - SQ2 * (0.5 - br.p))) < 1e-10
    # the residual of the full connection problem is below tolerance at every row
    res_norm = [np.max(np.abs(br.problem.residual(br.x[i], br.p[i]))) for i in range(len(br))]
    assert max(res_norm) < 1e-9
    # one progress call per accepted point (the start point once per direction)
    assert len(seen) == len(br) + 1
    assert np.allclose(np.unique(seen), br.p)
    # stability is not defined for connections: no spurious special points
    assert br.special_points == ()
    assert np.all(br.records["riccati_norm"] < 1.0)


def test_connection_at_branch_row_is_a_converged_connection(nagumo_start):
    settings = ContinuationSettings(ds=0.05, ds_max=0.05, p_min=0.25, p_max=0.35)
    br = continue_connection(nagumo_start, "a", settings)
    row = connection_at(br, -1)
    assert row.success and row.params["a"] == pytest.approx(0.35, abs=1e-10)
    assert row.value("c") == pytest.approx(SQ2 * 0.15, abs=1e-10)
    assert row.residual_norm < 1e-9
    # the attached problem is rebased at the row: solving again converges at once
    again = solve_connection(row.problem, row)
    assert again.success and again.newton_iters <= 2
    assert again.value("c") == pytest.approx(row.value("c"), abs=1e-12)
    with pytest.raises(ValueError, match="index"):
        connection_at(br, len(br))


def test_damped_pendulum_curve_against_shooting():
    """F(gamma) of the connection to the shifted saddle; events locate gamma = 0.3, 0.7."""
    s = pendulum()
    T = 40.0
    prob = HeteroclinicProblem(
        s,
        s.params(gamma=0.1, F=0.1),
        "F",
        saddle_from=[-np.pi, 0.0],
        shift={"theta": 2 * np.pi},
        mesh=CollocationMesh(120, 4, T),
    )
    t = np.linspace(-T / 2, T / 2, 400)
    guess = (t, np.column_stack([4 * np.arctan(np.exp(t)) - np.pi, 2 / np.cosh(t)]))
    start = solve_connection(prob, guess)
    assert start.success
    events = [Event("g03", lambda z, p: p - 0.3), Event("g07", lambda z, p: p - 0.7)]
    settings = ContinuationSettings(
        ds=0.05, ds_max=0.1, p_min=0.05, p_max=0.8, newton=NewtonSettings(tol=1e-10)
    )
    br = continue_connection(start, "gamma", settings, direction="both", events=events)
    assert br.status is Status.PARAM_BOUND, br.message
    F = br.records["F"]
    # the curve is increasing and tends to Melnikov's 4 gamma / pi at small gamma
    assert np.all(np.diff(F) > 0)
    i0 = int(np.argmin(br.p))
    assert F[i0] / (4 * br.p[i0] / np.pi) == pytest.approx(1.0, abs=2e-3)
    res_norm = [np.max(np.abs(br.problem.residual(br.x[i], br.p[i]))) for i in range(len(br))]
    assert max(res_norm) < 1e-9
    found = {sp.label: sp for sp in br.special_points}
    assert set(found) == {"g03", "g07"}
    for label, gamma in (("g03", 0.3), ("g07", 0.7)):
        sp = found[label]
        assert sp.located and sp.p == pytest.approx(gamma, abs=1e-10)
        F_bvp = connection_at_point(br, sp)
        assert F_bvp == pytest.approx(shooting_F(gamma), abs=1e-9)


def connection_at_point(br, sp) -> float:
    """F stored in the unknowns at a located special point."""
    prob = br.problem
    return float(prob.unpack(sp.x)["params"]["F"])


def test_continue_connection_bad_input(nagumo_start):
    with pytest.raises(ValueError, match="vary.*free"):
        continue_connection(nagumo_start, "c")  # c is the solved parameter
    with pytest.raises(ValueError, match="vary"):
        continue_connection(nagumo_start, "b")
    with pytest.raises(ValueError, match="result"):
        continue_connection("not a result", "a")
