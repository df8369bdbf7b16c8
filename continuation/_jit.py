"""The engine's compiled kernels, imported at their first use: the one kernel loader.

Numba is a hard dependency (``pyproject.toml``): every kernel module is compiled code and
there is no NumPy twin of it. The kernel modules (``continuation._kernel``, the
compiled PALC step; ``continuation.bvp._condense_jit``;
``continuation.bvp._collocation_jit``; ``continuation.periodic._floquet_jit``)
import Numba, which takes about half a second, so each is imported only when first
needed, by :func:`compiled`.
"""

from __future__ import annotations

import importlib
from types import ModuleType


def compiled(name: str) -> ModuleType:
    """The kernel module ``name`` (absolute, e.g. ``"continuation.bvp._condense_jit"``).

    Imported at the first call (Python keeps it in ``sys.modules`` afterwards).

    Raises
    ------
    ImportError
        If Numba is not installed (it is a required dependency).
    """
    return importlib.import_module(name)


__all__ = ["compiled"]
