"""Continuation runs of small-to-moderate systems use one BLAS thread (continuation._threads)."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from continuation import Event, System, continue_equilibria
from continuation._threads import DENSE_SHARED_MIN, blas_threads_for


def _blas_threads() -> list[int]:
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_limit_inside_and_restored_after():
    before = _blas_threads()
    if not before:
        pytest.skip("no BLAS library seen by threadpoolctl")
    with blas_threads_for(150, sparse=False):
        assert _blas_threads() == [1] * len(before)
    assert _blas_threads() == before
    with blas_threads_for(10**5, sparse=True):
        assert _blas_threads() == [1] * len(before)
    for n in (1, 8):  # tiny dense too (OpenBLAS threads slowed an 8-state run 2x)
        with blas_threads_for(n, sparse=False):
            assert _blas_threads() == [1] * len(before)
    with blas_threads_for(DENSE_SHARED_MIN, sparse=False):  # large dense: untouched
        assert _blas_threads() == before


def test_a_dense_run_of_60_unknowns_runs_on_one_blas_thread():
    """Inside the run (seen from a user event, evaluated at every row) BLAS has one
    thread; the branch itself is the closed form x_i = mu / (i + 1)."""
    n = 60
    seen: list[list[int]] = []

    def rhs(x, p, ops):
        return ops.stack([p[0] - (i + 1) * x[i] for i in range(n)])

    def probe(x, p):
        seen.append(_blas_threads())
        return float(p) - 10.0  # never crossed

    sys = System(rhs, tuple(f"x{i}" for i in range(n)), ("mu",))
    br = continue_equilibria(
        sys, np.zeros(n), {"mu": 0.0}, "mu", p_max=1.0, direction="forward",
        events=[Event("probe", probe)],
    )  # fmt: skip
    np.testing.assert_allclose(br.x, br.p[:, None] / np.arange(1, n + 1), atol=1e-12)
    if _blas_threads():
        assert seen and all(t == [1] * len(t) for t in seen)
