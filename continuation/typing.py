"""Public type aliases of the continuation engine.

Array shapes are given in the docstrings that use them.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
ComplexArray = npt.NDArray[np.complex128]
IntArray = npt.NDArray[np.int_]
BoolArray = npt.NDArray[np.bool_]

__all__ = ["FloatArray", "ComplexArray", "IntArray", "BoolArray"]
