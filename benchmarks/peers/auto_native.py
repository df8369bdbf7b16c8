"""AUTO-07p as native executables, built from equation files this benchmark writes.

AUTO-07p's library (``libbifpy.a``) and its command-line main program (``main.o``, AUTO's
``PROGRAM AUTO`` that reads the constants from ``fort.2`` and restart data from
``fort.3``) come from the ``bifpy`` package on PyPI (``benchmarks/setup_env.sh`` installs
it into ``benchmarks/_work/venv``; bifpy compiles AUTO-07p's Fortran when installed). The
equation file (``FUNC``, ``STPNT``, ``BCND``, ``ICND``, ``FOPT``, ``PVLS``) is Fortran
written by the benchmark itself (see ``connections_vs_auto.py``), compiled with
``gfortran -O2`` and linked as ``gfortran main.o model.o libbifpy.a``: the same executable
AUTO's own ``@r`` builds from a demo directory. No AUTO-07p source file is copied.

A *chain* is a list of AUTO runs (one constants file each) executed one after the other
in one directory, each restarting (``IRS``) from the ``fort.8`` of the previous one, as
``run(r1('UZ1'), c=...)`` does in AUTO's Python front end. Its wall time is measured
around the executables only (process start to exit); AUTO's own ``Total Time`` (from its
standard output) is recorded too.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import os
import pathlib
import re
import shutil
import subprocess
import time
from collections.abc import Mapping, Sequence
from typing import Any

from .common import PeerUnavailable

#: Opening of an equation file's ``FUNC`` (AUTO-07p's interface: the right-hand side
#: ``f`` and, per ``ijac``, its Jacobians ``dfdu``, ``dfdp``); the body and
#: ``end subroutine func`` follow.
FUNC_HEAD = """subroutine func(ndim, u, icp, par, ijac, f, dfdu, dfdp)
  implicit none
  integer, intent(in) :: ndim, icp(*), ijac
  double precision, intent(in) :: u(ndim), par(*)
  double precision, intent(out) :: f(ndim)
  double precision, intent(inout) :: dfdu(ndim, ndim), dfdp(ndim, *)
"""

#: Opening of an equation file's ``STPNT`` (the starting state ``u`` and parameters
#: ``par``, at ``t`` for a periodic or connecting start); the body and
#: ``end subroutine stpnt`` follow.
STPNT_HEAD = """subroutine stpnt(ndim, u, par, t)
  implicit none
  integer, intent(in) :: ndim
  double precision, intent(inout) :: u(ndim), par(*)
  double precision, intent(in) :: t
"""

#: The user routines AUTO-07p links against that the benchmarks' equation files leave
#: empty (boundary and integral conditions, optimisation, user values).
EMPTY_ROUTINES = """subroutine bcnd
end subroutine bcnd
subroutine icnd
end subroutine icnd
subroutine fopt
end subroutine fopt
subroutine pvls
end subroutine pvls
"""


def library_paths() -> tuple[pathlib.Path, pathlib.Path]:
    """``(main.o, libbifpy.a)`` of the installed bifpy; PeerUnavailable if missing."""
    spec = importlib.util.find_spec("bifpy")
    if spec is None or spec.origin is None:
        raise PeerUnavailable("bifpy is not installed (run benchmarks/setup_env.sh)")
    lib = pathlib.Path(spec.origin).parent / "auto" / "_lib"
    main, archive = lib / "main.o", lib / "libbifpy.a"
    if not (main.exists() and archive.exists()):
        raise PeerUnavailable(f"bifpy has no main.o/libbifpy.a in {lib}")
    if shutil.which("gfortran") is None:
        raise PeerUnavailable("gfortran not on PATH")
    return main, archive


def build(source: str, directory: str | os.PathLike[str], name: str = "model") -> pathlib.Path:
    """Compile the Fortran ``source`` and link it against AUTO-07p; return the executable."""
    main, archive = library_paths()
    d = pathlib.Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    src = d / f"{name}.f90"
    src.write_text(source)
    obj, exe = d / f"{name}.o", d / f"{name}.exe"
    for cmd in (
        ["gfortran", "-O2", "-c", "-o", str(obj), str(src)],
        ["gfortran", "-O2", "-o", str(exe), str(main), str(obj), str(archive)],
    ):
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd[:2])} failed:\n{proc.stderr}")
    return exe


def _value(v: Any) -> str:
    if isinstance(v, bool):
        raise TypeError("no booleans in AUTO constants")
    if isinstance(v, Mapping):
        return "{" + ", ".join(f"{k}: {_value(x)}" for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, str):
        return repr(v)
    return repr(v)


def constants_text(constants: Mapping[str, Any]) -> str:
    """An AUTO-Constants file (keyword form, one ``KEY = value`` a line)."""
    return "".join(f"{k} = {_value(v)}\n" for k, v in constants.items())


@dataclasses.dataclass(frozen=True)
class Point:
    """One row of ``fort.7``: branch, point number, type code, label, named columns."""

    branch: int
    pt: int
    ty: int
    lab: int
    values: dict[str, float]


#: AUTO's two-letter label of each type code (``TY``).
TYPE_LABEL = {
    1: "BP",
    2: "LP",
    3: "HB",
    4: "UZ",
    -4: "UZ",
    5: "LP",
    6: "BP",
    7: "PD",
    8: "TR",
    9: "EP",
    -9: "MX",
}


def parse_fort7(path: str | os.PathLike[str]) -> list[Point]:
    """The solution rows of AUTO's ``fort.7`` with their column names (``PAR(1)``, ...)."""
    names: list[str] = []
    rows: list[Point] = []
    for line in pathlib.Path(path).read_text().splitlines():
        tok = line.split()
        if len(tok) < 4:
            continue
        if tok[0] == "0" and "PT" in tok:
            # header: "0 PT TY LAB PAR(11) L2-NORM U(1) ... PAR(1)" (names may contain spaces)
            names = re.split(r"\s{2,}", line.split("LAB", 1)[1].strip())
            continue
        if tok[0] == "0" or not names:
            continue
        try:
            br, pt, ty, lab = (int(t) for t in tok[:4])
            vals = [float(t.replace("D", "E")) for t in tok[4:]]
        except ValueError:
            continue
        rows.append(Point(br, abs(pt), ty, lab, dict(zip(names, vals, strict=False))))
    return rows


#: AUTO's type codes (``TY`` of ``fort.7``) of the special points the benchmarks count.
KIND = {1: "bp", 2: "fold", 3: "hopf", 5: "fold", 6: "bp"}


def run_executable(
    exe: str | os.PathLike[str], directory: str | os.PathLike[str]
) -> tuple[float, subprocess.CompletedProcess[str]]:
    """Run an AUTO executable in ``directory``; ``(wall s from start to exit, process)``.

    The one way the benchmarks start AUTO-07p: output captured, no exception on a
    non-zero exit (the caller reads ``returncode``).
    """
    t0 = time.perf_counter()
    proc = subprocess.run(
        [str(pathlib.Path(exe).resolve())],
        cwd=directory,
        capture_output=True,
        text=True,
        check=False,
    )
    return time.perf_counter() - t0, proc


@dataclasses.dataclass(frozen=True)
class ChainResult:
    """Wall times and output of one chain of AUTO runs."""

    seconds: float  # wall time of all executables (start to exit)
    auto_seconds: float  # sum of AUTO's own "Total Time"
    runs: list[list[Point]]  # fort.7 rows of each run
    directory: pathlib.Path


def run_chain(
    exe: str | os.PathLike[str],
    directory: str | os.PathLike[str],
    chain: Sequence[Mapping[str, Any]],
    files: Mapping[str, str] | None = None,
    fort3: str | os.PathLike[str] | None = None,
) -> ChainResult:
    """Run AUTO runs ``chain`` (constants dicts) in ``directory`` one after the other.

    A constants dict may hold ``IRS`` (restart label in the previous run's ``fort.8``,
    copied to ``fort.3``); ``files`` are written into the directory first (data files
    named by ``dat``). A run that exits non-zero or writes no solution raises
    RuntimeError with AUTO's output. ``fort3``: a ``fort.8`` of an earlier chain that
    the first run restarts from.
    """
    d = pathlib.Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    for name, text in (files or {}).items():
        (d / name).write_text(text)
    for name in ("fort.3", "fort.7", "fort.8", "fort.9"):
        (d / name).unlink(missing_ok=True)
    if fort3 is not None:
        shutil.copyfile(fort3, d / "fort.3")
    wall = auto_total = 0.0
    runs: list[list[Point]] = []
    for k, constants in enumerate(chain):
        if k > 0:
            shutil.copyfile(d / "fort.8", d / "fort.3")
        (d / "fort.2").write_text(constants_text(constants))
        dt, proc = run_executable(exe, d)
        wall += dt
        m = re.search(r"Total Time\s+([0-9.E+-]+)", proc.stdout)
        auto_total += float(m.group(1)) if m else float("nan")
        rows = parse_fort7(d / "fort.7") if (d / "fort.7").exists() else []
        if proc.returncode != 0 or not rows:
            raise RuntimeError(
                f"AUTO run {k + 1} of {len(chain)} failed (exit {proc.returncode}):\n"
                f"{proc.stdout[-2000:]}{proc.stderr[-2000:]}"
            )
        runs.append(rows)
    return ChainResult(wall, auto_total, runs, d)


def last(rows: Sequence[Point], ty: str | None = None) -> Point:
    """The last row (of type ``ty``, e.g. "UZ", if given)."""
    sel = [r for r in rows if ty is None or TYPE_LABEL.get(r.ty) == ty]
    if not sel:
        raise RuntimeError(f"no {ty} point in AUTO's output")
    return sel[-1]


def label_of(rows: Sequence[Point], ty: str, k: int = 1) -> int:
    """Label of the ``k``-th point of type ``ty``."""
    sel = [r.lab for r in rows if TYPE_LABEL.get(r.ty) == ty and r.lab > 0]
    if len(sel) < k:
        raise RuntimeError(f"AUTO's output has {len(sel)} {ty} points, wanted number {k}")
    return sel[k - 1]


__all__ = [
    "KIND",
    "TYPE_LABEL",
    "ChainResult",
    "Point",
    "build",
    "constants_text",
    "label_of",
    "last",
    "library_paths",
    "parse_fort7",
    "run_chain",
    "run_executable",
]
