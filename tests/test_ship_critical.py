"""Critical Fn of the heteroclinic bifurcation by bisection on the upslope fate.

References used:
- the bracket's own consistency: its ends, re-simulated independently, have
  different fates (periodic below, capsize above) and its width is within ``tol``;
- an independent method: the saddle-to-shifted-saddle connection solved as a
  boundary-value problem by collocation (:func:`ship_models.analysis.connection.
  critical_fn_bvp`, Beyn 1990), whose Fn must lie inside the bisection bracket.
"""

from __future__ import annotations

import math

import pytest

from continuation.errors import ContinuationError
from continuation.status import Status
from ship_models import purse_seiner
from ship_models.analysis.critical import critical_fn, outcome
from ship_models.analysis.manifold import unstable_manifold

CHI_C = math.radians(10.0)


@pytest.fixture(scope="module")
def model():
    return purse_seiner()


@pytest.fixture(scope="module")
def result(model):
    return critical_fn(model, CHI_C, fn_bracket=(0.300, 0.305), tol=1e-5)


def test_bracket_is_consistent(model, result):
    assert result.status is Status.SUCCESS, result.message
    lo, hi = result.bracket
    assert 0 < hi - lo <= 1e-5
    assert result.fn_critical == pytest.approx(0.5 * (lo + hi))
    assert (result.fate_lo, result.fate_hi) == ("periodic", "capsize")
    assert result.n_evaluations == len(result.evaluations)
    # independent re-simulation of both ends (fresh fixed points, default options)
    p = model.default_params().replace(chi_c=CHI_C)
    for fn, expected in ((lo, "periodic"), (hi, "capsize")):
        man = unstable_manifold(model, p.replace(Fn=fn), branches=("upslope",), t_max=3000.0)
        assert outcome(man.branches["upslope"].fate) == expected
    # every evaluation below the bracket was periodic, every one above capsized
    for ev in result.evaluations:
        if ev.Fn <= lo:
            assert outcome(ev.fate) == "periodic"
        elif ev.Fn >= hi:
            assert outcome(ev.fate) == "capsize"


def test_agrees_with_the_collocation_connection(result):
    """The boundary-value solution of the heteroclinic connection lies in the bracket."""
    connection = pytest.importorskip("ship_models.analysis.connection")
    bvp = connection.critical_fn_bvp(CHI_C)
    lo, hi = result.bracket
    assert lo - 2e-6 <= bvp.Fn <= hi + 2e-6


def test_no_bracket_and_bad_input(model):
    res = critical_fn(model, CHI_C, fn_bracket=(0.33, 0.40), tol=1e-3)
    assert res.status is Status.NO_BRACKET
    assert res.fate_lo == res.fate_hi == "capsize"
    assert math.isnan(res.fn_critical)
    with pytest.raises(ContinuationError):
        critical_fn(model, CHI_C, fn_bracket=(0.33, 0.40), tol=1e-3, throw=True)
    with pytest.raises(ValueError, match="method"):
        critical_fn(model, CHI_C, method="bvp")
    with pytest.raises(ValueError, match="fn_bracket"):
        critical_fn(model, CHI_C, fn_bracket=(0.4, 0.3))
    with pytest.raises(ValueError, match="tol"):
        critical_fn(model, CHI_C, fn_bracket=(0.30, 0.31), tol=0.1)
    with pytest.raises(ValueError, match="branch"):
        critical_fn(model, CHI_C, branch="sideways")
