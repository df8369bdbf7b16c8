"""The sudden-change capsizing boundary as a landing BVP (ship_models.analysis.capsize_boundary).

Reference: the bisection by simulation (``sudden_change_boundary``, CVODES runs
classified by their outcome) at the same initial position, an independent method: the
BVP's Fn must lie inside its bracket. Setup of Umeda (1999), Fig. 16: from the periodic
orbit at Fn = 0.1, chi_c = 0 to chi_c = 10 deg.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import CHI10

from continuation.status import Status
from ship_models.analysis.capsize_boundary import (
    ROW_HEADER,
    capsizing_boundary_bvp,
    landing_guess,
)
from ship_models.analysis.events import capsize_angle


def _check_point(p, model):
    assert p.success, p.message
    lo, hi = p.bisection.bracket
    assert p.bisection.success and hi - lo <= 1.01e-6
    assert lo <= p.Fn <= hi, (p.Fn, lo, hi)  # the BVP inside the simulation's bracket
    assert p.inside
    assert p.error < 0.1 * (hi - lo)  # its own estimate is far below the bracket
    assert p.k < 0  # overtaken by waves before it lands
    assert p.max_roll_deg < math.degrees(capsize_angle(model))


def test_landing_inside_the_bisection_bracket_at_xi_0(model, orbit, fn_het):
    """xi_0 = 0: the transient lands on the crest saddle after some waves; BVP in bracket."""
    cb = capsizing_boundary_bvp(
        model, None, CHI10, [0.0], (fn_het - 1e-3, fn_het + 5e-4), orbit=orbit, tol=1e-6
    )
    (p,) = cb.points
    _check_point(p, model)
    assert abs(p.difference) <= p.bracket_width
    assert len(cb.rows()[0]) == len(ROW_HEADER)
    # the landing orbit starts on the old orbit and ends near the shifted crest saddle
    assert np.allclose(p.orbit.x[0], orbit.state_at(0.0), atol=1e-9)
    assert p.end_distance < 0.05
    assert p.orbit.x_eq[0] == pytest.approx(p.k + (p.orbit.x_eq[0] - p.k) % 1.0)


@pytest.mark.slow
def test_boundary_over_positions_and_its_continuation(model, orbit, fn_het):
    """Several positions, bisection to 1e-6, and the continuation between equal k."""
    xs = [0.0, 0.1, 0.9]
    cb = capsizing_boundary_bvp(
        model, None, CHI10, xs, (fn_het - 1e-3, fn_het + 5e-4), orbit=orbit, tol=1e-6
    )
    for p in cb.points:
        _check_point(p, model)
    assert cb.segments, cb.notes  # 0 and 0.1 land after the same number of waves
    assert any("jump in k" in n for n in cb.notes)  # 0.9 lands one wave earlier
    for seg in cb.segments:  # a continued piece ends on the next position's own solve
        nxt = next(p for p in cb.points if math.isclose(p.xi_0, seg.xi_0[-1]))
        assert seg.status is Status.PARAM_BOUND
        assert abs(seg.end_Fn - nxt.Fn) <= seg.end_error + nxt.error
        # the branch rows (no error control) stay well inside the bracket width
        assert abs(seg.Fn[-1] - nxt.Fn) < 0.1 * nxt.bracket_width


def test_bad_input(model, orbit):
    with pytest.raises(ValueError, match="`xi_0`"):
        capsizing_boundary_bvp(model, None, CHI10, [], (0.3, 0.31), orbit=orbit)
    with pytest.raises(ValueError, match="`xi_0`"):
        capsizing_boundary_bvp(model, None, CHI10, ["a"], (0.3, 0.31), orbit=orbit)
    with pytest.raises(ValueError, match="`bisections`"):
        capsizing_boundary_bvp(model, None, CHI10, [0.0], (0.3, 0.31), orbit=orbit,
                               bisections=[])  # fmt: skip
    with pytest.raises(ValueError, match="`params_from`"):
        capsizing_boundary_bvp(model, None, CHI10, [0.0], (0.3, 0.31))
    # a run that does not capsize gives no landing guess
    from continuation.errors import ContinuationError

    with pytest.raises(ContinuationError, match="does not capsize"):
        landing_guess(orbit, orbit.params.replace(Fn=0.25, chi_c=CHI10), 0.0, t_max=60.0)


def test_sweep_method_is_checked(capsys):
    from broachkit_cli.main import main
    from ship_models.analysis.sweeps import boundary_sweep

    with pytest.raises(ValueError, match="`method`"):
        boundary_sweep(method="newton")
    with pytest.raises(SystemExit) as exc:
        main(["sweep", "boundary", "--method", "newton"])
    assert exc.value.code != 0
    assert "Traceback" not in capsys.readouterr().err
