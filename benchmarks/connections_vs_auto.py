"""Connecting orbits: broachkit against AUTO-07p/HomCont (native) on the demos cir and san.

For each problem, one continuation of the connecting orbit in a second parameter over
the same range, by both tools, and the error of the solved parameter at the end of the
range against a tight reference (broachkit at ``rtol = 1e-11``):

* ``cir`` (Freire et al. 1993; HomCont demo cir, run 2 without its test functions):
  saddle-focus homoclinic orbit, ``nu`` solved, ``beta`` from 0.6 down to 0.1. AUTO
  starts from its run 1 at ``PERIOD = 100`` (label UZ2); broachkit from
  :func:`find_connection` at ``beta = 0.6`` (the saddle alone).
* ``san`` (Sandstede 1995; HomCont demo san, run 1): homoclinic orbit, ``mu~`` solved,
  ``a`` from 0 to 0.25, from the explicit solution at ``a = 0`` (AUTO: STPNT, ``T = 20``;
  broachkit: :func:`find_connection` at ``a = 0``).

Also timed: broachkit's one solve from the saddle alone (:func:`find_connection`:
manifold simulation, adaptive mesh, discretisation and truncation estimates). AUTO has
no such one-shot solve; its start-point correction is part of its run.

AUTO-07p is built from its sources (``git archive`` of github.com/auto-07p/auto-07p, then
``./configure && make -C src``, serially) into ``$AUTO_DIR`` (default
``/tmp/conn_auto``); each demo is compiled against ``$AUTO_DIR/lib/*.o`` (setup, not
timed) and its executable run in a scratch directory (timed: wall clock of the
process, AUTO's normal ``@r``). Times are CPU times (user + system: of the AUTO child
process, of this process for broachkit), best of ``--repeats`` runs: the machine is
shared and wall times swing with its load. broachkit's "cold" solve builds its CasADi
functions (a fresh System); "warm" and the curve reuse them (as AUTO's executable is
compiled before the timed runs).

Usage::

    python benchmarks/connections_vs_auto.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import pathlib
import resource
import shutil
import subprocess
import sys
import tempfile
import time

# one BLAS/OpenMP thread, as AUTO-07p's runs (OMP_NUM_THREADS=1): idle OpenBLAS threads
# spin and double the CPU time of the small dense products (set before NumPy loads)
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from continuation.bvp import ConnectionAccuracy, continue_connection, find_connection  # noqa: E402
from continuation.settings import ContinuationSettings  # noqa: E402
from tests.connection_problems import cir, san  # noqa: E402

AUTO_DIR = pathlib.Path(os.environ.get("AUTO_DIR", "/tmp/conn_auto"))
LIBS = (
    "main auto_constants compat blas lapack ae bvp equilibrium floquet homcont interfaces "
    "io maps mesh mpi optimization parabolic periodic solvebv support timeint toolboxae "
    "toolboxbv"
).split()

CIR_PARAMS = {"nu": -0.72, "beta": 0.6, "gamma": 0.0, "r": 0.6, "a3": 0.328578, "b3": 0.933578}
SAN_PARAMS = {
    "a": 0.0, "b": 1.0, "c": -2.0, "alpha": 0.0, "beta": 1.0, "gamma": 0.0, "mu": 0.0,
    "mut": 0.01,
}  # fmt: skip

CIR_C1 = (AUTO_DIR / "demos/cir/c.cir.1").read_text() if AUTO_DIR.exists() else ""
CIR_C2 = """NDIM=   3, IPS =   9, IRS =   2, ILP =   0
ICP =  [1, 2]
NTST=  35, NCOL=   4, IAD =   1, ISP =   0, ISW = 1, IPLT= 0, NBC= 0, NINT= 0
NMX=  200, NPR=  200, MXBF=   0, IID =   2, ITMX=  10, ITNW= 7, NWTN= 3, JAC= 1
EPSL= 1e-07, EPSU = 1e-07, EPSS = 1e-05
DS  =  0.01, DSMIN=0.0001, DSMAX=  0.01, IADS=   1
NPAR = 14, THL =  {}, THU =  {}
UZSTOP = {2: 0.1}
IEQUIB = 0
"""
SAN_C1 = """NDIM=   3, IPS =   9, IRS =   0, ILP =   0
ICP =  [1, 8]
NTST=  35, NCOL=   4, IAD =   3, ISP =   0, ISW = 1, IPLT= 0, NBC= 0, NINT= 0
NMX=99999, NPR=99999, MXBF=  10, IID =   2, ITMX= 9, ITNW= 7, NWTN= 3, JAC=-1
EPSL= 1e-07, EPSU = 1e-07, EPSS = 1e-05
DS  =  0.05, DSMIN= 0.005, DSMAX=   0.1, IADS=   1
NPAR = 14, THL =  {}, THU =  {}
UZSTOP = {1: 0.25}
IEQUIB=   0
"""


def _build(demo: str, work: pathlib.Path) -> pathlib.Path:
    src = AUTO_DIR / "demos" / demo / f"{demo}.f90"
    exe = work / f"{demo}.exe"
    objs = [str(AUTO_DIR / "lib" / f"{n}.o") for n in LIBS]
    subprocess.run(
        ["gfortran", "-O", "-fopenmp", str(src), f"-I{AUTO_DIR / 'include'}", *objs, "-o",
         str(exe)],
        check=True, cwd=work,
    )  # fmt: skip
    return exe


def _auto_run(exe: pathlib.Path, work: pathlib.Path, constants: str, fort3: pathlib.Path | None):
    """Run once in ``work``: fort.2 = constants, fort.3 = start data; returns (s, fort.8 path)."""
    for f in ("fort.7", "fort.8", "fort.9"):
        (work / f).unlink(missing_ok=True)
    (work / "fort.2").write_text(constants)
    if fort3 is not None:
        shutil.copy(fort3, work / "fort.3")
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    env = {**os.environ, "OMP_NUM_THREADS": "1"}  # one thread, as broachkit's solves
    subprocess.run([str(exe)], cwd=work, check=True, stdout=subprocess.DEVNULL, env=env)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return cpu, work / "fort.8"


def _last_par(fort8: pathlib.Path, index: int) -> float:
    """``PAR(index)`` of the last solution in an AUTO solution file."""
    sys.path.insert(0, str(AUTO_DIR / "python"))
    from auto import parseS  # AUTO-07p's own reader of its solution files

    sols = parseS.parseS(str(fort8))
    return float(sols[-1][f"PAR({index})"])


def _best(fn, repeats: int):
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t0)
    return best, out


def bench_cir(repeats: int) -> dict:
    s = cir()
    work = pathlib.Path(tempfile.mkdtemp(prefix="cir_"))
    exe = _build("cir", work)
    # setup: run 1 (continuation in PERIOD) gives the start at PERIOD = 100 (label 2);
    # its constants name the data file (dat = 'cir': cir.dat in the run directory)
    shutil.copy(AUTO_DIR / "demos/cir/cir.dat", work / "cir.dat")
    _auto_run(exe, work, CIR_C1, None)
    shutil.copy(work / "fort.8", work / "s.start")
    t_auto = min(_auto_run(exe, work, CIR_C2, work / "s.start")[0] for _ in range(repeats))
    nu_auto = _last_par(work / "fort.8", 1)
    beta_auto = _last_par(work / "fort.8", 2)

    def ours_solve(system=None):
        sy = cir() if system is None else system
        return find_connection(sy, sy.params(**CIR_PARAMS), "nu", source=[0, 0, 0], shift=0)

    t_cold, _ = _best(ours_solve, repeats)  # a fresh System: CasADi functions built
    start = ours_solve(s)
    t_solve, start = _best(lambda: ours_solve(s), repeats)
    settings = ContinuationSettings(ds=-0.02, ds_max=0.1, p_min=0.1, p_max=0.61)
    t_curve, br = _best(lambda: continue_connection(start, "beta", settings), repeats)
    i = int(np.argmin(br.p))
    nu_ours = float(br.records["nu"][i])
    ref = find_connection(
        s, s.params(**{**CIR_PARAMS, "beta": float(br.p[i]), "nu": nu_ours}), "nu",
        source=[0, 0, 0], shift=0, accuracy=ConnectionAccuracy(rtol=1e-11, atol=1e-13),
    )  # fmt: skip
    ref_auto = find_connection(
        s, s.params(**{**CIR_PARAMS, "beta": beta_auto, "nu": nu_auto}), "nu",
        source=[0, 0, 0], shift=0, accuracy=ConnectionAccuracy(rtol=1e-11, atol=1e-13),
    )  # fmt: skip
    return {
        "problem": "cir: nu(beta), beta 0.6 -> 0.1",
        "t_auto": t_auto, "t_ours_curve": t_curve, "t_ours_solve": t_solve, "t_ours_cold": t_cold,
        "err_auto": abs(nu_auto - ref_auto.value("nu")),
        "err_ours": abs(nu_ours - ref.value("nu")),
        "end_ours": float(br.p[i]), "end_auto": beta_auto, "steps_ours": len(br.p),
    }  # fmt: skip


def bench_san(repeats: int) -> dict:
    s = san()
    work = pathlib.Path(tempfile.mkdtemp(prefix="san_"))
    exe = _build("san", work)
    t_auto = min(_auto_run(exe, work, SAN_C1, None)[0] for _ in range(repeats))
    mut_auto = _last_par(work / "fort.8", 8)

    def ours_solve(system=None):
        sy = san() if system is None else system
        return find_connection(sy, sy.params(**SAN_PARAMS), "mut", source=[0, 0, 0], shift=0)

    t_cold, _ = _best(ours_solve, repeats)
    start = ours_solve(s)
    t_solve, start = _best(lambda: ours_solve(s), repeats)
    settings = ContinuationSettings(ds=0.05, ds_max=0.1, p_min=-0.01, p_max=0.25)
    t_curve, br = _best(lambda: continue_connection(start, "a", settings), repeats)
    i = int(np.argmax(br.p))
    return {
        "problem": "san: mu~(a), a 0 -> 0.25",
        "t_auto": t_auto, "t_ours_curve": t_curve, "t_ours_solve": t_solve, "t_ours_cold": t_cold,
        "err_auto": abs(mut_auto), "err_ours": abs(float(br.records["mut"][i])),
        "end_ours": float(br.p[i]), "end_auto": 0.25, "steps_ours": len(br.p),
    }  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    if not (AUTO_DIR / "lib" / "main.o").exists():
        raise SystemExit(f"AUTO-07p is not built in {AUTO_DIR} (see the module docstring)")
    rows = [bench_cir(args.repeats), bench_san(args.repeats)]
    print(
        "| problem | AUTO-07p curve (CPU s) | broachkit curve (CPU s) | ratio AUTO/broachkit | "
        "end (AUTO / broachkit) | error AUTO | error broachkit | broachkit solve from the "
        "saddle, warm / cold (CPU s) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['problem']} | {r['t_auto']:.3f} | {r['t_ours_curve']:.3f} | "
            f"{r['t_auto'] / r['t_ours_curve']:.2f} | {r['end_auto']:.4g} / {r['end_ours']:.4g}"
            f" | {r['err_auto']:.1e} | {r['err_ours']:.1e} | {r['t_ours_solve']:.3f} / "
            f"{r['t_ours_cold']:.3f} |"
        )


if __name__ == "__main__":
    main()
