"""Fixed points tracked in Fn between two full traces (:class:`FixedPointsInFn`).

Reference: the full :func:`~ship_models.analysis.fixed_points.fixed_points` (the trace of
every surge root in the course) at the same ``Fn``; the tracked set must be the same
points (labels, saddle indices, states to the Newton tolerance). Where a pair of fixed
points is born between the anchors (at 30 deg, crest-3 and crest-4 between Fn 0.315 and
0.32) the signatures differ and the full trace must run.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ship_models import purse_seiner
from ship_models.analysis.fixed_points import FixedPointsInFn, fixed_points


@pytest.fixture(scope="module")
def model():
    return purse_seiner()


def _same(model, got, ref) -> None:
    assert [(f.label, f.saddle_index) for f in got] == [(f.label, f.saddle_index) for f in ref]
    for g, r in zip(got, ref, strict=True):
        # both polished by Newton to a residual of 1e-10: the same point to ~1e-9
        assert np.max(np.abs(model.difference(g.x, r.x))) < 1e-8


@pytest.mark.parametrize("deg", [10.0, 30.0])
def test_tracked_points_equal_the_full_trace(model, deg: float) -> None:
    par = model.default_params().replace(chi_c=math.radians(deg))
    fps = FixedPointsInFn(model, par)
    fps(0.296)
    fps(0.304)
    assert fps.n_traced == 2
    for fn in (0.2965, 0.299, 0.3001, 0.3035):
        _same(model, fps(fn), fixed_points(model, par.replace(Fn=fn)))
    assert fps.n_tracked == 4 and fps.n_traced == 2


def test_traces_outside_anchors_and_wide_gaps(model) -> None:
    par = model.default_params().replace(chi_c=math.radians(10.0))
    fps = FixedPointsInFn(model, par, max_gap=0.005)
    fps(0.29)
    fps(0.30)  # gap 0.01 > max_gap: the point between is traced
    fps(0.295)
    fps(0.31)  # above every anchor: traced
    assert fps.n_tracked == 0 and fps.n_traced == 4
    fps(0.2975)  # between 0.295 and 0.30 (gap 0.005): tracked
    assert fps.n_tracked == 1


def test_a_pair_born_between_the_anchors_is_found(model) -> None:
    par = model.default_params().replace(chi_c=math.radians(30.0))
    fps = FixedPointsInFn(model, par)
    lo, hi = fps(0.312), fps(0.321)
    assert len(hi) == len(lo) + 2  # crest-3 and crest-4 are born in between
    for fn in (0.3125, 0.3205):
        _same(model, fps(fn), fixed_points(model, par.replace(Fn=fn)))
    assert fps.n_tracked == 0


def test_bad_gap(model) -> None:
    with pytest.raises(ValueError, match="max_gap"):
        FixedPointsInFn(model, model.default_params(), max_gap=-1.0)
