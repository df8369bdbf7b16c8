r"""Experiment: a compiled multi-iteration corrector against broachkit's Python corrector.

Run on demand: ``python benchmarks/corrector_kernel.py [--iters 3]`` (a few seconds; the
JIT part needs a C compiler, CasADi's ``shell`` plugin calls ``gcc``/``cc``).

For the eight-state cubic of the continuation benchmark (``n = 8``), a continuation
step's corrector is 2-3 Newton iterations of the bordered system, each one compiled
CasADi call plus one LAPACK ``gesv`` and a few NumPy operations from Python
(``continuation.algorithms.corrector._correct_fused``). This script builds the alternative
that issue 2's last target (beating native AUTO-07p on that problem) suggested: ``K``
unrolled Newton iterations -- bordered residual and Jacobian, a Householder QR solve
for the correction and the tangent (Golub & Van Loan 2013, Alg. 5.2.1), the
determinant's sign -- in ONE CasADi SX function, and times

* ``python``: one call of the engine's corrector from a tangent predictor,
* ``kernel, VM``: one call of the kernel in CasADi's virtual machine,
* ``kernel, JIT``: the same compiled to machine code by the system C compiler,

on the same predictor mid-branch, checking that the kernel's iterate after the
engine's iteration count equals the engine's corrected point (to 1e-12). The kernel
does not decide anything (the engine's acceptance rules would be replayed on its
per-iteration norms); that replay and the extraction of the accepted iterate cost a few
microseconds more in Python. Measured on 2026-11-22 (2 cores, load ~1): python
16.5 us for this two-iteration step (about 11 us for the one-iteration steps that the
engine's Hermite predictor makes common), VM 6.5 us, JIT 2.0 us (0.5 s to compile).
Integrated into the engine (an experiment, not on main: decisions replayed, accepted
iterate copied out, fallback to the Python corrector beyond K iterations), the VM kernel
made the whole cubic8 run slower (5.6 against 5.3 ms: the replay and the copies ate the
gain) and the JIT kernel took it to 4.5 ms, still not safely below AUTO-07p's 4.5-5 ms
wall time and at the price of a C compiler at run time, so the engine does not use it
(see ``benchmarks/README.md``).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import casadi as ca  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.engine_per_step import PROBLEMS  # noqa: E402
from continuation.algorithms import PALC  # noqa: E402
from continuation.algorithms.corrector import correct  # noqa: E402
from continuation.problem import EquilibriumProblem  # noqa: E402
from continuation.settings import ContinuationSettings  # noqa: E402

N_SCALARS = 8


def householder_solve(A: Any, B: Any) -> tuple[Any, Any, Any]:
    """Solve ``A X = B`` by Householder QR in CasADi scalar expressions.

    Parameters
    ----------
    A : casadi.SX, shape (N, N)
    B : casadi.SX, shape (N, m)

    Returns
    -------
    X : casadi.SX, shape (N, m)
    sign : casadi.SX
        Sign of ``det A`` (0 if a diagonal entry of ``R`` is exactly zero).
    logabsdet : casadi.SX
        ``log |det A|`` (``-inf`` if singular).

    Notes
    -----
    Column ``k`` is reflected onto ``alpha e_1`` with ``alpha = -sign(x_0) ||x||`` (the
    choice that avoids cancellation); a zero column makes ``v . v = 0`` and the result
    non-finite, which callers treat as a singular matrix.
    """
    N = int(A.shape[0])
    m = int(B.shape[1])
    a = [[A[i, j] for j in range(N)] for i in range(N)]
    b = [[B[i, j] for j in range(m)] for i in range(N)]
    diag = []
    for k in range(N - 1):
        x0 = a[k][k]
        nrm = ca.sqrt(sum(a[i][k] * a[i][k] for i in range(k, N)))
        alpha = ca.if_else(x0 >= 0, -nrm, nrm)
        v = [x0 - alpha] + [a[i][k] for i in range(k + 1, N)]
        beta = 2.0 / sum(vi * vi for vi in v)
        diag.append(alpha)
        for j in range(k + 1, N):
            s = beta * sum(v[i - k] * a[i][j] for i in range(k, N))
            for i in range(k, N):
                a[i][j] = a[i][j] - s * v[i - k]
        for j in range(m):
            s = beta * sum(v[i - k] * b[i][j] for i in range(k, N))
            for i in range(k, N):
                b[i][j] = b[i][j] - s * v[i - k]
    diag.append(a[N - 1][N - 1])
    x: list[list[Any]] = [[0.0] * m for _ in range(N)]
    for j in range(m):
        for i in range(N - 1, -1, -1):
            r_ii = diag[i]
            acc = b[i][j] - sum(a[i][col] * x[col][j] for col in range(i + 1, N))
            x[i][j] = acc / r_ii
    sign = ca.SX(1.0 if (N - 1) % 2 == 0 else -1.0)
    logdet = ca.SX(0.0)
    for d in diag:
        sign = sign * ca.sign(d)
        logdet = logdet + ca.log(ca.fabs(d))
    X = ca.vertcat(*[ca.horzcat(*row) for row in x])
    return X, sign, logdet


def build_kernel_function(
    bordered: ca.Function, n: int, m: int, K: int, opts: dict[str, Any]
) -> ca.Function:
    """The SX function of :class:`CorrectorKernel` from the bordered evaluator's function.

    ``bordered(u, p, c, h) -> (r, M, norms)`` as built by
    :meth:`continuation.system.System.bordered_evaluator`.
    """
    N = n + 1
    U0 = ca.SX.sym("u0", N)
    P = ca.SX.sym("p", m)
    C = ca.SX.sym("c", N)
    H = ca.SX.sym("h")
    E = ca.SX.zeros(N, 1)
    E[n] = 1.0
    outs = [ca.norm_inf(U0)]
    uk = U0
    for _ in range(K):
        res = bordered(uk, P, C, H)
        r, M = res[0], res[1]
        X, sign, logdet = householder_solve(M, ca.horzcat(r, E))
        du = X[:, 0]
        Mv = ca.vec(M)
        u_next = uk - du
        outs += [
            u_next,
            r,
            Mv,
            X[:, 1],
            ca.norm_inf(r),
            ca.dot(r, r),
            ca.norm_inf(r[:n]),
            ca.dot(Mv, Mv),
            ca.norm_inf(du),
            ca.dot(du, du),
            sign,
            logdet,
        ]
        uk = u_next
    return ca.Function("corrector_kernel", [U0, P, C, H], [ca.vertcat(*outs)], opts)


def _time(fn: Any, n: int = 20000) -> float:
    fn()
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        best = min(best, (time.perf_counter() - t0) / n)
    return best


def main(argv: list[str] | None = None) -> None:
    """Print the three timings and the consistency check (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--iters", type=int, default=3, help="unrolled Newton iterations K")
    args = ap.parse_args(argv)
    sys_, params, free, x0, bounds, _ = PROBLEMS["cubic8"]()
    problem = EquilibriumProblem(sys_, sys_.params(**params), free)
    st = ContinuationSettings(ds=0.01, ds_min=1e-8, ds_max=0.1, max_steps=2000, **bounds)
    alg = PALC(predictor="tangent")
    state = alg.init(problem, x0, params[free], st)
    for _ in range(30):  # mid-branch, full step length
        state, _ = alg.step(problem, state, st)
        state.ds = min(state.ds * 1.5, 0.1)
    a = state.point
    c = state.w * a.tau
    u_pred = a.u + state.ds * a.tau
    res = correct(problem, u_pred, a.u, c, state.ds, st.newton, max_contraction=0.8, exact=False)
    t_py = _time(
        lambda: correct(
            problem, u_pred, a.u, c, state.ds, st.newton, max_contraction=0.8, exact=False
        )
    )
    n, m = sys_.n_states, sys_.n_params
    k = problem._index
    bordered = sys_.__dict__["_ca_bordered"][k]
    print(f"cubic8, n = {n}: the engine's corrector takes {res.iters} iteration(s)")
    print(f"python  (engine corrector)     {t_py * 1e6:7.2f} us per call")
    per = 3 * (n + 1) + (n + 1) ** 2 + N_SCALARS
    for label, opts in (
        ("kernel, VM ", {}),
        ("kernel, JIT", {"jit": True, "compiler": "shell", "jit_options": {"flags": ["-O1"]}}),
    ):
        t0 = time.perf_counter()
        try:
            fn = build_kernel_function(bordered, n, m, args.iters, opts)
        except RuntimeError as exc:  # no compiler
            print(f"{label}: not available ({str(exc).splitlines()[0][:80]})")
            continue
        build = time.perf_counter() - t0
        inputs = [
            u_pred.copy(),
            problem.params.values.copy(),
            c.copy(),
            np.array([c @ a.u + state.ds]),
        ]
        out = np.zeros(fn.nnz_out(0))
        buf, run = fn.buffer()
        for i, arr in enumerate(inputs):
            buf.set_arg(i, memoryview(arr))
        buf.set_res(0, memoryview(out))
        t_k = _time(run)
        it = min(res.iters, args.iters - 1)
        # iterate u_{it+1} (the engine applies its last, tiny correction too)
        u_k = out[1 + it * per : 1 + it * per + n + 1]
        err = float(np.max(np.abs(u_k - res.u)))
        print(
            f"{label} (K = {args.iters})          {t_k * 1e6:7.2f} us per call "
            f"(built in {build:.2f} s; |u_kernel - u_engine| = {err:.1e})"
        )
        assert err < 1e-12, "kernel and engine corrector disagree"


if __name__ == "__main__":
    main()
