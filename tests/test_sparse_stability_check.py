"""The saddle index of sparse branches is checked against the rightmost eigenvalues.

Brusselator reaction-diffusion on [0, 1] with Dirichlet data (A, B/A), N nodes (n = 2N
unknowns, sparse path): u_t = D1 u_xx + A - (B+1) u + u^2 v, v_t = D2 v_xx + B u - u^2 v.
Mode k of the discrete Laplacian, mu_k = 4/h^2 sin^2(k pi h / 2), has its Hopf point at
B = 1 + A^2 + (D1 + D2) mu_k (exact for the discretisation). With small diffusion many
slow real modes lie closer to 0 than the critical pair (about +-2i), so the shift-invert
eigenvalues nearest 0 miss it: the branch must say so instead of reporting a stable
branch silently (reported by the generality audit, /work/notes/repro_sparse_hopf_missed).
"""

from __future__ import annotations

import numpy as np
import pytest

from continuation import DetectionSettings, System, continue_equilibria
from continuation.settings import ContinuationSettings


def _brusselator_rd(N: int, D1: float, D2: float) -> System:
    h2 = (1.0 / (N + 1)) ** 2

    def rhs(x, p, ops):
        A, B = p[0], p[1]
        out = []
        for i in range(N):
            ul = x[i - 1] if i > 0 else A
            ur = x[i + 1] if i < N - 1 else A
            out.append(D1 * (ul - 2 * x[i] + ur) / h2 + A - (B + 1) * x[i] + x[i] ** 2 * x[N + i])
        for i in range(N):
            vl = x[N + i - 1] if i > 0 else B / A
            vr = x[N + i + 1] if i < N - 1 else B / A
            out.append(D2 * (vl - 2 * x[N + i] + vr) / h2 + B * x[i] - x[i] ** 2 * x[N + i])
        return ops.stack(out)

    names = tuple(f"u{i}" for i in range(N)) + tuple(f"v{i}" for i in range(N))
    return System(rhs, names, ("A", "B"))


N, A, D1, D2 = 100, 2.0, 1e-4, 2e-4
H = 1.0 / (N + 1)
MU = 4 / H**2 * np.sin(np.arange(1, N + 1) * np.pi * H / 2) ** 2
B_HOPF = 1 + A**2 + (D1 + D2) * MU  # exact Hopf points of the discretisation


@pytest.fixture(scope="module")
def system() -> System:
    return _brusselator_rd(N, D1, D2)


def _run(system: System, **detect) -> object:
    st = ContinuationSettings(
        p_min=2.0,
        p_max=float(B_HOPF[0] + B_HOPF[1]) / 2,
        ds_max=0.2,
        detect=DetectionSettings(**detect),
    )
    x0 = np.r_[np.full(N, A), np.full(N, 3.0 / A)]
    return continue_equilibria(
        system, x0, {"A": A, "B": 3.0}, "B", settings=st, direction="forward"
    )


def test_missed_unstable_pair_is_reported(system, caplog):
    with caplog.at_level("WARNING", logger="continuation.driver"):
        br = _run(system)  # 6 eigenvalues nearest 0 (shift-invert)
    assert br.problem.sparse
    assert br.n_unstable.max() == 0  # the nearest-0 set sees no unstable eigenvalue ...
    assert "Stability incomplete" in br.message  # ... and the branch says it is partial
    assert any("Stability incomplete" in r.message for r in caplog.records)


def test_dense_eigenvalues_find_the_exact_hopf_point(system):
    br = _run(system, dense_eigs_max=1000)
    (h,) = br.find("hopf")
    assert h.located
    assert h.p == pytest.approx(B_HOPF[0], abs=1e-8)
    assert "Stability incomplete" not in br.message
    assert br.n_unstable[-1] == 2  # one pair unstable past the first Hopf point only
