r"""Per-step cost of the continuation engine against the raw linear-algebra floor.

Run on demand: ``python benchmarks/engine_per_step.py [--repeat 5] [problem ...]``
(about 20 s on one core).

For each problem the script

* builds the CasADi :class:`~continuation.system.System` once and runs
  :func:`~continuation.driver.continue_branch` once untimed (warm-up), then times
  ``--repeat`` runs in CPU time (``time.process_time``) and keeps the fastest;
  *per step* is that time divided by the number of accepted steps (rows - 1). It
  includes everything the driver does: prediction, correction, tangent, stability
  eigenvalues, test functions, location of the special points, rows;
* measures the *floor*: the CPU time of one factorisation and solve of the bordered
  matrix ``[[G_z, G_p], [c^T]]`` plus one eigenvalue solve of ``G_z`` of the kind the
  engine needs, on matrices taken at a point of the branch, the fastest of many
  repetitions. ``floor`` uses the ordinary calls (``scipy.linalg.lu_factor`` /
  ``lu_solve`` and ``numpy.linalg.eigvals`` when dense; SuperLU ``splu`` and ARPACK
  shift-invert ``scipy.sparse.linalg.eigs`` for the 6 eigenvalues nearest 0 when
  sparse): this is the floor of the issue's target (per step within 3x of it).
  ``raw floor`` calls LAPACK ``getrf``/``getrs``/``dgeev`` directly (dense only): the
  bare arithmetic, which no Python-driven step can approach for tiny systems;

and prints both with their ratios. One BLAS thread is forced before NumPy is imported.

The problems mirror the shared continuation benchmark (``benchmarks/problems.py``):
Brusselator (A = 1.5, B from 1 to 4, Hopf at B = 3.25), discrete Bratu with N = 20
(dense) and N = 200 (sparse) from lam = 0 past the fold until ``||u||_2 = 3 sqrt(N+1)``,
and the eight-state cubic with two folds; ``ds = 0.01``, ``ds_max = 0.1``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
import scipy.linalg as la  # noqa: E402
import scipy.sparse as sp  # noqa: E402
import scipy.sparse.linalg as spla  # noqa: E402

from continuation.driver import continue_branch  # noqa: E402
from continuation.events import Event  # noqa: E402
from continuation.problem import EquilibriumProblem  # noqa: E402
from continuation.settings import ContinuationSettings  # noqa: E402
from continuation.system import System  # noqa: E402


# ----------------------------------------------------------------------------- problems
def _bratu(n: int) -> tuple[System, dict[str, float], str, Any, dict[str, float], float]:
    inv_h2 = float(n + 1) ** 2

    def rhs(x: Any, p: Any, ops: Any) -> Any:
        out = []
        for i in range(n):
            left = x[i - 1] if i > 0 else 0.0
            right = x[i + 1] if i < n - 1 else 0.0
            out.append((left - 2.0 * x[i] + right) * inv_h2 + p[0] * ops.exp(x[i]))
        return ops.stack(out)

    sys = System(rhs, tuple(f"u{i + 1}" for i in range(n)), ("lam",), name=f"bratu{n}")
    return sys, {"lam": 0.0}, "lam", np.zeros(n), {"p_min": -1.0, "p_max": 4.0}, 3 * (n + 1) ** 0.5


def _brusselator() -> tuple[System, dict[str, float], str, Any, dict[str, float], float]:
    def rhs(x: Any, p: Any, ops: Any) -> Any:
        a, b = p[0], p[1]
        return ops.stack([a - (b + 1.0) * x[0] + x[0] ** 2 * x[1], b * x[0] - x[0] ** 2 * x[1]])

    sys = System(rhs, ("x", "y"), ("A", "B"), name="brusselator")
    a = 1.5
    return sys, {"A": a, "B": 1.0}, "B", np.array([a, 1.0 / a]), {"p_min": 0.0, "p_max": 4.0}, 0


def _cubic8() -> tuple[System, dict[str, float], str, Any, dict[str, float], float]:
    def rhs(x: Any, p: Any, ops: Any) -> Any:
        out = [p[0] - x[0] ** 3 + 3.0 * x[0]]
        for k in range(1, 8):
            out.append(-float(k) * x[k] + p[1] * ops.tanh(x[k - 1]))
        return ops.stack(out)

    sys = System(rhs, tuple(f"x{k}" for k in range(8)), ("p", "c"), name="cubic8")
    # lower sheet at p = -4: real root of x^3 - 3 x + 4 = 0, then x_k = c tanh(x_{k-1}) / k
    r = np.roots([1.0, 0.0, -3.0, 4.0])
    x = np.zeros(8)
    x[0] = float(r[np.argmin(np.abs(r.imag))].real)
    for k in range(1, 8):
        x[k] = 0.2 * math.tanh(x[k - 1]) / k
    return sys, {"p": -4.0, "c": 0.2}, "p", x, {"p_min": -4.5, "p_max": 4.0}, 0


PROBLEMS: dict[str, Callable[[], Any]] = {
    "brusselator": _brusselator,
    "bratu20": lambda: _bratu(20),
    "bratu200": lambda: _bratu(200),
    "cubic8": _cubic8,
}


# ----------------------------------------------------------------------------- timing
def _best(fn: Callable[[], Any], repeat: int) -> float:
    best = math.inf
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


def _floor(problem: EquilibriumProblem, z: Any, p: float, n_eigs: int = 6) -> tuple[float, float]:
    """CPU seconds of one bordered factorisation + solve + one eigenvalue solve.

    Returns ``(api, raw)``: through the ordinary SciPy/NumPy calls
    (``scipy.linalg.lu_factor``/``lu_solve`` and ``numpy.linalg.eigvals`` when dense;
    ``splu`` and ``scipy.sparse.linalg.eigs`` when sparse), and through LAPACK
    ``getrf``/``getrs``/``geev`` directly (dense only; equal to ``api`` when sparse).
    """
    G, Gz, Gp = problem.linearize(z, p)
    n = z.size
    c = np.ones(n + 1) / (n + 1)
    rhs = np.zeros(n + 1)
    rhs[-1] = 1.0
    if sp.issparse(Gz):
        M = sp.bmat([[Gz, Gp[:, None]], [c[None, :n], c[None, n:]]], format="csc")
        Gz = sp.csc_matrix(Gz)
        v0 = np.cos(np.arange(n) + 1.0)

        def api() -> None:
            spla.splu(M).solve(rhs)
            spla.eigs(Gz, k=n_eigs, sigma=0.0, which="LM", v0=v0, return_eigenvectors=False)

        raw = api
    else:
        getrf, getrs, geev = la.get_lapack_funcs(("getrf", "getrs", "geev"), (np.zeros(1),))
        M = np.block([[Gz, Gp[:, None]], [c[None, :]]])
        Gz = np.asarray(Gz)

        def api() -> None:
            la.lu_solve(la.lu_factor(M), rhs)
            np.linalg.eigvals(Gz)

        def raw() -> None:
            lu, piv, _ = getrf(M)
            getrs(lu, piv, rhs)
            geev(Gz, compute_vl=0, compute_vr=0)

    out = []
    for once in (api, raw):
        inner = max(1, int(2e-3 / max(_best(once, 3), 1e-7)))

        def many(once: Callable[[], None] = once, inner: int = inner) -> None:
            for _ in range(inner):
                once()

        out.append(_best(many, 7) / inner)
    return out[0], out[1]


def measure(name: str, repeat: int) -> dict[str, float]:
    """Per-step CPU time, floor and counts for one problem."""
    sys, params, free, x0, bounds, norm_max = PROBLEMS[name]()
    problem = EquilibriumProblem(sys, sys.params(**params), free)
    st = ContinuationSettings(ds=0.01, ds_min=1e-8, ds_max=0.1, max_steps=2000, **bounds)
    events = ()
    if norm_max:
        events = (Event("norm", lambda x, p: float(np.linalg.norm(x)) - norm_max, terminal=True),)

    def run() -> Any:
        return continue_branch(problem, x0, params[free], settings=st, events=events)

    br = run()  # warm-up (CasADi function objects, caches)
    t = _best(run, repeat)
    steps = len(br) - 1
    k = len(br) // 2
    floor, raw = _floor(problem, br.x[k], float(br.p[k]))
    return {
        "n": float(x0.size),
        "steps": float(steps),
        "newton": float(br.newton_iters[1:].mean()),
        "specials": float(len(br.special_points)),
        "per_step": t / steps,
        "floor": floor,
        "raw": raw,
    }


def main(argv: list[str] | None = None) -> None:
    """Print the table (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("problems", nargs="*", help=f"subset of {list(PROBLEMS)} (default: all)")
    ap.add_argument("--repeat", type=int, default=5, help="timed runs per problem (best kept)")
    args = ap.parse_args(argv)
    bad = [p for p in args.problems if p not in PROBLEMS]
    if bad:
        ap.error(f"unknown problem(s) {bad}; choose from {list(PROBLEMS)}")
    head = f"{'problem':<12}{'n':>5}{'steps':>7}{'newton':>8}{'per step':>12}{'floor':>11}"
    print(head + f"{'ratio':>8}{'raw floor':>13}{'ratio':>8}")
    for name in args.problems or list(PROBLEMS):
        m = measure(name, args.repeat)
        print(
            f"{name:<12}{int(m['n']):>5}{int(m['steps']):>7}{m['newton']:>8.2f}"
            f"{m['per_step'] * 1e6:>9.1f} us{m['floor'] * 1e6:>8.1f} us"
            f"{m['per_step'] / m['floor']:>7.2f}x"
            f"{m['raw'] * 1e6:>10.1f} us{m['per_step'] / m['raw']:>7.2f}x"
        )


if __name__ == "__main__":
    main()
