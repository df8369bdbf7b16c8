"""Periodic-orbit continuation: broachkit (continuation.periodic) against AUTO-07p.

Problem: the Brusselator ``x' = A - (B + 1) x + x^2 y``, ``y' = B x - x^2 y``, A = 1.5,
whose cycles are born at the Hopf point B = 1 + A^2 = 3.25 (supercritical). Both tools
continue the cycles in B from B0 = 3.3 to B = 5 on the same discretisation (NTST = 40
intervals of NCOL = 4 Gauss points, no mesh adaptation), with Newton tolerances 1e-10,
the same step limits (DS = 0.02, DSMIN = 1e-4, DSMAX = 0.1), Floquet multipliers at
every point (AUTO: ISP = 2; broachkit: always) and folds detected (ILP = 1).

bifpy 0.3.0 cannot switch AUTO onto cycles at a Hopf label (its C API lacks the
branch switch), so both tools cold-start from the same analytic first-harmonic guess
at B0: the cycle of :func:`continuation.periodic.periodic_orbit_from_hopf` at B0,
written as ``x0 + a cos(2 pi t) + b sin(2 pi t)`` (AUTO's stpnt) -- broachkit corrects
the same guess. Timed: AUTO-07p's compiled executable (``transpile=True``, exact
Jacobian from SymPy, as AUTO's own ``@r``) from process start to exit; broachkit's
``continue_periodic`` call. Setup (tracing, compiling) is excluded on both sides.

Run (needs ``benchmarks/_work/venv`` from ``setup_env.sh``, or bifpy + gfortran)::

    benchmarks/_work/venv/bin/python benchmarks/periodic_vs_auto.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import shutil
import statistics
import subprocess
import sys
import time

# measure the checkout this script is in (the venv's editable install may point at
# another one)
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from continuation import (  # noqa: E402
    ContinuationSettings,
    NewtonSettings,
    Params,
    System,
    continue_equilibria,
)
from continuation.bvp import CollocationMesh  # noqa: E402
from continuation.periodic import (  # noqa: E402
    PeriodicOrbit,
    continue_periodic,
    multipliers,
    periodic_orbit_from_hopf,
)

A = 1.5
B0, B1 = 3.3, 5.0
NTST, NCOL = 40, 4
DS, DSMIN, DSMAX, NMX = 0.02, 1e-4, 0.1, 500
TOL = 1e-10


def rhs(x, p, ops):
    a, b = p[0], p[1]
    return ops.stack([a - (b + 1) * x[0] + x[0] ** 2 * x[1], b * x[0] - x[0] ** 2 * x[1]])


def first_harmonic() -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """``(x0, a, b, T)`` of the first-harmonic guess at B0 (from the Hopf start)."""
    s = System(rhs, ("x", "y"), ("A", "B"))
    eq = continue_equilibria(s, [A, 3.0 / A], {"A": A, "B": 3.0}, "B", p_min=2.0, p_max=4.0,
                             direction="forward", ds=0.05)  # fmt: skip
    (h,) = eq.find("hopf")
    # amplitude chosen so that the normal-form offset lands at B0
    orb0 = periodic_orbit_from_hopf(eq, h.label, amplitude=1e-2, correct=False)
    amp = 1e-2 * math.sqrt((B0 - h.p) / (orb0.param("B") - h.p))
    orb = periodic_orbit_from_hopf(eq, h.label, amplitude=amp, correct=False,
                                   mesh=CollocationMesh(NTST, NCOL, 1.0))  # fmt: skip
    tau = orb.mesh.tau
    X = orb.X
    x0 = X.mean(axis=0)
    c, sn = np.cos(2 * np.pi * tau), np.sin(2 * np.pi * tau)
    a = 2 * np.array([np.trapezoid(X[:, i] * c, tau) for i in range(2)])
    b = 2 * np.array([np.trapezoid(X[:, i] * sn, tau) for i in range(2)])
    return x0, a, b, orb.T


def run_broachkit(guess: tuple, repeats: int) -> dict:
    x0, a, b, T = guess
    s = System(rhs, ("x", "y"), ("A", "B"))
    mesh = CollocationMesh(NTST, NCOL, 1.0)
    tau = mesh.tau
    X = (x0[None, :] + a[None, :] * np.cos(2 * np.pi * tau)[:, None]
         + b[None, :] * np.sin(2 * np.pi * tau)[:, None])  # fmt: skip
    orb = PeriodicOrbit(s, Params(("A", "B"), (A, B0)), mesh, X, T)
    st = ContinuationSettings(ds=DS, ds_min=DSMIN, ds_max=DSMAX, p_max=B1, max_steps=NMX,
                              newton=NewtonSettings(tol=TOL))  # fmt: skip
    br = continue_periodic(s, orb, orb.params, "B", st)  # warm-up (CasADi maps built)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        br = continue_periodic(s, orb, orb.params, "B", st)
        times.append(time.perf_counter() - t0)
    mu = multipliers(br)[:, 0]
    return {
        "median_s": statistics.median(times),
        "steps": len(br) - 1,
        "T_end": float(br.records["T"][-1]),
        "B_end": float(br.p[-1]),
        "mu_end": float(abs(mu[-1])),
        "status": br.status.name,
    }


def run_auto(guess: tuple, repeats: int, workdir: pathlib.Path) -> dict:
    from bifpy import auto
    from bifpy.auto import _parsing

    x0, a, b, T = guess

    def func(u, par):
        return rhs(u, par, _Ops())

    def stpnt(u, par, t):
        par[0] = A
        par[1] = B0
        par[auto.PERIOD_INDEX - 1] = T
        for i in range(2):
            u[i] = x0[i] + a[i] * np.cos(2 * np.pi * t) + b[i] * np.sin(2 * np.pi * t)

    settings = dict(
        ips=auto.IPS_PERIODIC_ORBIT, ndim=2, npar=2, nmx=NMX, ntst=NTST, ncol=NCOL, iad=0,
        ilp=1, isp=2, mxbf=0, iads=1, itmx=9, itnw=7, nwtn=3, jac=1, npr=0, iid=0,
        ds=DS, dsmin=DSMIN, dsmax=DSMAX, rl0=0.0, rl1=B1, a0=-1e300, a1=1e300,
        epsl=TOL, epsu=TOL, epss=1e-8,
    )  # fmt: skip
    res = auto.run(func, stpnt, settings, icu=[2, auto.PERIOD_INDEX], jac=auto.AUTO_JACOBIAN,
                   transpile=True, keep_output=True)  # fmt: skip
    d = pathlib.Path(res.output_directory)
    exe = d / "model_exe"
    times = []
    for _ in range(repeats + 1):
        for name in ("fort.7", "fort.8", "fort.9"):
            (d / name).unlink(missing_ok=True)
        t0 = time.perf_counter()
        subprocess.run([str(exe)], cwd=d, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, check=True)  # fmt: skip
        times.append(time.perf_counter() - t0)
    times = times[1:]
    parsed = _parsing.parse_fort7(d / "fort.7")
    pts = [pt for br in parsed.branches for pt in br.points]
    last = pts[-1]
    out = {
        "median_s": statistics.median(times),
        "steps": len(pts) - 1,
        "B_end": float(last.parameters[0]),
        "T_end": float(last.parameters[1]) if len(last.parameters) > 1 else math.nan,
        "status": last.point_type.name,
    }
    shutil.rmtree(d, ignore_errors=True)
    return out


class _Ops:
    """NumPy ops with ``stack=list`` so that bifpy's SymPy placeholders trace through."""

    def __getattr__(self, name):
        from continuation.ops import NUMPY_OPS

        if name == "stack":
            return list
        return getattr(NUMPY_OPS, name)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    default_json = pathlib.Path(__file__).parent / "results" / "periodic.json"
    ap.add_argument("--json", type=pathlib.Path, default=default_json)
    args = ap.parse_args()
    guess = first_harmonic()
    out = {"broachkit": run_broachkit(guess, args.repeats)}
    try:
        out["auto07p"] = run_auto(guess, args.repeats, pathlib.Path("/tmp"))
    except Exception as exc:  # report, do not hide
        out["auto07p"] = {"error": f"{type(exc).__name__}: {exc}"}
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(out, indent=2))
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
