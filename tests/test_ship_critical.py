"""Critical Fn of the heteroclinic bifurcation by bisection on the upslope fate.

References used:
- the bracket's own consistency: its ends, re-simulated independently, have
  different fates (periodic below, capsize above) and its width is within ``tol``;
  with the default first-passage criterion the ends leave the neighbouring crest
  saddle on opposite sides of its stable manifold;
- an independent method: the saddle-to-shifted-saddle connection solved as a
  boundary-value problem by collocation (:func:`ship_models.analysis.critical_bvp.
  critical_fn_bvp`, Beyn 1990), whose Fn must lie inside the bisection bracket, for
  the hull derivatives taken about G and moved from midship (``x_ref = 0``, Inoue,
  Hirano & Kijima 1981), where the final fate switches 1.6e-5 below the connection.
"""

from __future__ import annotations

import math

import pytest

from continuation.errors import ContinuationError
from continuation.status import Status
from ship_models.analysis.critical import critical_fn
from ship_models.analysis.critical_bisection import RETURNED, first_passage, outcome
from ship_models.analysis.manifold import SaddleVisit, ShipFate, unstable_manifold
from ship_models.registry import get_vessel_data
from ship_models.umeda_4dof import Umeda4DOF

CHI_C = math.radians(10.0)


@pytest.fixture(scope="module")
def result(model):
    return critical_fn(model, chi_c=CHI_C, method="bisection", Fn_bracket=(0.300, 0.305), tol=1e-5)


def test_bracket_is_consistent(model, result):
    assert result.status is Status.SUCCESS, result.message
    assert result.criterion == "first_passage"
    lo, hi = result.bracket
    assert 0 < hi - lo <= 1e-5
    assert result.Fn == pytest.approx(0.5 * (lo + hi))
    assert (result.fate_lo, result.fate_hi) == ("periodic", "capsize")
    assert result.n_evaluations == len(result.evaluations)
    # independent re-simulation of both ends (fresh fixed points, default options): they
    # leave the crest saddle one wave back on opposite sides (upslope -1, back down +1)
    p = model.default_params().replace(chi_c=CHI_C)
    for fn, expected, side in ((lo, "periodic", -1), (hi, "capsize", 1)):
        man = unstable_manifold(model, p.replace(Fn=fn), branches=("upslope",), t_max=3000.0)
        fate = man.branches["upslope"].fate
        assert first_passage(fate) == expected
        assert (fate.visits[0].label, fate.visits[0].shift, fate.visits[0].side) == (
            "crest",
            -1,
            side,
        )
    # every evaluation below the bracket passed upslope, every one above turned back
    for ev in result.evaluations:
        assert ev.outcome == first_passage(ev.fate)
        if ev.Fn <= lo:
            assert ev.outcome == "periodic"
        elif ev.Fn >= hi:
            assert ev.outcome == "capsize"


def test_final_fate_criterion_bracket_is_consistent(model):
    """The final-fate variant: its ends, re-simulated, end periodic and capsized."""
    res = critical_fn(
        model, chi_c=CHI_C, method="bisection", Fn_bracket=(0.300, 0.305), tol=1e-5,
        criterion="final",
    )  # fmt: skip
    assert res.status is Status.SUCCESS, res.message
    assert res.criterion == "final"
    lo, hi = res.bracket
    assert 0 < hi - lo <= 1e-5
    assert (res.fate_lo, res.fate_hi) == ("periodic", "capsize")
    p = model.default_params().replace(chi_c=CHI_C)
    for fn, expected in ((lo, "periodic"), (hi, "capsize")):
        man = unstable_manifold(model, p.replace(Fn=fn), branches=("upslope",), t_max=3000.0)
        assert outcome(man.branches["upslope"].fate) == expected
    for ev in res.evaluations:
        assert ev.outcome == outcome(ev.fate)
        if ev.Fn <= lo:
            assert outcome(ev.fate) == "periodic"
        elif ev.Fn >= hi:
            assert outcome(ev.fate) == "capsize"


def _vessel(x_ref: str) -> Umeda4DOF:
    """The purse seiner with its hull derivatives about G or moved from midship."""
    if x_ref == "G":  # x_ref at G: the derivatives are used as given
        x_g = get_vessel_data("purse_seiner").info["x_G"]
        return Umeda4DOF(get_vessel_data("purse_seiner", overrides={"hydrodynamics.x_ref": x_g}))
    return Umeda4DOF(get_vessel_data("purse_seiner", overrides={"hydrodynamics.x_ref": 0.0}))


@pytest.mark.parametrize("x_ref", ["G", "midship"])
def test_first_passage_bracket_contains_the_collocation_connection(x_ref):
    """To the bracket width (1e-6), for both reference points of the hull derivatives.

    With ``x_ref = 0`` the final fate switches at a secondary connection ~1.6e-5 below
    the primary one (measured: final-fate bracket [0.3015955, 0.3015961] against the
    collocation 0.3016117); the first passage does not.
    """
    m = _vessel(x_ref)
    connection = pytest.importorskip("ship_models.analysis.critical_bvp")
    bvp = connection.critical_fn_bvp(CHI_C, model=m)
    assert bvp.status is Status.SUCCESS, bvp.message
    res = critical_fn(m, chi_c=CHI_C, method="bisection", Fn_bracket=(0.3010, 0.3022), tol=1e-6)
    assert res.status is Status.SUCCESS, res.message
    lo, hi = res.bracket
    w = hi - lo
    assert 0 < w <= 1e-6
    assert lo - w <= bvp.Fn <= hi + w
    ends = {ev.Fn: ev for ev in res.evaluations}
    sides = []
    for fn in (lo, hi):
        v = ends[fn].fate.visits[0]
        assert (v.label, v.shift) == ("crest", -1)
        sides.append(v.side)
    assert sides == [-1, 1]
    assert (res.fate_lo, res.fate_hi) == ("periodic", "capsize")


def test_first_passage_rules():
    """The outcome compared by the bisection, on hand-made fates."""

    def fate(kind, *visits):
        return ShipFate(
            kind, 100.0, tuple(SaddleVisit("crest", k, 1.0, 1e-3, s) for k, s in visits)
        )

    assert first_passage(fate("capsize", (-1, -1), (-2, 1))) == "periodic"
    assert first_passage(fate("periodic", (-1, 1))) == RETURNED
    assert first_passage(fate("capsize", (-1, 1))) == "capsize"
    assert first_passage(fate("capsize", (-2, 1))) == "periodic"  # passed -1 out of range
    assert first_passage(fate("recurrent")) == "periodic"  # no visit: the final fate
    assert first_passage(fate("undecided", (-1, 0))) is None
    assert first_passage(fate("undecided")) is None
    assert first_passage(fate("undecided", (-1, 1))) is None  # turned back: where to?
    assert first_passage(fate("undecided", (-1, -1))) == "periodic"  # passed: decided
    assert first_passage(fate("capsize", (1, 1), (-1, -1))) == "periodic"
    assert first_passage(fate("capsize", (-1, 1)), branch="downslope") == "capsize"
    with pytest.raises(ValueError, match="branch"):
        first_passage(fate("capsize"), branch="sideways")


def test_agrees_with_the_collocation_connection(result):
    """The boundary-value solution of the heteroclinic connection lies in the bracket."""
    connection = pytest.importorskip("ship_models.analysis.critical_bvp")
    bvp = connection.critical_fn_bvp(CHI_C)
    lo, hi = result.bracket
    assert lo - 2e-6 <= bvp.Fn <= hi + 2e-6


def test_no_bracket_and_bad_input(model):
    bis = {"chi_c": CHI_C, "method": "bisection"}
    res = critical_fn(model, **bis, Fn_bracket=(0.33, 0.40), tol=1e-3)
    assert res.status is Status.NO_BRACKET
    assert res.fate_lo == res.fate_hi == "capsize"
    assert math.isnan(res.Fn)
    with pytest.raises(ContinuationError):
        critical_fn(model, **bis, Fn_bracket=(0.33, 0.40), tol=1e-3, throw=True)
    with pytest.raises(ValueError, match="method"):
        critical_fn(model, chi_c=CHI_C, method="shooting")
    with pytest.raises(ValueError, match="Fn_bracket"):
        critical_fn(model, **bis, Fn_bracket=(0.4, 0.3))
    with pytest.raises(ValueError, match="tol"):
        critical_fn(model, **bis, Fn_bracket=(0.30, 0.31), tol=0.1)
    with pytest.raises(ValueError, match="branch"):
        critical_fn(model, **bis, branch="sideways")
    with pytest.raises(ValueError, match="criterion"):
        critical_fn(model, **bis, criterion="last")
