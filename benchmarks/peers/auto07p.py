"""AUTO-07p (Doedel et al., "AUTO-07P: continuation and bifurcation software for ordinary
differential equations", Concordia University, 2007/2012) through the ``bifpy`` 0.3.0
Python interface, in two ways:

* ``native``: ``bifpy.auto.run(..., transpile=True, jac=AUTO_JACOBIAN)`` traces the
  model with SymPy, writes a Fortran equation file with exact Jacobians and links it
  against AUTO-07p's library into a standalone executable (AUTO's normal way of working).
  The Fortran is generated from the problem's ``rhs(x, p, ops)``, the same source our
  engine traces with CasADi. Tracing and compiling are *setup*; a timed run executes
  that executable in its own directory (it reads ``fort.2`` and writes ``fort.7/8/9``),
  as ``@r`` in AUTO's own command line does. This is AUTO-07p at full speed.
* ``ctypes``: the default ``bifpy.auto.run(...)`` path: AUTO-07p runs in a forked child
  process and calls our NumPy ``f``/``jac`` back through ctypes; the run includes the
  fork and bifpy's parsing of AUTO's output files.

Problem type ``IPS=1`` (equilibria of an ODE: AUTO computes the eigenvalues of ``f_x``
at every point, detects folds (``ILP=1``), Hopf and branch points (``ISP=2``) and
locates them to ``EPSS``). Settings are mapped from the benchmark problem: ``DS``,
``DSMIN``, ``DSMAX``, ``RL0/RL1 = p_min/p_max``, ``A1 = norm_max`` (AUTO's L2-NORM of an
algebraic solution is the Euclidean norm of ``U``), ``NMX = max_steps``,
``EPSL = EPSU = 1e-10``, ``EPSS = 1e-10``, ``IAD = 3``, ``ITNW = 7``, ``NWTN = 3``,
``JAC = 1`` (exact Jacobian). AUTO doubles the step when Newton needed at most
``ITNW // 2`` iterations; with its default ``ITNW = 5`` and these tight tolerances it
never grew beyond ``DS = 0.01`` (1071 steps on Bratu N=20 instead of 174), so ``ITNW = 7``
gives it the same rule as broachkit and the baseline (grow after <= 3 iterations).
"""

from __future__ import annotations

import contextlib
import math
import os
import pathlib
import shutil
import subprocess
import time
from typing import Any

import numpy as np

from . import auto_native
from .common import PeerResult, PeerUnavailable

_KIND = {"FOLD": "fold", "HOPF_BIFURCATION": "hopf", "BRANCH_POINT": "bp"}


def _auto() -> Any:
    try:
        from bifpy import auto
    except Exception as exc:  # ImportError, or AUTO's shared library failing to load
        raise PeerUnavailable(f"bifpy not importable: {type(exc).__name__}: {exc}") from exc
    return auto


def settings_for(problem: Any) -> dict[str, Any]:
    """AUTO-07p constants for ``problem`` (see module docstring)."""
    auto = _auto()
    big = 1e300
    return {
        "ips": auto.IPS_EQUILIBRIUM,
        "ndim": problem.n,
        "npar": len(problem.param_names),
        "nmx": problem.max_steps,
        "npr": 0,
        "ilp": 1,
        "isp": 2,
        "iad": 3,
        "itmx": 9,
        "itnw": 7,
        "nwtn": 3,
        "jac": 1,
        "iid": 0,
        "ds": problem.ds,
        "dsmin": problem.ds_min,
        "dsmax": problem.ds_max,
        "rl0": problem.p_min,
        "rl1": problem.p_max,
        "a0": -big,
        "a1": problem.norm_max if math.isfinite(problem.norm_max) else big,
        "epsl": 1e-10,
        "epsu": 1e-10,
        "epss": 1e-10,
    }


def _tracing_ops() -> Any:
    """``continuation.ops.NUMPY_OPS`` with ``stack=list``: NumPy ufuncs applied to one
    bifpy placeholder at a time dispatch to its ``__array_ufunc__``, so ``problem.rhs``
    traces into SymPy element by element."""
    import dataclasses

    from continuation.ops import NUMPY_OPS

    return dataclasses.replace(NUMPY_OPS, name="bifpy-trace", stack=list)


def _callbacks(problem: Any, symbolic: bool = False) -> tuple[Any, Any, Any]:
    n = problem.n
    m = len(problem.param_names)
    x0 = [float(v) for v in problem.x0]
    pv = [float(v) for v in problem.param_vector()]
    f = problem.f
    rhs = problem.rhs
    ops = _tracing_ops() if symbolic else None

    def func(u: Any, par: Any) -> Any:
        if symbolic:  # the same ``rhs(x, p, ops)`` our engine traces with CasADi
            return rhs(u, par, ops)
        return f(u[:n], par[:m])

    def stpnt(u: Any, par: Any, t: Any) -> None:
        for i in range(n):
            u[i] = x0[i]
        for j in range(m):
            par[j] = pv[j]

    def jac(u: Any, par: Any) -> tuple[Any, Any]:
        uu = np.asarray(u[:n], dtype=float)
        pp = np.asarray(par[:m], dtype=float)
        J = problem.jac(uu, pp)
        J = J.toarray() if hasattr(J, "toarray") else np.asarray(J)
        return J, problem.dfdp(uu, pp).reshape(n, 1)

    return func, stpnt, jac


def _result(res: Any, problem: Any) -> PeerResult:
    points = [pt for br in res.branches for pt in br.points]
    fi = 0  # ``point.parameters`` lists the ICP parameters only: the free one is first
    special = [
        (_KIND[pt.point_type.name], float(pt.parameters[fi]))
        for pt in points
        if pt.point_type.name in _KIND
    ]
    last = points[-1]
    return PeerResult(
        steps=len(points) - 1,
        special=special,
        p_end=float(last.parameters[fi]),
        status=last.point_type.name,
        extra={"branches": len(res.branches)},
    )


def rows_result(rows: list[auto_native.Point], problem: Any) -> PeerResult:
    """A :class:`PeerResult` from the rows of a ``fort.7`` (status: AUTO's type label)."""
    if not rows:
        raise RuntimeError("AUTO-07p wrote no solution rows")
    col = f"PAR({problem.free_index + 1})"
    special = [
        (auto_native.KIND[r.ty], float(r.values[col])) for r in rows if r.ty in auto_native.KIND
    ]
    last = rows[-1]
    return PeerResult(
        steps=len(rows) - 1,
        special=special,
        p_end=float(last.values[col]),
        status=auto_native.TYPE_LABEL.get(last.ty, str(last.ty)),
        extra={"branches": len({r.branch for r in rows})},
    )


def run_ctypes(problem: Any) -> PeerResult:
    """One AUTO-07p run through bifpy's ctypes callbacks (fork + run + parse)."""
    auto = _auto()
    func, stpnt, jac = _callbacks(problem)
    res = auto.run(func, stpnt, settings_for(problem), icu=[problem.free_index + 1], jac=jac)
    return _result(res, problem)


class NativeAuto:
    """A compiled AUTO-07p executable for one problem (see module docstring).

    Parameters
    ----------
    problem : BenchmarkProblem
    workdir : path-like
        Parent directory for the build; the build directory is removed by :meth:`close`.
    """

    def __init__(self, problem: Any, workdir: str | os.PathLike[str]) -> None:
        auto = _auto()
        if shutil.which("gfortran") is None:
            raise PeerUnavailable("gfortran not on PATH (needed by bifpy transpile=True)")
        self.problem = problem
        func, stpnt, _ = _callbacks(problem, symbolic=True)
        t0 = time.perf_counter()
        res = auto.run(
            func,
            stpnt,
            settings_for(problem),
            icu=[problem.free_index + 1],
            jac=auto.AUTO_JACOBIAN,
            transpile=True,
            keep_output=True,
        )
        self.setup_seconds = time.perf_counter() - t0
        self.directory = pathlib.Path(res.output_directory)
        self.first = _result(res, problem)
        exe = self.directory / "model_exe"
        if not exe.exists():
            raise PeerUnavailable(f"bifpy did not leave an executable in {self.directory}")
        self.exe = exe
        self.workdir = pathlib.Path(workdir)

    def _clean(self) -> None:
        for name in ("fort.7", "fort.8", "fort.9"):
            with contextlib.suppress(FileNotFoundError):
                (self.directory / name).unlink()

    def run(self) -> float:
        """Run the executable once; return its wall time in seconds (start to exit)."""
        self._clean()
        dt, proc = auto_native.run_executable(self.exe, self.directory)
        if proc.returncode != 0:
            raise RuntimeError(f"AUTO-07p executable exited with {proc.returncode}")
        return dt

    def peak_rss_kib(self) -> int | None:
        """Peak RSS of one run of the executable alone, KiB (``/usr/bin/time -f %M``).

        A child's ``ru_maxrss`` seen from Python would include the image of the Python
        process it was forked from, so the executable is started by GNU ``time``
        instead. Returns None when ``/usr/bin/time`` is missing.
        """
        if not os.path.exists("/usr/bin/time"):
            return None
        self._clean()
        proc = subprocess.run(
            ["/usr/bin/time", "-f", "%M", str(self.exe)],
            cwd=self.directory,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            check=False,
        )
        try:
            return int(proc.stderr.strip().splitlines()[-1])
        except (ValueError, IndexError):
            return None

    def result(self) -> PeerResult:
        """The ``fort.7`` of the last run (:func:`auto_native.parse_fort7`)."""
        return rows_result(auto_native.parse_fort7(self.directory / "fort.7"), self.problem)

    def close(self) -> None:
        """Remove the build directory."""
        shutil.rmtree(self.directory, ignore_errors=True)


__all__ = ["NativeAuto", "run_ctypes", "settings_for"]
