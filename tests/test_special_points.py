"""Special points of normal forms, located against their exact positions (mu = 0)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import (
    assert_invariants,
    fold_normal_form,
    hopf_normal_form,
    periodic_sine,
    pitchfork,
    pitchfork_2d,
    transcritical,
)

from continuation.api import continue_equilibria
from continuation.branch import SpecialKind
from continuation.driver import continue_branch
from continuation.events import Event
from continuation.problem import EquilibriumProblem
from continuation.settings import ContinuationSettings
from continuation.status import Status
from continuation.system import System

TOL = 1e-8  # required location accuracy on normal forms


def test_fold_normal_form_located():
    br = continue_equilibria(fold_normal_form(), [1.0], {"mu": 1.0}, "mu", p_min=-1.0, p_max=2.0)
    folds = br.find("fold")
    assert len(folds) == 1 and len(br.special_points) == 1
    f = folds[0]
    assert f.located and f.label == "F1"
    assert abs(f.p) < TOL and abs(f.x[0]) < 1e-4  # x ~ sqrt(error in p)
    # the upper branch x = sqrt(mu) is stable, the lower one unstable
    assert np.all(br.stable[br.x[:, 0] > 1e-6])
    assert np.all(~br.stable[br.x[:, 0] < -1e-6])
    assert f.delta_unstable in ((1, 0), (-1, 0))
    assert br.status is Status.PARAM_BOUND
    assert br.p[0] == pytest.approx(2.0, abs=1e-12) and br.p[-1] == pytest.approx(2.0, abs=1e-12)
    assert br.newton_iters.mean() < 4
    assert_invariants(br)


def test_fold_start_guess_is_corrected():
    br = continue_equilibria(
        fold_normal_form(), [1.3], {"mu": 1.0}, "mu", p_max=1.5, direction="forward"
    )
    assert br.x[0, 0] == pytest.approx(1.0, abs=1e-12)
    assert br.p[0] == 1.0


def test_hopf_normal_form_located_with_omega():
    br = continue_equilibria(
        hopf_normal_form(),
        [0.0, 0.0],
        {"mu": -1.0},
        "mu",
        p_min=-1.0,
        p_max=1.0,
        direction="forward",
    )
    (h,) = br.find("hopf")
    assert h.located and abs(h.p) < TOL
    assert h.data["omega"] == pytest.approx(1.0, abs=1e-10)
    assert h.delta_unstable == (0, 1)
    assert br.n_unstable[0] == 0 and br.n_unstable[-1] == 2
    assert_invariants(br)


def test_hopf_normal_form_shifted():
    """Hopf at mu=0.3137 for the normal form shifted in mu (not a grid point)."""
    from continuation.system import System

    def rhs(x, p, ops):
        m = p[0] - 0.3137
        r2 = x[0] ** 2 + x[1] ** 2
        return ops.stack([m * x[0] - 2.5 * x[1] - x[0] * r2, 2.5 * x[0] + m * x[1] - x[1] * r2])

    br = continue_equilibria(
        System(rhs, ("x", "y"), ("mu",)),
        [0.0, 0.0],
        [-0.77],
        "mu",
        p_max=1.0,
        direction="forward",
        ds=0.037,
    )
    (h,) = br.find("hopf")
    assert abs(h.p - 0.3137) < TOL and h.data["omega"] == pytest.approx(2.5, abs=1e-10)


@pytest.mark.parametrize("factory", [transcritical, pitchfork])
@pytest.mark.parametrize("ds", [0.1, 0.037])
def test_branch_points_on_trivial_branch(factory, ds):
    br = continue_equilibria(
        factory(),
        [0.0],
        {"mu": -1.0},
        "mu",
        p_min=-1.0,
        p_max=1.0,
        direction="forward",
        ds=ds,
        ds_max=ds,
    )
    bps = br.find("bp")
    assert len(bps) == 1 and not br.find("fold")
    assert bps[0].located and abs(bps[0].p) < TOL
    assert bps[0].delta_unstable == (1, 0)
    assert_invariants(br)


def test_pitchfork_jumped_by_large_step_is_detected():
    """A symmetric step across mu = 0 (rows at -0.5, +0.5) still finds the BP."""
    sys = pitchfork_2d()
    prob = EquilibriumProblem(sys, sys.params(mu=-0.5), "mu")
    st = ContinuationSettings(ds=0.5, ds_max=0.5, ds_min=1e-3, p_min=-0.6, p_max=0.6)
    br = continue_branch(prob, [0.0, 0.0], -0.5, settings=st)
    (bp,) = br.find("bp")
    assert bp.located and abs(bp.p) < TOL
    assert_invariants(br)


def test_transcritical_nontrivial_branch():
    """Along x = mu the BP is at (0, 0) too; the branch crosses the trivial one."""
    br = continue_equilibria(
        transcritical(), [-0.8], {"mu": -0.8}, "mu", p_min=-1.0, p_max=1.0, direction="forward"
    )
    (bp,) = br.find("bp")
    assert abs(bp.p) < TOL and abs(bp.x[0]) < TOL
    np.testing.assert_allclose(br.x[:, 0], br.p, atol=1e-9)


_FOLD_RUN = {"p_min": -1.0, "p_max": 2.0, "direction": "forward", "ds": -0.01}


def _fold_branch(event: Event):
    """The upper fold-normal-form branch from mu = 1 down through its fold, with ``event``."""
    return continue_equilibria(
        fold_normal_form(), [1.0], {"mu": 1.0}, "mu", events=[event], **_FOLD_RUN
    )


def test_user_event_located_and_terminal():
    ev = Event("x_half", lambda x, p: x[0] - 0.5, direction="down")
    br = _fold_branch(ev)
    (e,) = br.find("x_half")
    assert e.kind is SpecialKind.USER and e.located
    assert e.p == pytest.approx(0.25, abs=1e-12) and e.x[0] == pytest.approx(0.5, abs=1e-12)
    term = Event("stop", lambda x, p: x[0] + 0.5, terminal=True)
    br2 = _fold_branch(term)
    assert br2.status is Status.EVENT
    assert br2.x[-1, 0] == pytest.approx(-0.5, abs=1e-12)
    assert [sp.kind.value for sp in br2.special_points] == ["fold", "user"]
    assert_invariants(br2)


def test_event_direction_filter():
    up = Event("up", lambda x, p: x[0] - 0.5, direction="up")
    br = _fold_branch(up)
    assert not br.find("up")  # x decreases along this branch


def test_periodic_branch_closes_with_two_folds():
    sys = periodic_sine()
    br = continue_equilibria(sys, [0.0], {"mu": 0.0}, "mu", direction="forward", max_steps=2000)
    assert br.status is Status.CLOSED_LOOP
    folds = br.find("fold")
    assert len(folds) == 2
    ps = sorted(f.p for f in folds)
    assert ps[0] == pytest.approx(-1.0, abs=1e-10) and ps[1] == pytest.approx(1.0, abs=1e-10)
    assert_invariants(br)


def test_hopf_picks_the_crossing_pair_not_the_nearest():
    """Two oscillators: pair A stays at Re = -0.01 (omega 3), pair B = mu +- i crosses.

    At the row before the crossing pair A is nearer the axis than pair B; the Hopf must
    still be located at mu = 0 with omega = 1.
    """
    from continuation.system import System

    def rhs(x, p, ops):
        mu = p[0]
        r2 = x[2] ** 2 + x[3] ** 2
        return ops.stack(
            [
                -0.01 * x[0] - 3 * x[1],
                3 * x[0] - 0.01 * x[1],
                mu * x[2] - x[3] - x[2] * r2,
                x[2] + mu * x[3] - x[3] * r2,
            ]
        )

    sys = System(rhs, ("a1", "a2", "b1", "b2"), ("mu",))
    br = continue_equilibria(
        sys, np.zeros(4), {"mu": -0.5}, "mu", p_max=0.5, ds=0.2, ds_max=0.3, direction="forward"
    )
    (h,) = br.find("hopf")
    assert h.located and abs(h.p) < TOL
    assert h.data["omega"] == pytest.approx(1.0, abs=1e-10)
    assert_invariants(br)


def test_event_on_a_jump_is_bracketed_not_located():
    jump = Event("jump", lambda x, p: 1.0 if p > 0.3 else -1.0)
    br = _fold_branch(jump)
    jumps = br.find("jump")
    assert len(jumps) == 2  # mu passes 0.3 on the way down and on the way back up
    for e in jumps:
        assert not e.located
        lo, hi = sorted(e.bracket)
        assert lo <= 0.3 <= hi


class _RoundOffBlock:
    """x0 = mu on a branch, plus two states (y1, y2) = 0 whose 2x2 Jacobian block
    ``[[1, 1], [1, 1 + d(mu)]]`` is singular to working precision: ``1 + d`` is the
    floating-point neighbour of 1 above or below it, alternating with
    ``sign(sin(40 mu))``. The determinant of the bordered matrix is then one rounding
    unit whose sign flips every ``pi / 40`` in ``mu``: a sign change of the branch-point
    test that is pure round-off (the block is not near a singular point of the
    branch; it is singular everywhere to working precision). The residual does not see
    ``d`` on the branch (``y = 0``)."""

    free = "mu"
    n_unknowns = 3

    def _d(self, p):
        return np.nextafter(1.0, 2.0 if math.sin(40.0 * p) >= 0 else 0.0)

    def residual(self, z, p):
        return np.array([z[0] - p, z[1] + z[2], z[1] + self._d(p) * z[2]])

    def jacobian(self, z, p):
        return np.array([[1.0, 0, 0], [0, 1.0, 1.0], [0, 1.0, self._d(p)]])

    def dp(self, z, p):
        return np.array([-1.0, 0.0, 0.0])

    def stability(self, z, p):
        return None

    def record(self, z, p):
        return {}


def test_round_off_sign_flips_of_the_bp_test_are_ignored():
    """Regression (issue 2): the determinant's sign flips from round-off where the
    bordered Jacobian is numerically singular at both rows; these used to be reported
    as (unlocated) branch points."""
    st = ContinuationSettings(ds=0.05, ds_max=0.05, p_min=0.0, p_max=1.0)
    br = continue_branch(_RoundOffBlock(), [0.0, 0.0, 0.0], 0.0, settings=st)
    assert br.status is Status.PARAM_BOUND
    signs = [math.sin(40 * p) >= 0 for p in br.p]
    assert sum(s != t for s, t in zip(signs, signs[1:], strict=False)) >= 5  # flips happen
    assert not br.find("bp")
    np.testing.assert_allclose(br.x[:, 0], br.p, atol=1e-12)
    assert np.all(br.x[:, 1:] == 0.0)


def test_located_branch_points_are_verified_singular():
    """Every located BP of the normal forms carries the reciprocal condition of its
    bordered Jacobian relative to the rows around it: at the exact pitchfork and
    transcritical points it is at round-off level."""
    for factory in (transcritical, pitchfork):
        br = continue_equilibria(
            factory(), [0.0], {"mu": -1.0}, "mu", p_min=-1.0, p_max=1.0, direction="forward"
        )
        (bp,) = br.find("bp")
        assert bp.located and bp.data["rcond_ratio"] < 1e-12


@pytest.mark.parametrize("ds", [0.1, 0.05, 0.037, 0.01, 0.003])
def test_pitchfork_met_along_its_nontrivial_branch_fold_is_the_branch_point(ds):
    """x' = mu x - x^3 from (1, 1) along x^2 = mu: the branch turns (fold) exactly at the
    pitchfork (0, 0), so the fold and the branch point coincide (closed form). Both are
    reported located there, at every step size (before, the determinant's zero was
    sought separately next to the singular bordered matrix and was often not located,
    with a bracket in p excluding 0; reported by the generality audit)."""
    sys = System(lambda x, p, ops: ops.stack([p[0] * x[0] - x[0] ** 3]), ("x",), ("mu",))
    br = continue_equilibria(sys, [1.0], {"mu": 1.0}, "mu", p_min=-1, p_max=2, ds=ds, ds_max=ds)
    (fold,) = br.find("fold")
    (bp,) = br.find("bp")
    for q in (fold, bp):
        assert q.located
        assert abs(q.p) < 1e-12
        assert abs(float(q.x[0])) < 1e-6  # x = sqrt(mu): mu to 1e-14 gives x to 1e-7
    assert bp.data["rcond_ratio"] <= 0.1


def test_an_event_at_a_parameter_value_is_solved_exactly_on_it():
    # x' = mu - x^2 from x = 1: down the upper branch x = sqrt(mu), round the fold at
    # mu = 0, up the lower one x = -sqrt(mu). mu = 0.25 is met twice, at x = +-0.5; mu =
    # 3e-5 twice at x = -+sqrt(3e-5), within the step across the fold at these settings
    # (rows at mu = 4.1e-3 and 5.0e-5: no sign change, found by the dip test on the end
    # slopes dmu/ds, then located by the general search).
    evs = [Event("quarter", param_value=0.25), Event("near_fold", param_value=3e-5),
           Event("quarter_up", param_value=0.25, direction="up")]  # fmt: skip
    br = continue_equilibria(
        fold_normal_form(), [1.0], {"mu": 1.0}, "mu", p_min=-1.0, p_max=2.0, events=evs,
        direction="forward", ds=-0.05, ds_max=0.05,
    )  # fmt: skip
    q = sorted(br.find("quarter"), key=lambda sp: sp.x[0])
    assert [sp.located for sp in q] == [True, True]
    assert [sp.p for sp in q] == [0.25, 0.25]  # on the value itself, not within a tolerance
    np.testing.assert_allclose([sp.x[0] for sp in q], [-0.5, 0.5], atol=1e-10)
    (up,) = br.find("quarter_up")  # mu increases on the lower branch only
    assert up.x[0] == pytest.approx(-0.5, abs=1e-10)
    nf = sorted(br.find("near_fold"), key=lambda sp: sp.x[0])
    assert len(nf) == 2 and all(sp.located for sp in nf)
    np.testing.assert_allclose([sp.p for sp in nf], [3e-5, 3e-5], atol=TOL)
    r = math.sqrt(3e-5)
    np.testing.assert_allclose([sp.x[0] for sp in nf], [-r, r], rtol=1e-3)
    assert_invariants(br)


def test_an_event_at_a_parameter_value_refuses_bad_input():
    with pytest.raises(ValueError, match="`fn` or `param_value`, not both"):
        Event("a", lambda x, p: p, param_value=1.0)
    with pytest.raises(ValueError, match="`param_value` of event 'a' must be a finite"):
        Event("a", param_value=math.inf)
    with pytest.raises(ValueError, match="`fn` of event 'a' must be callable"):
        Event("a")
    e = Event("a", param_value=2)
    assert e.value(np.zeros(1), 3.5) == 1.5 and e.param_value == 2.0


def test_an_event_without_slopes_is_evaluated_on_the_rows_only():
    # the pair of zeros of mu - 3e-5 inside the step across the fold (see above) is
    # found with slopes and, as documented, not without; fn is then called once per row
    calls = {"with": 0, "without": 0}

    def fn(key):
        def g(x, p):
            calls[key] += 1
            return p - 3e-5

        return g

    kw = dict(p_min=-1.0, p_max=2.0, direction="forward", ds=-0.05, ds_max=0.05)
    with_s = continue_equilibria(
        fold_normal_form(), [1.0], {"mu": 1.0}, "mu", events=[Event("e", fn("with"))], **kw
    )
    without = continue_equilibria(
        fold_normal_form(), [1.0], {"mu": 1.0}, "mu",
        events=[Event("e", fn("without"), slope=False)], **kw,
    )  # fmt: skip
    assert len(with_s.find("e")) == 2
    assert len(without.find("e")) == 0
    assert len(without) == len(with_s)
    # about one call per row (the row that meets the bound is evaluated twice), none off
    # the branch; with slopes two per row and more inside the fold's step
    assert len(without) <= calls["without"] <= len(without) + 2
    assert calls["with"] >= 2 * len(with_s)


def test_the_hermite_guess_at_a_parameter_value_is_fourth_order():
    # on the unit circle (x, p) = (sin th, cos th) between th = 0.3 and 0.3 + h, the
    # point at p = cos(0.3 + h/2): the chord's error is O(h^2), the cubic's O(h^4)
    from continuation.detection import _hermite_at_p

    def errors(h):
        th0, th1, thm = 0.3, 0.3 + h, 0.3 + h / 2
        ua, ub = (np.array([math.sin(t), math.cos(t)]) for t in (th0, th1))
        ta, tb = (np.array([math.cos(t), -math.sin(t)]) for t in (th0, th1))
        p = math.cos(thm)
        g = _hermite_at_p(ua, ub, ta, tb, float(np.linalg.norm(ub - ua)), p)
        s_lin = (p - ua[1]) / (ub[1] - ua[1])
        chord = ua + s_lin * (ub - ua)
        return abs(g[0] - math.sin(thm)), abs(chord[0] - math.sin(thm))

    (e1, c1), (e2, c2) = errors(0.05), errors(0.025)
    assert c1 / c2 == pytest.approx(4.0, rel=0.1)  # the chord: second order
    assert e1 / e2 > 12.0 and e1 < 1e-3 * c1  # the cubic: fourth order (16), far smaller
