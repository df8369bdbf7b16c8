"""The ship layer's one outcome enumeration and one parameter coercion.

* :class:`~ship_models.analysis.outcomes.ShipOutcome` values are the strings the ship
  layer reports, equal to the engine's :class:`~continuation.dynamics.fates.FateKind` values
  where the meanings coincide.
* :func:`~ship_models.analysis.params.ship_params` accepts Params, mappings and
  arrays, and names the argument in one-line errors.
"""

from __future__ import annotations

import json
import math

import pytest

from continuation.dynamics import FateKind
from continuation.status import Status
from ship_models import PAPER_FN
from ship_models.analysis.critical_result import CriticalFn
from ship_models.analysis.outcomes import CAPTURED_BY_WAVE, ShipOutcome
from ship_models.analysis.params import course, ship_params


def test_outcomes_and_fate_kinds():
    for o in ShipOutcome:
        k = o.fate_kind
        if k is not None and o is not ShipOutcome.CAPSIZE and o is not ShipOutcome.SURF_RIDING:
            assert str(o) == str(k)  # the same word for the same meaning
    assert ShipOutcome.CAPSIZE.fate_kind is FateKind.EVENT
    assert ShipOutcome.SURF_RIDING.fate_kind is FateKind.EQUILIBRIUM
    assert ShipOutcome.RECURRENT.fate_kind is None
    assert ShipOutcome("surf-riding") is ShipOutcome.SURF_RIDING
    assert (
        f"{ShipOutcome.CAPSIZE}" == "capsize"
        and json.dumps([ShipOutcome.PERIODIC]) == '["periodic"]'
    )
    assert {o for o in ShipOutcome if o.captured} == set(CAPTURED_BY_WAVE) | {ShipOutcome.CAPTURED}
    assert not ShipOutcome.PERIODIC.captured


def test_ship_params_forms_and_errors(model):
    p = model.default_params()
    assert p["Fn"] == PAPER_FN
    assert ship_params(model, None) == p
    assert list(ship_params(model, p.values).values) == list(p.values)
    q = ship_params(model, {"Fn": 0.31}, chi_c=0.2)
    assert (q["Fn"], q["chi_c"]) == (0.31, 0.2)
    with pytest.raises(ValueError, match="params_to"):
        ship_params(model, [0.3, 0.1], "params_to")
    with pytest.raises(ValueError, match="chi_c"):
        ship_params(model, None, chi_c=math.nan)
    assert course(0.1) == 0.1
    with pytest.raises(ValueError, match="chi_c_values"):
        course(2.0, "chi_c_values")


def test_critical_fn_json_uses_one_name():
    r = CriticalFn(0.1, 0.3, "bisection", Status.SUCCESS, "ok", bracket=(0.29, 0.31))
    js = r.to_json()
    assert js["Fn"] == 0.3 and "fn_critical" not in js
    assert r.width == pytest.approx(0.02)
    with pytest.raises(ValueError, match="bvp"):
        _ = r.end_distances
