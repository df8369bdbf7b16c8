"""Saddle visits of the fate scan: the vectorised tracking against the sample-by-sample rule.

A visit to a saddle starts at the first sample within ``r`` of it and ends at the
first sample beyond ``2 r``; it records the closest sample (the first of equals).
:meth:`continuation.dynamics.fate_scan._ScanState._track_visits` jumps from entry to
exit with NumPy; here it must give the same visits and open states as the plain
loop, on random distance histories fed in random blocks (a visit may span blocks).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from continuation.dynamics.fate_scan import _EXIT, _ScanState


class _Recorder(_ScanState):
    """The scan state with its visit bookkeeping reduced to a record of events."""

    def __init__(self, n_saddles: int, r: float) -> None:
        self.c = SimpleNamespace(saddle_radius=r)
        self.saddles = list(range(n_saddles))
        self.inside: dict[int, tuple[float, float, np.ndarray]] = {}
        self.visits: list = []
        self.closed: list[tuple[int, float, float, float]] = []

    def _close_visit(self, i, x_exit):  # noqa: D102
        dmin, tmin, _ = self.inside.pop(i)
        self.closed.append((i, dmin, tmin, float(x_exit[0])))


def _reference(state: _Recorder, t, x, D) -> None:
    r = state.c.saddle_radius
    for i in state.saddles:
        col = D[:, i]
        for k in range(col.size):
            cur = state.inside.get(i)
            if cur is not None:
                if col[k] > _EXIT * r:
                    state._close_visit(i, x[k])
                elif col[k] < cur[0]:
                    state.inside[i] = (float(col[k]), float(t[k]), np.array(x[k]))
            elif col[k] <= r:
                state.inside[i] = (float(col[k]), float(t[k]), np.array(x[k]))


@pytest.mark.parametrize("seed", range(20))
def test_vectorised_visits_equal_the_sample_by_sample_rule(seed):
    rng = np.random.default_rng(seed)
    n, n_saddles, r = 400, 3, 0.1
    t = np.arange(n) * 0.05
    x = np.column_stack([t, rng.standard_normal(n)])
    # distances wandering in and out of [0, 3 r], with repeated values (ties)
    D = np.abs(np.cumsum(rng.standard_normal((n, n_saddles)) * 0.05, axis=0)) % (3 * r)
    D = np.round(D, 2)
    new, ref = _Recorder(n_saddles, r), _Recorder(n_saddles, r)
    if seed % 2:  # a visit already open at the start (inside at t0, at infinite distance)
        new.inside[1] = ref.inside[1] = (math.inf, 0.0, x[0])
    cuts = np.sort(rng.choice(np.arange(1, n), size=5, replace=False))
    for a, b in zip(np.r_[0, cuts], np.r_[cuts, n], strict=True):
        new._track_visits(t[a:b], x[a:b], D[a:b])
        _reference(ref, t[a:b], x[a:b], D[a:b])
    assert new.closed == ref.closed
    assert new.inside.keys() == ref.inside.keys()
    for i in ref.inside:
        assert new.inside[i][:2] == ref.inside[i][:2]
        np.testing.assert_array_equal(new.inside[i][2], ref.inside[i][2])
    assert len(ref.closed) > 3  # the histories do enter and leave
