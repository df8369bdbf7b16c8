"""The locator keeps to the branch next to a branch point (continuation.locate).

Transcritical normal form ``xi' = p xi - xi^2`` (Kuznetsov 2004, sec. 3.3), ``xi = x -
p^2``: the trivial branch ``xi = 0`` and the branch ``xi = p`` cross at ``p = 0``. An
event smooth along the trivial branch, ``g = p - 2 xi``, vanishes exactly at the
crossing, where the bordered Jacobian is singular; on the crossing branch it is ``-p``,
of the other sign. Trial
points corrected next to the crossing may converge onto it; the locator must not
evaluate ``g`` there (the bracket would close on that jump, or a point of the other
branch would be reported), but interpolate the zero through points of the trivial
branch, within its tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest

from continuation.algorithms.point import make_point
from continuation.api import continue_equilibria
from continuation.events import Event
from continuation.locate import tangent_agrees
from continuation.problem import EquilibriumProblem, linearize
from continuation.settings import ContinuationSettings
from continuation.system import System


def transcritical_2d() -> System:
    """``xi' = p xi - xi^2`` with ``xi = x - p^2`` (the trivial branch ``x = p^2`` is
    curved, so chord predictors have a residual for Newton to correct) and a slaved
    ``y' = -y + x^2``."""

    def rhs(x, p, ops):
        xi = x[0] - p[0] ** 2
        return ops.stack([p[0] * xi - xi**2, -x[1] + x[0] ** 2])

    return System(rhs, ("x", "y"), ("p",))


@pytest.mark.parametrize("ds", [0.3, 0.17, 0.05])
def test_event_at_a_branch_point_is_located_on_the_branch(ds):
    ev = Event("g", lambda x, p: p - 2.0 * (x[0] - p**2), continuity=10.0)
    br = continue_equilibria(
        transcritical_2d(), [1.0, 1.0], {"p": -1.0}, "p",
        ds=ds, ds_max=ds, p_min=-1.0, p_max=1.0, direction="forward", events=[ev],
    )  # fmt: skip
    assert br.status.ok, br.message
    (sp,) = [s for s in br.special_points if s.label == "g"]
    st = ContinuationSettings()
    # located within the locator's tolerance (theta-norm tol: each component within
    # tol / sqrt(w_i)), and on the trivial branch, not on x = p
    assert sp.located, sp
    assert sp.p == pytest.approx(0.0, abs=st.detect.tol / np.sqrt(st.theta))
    assert np.all(np.abs(sp.x) <= st.detect.tol / np.sqrt((1 - st.theta) / 2))


def test_tangent_of_the_crossing_branch_is_rejected():
    """At a point of ``xi = p`` inside a step of the trivial branch the tangent is the
    crossing branch's and fails the check; a point of the trivial branch passes."""
    s = transcritical_2d()
    prob = EquilibriumProblem(s, {"p": -1.0}, "p")
    w = np.array([0.25, 0.25, 0.5])

    def point(xi, p, border):
        x = xi + p**2
        z = np.array([x, x**2])
        return make_point(z, p, linearize(prob, z, p), border, w)

    e_p = np.array([0.0, 0.0, 1.0])
    a = point(0.0, -0.1, e_p)
    b = point(0.0, 0.1, w * a.tau)
    c = w * a.tau
    assert tangent_agrees(point(0.0, 0.02, c), a, b, w)
    assert not tangent_agrees(point(0.02, 0.02, c), a, b, w)
