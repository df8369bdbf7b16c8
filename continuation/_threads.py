"""One BLAS thread for continuation runs whose linear algebra is too small to share.

A continuation step factorises and solves systems of the problem's size and computes
eigenvalues of its Jacobian, hundreds of times in sequence. For dense systems of up to a
few hundred unknowns (and for the sparse path, where SuperLU is single-threaded and
ARPACK's dense work is on ``n x k`` blocks) a second BLAS thread gains little on an idle
machine, while on a loaded one its synchronisation costs several times the work:
``numpy.linalg.eigvals`` of a 150 x 150 matrix measured 15.8 ms with OpenBLAS's two
threads against 6.6 ms with one, with two other busy processes on the 2 cores
(2026-11-22). Tiny systems are not spared: with the compiled step of an 8-state
system (LAPACK ``dgetrf``/``dgetrs``/``dgeev`` on 9 x 9 and 8 x 8 matrices, called from
Numba), a run took 24 ms wall and 33 ms CPU with OpenBLAS's two threads on a loaded
machine against 13 ms with one (2026-12-01), and the benchmark's wall time doubled.
:func:`blas_threads_for` limits BLAS to one thread for all such runs with threadpoolctl
(a controller built once, about 3 us per limit), and does nothing for large dense
systems.
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
