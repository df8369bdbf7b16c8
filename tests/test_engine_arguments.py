"""The shared check of a finite scalar argument (continuation.arguments.finite_number)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from continuation.arguments import finite_number


@pytest.mark.parametrize("value", [1, 2.5, np.float64(-3.25), np.int32(7), "0.125", True])
def test_finite_number_returns_the_float(value):
    out = finite_number("x", value)
    assert type(out) is float
    assert out == float(value)


@pytest.mark.parametrize(
    "value", [None, "abc", [1.0, 2.0], math.nan, -math.inf, np.float64(np.nan), "inf"]
)
def test_finite_number_rejects_with_a_one_line_message_naming_the_argument(value):
    with pytest.raises(ValueError, match=r"^`p0` must be a finite number, got ") as info:
        finite_number("p0", value)
    msg = str(info.value)
    assert "\n" not in msg
    assert "np.float64" not in msg and "Error" not in msg
