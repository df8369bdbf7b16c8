"""One BLAS thread for a command whose linear algebra is small (issue 27, item 6).

A single query (``broachkit fixed-points``) solves systems of the ship's eight states
and fits a few columns: a second BLAS thread only costs, both when the BLAS libraries
load (NumPy's and SciPy's OpenBLAS each start a thread pool, about 0.05 s of CPU each
on a 2-core machine, measured with ``import numpy`` and with the whole query) and in
every call on a busy machine (``continuation._threads``). :func:`one_blas_thread`
covers both: a library loaded inside it starts with one thread (the thread-count
variables are set while NumPy and SciPy's linear algebra load, and put back as they
were, so that child processes and later commands see the user's environment; a count
the user set is kept), and libraries loaded earlier are limited by threadpoolctl for
the duration.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import sys
from collections.abc import Iterator

#: Thread-count variables of the BLAS builds NumPy and SciPy ship with (OpenBLAS) or
#: may be built against (an OpenMP BLAS, MKL).
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")

#: Modules whose import loads a BLAS library.
BLAS_MODULES = ("numpy", "scipy.linalg")


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Context in which BLAS runs on one thread (see module)."""
    if any(m not in sys.modules for m in BLAS_MODULES):
        unset = [v for v in THREAD_VARIABLES if v not in os.environ]
        for v in unset:
            os.environ[v] = "1"
        try:
            for m in BLAS_MODULES:
                importlib.import_module(m)
        finally:
            for v in unset:
                os.environ.pop(v, None)
    from continuation._threads import blas_threads_for

    with blas_threads_for(0, sparse=False):  # any size below the dense threshold
        yield


__all__ = ["THREAD_VARIABLES", "one_blas_thread"]
