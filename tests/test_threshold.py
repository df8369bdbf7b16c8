"""The ship's capsizing threshold (ship_models.analysis.threshold) and its Fn window.

References: the ship's own fates, computed independently by
:func:`ship_models.analysis.manifold.unstable_manifold` at ``Fn_c -+ 0.002`` (the
paper's criterion: the upslope branch capsizes or not); the heteroclinic Fn by the
connecting-orbit solver; the overtaken cycle's period doubling by collocation.
The surf-riding window against its definition: surge equilibria exist just inside it
and not just outside.
"""

from __future__ import annotations

import math

import pytest

from ship_models import get_model
from ship_models.analysis.fixed_points import surge_model_of
from ship_models.analysis.fn_window import surf_riding_window
from ship_models.analysis.manifold import unstable_manifold
from ship_models.analysis.params import ship_params
from ship_models.analysis.threshold import capsizing_threshold


@pytest.fixture(scope="module")
def ship():
    return get_model("purse_seiner")


def _fate(model, chi_deg: float, Fn: float) -> str:
    p = ship_params(model, None, Fn=Fn, chi_c=math.radians(chi_deg))
    man = unstable_manifold(model, p, branches=("upslope",), t_max=2400.0)
    return str(man.branches["upslope"].fate.label)


def test_threshold_at_10_deg_is_the_heteroclinic_fn(ship):
    th = capsizing_threshold(ship, chi_c=math.radians(10.0))
    assert th.success, th.message
    assert th.mechanism == "heteroclinic" and th.is_heteroclinic
    # the connection, solved by collocation, within the stated coincidence
    assert abs(th.Fn - th.Fn_heteroclinic) <= th.error + 1e-3 + th.Fn_heteroclinic_error
    assert th.confirmed
    # the ship's own fates, independently: no capsize 0.002 below, capsize 0.002 above
    assert _fate(ship, 10.0, th.Fn - 0.002) != "capsize"
    assert _fate(ship, 10.0, th.Fn + 0.002) == "capsize"


def test_threshold_at_34_deg_lies_below_the_connection(ship):
    """Beyond the parting course the ship capsizes below the heteroclinic Fn: the
    overtaken cycle's basin is lost at its period doubling first."""
    th = capsizing_threshold(ship, chi_c=math.radians(34.0))
    assert th.success, th.message
    assert not th.is_heteroclinic
    assert th.Fn < th.Fn_heteroclinic - 0.005
    assert "period doubling" in th.mechanism or "period-doubling" in th.mechanism
    pd = th.bifurcations.PD
    assert pd and th.Fn - th.error <= pd[0] <= th.Fn + 0.25 * (th.Fn_heteroclinic - th.Fn)
    assert _fate(ship, 34.0, th.Fn - 0.002) != "capsize"
    assert _fate(ship, 34.0, th.Fn + 0.002) == "capsize"
    # and just below the connection it already capsizes: the connection is no boundary here
    assert _fate(ship, 34.0, th.Fn_heteroclinic - 0.002) == "capsize"


@pytest.mark.slow
@pytest.mark.parametrize(("chi_deg", "heteroclinic"),
                         [(20.0, True), (25.0, True), (30.0, False), (38.0, False)])  # fmt: skip
def test_threshold_parts_from_the_connection_between_25_and_30_deg(ship, chi_deg, heteroclinic):
    th = capsizing_threshold(ship, chi_c=math.radians(chi_deg))
    assert th.success, th.message
    assert th.is_heteroclinic is heteroclinic
    assert _fate(ship, chi_deg, th.Fn - 0.002) != "capsize"
    assert _fate(ship, chi_deg, th.Fn + 0.002) == "capsize"


def test_a_course_the_rudder_cannot_hold_gets_no_threshold(ship):
    from ship_models.analysis import threshold as thr

    class Weak:
        delta_max = 1e-3

    class Ship:
        forces = Weak()
        state_names = ship.state_names
        state_index = ship.state_index

    p = ship_params(ship, None, chi_c=math.radians(10.0))
    from ship_models.analysis.fixed_points import find_fixed_point

    sp = find_fixed_point(ship, p, "crest")
    assert thr._rudder_saturated(Ship(), sp)
    assert not thr._rudder_saturated(ship, sp)


@pytest.mark.parametrize("H_over_lambda", [0.05, 0.15])
@pytest.mark.parametrize("lambda_over_L", [1.0, 3.0])
def test_fn_window_has_surf_riding_equilibria_inside_and_none_outside(
    ship, H_over_lambda, lambda_over_L
):
    p = ship_params(ship, None, H_over_lambda=H_over_lambda, lambda_over_L=lambda_over_L)
    w = surf_riding_window(ship, p)
    assert w.exists
    sm = surge_model_of(ship)

    def n_eq(Fn: float) -> int:
        return len(sm.fixed_points(sm.params(Fn=Fn, H_over_lambda=H_over_lambda,
                                             lambda_over_L=lambda_over_L)))  # fmt: skip

    assert n_eq(0.5 * (w.Fn_lo + w.Fn_hi)) >= 2
    assert n_eq(w.Fn_hi - 1e-4) >= 2 and n_eq(w.Fn_hi + 1e-3) == 0
    if w.Fn_lo > 0.01:  # not clipped at the search's lower end
        assert n_eq(w.Fn_lo + 1e-4) >= 2 and n_eq(w.Fn_lo - 1e-3) == 0


def test_critical_curve_without_thresholds(capsys):
    """``--threshold-step 0``: the heteroclinic line only, as the option's help says."""
    import json

    from broachkit_cli.main import main

    assert main(["critical-curve", "--chi-c", "0:2", "--threshold-step", "0", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert "threshold" not in doc and len(doc["Fn"]) == 3
