"""Bad input raises ValueError naming the offending argument or field."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import brusselator, fold_normal_form

from continuation.api import continue_equilibria
from continuation.branch import SpecialPoint
from continuation.driver import continue_branch
from continuation.events import Event
from continuation.params import Params
from continuation.problem import EquilibriumProblem
from continuation.settings import ContinuationSettings, DetectionSettings, NewtonSettings


@pytest.fixture
def sys():
    return brusselator()


def test_unknown_free_parameter(sys):
    with pytest.raises(ValueError, match="`free`"):
        continue_equilibria(sys, [1.0, 1.0], {"A": 1.0, "B": 1.0}, "C")


def test_unknown_parameter_name_in_params(sys):
    with pytest.raises(ValueError, match="`params`.*'C'"):
        continue_equilibria(sys, [1.0, 1.0], {"A": 1.0, "C": 1.0}, "B")


def test_params_of_wrong_length(sys):
    with pytest.raises(ValueError, match="`params`"):
        continue_equilibria(sys, [1.0, 1.0], [1.0, 2.0, 3.0], "B")
    with pytest.raises(ValueError, match="`params`"):
        continue_equilibria(sys, [1.0, 1.0], Params(("A",), [1.0]), "B")


def test_params_nan(sys):
    with pytest.raises(ValueError, match="`params`"):
        continue_equilibria(sys, [1.0, 1.0], [1.0, math.nan], "B")


@pytest.mark.parametrize("x0", [[1.0], [1.0, 2.0, 3.0], [[1.0, 2.0]]])
def test_wrong_shape_of_x0(sys, x0):
    with pytest.raises(ValueError, match="`x0`"):
        continue_equilibria(sys, x0, {"A": 1.0, "B": 1.0}, "B")


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_nonfinite_start(sys, bad):
    with pytest.raises(ValueError, match="`x0`"):
        continue_equilibria(sys, [1.0, bad], {"A": 1.0, "B": 1.0}, "B")
    prob = EquilibriumProblem(sys, sys.params(A=1.0, B=1.0), "B")
    with pytest.raises(ValueError, match="`z0`"):
        continue_branch(prob, [1.0, bad], 1.0)
    with pytest.raises(ValueError, match="`p0`"):
        continue_branch(prob, [1.0, 1.0], bad)


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"ds": 0.5, "ds_max": 0.1}, "ds"),
        ({"ds": 1e-9, "ds_min": 1e-8}, "ds"),
        ({"ds_min": 0.0}, "ds_min"),
        ({"ds": math.nan}, "ds"),
        ({"p_min": 2.0, "p_max": 1.0}, "p_min"),
        ({"max_steps": 0}, "max_steps"),
    ],
)
def test_step_settings_out_of_order(sys, kw, name):
    with pytest.raises(ValueError, match=name):
        continue_equilibria(sys, [1.0, 1.0], {"A": 1.0, "B": 1.0}, "B", **kw)
    with pytest.raises(ValueError, match=name):
        ContinuationSettings(**kw)


def test_nested_settings_validate():
    with pytest.raises(ValueError, match="tol"):
        NewtonSettings(tol=-1.0)
    with pytest.raises(ValueError, match="n_eigs"):
        DetectionSettings(n_eigs=0)
    with pytest.raises(ValueError, match="theta"):
        ContinuationSettings(theta=0.0)


def test_start_outside_bounds(sys):
    with pytest.raises(ValueError, match="`p0`"):
        continue_equilibria(sys, [1.0, 1.0], {"A": 1.0, "B": 5.0}, "B", p_max=3.0)


def test_driver_arguments(sys):
    prob = EquilibriumProblem(sys, sys.params(A=1.0, B=1.0), "B")
    with pytest.raises(ValueError, match="`direction`"):
        continue_branch(prob, [1.0, 1.0], 1.0, direction="sideways")
    with pytest.raises(ValueError, match="`events`"):
        continue_branch(prob, [1.0, 1.0], 1.0, events=[lambda x, p: x[0]])
    with pytest.raises(ValueError, match="`settings`"):
        continue_branch(prob, [1.0, 1.0], 1.0, settings={"ds": 0.1})
    with pytest.raises(ValueError, match="`algorithm`"):
        continue_branch(prob, [1.0, 1.0], 1.0, algorithm="palc")


def test_event_validation():
    with pytest.raises(ValueError, match="`name`"):
        Event("", lambda x, p: 0.0)
    with pytest.raises(ValueError, match="`fn`"):
        Event("e", 3.0)
    with pytest.raises(ValueError, match="`direction`"):
        Event("e", lambda x, p: 0.0, direction="left")
    with pytest.raises(ValueError, match="continuity"):
        Event("e", lambda x, p: 0.0, continuity=0.0)


def test_special_point_kind_validated():
    with pytest.raises(ValueError, match="`kind`"):
        SpecialPoint("flod", 0, 0.0, np.zeros(1), True, (0.0, 1.0))


def test_exception_in_rhs_keeps_its_type():
    from continuation.system import System

    def rhs(x, p):
        if p[0] > 0.5:
            raise ZeroDivisionError("model blew up at mu > 0.5")
        return np.array([p[0] - x[0] ** 2])

    s = System(rhs, ("x",), ("mu",))
    with pytest.raises(ZeroDivisionError, match="blew up"):
        continue_equilibria(s, [0.5], {"mu": 0.25}, "mu", p_max=1.0)


def test_settings_and_keywords_combine():
    st = ContinuationSettings(ds=0.05, ds_max=0.05, max_steps=3)
    br = continue_equilibria(
        fold_normal_form(),
        [1.0],
        {"mu": 1.0},
        "mu",
        settings=st,
        max_steps=5,
        direction="forward",
    )
    assert br.settings.max_steps == 5 and br.settings.ds == 0.05 and len(br) == 6
