"""Branch switching at simple branch points, against closed-form crossing branches.

References: the algebraic bifurcation equation (ABE) of Keller (1977) and Doedel,
Keller & Kernevez (1991, Int. J. Bifurcation and Chaos 1:493-520); every system below
has its branches in closed form, so the switched branch, its tangent at the branch point
and the angle between the branches are checked exactly.
"""

from __future__ import annotations

import dataclasses
import math
from functools import cache

import numpy as np
import pytest
from helpers import bratu, bratu_branch, pitchfork, transcritical

import continuation.switching.switch as sw
from continuation.algorithms.base import theta_weights
from continuation.api import continue_equilibria
from continuation.branch import Branch
from continuation.driver import continue_branch
from continuation.errors import ContinuationError
from continuation.events import Event
from continuation.params import Params
from continuation.problem import EquilibriumProblem
from continuation.settings import ContinuationSettings
from continuation.status import Status
from continuation.switching import crossing_tangents, switch_branch
from continuation.system import System

A_SLOPE, B_SLOPE = 0.5, 3.0  # the two lines x = a mu, x = b mu of the oblique system
W1 = theta_weights(1, 0.5)


def oblique(backend: str = "auto") -> System:
    """G = (x - a mu)(x - b mu): two lines crossing at the origin at an oblique angle."""
    if backend == "numpy":
        return System(
            lambda x, p: np.array([(x[0] - A_SLOPE * p[0]) * (x[0] - B_SLOPE * p[0])]),
            ("x",),
            ("mu",),
            backend="numpy",
        )
    return System(
        lambda x, p, ops: ops.stack([(x[0] - A_SLOPE * p[0]) * (x[0] - B_SLOPE * p[0])]),
        ("x",),
        ("mu",),
    )


def plane_system() -> System:
    """A 2-D system with a branch point at (x, y, mu) = (1, 2, 1):

    x' = (x - 1 - a (mu - 1)) (x - 1 - b (mu - 1)) + r,  y' = r,  r = y - x^2 - mu;
    the equilibria are the curves x = 1 + a (mu - 1) and x = 1 + b (mu - 1), y = x^2 + mu.
    """

    def rhs(x, p, ops):
        mu = p[0]
        r = x[1] - x[0] ** 2 - mu
        P = (x[0] - 1 - A_SLOPE * (mu - 1)) * (x[0] - 1 - B_SLOPE * (mu - 1))
        return ops.stack([P + r, r])

    return System(rhs, ("x", "y"), ("mu",))


def _cos_theta(a, b, w):
    return float((w * a).dot(b)) / math.sqrt(float((w * a).dot(a)) * float((w * b).dot(b)))


@cache
def trivial_branch(kind: str) -> Branch:
    """x = 0 for mu in [-0.5, 0.5] of the pitchfork / transcritical normal form."""
    system = pitchfork() if kind == "pf" else transcritical()
    br = continue_equilibria(system, [0.0], {"mu": -0.5}, "mu", p_max=0.5, direction="forward")
    assert br.status is Status.PARAM_BOUND
    return br


BOUNDED = ContinuationSettings(p_min=-0.5, p_max=0.5, ds=0.01, ds_max=0.05)


# ----------------------------------------------------------------------------- pitchfork
def test_pitchfork_switch_gives_both_halves_of_the_parabola_with_its_fold_at_the_bp():
    """x' = mu x - x^3: from x = 0 the switched branch is x^2 = mu (both signs of x),
    stable with eigenvalue -2 mu, with its fold (and the branch point) at mu = 0."""
    br = trivial_branch("pf")
    calls = []
    nb = switch_branch(br, "BP1", settings=BOUNDED, progress=calls.append)
    assert nb.status is Status.PARAM_BOUND and "angle 90 deg" in nb.message
    x, mu = nb.x[:, 0], nb.p
    np.testing.assert_allclose(x**2, mu, rtol=0, atol=1e-12)
    assert x.min() == pytest.approx(-math.sqrt(0.5), abs=1e-12)  # both ends on p_max
    assert x.max() == pytest.approx(math.sqrt(0.5), abs=1e-12)
    assert np.all(np.diff(x) > 0)  # one branch, ordered from x < 0 through 0 to x > 0
    # (the driver's eigenvalues come from the Jacobian of the last corrector iterate,
    # within newton.step_tol = 1e-8 of the row: |d(mu - 3 x^2)/dx| <= 6 gives 6e-8)
    np.testing.assert_allclose(nb.eigenvalues[:, 0].real, -2 * mu, atol=1e-7)
    assert np.all(nb.n_unstable == 0)
    (fold,) = nb.find("fold")
    assert fold.located and fold.p == pytest.approx(0.0, abs=1e-10)
    (bp,) = nb.find("bp")
    assert bp.located and bp.p == pytest.approx(0.0, abs=1e-10)
    assert abs(bp.x[0]) < 1e-5  # (located on the branch to the locator's tolerance)
    assert len(calls) >= len(nb)  # every row reported (the start row by both runs)


def test_pitchfork_halves_follow_the_orientation_rule_and_amplitude():
    """The crossing branch is vertical at the pitchfork, so "forward" is the half with
    the larger state component positive; the first row is the start point at distance
    `amplitude` along x: <phi2, u - u*>_theta = a with phi2 = (sqrt 2, 0), x = sqrt(2) a."""
    br = trivial_branch("pf")
    amp = 0.02
    fwd = switch_branch(br, "BP1", settings=BOUNDED, direction="forward", amplitude=amp)
    bwd = switch_branch(br, "BP1", settings=BOUNDED, direction="backward", amplitude=amp)
    assert fwd.status is Status.PARAM_BOUND and bwd.status is Status.PARAM_BOUND
    assert np.all(fwd.x[:, 0] > 0) and np.all(bwd.x[:, 0] < 0)
    assert fwd.x[0, 0] == pytest.approx(math.sqrt(2) * amp, rel=1e-10)
    assert bwd.x[0, 0] == pytest.approx(-math.sqrt(2) * amp, rel=1e-10)
    for b in (fwd, bwd):
        np.testing.assert_allclose(b.x[:, 0] ** 2, b.p, atol=1e-12)
        assert b.p[-1] == pytest.approx(0.5, abs=1e-12)


def test_pitchfork_switch_from_the_parabola_gives_the_trivial_branch():
    """Along x^2 = mu the pitchfork is met at the fold; switching there gives x = 0
    (through mu = 0, where the trivial branch has its own branch point)."""
    br = continue_equilibria(
        pitchfork(), [0.5], {"mu": 0.25}, "mu", p_max=0.3, ds=0.01, ds_max=0.05
    )
    (bp,) = br.find("bp")
    assert bp.located and bp.p == pytest.approx(0.0, abs=1e-10)
    nb = switch_branch(br, bp, settings=ContinuationSettings(p_min=-0.3, p_max=0.3, ds_max=0.05))
    assert nb.status is Status.PARAM_BOUND
    np.testing.assert_allclose(nb.x[:, 0], 0.0, atol=1e-12)
    assert nb.p.min() == pytest.approx(-0.3, abs=1e-12)
    assert nb.p.max() == pytest.approx(0.3, abs=1e-12)
    (bp2,) = nb.find("bp")
    assert bp2.p == pytest.approx(0.0, abs=1e-10)


# ----------------------------------------------------------------------------- transcritical
def test_transcritical_switch_gives_the_line_x_equals_mu_on_both_sides():
    """x' = mu x - x^2: the crossing branch x = mu (eigenvalue -mu: stable for mu > 0),
    at 45 degrees to x = 0 (theta = 0.5, one unknown: the Euclidean angle)."""
    br = trivial_branch("tc")
    nb = switch_branch(br, "BP1", settings=BOUNDED)
    assert nb.status is Status.PARAM_BOUND
    np.testing.assert_allclose(nb.x[:, 0], nb.p, atol=1e-12)
    assert nb.p[0] == pytest.approx(-0.5, abs=1e-12)  # ordered from dp/ds < 0 ...
    assert nb.p[-1] == pytest.approx(0.5, abs=1e-12)  # ... to dp/ds > 0 (ds > 0)
    np.testing.assert_allclose(nb.eigenvalues[:, 0].real, -nb.p, atol=1e-7)  # (as above)
    (bp,) = nb.find("bp")
    assert bp.located and bp.p == pytest.approx(0.0, abs=1e-10)
    assert bp.delta_unstable == (-1, 0)  # exchange of stability
    # a negative ds reverses which half is "forward"
    neg = dataclasses.replace(BOUNDED, ds=-0.01)
    fwd = switch_branch(br, "BP1", settings=neg, direction="forward")
    assert np.all(fwd.p < 0) and fwd.p[-1] == pytest.approx(-0.5, abs=1e-12)


def test_switch_with_the_branch_point_on_a_parameter_bound():
    """p_max = 0 at the branch point: "both" starts on the admissible half (mu < 0) and
    stops on the bound at the branch point; the half mu > 0 is refused (PARAM_BOUND)."""
    br = trivial_branch("tc")
    st = dataclasses.replace(BOUNDED, p_max=0.0)
    nb = switch_branch(br, "BP1", settings=st)
    assert nb.status is Status.PARAM_BOUND
    assert np.all(nb.p <= 0.0) and nb.p.min() == pytest.approx(-0.5, abs=1e-12)
    assert nb.p.max() == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(nb.x[:, 0], nb.p, atol=1e-12)
    out = switch_branch(br, "BP1", settings=st, direction="forward")
    assert out.status is Status.PARAM_BOUND and len(out) == 0


# ----------------------------------------------------------------------------- oblique
@pytest.mark.parametrize("backend", ["auto", "numpy"])
def test_oblique_crossing_needs_the_bifurcation_equation(backend):
    """G = (x - a mu)(x - b mu), a = 1/2, b = 3: from x = a mu the switched branch is
    x = b mu, whose tangent (b, 1) is NOT the kernel direction orthogonal to (a, 1)
    (35 degrees apart): only the ABE gives it. CasADi and finite-difference second
    derivatives."""
    system = oblique(backend)
    br = continue_equilibria(
        system, [-0.5 * A_SLOPE], {"mu": -0.5}, "mu", p_max=0.5, direction="forward"
    )
    (bp,) = br.find("bp")
    ct = crossing_tangents(br.problem, bp.x, bp.p, reference=[A_SLOPE, 1.0])
    assert ct.status is Status.SUCCESS
    assert ct.second_derivatives == ("casadi" if backend == "auto" else "finite differences")
    t_old, t_new = np.array([A_SLOPE, 1.0]), np.array([B_SLOPE, 1.0])
    tol = 1e-12 if backend == "auto" else 1e-7
    assert abs(_cos_theta(ct.t_new, t_new, W1)) == pytest.approx(1.0, abs=tol)
    assert abs(_cos_theta(ct.t_old, t_old, W1)) == pytest.approx(1.0, abs=tol)
    angle = math.degrees(math.acos(_cos_theta(t_old, t_new, W1)))
    assert ct.angle_deg == pytest.approx(angle, abs=1e-5)
    assert 90.0 - angle > 20.0  # the orthogonal guess would be far off
    nb = switch_branch(br, bp, settings=BOUNDED)
    assert nb.status is Status.PARAM_BOUND
    np.testing.assert_allclose(nb.x[:, 0], B_SLOPE * nb.p, atol=1e-12)
    assert nb.p.min() < -0.1 and nb.p.max() > 0.1
    # and back: from x = b mu onto x = a mu
    back = switch_branch(nb, "BP1", settings=BOUNDED)
    np.testing.assert_allclose(back.x[:, 0], A_SLOPE * back.p, atol=1e-12)
    assert back.p.min() == pytest.approx(-0.5) and back.p.max() == pytest.approx(0.5)


@pytest.mark.parametrize(("a", "b"), [(1.0, 1.02), (100.0, 101.0)])
def test_nearly_tangent_lines(a, b):
    """G = (x - a mu)(x - b mu) with the lines 0.57 and 0.0057 degrees apart (theta
    metric): the ABE still separates them and the switched branch is x = b mu."""
    system = System(lambda x, p, ops: ops.stack([(x[0] - a * p[0]) * (x[0] - b * p[0])]), "x", "mu")
    br = continue_equilibria(system, [-0.5 * a], {"mu": -0.5}, "mu", p_max=0.5, direction="forward")
    (bp,) = br.find("bp")
    nb = switch_branch(br, bp, settings=dataclasses.replace(BOUNDED, ds_max=2.0))
    angle = math.degrees(math.acos(_cos_theta(np.array([a, 1.0]), np.array([b, 1.0]), W1)))
    assert f"angle {angle:.4g} deg" in nb.message
    assert nb.status is Status.PARAM_BOUND
    np.testing.assert_allclose(nb.x[:, 0], b * nb.p, atol=1e-12 * b)
    assert nb.p.min() == pytest.approx(-0.5) and nb.p.max() == pytest.approx(0.5)


def test_two_dimensional_branch_point_away_from_the_origin():
    """The plane system's branch point at (1, 2, 1): the switched branch is
    x = 1 + b (mu - 1), y = x^2 + mu; tangent (b, 2b + 1, 1) and the theta-angle to
    (a, 2a + 1, 1) from the closed form."""
    br = continue_equilibria(
        plane_system(), [1 - A_SLOPE, (1 - A_SLOPE) ** 2], {"mu": 0.0}, "mu", p_max=2.0,
        direction="forward",
    )  # fmt: skip
    (bp,) = br.find("bp")
    assert bp.p == pytest.approx(1.0, abs=1e-10)
    w = theta_weights(2, 0.5)
    chord = np.append(br.x[bp.index + 1] - br.x[bp.index], br.p[bp.index + 1] - br.p[bp.index])
    ct = crossing_tangents(br.problem, bp.x, bp.p, chord)
    t_old = np.array([A_SLOPE, 2 * A_SLOPE + 1, 1.0])
    t_new = np.array([B_SLOPE, 2 * B_SLOPE + 1, 1.0])
    assert abs(_cos_theta(ct.t_new, t_new, w)) == pytest.approx(1.0, abs=1e-10)
    angle = math.degrees(math.acos(_cos_theta(t_old, t_new, w)))
    assert ct.angle_deg == pytest.approx(angle, abs=1e-5)
    nb = switch_branch(br, "BP1", settings=ContinuationSettings(p_min=0.0, p_max=2.0))
    assert nb.status is Status.PARAM_BOUND
    x_exact = 1 + B_SLOPE * (nb.p - 1)
    np.testing.assert_allclose(nb.x[:, 0], x_exact, atol=1e-11)
    np.testing.assert_allclose(nb.x[:, 1], x_exact**2 + nb.p, atol=1e-10)
    assert nb.p.min() == pytest.approx(0.0, abs=1e-12)
    assert nb.p.max() == pytest.approx(2.0, abs=1e-12)


def test_bordered_kernel_for_sparse_problems(monkeypatch):
    """The sparse path (bordered solves instead of an SVD) gives the same crossing
    tangent and the same switched branch on the plane system."""
    system = plane_system()
    problem = EquilibriumProblem(system, Params(("mu",), np.array([0.0])), "mu", sparse=True)
    x0 = np.array([1 - A_SLOPE, (1 - A_SLOPE) ** 2])
    br = continue_branch(problem, x0, 0.0, settings=ContinuationSettings(p_max=2.0))
    (bp,) = br.find("bp")
    w = theta_weights(2, 0.5)
    chord = np.append(br.x[bp.index + 1] - br.x[bp.index], br.p[bp.index + 1] - br.p[bp.index])
    ct_b = crossing_tangents(problem, bp.x, bp.p, chord, kernel="bordered")
    ct_s = crossing_tangents(problem, bp.x, bp.p, chord, kernel="svd")
    assert ct_b.kernel == "bordered" and ct_b.status is Status.SUCCESS
    assert ct_b.kernel_gap < 1e-10  # relative residual of the kernel vectors
    t_new = np.array([B_SLOPE, 2 * B_SLOPE + 1, 1.0])
    assert abs(_cos_theta(ct_b.t_new, t_new, w)) == pytest.approx(1.0, abs=1e-10)
    assert ct_b.angle_deg == pytest.approx(ct_s.angle_deg, abs=1e-8)
    monkeypatch.setattr(sw, "DENSE_KERNEL_MAX", 1)  # force the bordered path
    nb = switch_branch(br, "BP1", settings=ContinuationSettings(p_min=0.0, p_max=2.0))
    assert nb.status is Status.PARAM_BOUND
    x_exact = 1 + B_SLOPE * (nb.p - 1)
    np.testing.assert_allclose(nb.x[:, 0], x_exact, atol=1e-11)


# ----------------------------------------------------------------------------- published
def test_lorenz_pitchfork_onto_the_convection_branches():
    """Lorenz (1963) x' = s (y - x), y' = r x - y - x z, z' = x y - b z, s = 10,
    b = 8/3: from the origin's branch point at r = 1 the switched branch is
    C+- = (+-sqrt(b (r - 1)), +-sqrt(b (r - 1)), r - 1), both of whose halves lose
    stability in a Hopf bifurcation at r_H = s (s + b + 3) / (s - b - 1) = 470/19
    (Sparrow 1982, The Lorenz Equations, Sec. 1.2)."""
    s_, b_ = 10.0, 8.0 / 3.0

    def rhs(x, p, ops):
        r = p[0]
        return ops.stack(
            [s_ * (x[1] - x[0]), r * x[0] - x[1] - x[0] * x[2], x[0] * x[1] - b_ * x[2]]
        )

    lorenz = System(rhs, ("x", "y", "z"), ("r",))
    br = continue_equilibria(
        lorenz, [0.0, 0.0, 0.0], {"r": 0.0}, "r", p_max=30.0, ds_max=0.5, direction="forward"
    )
    (bp,) = br.find("bp")
    assert bp.p == pytest.approx(1.0, abs=1e-10)
    nb = switch_branch(br, bp, settings=ContinuationSettings(p_min=0.0, p_max=30.0, ds_max=0.5))
    assert nb.status is Status.PARAM_BOUND
    r = nb.p
    np.testing.assert_allclose(nb.x[:, 0] ** 2, b_ * (r - 1), atol=1e-11)
    np.testing.assert_allclose(nb.x[:, 1], nb.x[:, 0], atol=1e-12)
    np.testing.assert_allclose(nb.x[:, 2], r - 1, atol=1e-12)
    assert nb.x[0, 0] < -8.0 and nb.x[-1, 0] > 8.0  # both halves, up to r = 30
    hopf = nb.find("hopf")
    assert len(hopf) == 2 and {np.sign(h.x[0]) for h in hopf} == {-1.0, 1.0}
    for h in hopf:
        assert h.located and h.p == pytest.approx(470.0 / 19.0, rel=1e-8)


def test_periodic_state_crossing_branch_is_a_closed_loop():
    """th' = sin(th) (mu - 2 cos th), th periodic: the trivial branch th = 0 has a
    pitchfork at mu = 2; the crossing branch cos(th) = mu / 2 is a closed loop through
    the second pitchfork at (th, mu) = (pi, -2)."""
    system = System(
        lambda x, p, ops: ops.stack([ops.sin(x[0]) * (p[0] - 2 * ops.cos(x[0]))]),
        ("th",),
        ("mu",),
        periodic={"th": 2 * np.pi},
    )
    br = continue_equilibria(system, [0.0], {"mu": 0.0}, "mu", p_max=4.0, direction="forward")
    (bp,) = br.find("bp")
    assert bp.p == pytest.approx(2.0, abs=1e-10)
    nb = switch_branch(br, bp, settings=ContinuationSettings(p_min=-3.0, p_max=3.0))
    assert nb.status is Status.CLOSED_LOOP
    np.testing.assert_allclose(np.cos(nb.x[:, 0]), nb.p / 2, atol=1e-12)
    far = [s for s in nb.find("bp") if s.p < 0]
    assert len(far) == 1 and far[0].p == pytest.approx(-2.0, abs=1e-8)
    assert abs(np.cos(far[0].x[0]) + 1) < 1e-8  # th = pi (mod 2 pi)


# ----------------------------------------------------------------------------- Bratu
def test_bratu_symmetry_breaking_pitchfork():
    """Discrete Bratu N = 20 (see test_reference_problems): at lam ~ 1.48e-6 the
    symmetric branch meets a pitchfork whose kernel vector is antisymmetric. The ABE
    tangent is that antisymmetric vector with dp = 0 (both kernel paths); the switched
    branch solves G = 0, is asymmetric on both halves (mirror images: u_1 - u_N of
    either sign) and symmetric only at the branch point."""
    n = 20
    stop = Event("far", lambda x, p: float(np.max(x)) - 21.0, terminal=True)
    br = bratu_branch(
        n, p_min=0.0, p_max=4.0, ds=0.5, ds_max=0.5, direction="forward", events=[stop]
    )
    (bp,) = br.find("bp")
    chord = np.append(br.x[bp.index + 1] - br.x[bp.index], br.p[bp.index + 1] - br.p[bp.index])
    for kernel in ("svd", "bordered"):
        ct = crossing_tangents(br.problem, bp.x, bp.p, chord, kernel=kernel)
        z = ct.t_new[:-1]
        # antisymmetric up to the asymmetry of the located point (|u - u[::-1]| ~ 1e-5 u)
        assert np.max(np.abs(z + z[::-1])) < 1e-3 * np.max(np.abs(z))
        assert abs(ct.t_new[-1]) < 1e-8
        assert ct.angle_deg == pytest.approx(90.0, abs=0.01)
    asym = Event("asym", lambda x, p: float(np.max(np.abs(x - x[::-1]))) - 5.0, terminal=True)
    nb = switch_branch(br, bp, events=[asym])
    assert nb.status is Status.EVENT
    system = bratu(n)
    scale = (n + 1) ** 2 * np.max(np.abs(nb.x), axis=1)  # size of the terms of G
    for k in range(len(nb)):
        assert np.max(np.abs(system.f(nb.x[k], nb.p[k : k + 1]))) <= 1e-12 * scale[k]
    d = nb.x[:, 0] - nb.x[:, -1]
    a = np.max(np.abs(nb.x - nb.x[:, ::-1]), axis=1)
    assert d[0] < -0.1 and d[-1] > 0.1  # both halves
    assert a[0] == pytest.approx(5.0, abs=1e-6) and a[-1] == pytest.approx(5.0, abs=1e-6)
    k = int(np.argmin(a))
    assert a[k] < 0.05 * np.max(nb.x[k])  # passes the symmetric branch point ...
    assert nb.p[k] == pytest.approx(bp.p, rel=0.05)  # ... at lam*
    assert nb.event_names == ("asym",)


# ----------------------------------------------------------------------------- failures
def test_degenerate_branch_point_is_refused():
    """G = x (mu^3 - x^2): the trivial branch's branch point at 0 has all second
    derivatives zero (the other branch x^2 = mu^3 has a cusp there): no simple branch
    point, so SINGULAR and an empty branch (ContinuationError with throw=True)."""
    system = System(lambda x, p, ops: ops.stack([x[0] * (p[0] ** 3 - x[0] ** 2)]), "x", "mu")
    br = continue_equilibria(system, [0.0], {"mu": -0.5}, "mu", p_max=0.5, direction="forward")
    (bp,) = br.find("bp")
    nb = switch_branch(br, bp)
    assert nb.status is Status.SINGULAR and len(nb) == 0
    assert "degenerate" in nb.message
    with pytest.raises(ContinuationError, match="degenerate"):
        switch_branch(br, bp, throw=True)


def test_crossing_check_rejects_a_run_that_fell_back_onto_the_old_branch():
    """The row check next to the branch point: rows on x = mu pass; a row past the
    branch point on x = 0 (the old branch of the transcritical form) fails."""
    br = trivial_branch("tc")
    ct = crossing_tangents(br.problem, [0.0], 0.0, [0.0, 1.0])
    t_new = sw._orient(ct.t_new, 1.0)

    def fake(mu, x):
        N = len(mu)
        return Branch(
            problem=br.problem, free="mu", p=np.array(mu), x=np.array(x).reshape(N, 1),
            eigenvalues=np.zeros((N, 1), complex), n_unstable=np.zeros(N, int),
            ds=np.zeros(N), newton_iters=np.zeros(N, int), records={}, special_points=(),
            status=Status.SUCCESS,
        )  # fmt: skip

    good = fake([-0.03, -0.01, 0.02, 0.05], [-0.03, -0.01, 0.02, 0.05])
    assert sw._check_crossing(good, ct, t_new, W1, 3, 1.0, 0.01)[0]
    bad = fake([-0.03, -0.01, 0.02, 0.05], [0.0, 0.0, 0.02, 0.05])
    ok, k_bad, ratio = sw._check_crossing(bad, ct, t_new, W1, 3, 1.0, 0.01)
    assert not ok and k_bad == 1 and abs(ratio) < 1e-12
    # a start at u- (side -1) walks towards higher rows
    bad2 = fake([-0.05, -0.02, 0.01, 0.03], [-0.05, -0.02, 0.0, 0.0])
    ok, k_bad, _ = sw._check_crossing(bad2, ct, t_new, W1, 0, -1.0, 0.01)
    assert not ok and k_bad == 2
    good2 = fake([-0.05, -0.02, 0.01, 0.03], [-0.05, -0.02, 0.01, 0.03])
    assert sw._check_crossing(good2, ct, t_new, W1, 0, -1.0, 0.01)[0]


def test_failed_crossing_keeps_the_start_side_and_reports_it(monkeypatch):
    """If no run through the branch point passes the check, only the verified half is
    returned, with NEWTON_FAILED (ContinuationError with throw=True)."""
    monkeypatch.setattr(sw, "CROSSING_RATIO", 2.0)  # no row can pass (ratio = 1 here)
    br = trivial_branch("pf")
    nb = switch_branch(br, "BP1", settings=BOUNDED)
    assert nb.status is Status.NEWTON_FAILED and "left the crossing branch" in nb.message
    assert len(nb) > 3 and np.all(nb.x[:, 0] > 0)  # the x > 0 half (start side) only
    np.testing.assert_allclose(nb.x[:, 0] ** 2, nb.p, atol=1e-12)
    assert nb.ds[0] == 0.0
    with pytest.raises(ContinuationError, match="left the crossing branch"):
        switch_branch(br, "BP1", settings=BOUNDED, throw=True)


def test_bad_input_names_the_argument(tmp_path):
    br = trivial_branch("pf")
    (bp,) = br.find("bp")
    fold_br = continue_equilibria(
        System(lambda x, p, ops: ops.stack([p[0] - x[0] ** 2]), "x", "mu"),
        [1.0], {"mu": 1.0}, "mu", p_min=-0.5, p_max=1.0, ds=-0.05,
    )  # fmt: skip
    (fold,) = fold_br.find("fold")
    with pytest.raises(ValueError, match="`point` must be a branch point"):
        switch_branch(fold_br, fold)
    with pytest.raises(ValueError, match="`point`.*not located|`point`.*only bracketed"):
        switch_branch(br, dataclasses.replace(bp, located=False))
    with pytest.raises(ValueError, match="`point`.*not a special point of `branch`"):
        switch_branch(fold_br, bp)
    with pytest.raises(ValueError, match="`point`: no special point labelled 'BP7'"):
        switch_branch(br, "BP7")
    with pytest.raises(ValueError, match="`point` must be a SpecialPoint"):
        switch_branch(br, 3)
    for amp in (0.0, -1e-3, math.nan, "big"):
        with pytest.raises(ValueError, match="`amplitude`"):
            switch_branch(br, bp, amplitude=amp)
    with pytest.raises(ValueError, match="`direction`"):
        switch_branch(br, bp, direction="sideways")
    with pytest.raises(ValueError, match="`settings`"):
        switch_branch(br, bp, settings={"ds": 0.1})
    with pytest.raises(ValueError, match="`algorithm`"):
        switch_branch(br, bp, algorithm="palc")
    with pytest.raises(ValueError, match="`events`"):
        switch_branch(br, bp, events=["far"])
    with pytest.raises(ValueError, match="`branch` must be a Branch"):
        switch_branch("br", bp)
    loaded = Branch.load(br.save(tmp_path / "b"))
    with pytest.raises(ValueError, match="`branch` has no problem"):
        switch_branch(loaded, "BP1")
    # reattaching the problem makes a loaded branch switchable
    again = Branch.load(tmp_path / "b", problem=br.problem)
    nb = switch_branch(again, "BP1", settings=BOUNDED)
    np.testing.assert_allclose(nb.x[:, 0] ** 2, nb.p, atol=1e-12)
    with pytest.raises(ValueError, match="`reference`"):
        crossing_tangents(br.problem, [0.0], 0.0, [0.0, 0.0])
    with pytest.raises(ValueError, match="`kernel`"):
        crossing_tangents(br.problem, [0.0], 0.0, [0.0, 1.0], kernel="qr")
    with pytest.raises(ValueError, match="`z`"):
        crossing_tangents(br.problem, [0.0, 1.0], 0.0, [0.0, 1.0])


def test_vertical_tangent_orientation_ignores_mirror_round_off():
    """A vertical crossing tangent (dp = 0) whose two largest components are mirror
    images of opposite sign is oriented by the first of them, whichever one round-off
    (or the point's own 1e-5 asymmetry) makes larger: the same half is "forward" on
    every machine."""
    base = np.array([0.5, -2.0, 1.0, 2.0, 0.0])
    for eps in (3e-6, -3e-6):
        t = base.copy()
        t[3] *= 1 + eps
        for sign_ds in (1.0, -1.0):  # sign(ds) does not matter for a vertical tangent
            assert sw._orient(t, sign_ds)[1] > 0
            assert sw._orient(-t, sign_ds)[1] > 0
    # a clearly largest component still decides
    assert sw._orient(np.array([0.5, -1.0, 3.0, 0.0]), 1.0)[2] > 0
