"""The report's check of the periodic motion's end (``studies.paper``), on given numbers.

The numbers themselves are tested against the connection solver in
``tests/test_ship_cycles.py``; here only the verdict's logic: it agrees when the cycle's
period limit is within 1e-4 of the connection and the cycles stay below the angle of
vanishing stability, and says otherwise.
"""

from studies import paper

GOOD = {
    "Fn_fit_log": 0.3016148,
    "Fn_bvp": 0.3016117,
    "Fn_lost_stability": 0.30159,
    "max_roll_deg": 3.7,
    "vanishing_angle_deg": 63.3,
}


def test_cycle_end_agrees_on_matching_limits():
    f = paper._cycle_end({"cycles": GOOD})
    assert f.verdict == paper.AGREES
    assert dict(f.numbers)["Fn* from the period's blow-up, T = a - b ln(Fn* - Fn)"] == "0.30161480"


def test_cycle_end_differs_when_the_limits_disagree_or_the_cycle_capsizes():
    assert paper._cycle_end({"cycles": {**GOOD, "Fn_fit_log": 0.3030}}).verdict == paper.DIFFERS
    assert paper._cycle_end({"cycles": {**GOOD, "max_roll_deg": 70.0}}).verdict == paper.DIFFERS


def test_cycle_end_not_run():
    assert paper._cycle_end({}).verdict == paper.NOT_RUN
    assert any(c.key == "cycle_end" for c in paper.CLAIMS)
