"""The engine's optional compiled kernels, imported at their first use.

The kernel modules (``continuation.bvp._condense_jit``,
``continuation.periodic._collocation_jit``, ``continuation.periodic._floquet_jit``)
import Numba, which takes about half a second, so each is imported only when first
needed; where Numba is missing, :func:`compiled` returns None and the caller takes its
NumPy path. The outcome is kept per module for the life of the process (tests replace
an entry of :data:`LOADED` to exercise the NumPy path).
"""

from __future__ import annotations

import importlib
from types import ModuleType

#: Imported kernel modules by absolute name (None: Numba missing).
LOADED: dict[str, ModuleType | None] = {}


def compiled(name: str) -> ModuleType | None:
    """The kernel module ``name``, imported at the first call; None without Numba.

    Absolute, e.g. ``"continuation.bvp._condense_jit"``; None when it cannot be imported (no
    Numba).
    """
    if name not in LOADED:
        try:
            LOADED[name] = importlib.import_module(name)
        except ImportError:  # pragma: no cover - Numba missing: NumPy
            LOADED[name] = None
    return LOADED[name]


__all__ = ["LOADED", "compiled"]
