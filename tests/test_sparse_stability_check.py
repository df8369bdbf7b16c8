"""The saddle index of sparse branches is checked against the rightmost eigenvalues.

Brusselator reaction-diffusion on [0, 1] with Dirichlet data (A, B/A), N nodes (n = 2N
unknowns, sparse path): u_t = D1 u_xx + A - (B+1) u + u^2 v, v_t = D2 v_xx + B u - u^2 v.
Mode k of the discrete Laplacian, mu_k = 4/h^2 sin^2(k pi h / 2), has its Hopf point at
B = 1 + A^2 + (D1 + D2) mu_k (exact for the discretisation). With small diffusion many
slow real modes lie closer to 0 than the critical pair (about +-2i), so the shift-invert
eigenvalues nearest 0 miss it: the engine must notice and compute them, not report a
stable branch silently (reported by the generality audit).
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import brusselator_rd

from continuation import DetectionSettings, System, continue_equilibria
from continuation.settings import ContinuationSettings

N, A, D1, D2 = 100, 2.0, 1e-4, 2e-4
H = 1.0 / (N + 1)
MU = 4 / H**2 * np.sin(np.arange(1, N + 1) * np.pi * H / 2) ** 2
B_HOPF = 1 + A**2 + (D1 + D2) * MU  # exact Hopf points of the discretisation


@pytest.fixture(scope="module")
def system() -> System:
    return brusselator_rd(N, D1, D2)


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


def test_missed_unstable_pair_is_found_by_a_second_pass(system, caplog):
    """With the default 6 eigenvalues nearest 0 the critical pair is invisible; the
    end-of-branch check against the rightmost eigenvalues sees it, and the branch is
    continued again with the rightmost eigenvalues at every point: the exact Hopf point
    is then found and located, as with all eigenvalues (next test)."""
    with caplog.at_level("WARNING", logger="continuation.driver"):
        br = _run(system)  # 6 eigenvalues nearest 0 (shift-invert)
    assert br.problem.sparse
    assert "Second pass" in br.message and "still incomplete" not in br.message
    assert any("missed unstable ones" in r.message for r in caplog.records)
    (h,) = br.find("hopf")
    assert h.located
    assert h.p == pytest.approx(B_HOPF[0], abs=1e-8)
    assert br.n_unstable[-1] == 2


def test_dense_eigenvalues_find_the_exact_hopf_point(system):
    br = _run(system, dense_eigs_max=1000)
    (h,) = br.find("hopf")
    assert h.located
    assert h.p == pytest.approx(B_HOPF[0], abs=1e-8)
    assert "Second pass" not in br.message
    assert br.n_unstable[-1] == 2  # one pair unstable past the first Hopf point only


def test_two_turing_branch_points_in_one_step_are_both_located():
    """Brusselator RD with N = 30 (n = 60, dense), A = 2, D1 = 0.002, D2 = 0.045: the
    uniform state has a branch point (Turing bifurcation) where mode k of the discrete
    Laplacian has a zero eigenvalue, B_T,k = (1 + D1 mu_k)(A^2 + D2 mu_k)/(D2 mu_k)
    (exact for the discretisation). Two of them (3.4115, 3.5158) fit in one default
    step: the determinant changes sign twice and both went unseen, the real unstable
    count jumping by 2. A step in which two real eigenvalues cross zero is retried
    shorter, so all eight in (3, B_Hopf) are found. Next to some of them the
    corrector's trial points jump between the crossing branches, so the branch-point
    test jumps: those are reported bracketed (not located) rather than "located" off
    the true point; every located one is accurate."""
    n_nodes, a, d1, d2 = 30, 2.0, 0.002, 0.045
    sys = brusselator_rd(n_nodes, d1, d2)
    h = 1.0 / (n_nodes + 1)
    mu = 4 / h**2 * np.sin(np.arange(1, n_nodes + 1) * np.pi * h / 2) ** 2
    b_t = (1 + d1 * mu) * (a**2 + d2 * mu) / (d2 * mu)
    b_h = 1 + a**2 + (d1 + d2) * mu[0]
    expected = np.sort(b_t[(b_t > 3) & (b_t < b_h)])
    assert expected.size == 8
    x0 = np.r_[np.full(n_nodes, a), np.full(n_nodes, 3.0 / a)]
    br = continue_equilibria(sys, x0, {"A": a, "B": 3.0}, "B", p_min=2.0, p_max=b_h - 0.05,
                             direction="forward")  # fmt: skip
    bps = sorted(br.find("bp"), key=lambda q: q.p)
    assert len(bps) == 8
    for q, exact in zip(bps, expected, strict=True):
        lo, hi = sorted(q.bracket)
        assert lo <= exact <= hi
        if q.located:
            # next to a branch point the corrected points are determined to the Newton
            # tolerance over a vanishing singular value: 1e-8 relative
            assert q.p == pytest.approx(exact, rel=1e-8)
    assert sum(q.located for q in bps) >= 6
    # the saddle index rises by one at each
    assert br.n_unstable[-1] - br.n_unstable[0] == 8
