"""The ship's fate classification at its default tolerances against a tighter run.

The defaults of :class:`~ship_models.analysis.manifold.ShipFateSettings` (rtol 1e-9)
must decide the same fates as rtol = 1e-10: the kind, the period of a periodic fate
and the time at which it is decided, at Fn well below, near and above the capsizing
threshold of the default vessel at chi_c = 10 deg (about 0.3017).
"""

from __future__ import annotations

import math

import pytest

from ship_models.analysis.manifold import ShipFateSettings, unstable_manifold
from ship_models.analysis.params import ship_params

TIGHT = ShipFateSettings(rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("Fn", [0.25, 0.3, 0.3015, 0.302, 0.31])
def test_default_fate_tolerance_decides_as_a_tight_one(model, Fn):
    p = ship_params(model, Fn=Fn, chi_c=math.radians(10.0))
    default = unstable_manifold(model, p, branches=("upslope",))
    tight = unstable_manifold(model, p, branches=("upslope",), settings=TIGHT)
    a, b = default.branches["upslope"].fate, tight.branches["upslope"].fate
    assert a.kind == b.kind
    # the decision time: the same section crossing / event, located to ~1e-7 s
    assert a.t == pytest.approx(b.t, abs=0.5)
    if b.period is not None:
        # the period comes from a return map converged to `return_tol` (1e-4 in the
        # states), so it is known to about that relative error whatever the integrator
        assert a.period == pytest.approx(b.period, rel=TIGHT.return_tol)
