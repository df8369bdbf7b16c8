"""One BLAS thread for continuation runs whose linear algebra is too small to share.

A continuation step factorises and solves systems of the problem's size and computes
eigenvalues of its Jacobian, hundreds of times in sequence. For dense systems of up to a
few hundred unknowns (and for the sparse path, where SuperLU is single-threaded and
ARPACK's dense work is on ``n x k`` blocks) a second BLAS thread gains little on an idle
machine, while on a loaded one its synchronisation costs several times the work, for
tiny systems too (the compiled step of an 8-state system included; measurements in
``benchmarks/README.md``, *Engine design measurements*). :func:`blas_threads_for`
limits BLAS to one thread for all such runs with threadpoolctl (a controller built
once), and does nothing for large dense systems.
"""

from __future__ import annotations

import contextlib
from typing import Any

#: Dense systems of this many unknowns or more are left to BLAS's own threading.
DENSE_SHARED_MIN = 300
_CONTROLLER: Any = None


def _controller() -> Any:
    global _CONTROLLER
    if _CONTROLLER is None:
        try:
            from threadpoolctl import ThreadpoolController
        except ImportError:  # pragma: no cover - a project dependency
            _CONTROLLER = False
        else:
            _CONTROLLER = ThreadpoolController()
    return _CONTROLLER


def blas_threads_for(n: int, sparse: bool) -> contextlib.AbstractContextManager[Any]:
    """Context limiting BLAS to one thread for a run on ``n`` unknowns (see module)."""
    if not sparse and n >= DENSE_SHARED_MIN:
        return contextlib.nullcontext()
    ctl = _controller()
    if not ctl:
        return contextlib.nullcontext()
    return ctl.limit(limits=1, user_api="blas")


__all__ = ["DENSE_SHARED_MIN", "blas_threads_for"]
