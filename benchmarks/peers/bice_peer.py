"""bice 0.4.6 (Engelnkemper, Hartmann, Thiele et al., "bice: BIfurcation Continuation
Engine", Python package) on the benchmark problems.

The problem becomes a :class:`bice.Problem` with one :class:`bice.Equation` whose
``rhs`` is the problem's vectorised ``f`` and whose ``jacobian`` is the problem's exact
``jac`` (sparse CSC for the large Bratu grid). bice's own parts do the rest:
``PseudoArclengthContinuation`` (tangent by secant from the history, parameter
derivative by central differences, ``scipy.sparse.linalg.spsolve`` on the bordered
system every Newton iteration, convergence on ``||dz||_2 < 1e-10``, step adapted towards
3 Newton iterations), eigenvalues at every step (all of them, dense ``scipy.linalg.eig``,
for ``n <= 20``; otherwise the 6 nearest 0 by ARPACK shift-invert, as in our engine and the
baseline), and ``always_locate_bifurcations`` (bisection on the real part of the critical
eigenvalue to ``1e-5``).

bice reports an eigenvalue crossing as ``"+"``/``"-"`` (a real eigenvalue: it does not
tell a fold from a branch point) and ``"HP"`` (Hopf). The driver loop is ours (bice has
none): one ``continuation_step()`` at a time, stopping on the parameter window, the norm
cap or ``max_steps``, exactly like the other tools.
"""

from __future__ import annotations

import contextlib
import io
import math
from typing import Any

import numpy as np

from .common import PeerResult, PeerUnavailable


def _bice() -> Any:
    try:
        import bice
    except Exception as exc:
        raise PeerUnavailable(f"bice not importable: {type(exc).__name__}: {exc}") from exc
    return bice


def make_problem(problem: Any) -> Any:
    """A configured ``bice.Problem`` for the benchmark ``problem``."""
    bice = _bice()
    pv0 = problem.param_vector()
    fi = problem.free_index

    class _Eq(bice.Equation):  # type: ignore[misc, name-defined]
        def __init__(self) -> None:
            super().__init__(shape=(problem.n,))
            self.u = np.array(problem.x0, dtype=float)
            self.par = pv0.copy()

        # bice calls the continuation parameter by attribute name
        @property
        def free(self) -> float:
            return float(self.par[fi])

        @free.setter
        def free(self, value: float) -> None:
            self.par[fi] = value

        def rhs(self, u: Any) -> Any:
            return problem.f(u, self.par)

        def jacobian(self, u: Any) -> Any:
            return problem.jac(u, self.par)

    class _Prob(bice.Problem):  # type: ignore[misc, name-defined]
        def __init__(self) -> None:
            super().__init__()
            self.eq_ = _Eq()
            self.add_equation(self.eq_)
            self.continuation_parameter = (self.eq_, "free")

    prob = _Prob()
    st = prob.continuation_stepper
    st.ds = problem.ds
    st.ds_min = problem.ds_min
    st.ds_max = problem.ds_max
    st.convergence_tolerance = 1e-10
    prob.settings.neigs = None if problem.n <= 20 else 6
    prob.settings.eigval_zero_tolerance = 1e-10
    prob.settings.always_locate_bifurcations = True
    prob.settings.use_sparse_matrices = bool(problem.sparse)
    return prob


def run(problem: Any) -> PeerResult:
    """One bice continuation of ``problem`` (see module docstring)."""
    prob = make_problem(problem)
    steps = 0
    status = "max_steps"
    sink = io.StringIO()  # bice prints step-size messages
    with contextlib.redirect_stdout(sink):
        while steps < problem.max_steps:
            try:
                prob.continuation_step()
            except np.linalg.LinAlgError as exc:
                status = f"failed: {exc}"
                break
            steps += 1
            p = prob.get_continuation_parameter()
            if not problem.p_min <= p <= problem.p_max:
                status = "param_bound"
                break
            if math.isfinite(problem.norm_max) and np.linalg.norm(prob.u) > problem.norm_max:
                status = "norm_bound"
                break
    branch = prob.bifurcation_diagram.active_branch
    special = []
    for sol in branch.bifurcations():
        t = sol.bifurcation_type()
        kind = "hopf" if t == "HP" else t
        special.append((kind, float(sol.p)))
    return PeerResult(
        steps=steps,
        special=special,
        p_end=float(prob.get_continuation_parameter()),
        status=status,
        extra={"solutions": len(branch.solutions)},
    )


__all__ = ["make_problem", "run"]
