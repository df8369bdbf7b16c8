"""A located special point is within the error it carries (continuation.locate).

``SpecialPoint.error`` is the locator's estimate of the distance, in pseudo-arclength,
from the reported point to the zero of the test function; ``located`` promises
``error <= DetectionSettings.tol`` unless the point says otherwise (a larger
``error``). The unit tangent has ``|dp/ds| <= 1 / sqrt(theta)`` (``theta``-norm, weight
``theta`` on ``p``), so the parameter of a point carrying ``error`` is within
``error / sqrt(theta)`` of the zero; these tests check that bound against closed forms.

Regressions: a tiny ``|g|`` was taken as a zero (a zero of order 3 or 5, where ``g`` is
``1e-15`` already ``1e-5`` away, was "located" 1.5e-6 and 1.4e-4 off with tol 1e-10),
and a sign change of a noisy ``g`` was located as if ``g`` were exact.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from continuation import ContinuationSettings, System, continue_equilibria
from continuation.events import Event

THETA = ContinuationSettings().theta
TOL = ContinuationSettings().detect.tol
MU0 = 0.3


def _line() -> System:
    """``x' = mu - x``: the branch ``x = mu``."""
    return System(lambda x, p, ops: ops.stack([p[0] - x[0]]), ("x",), ("mu",))


def _run(event: Event):
    return continue_equilibria(
        _line(), [0.0], {"mu": 0.0}, "mu", p_min=-0.5, p_max=1.0, events=[event],
        direction="forward",
    )  # fmt: skip


@pytest.mark.parametrize("order", [1, 3, 5])
def test_zero_of_odd_order_is_located_within_tol(order):
    """``g = (x - mu0)^k`` changes sign at ``mu = mu0`` and is flat there for ``k > 1``:
    the bracket must close to ``tol`` around the zero (bisection once the secant
    stalls), not stop where ``|g|`` is tiny."""
    ev = Event("g", lambda x, p: float((x[0] - MU0) ** order))
    (sp,) = _run(ev).find("user")
    assert sp.located and sp.error <= TOL
    assert abs(sp.p - MU0) <= sp.error / math.sqrt(THETA)


def test_noisy_event_carries_the_uncertainty_of_its_zero():
    """``g = (x - mu0) + 1e-8 n(x)`` with a deterministic noise ``|n| <= 1`` that varies
    on the scale ``1e-12``: the sign changes of ``g`` within ``1e-8`` of ``mu0`` are
    noise, so the zero is only known to about ``1e-8`` (``|g|`` at the located point
    over the slope 1), and the point must say so: its ``error`` covers the distance to
    ``mu0`` and is above ``tol``, but of the order of the noise (below ``1e-6``)."""
    amp = 1e-8

    def g(x, p):
        return float((x[0] - MU0) + amp * math.sin(1e12 * x[0] + 1.0))

    (sp,) = _run(Event("noisy", g)).find("user")
    assert sp.located
    assert abs(sp.p - MU0) <= sp.error / math.sqrt(THETA)
    assert TOL < sp.error < 100 * amp


def test_error_is_saved_and_loaded(tmp_path):
    """``error`` goes through ``Branch.save``/``load`` (and old files without it read as
    NaN)."""
    from continuation.branch import Branch, SpecialPoint

    br = _run(Event("g", lambda x, p: float(x[0] - MU0)))
    br.save(tmp_path / "b")
    back = Branch.load(tmp_path / "b")
    (sp,) = back.find("user")
    assert sp.error == br.find("user")[0].error <= TOL
    d = sp.to_json()
    del d["error"]
    assert np.isnan(SpecialPoint.from_json(d).error)


def test_an_event_with_report_false_is_not_warned_about(caplog):
    """A jump of the test function is detected but not located and, by default, warned
    about; ``Event(report=False)`` (the codim-2 tests, whose zeros are classified and
    reported afterwards) keeps the point but leaves the warning to the caller."""
    import logging

    from continuation import System, continue_equilibria
    from continuation.events import Event

    s = System(lambda x, p, ops: ops.stack([p[0] - x[0]]), ("x",), ("mu",))
    for report in (True, False):
        caplog.clear()
        ev = Event("jump", lambda z, p: 1.0 if z[0] > 0.3 else -1.0, report=report)
        with caplog.at_level(logging.WARNING, logger="continuation.detection"):
            br = continue_equilibria(s, [0.0], {"mu": 0.0}, "mu", p_max=1.0, events=[ev])
        (sp,) = br.special_points
        assert sp.label == "jump" and not sp.located
        warned = any("detected but not located" in r.getMessage() for r in caplog.records)
        assert warned is report


@pytest.mark.parametrize("flag", ["terminal", "slope", "report"])
def test_an_event_flag_that_is_not_a_bool_is_refused_naming_it(flag):
    from continuation.events import Event

    with pytest.raises(ValueError, match=rf"`{flag}` must be True or False") as exc:
        Event("g", lambda z, p: p, **{flag: "no"})
    assert "\n" not in str(exc.value)
