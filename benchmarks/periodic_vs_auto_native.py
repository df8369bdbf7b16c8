r"""Periodic orbits from a Hopf point: broachkit against AUTO-07p (native), two demos.

Both tools continue the equilibria to a Hopf point and then the branch of cycles born
there, on the same collocation mesh (``NTST`` intervals of ``NCOL = 4`` Gauss points),
with the same Newton tolerances and step bounds. Only the periodic continuation is timed
(from the Hopf point: the start cycle included on both sides).

* ``ab``: AUTO's demo ``ab``, the A -> B reaction in a stirred tank (Uppal, Ray & Poore
  1974, Chem. Eng. Sci. 29:967-985) in AUTO's scaling::

      u1' = -u1 + D (1 - u1) e^{u2}
      u2' = -u2 + D B (1 - u1) e^{u2} - beta u2

  with ``B = 14, beta = 3``: equilibria in ``D`` from ``u = 0``, cycles in ``(D, T)``
  from HB1 as in the demo's run 3 (``IPS = 2``, ``NTST = 70``, ``NCOL = 4``, adaptive
  mesh ``IAD = 3``, ``EPSL = EPSU = 1e-7``, ``DS = 0.01``, ``DSMAX = 0.5``, ``ILP = 0``,
  ``ISP = 1``: Floquet multipliers computed, no folds, branch points, PD or torus
  points detected) up to ``D = 0.25`` (period cap 200). broachkit: the same mesh size,
  ``newton.tol = 1e-7``, the mesh equidistributed every 3 steps (``adapt_every=3``, as
  ``IAD = 3``), multipliers at every row, fold, branch-point, PD and NS detection off.
* ``bru``: the Brusselator ``x' = A - (B + 1) x + x^2 y``, ``y' = B x - x^2 y``,
  ``A = 1.5`` (Hopf at ``B = 1 + A^2 = 3.25``), cycles continued in ``B`` up to 5 on
  ``NTST = 40`` without mesh adaptation (``IAD = 0``), tolerances ``1e-10``, ``DS =
  0.02``, ``DSMIN = 1e-4``, ``DSMAX = 0.1``, Floquet multipliers at every point
  (``ISP = 2``; broachkit always), folds detected (``ILP = 1``). This replaces the
  older ``periodic_vs_auto.py``, which ran AUTO through bifpy's Python front end from
  a first-harmonic guess.

Special points (and the user points below) are located to AUTO's ``EPSS``
(broachkit's ``detect.tol``). Accuracy: the period at user points (AUTO ``UZR``,
broachkit a located event) of the continuation parameter, against a reference
computed at the *same* parameter value: broachkit on ``REF_FACTOR`` times the
intervals, mesh adapted 3 times, at AUTO's printed parameter for AUTO's error and at
broachkit's located value for broachkit's.
AUTO locates its user points only to ``EPSS``, and on ``ab`` the period changes by
about 140 per unit of ``D`` near ``D = 0.17``; comparing at the nominal value would
charge AUTO with its location error (2.6e-5). The reference is cross-checked against
AUTO on ``REF_FACTOR x NTST`` (reported). AUTO prints 10 significant digits, so its
errors below about 1e-9 relative are at the floor of the printed values.

Timing: medians of ``--repeats``. AUTO: wall time of the executable (start to exit,
file I/O included) and its CPU time (user + system of the child); broachkit: wall and
CPU time of the call in this process after one untimed warm-up (CasADi functions built
at the first call and cached per system). The equation files are this benchmark's own
Fortran (no AUTO-07p file is copied), linked against AUTO's library from bifpy
(``benchmarks/peers/auto_native.py``).

Run::

    benchmarks/_work/venv/bin/python benchmarks/periodic_vs_auto_native.py [--demos ab,bru]

writes ``benchmarks/results/periodic_vs_auto_native.{json,md}``. With
``--broachkit-only`` it times broachkit's side alone (no AUTO needed) and prints JSON,
for A/B runs of two checkouts (``benchmarks/README.md``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import math
import os
import pathlib
import platform
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from typing import Any

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
# measure the checkout this script is in (the venv's editable install may point at another)
sys.path.insert(0, str(HERE.parent))

from benchmarks.peers import auto_native as an  # noqa: E402
from benchmarks.peers.common import PeerUnavailable  # noqa: E402
from benchmarks.timing import cpu_children, cpu_self  # noqa: E402

#: Reference meshes: this many times the demo's intervals.
REF_FACTOR = 4

AB_F90 = (
    an.FUNC_HEAD
    + """  double precision :: e
  e = exp(u(2))
  f(1) = -u(1) + par(1) * (1d0 - u(1)) * e
  f(2) = -u(2) + par(1) * par(2) * (1d0 - u(1)) * e - par(3) * u(2)
  if (ijac == 0) return
  dfdu(1, :) = (/ -1d0 - par(1) * e, par(1) * (1d0 - u(1)) * e /)
  dfdu(2, :) = (/ -par(1) * par(2) * e, -1d0 + par(1) * par(2) * (1d0 - u(1)) * e - par(3) /)
  if (ijac == 1) return
  dfdp(:, 1) = (/ (1d0 - u(1)) * e, par(2) * (1d0 - u(1)) * e /)
  dfdp(:, 2) = (/ 0d0, par(1) * (1d0 - u(1)) * e /)
  dfdp(:, 3) = (/ 0d0, -u(2) /)
end subroutine func
"""
    + an.STPNT_HEAD
    + """  par(1:3) = (/ 0d0, 14d0, 3d0 /)
  u(1:2) = 0d0
end subroutine stpnt
"""
    + an.EMPTY_ROUTINES
)

BRU_F90 = (
    an.FUNC_HEAD
    + """  f(1) = par(1) - (par(2) + 1d0) * u(1) + u(1)**2 * u(2)
  f(2) = par(2) * u(1) - u(1)**2 * u(2)
  if (ijac == 0) return
  dfdu(1, :) = (/ -(par(2) + 1d0) + 2d0 * u(1) * u(2), u(1)**2 /)
  dfdu(2, :) = (/ par(2) - 2d0 * u(1) * u(2), -u(1)**2 /)
  if (ijac == 1) return
  dfdp(:, 1) = (/ 1d0, 0d0 /)
  dfdp(:, 2) = (/ -u(1), u(1) /)
end subroutine func
"""
    + an.STPNT_HEAD
    + """  par(1:2) = (/ 1.5d0, 3d0 /)
  u(1:2) = (/ 1.5d0, 2d0 /)
end subroutine stpnt
"""
    + an.EMPTY_ROUTINES
)

COMMON = {"NCOL": 4, "ISW": 1, "IPLT": 0, "NBC": 0, "NINT": 0, "MXBF": 10, "IID": 0,
          "ITMX": 8, "NWTN": 3, "JAC": 1, "IADS": 1, "NPR": 1000}  # fmt: skip


@dataclasses.dataclass(frozen=True)
class Demo:
    """One benchmark problem: AUTO's two runs and broachkit's equivalent settings."""

    name: str
    fortran: str
    state_names: tuple[str, ...]
    param_names: tuple[str, ...]
    params0: dict[str, float]
    x0: tuple[float, ...]
    free: str  # the continuation parameter (AUTO's PAR(1) or PAR(2))
    equilibria: dict[str, Any]  # AUTO constants, run 1
    periodic: dict[str, Any]  # AUTO constants, run 2 (restart from HB1)
    checks: tuple[float, ...]  # values of `free` where the period is compared
    eq_settings: dict[str, float]  # broachkit's continue_equilibria keywords
    bk_settings: dict[str, Any]  # ContinuationSettings keywords
    tol: float
    adapt_every: int
    period_max: float | None
    detect: bool  # folds, branch points, PD, NS (AUTO: ILP = 1 and ISP = 2)

    @property
    def ntst(self) -> int:
        return int(self.periodic["NTST"])

    @property
    def par_key(self) -> str:
        return f"PAR({self.param_names.index(self.free) + 1})"


def _ab_rhs(x: Any, p: Any, ops: Any) -> Any:
    e = ops.exp(x[1])
    return ops.stack(
        [-x[0] + p[0] * (1 - x[0]) * e, -x[1] + p[0] * p[1] * (1 - x[0]) * e - p[2] * x[1]]
    )


def _bru_rhs(x: Any, p: Any, ops: Any) -> Any:
    return ops.stack([p[0] - (p[1] + 1) * x[0] + x[0] ** 2 * x[1], p[1] * x[0] - x[0] ** 2 * x[1]])


RHS: dict[str, Callable[..., Any]] = {"ab": _ab_rhs, "bru": _bru_rhs}

#: AUTO constants shared by both runs of ``ab`` (problem size, Newton tolerances).
_AB_BOTH = {
    **COMMON,
    "NDIM": 2,
    "NPAR": 3,
    "ISP": 1,
    "IAD": 3,
    "ITNW": 5,
    "EPSL": 1e-7,
    "EPSU": 1e-7,
    "EPSS": 1e-5,
    "DSMIN": 0.001,
}

#: AUTO constants shared by both runs of ``bru`` (problem size, mesh, tolerances).
_BRU_BOTH = {
    **COMMON,
    "NDIM": 2,
    "NPAR": 2,
    "NTST": 40,
    "IAD": 0,
    "ITNW": 7,
    "EPSL": 1e-10,
    "EPSU": 1e-10,
    "EPSS": 1e-8,
    "DS": 0.02,
    "DSMIN": 1e-4,
}


def _equilibria_run(both: dict[str, Any], icp: int, more: dict[str, Any]) -> dict[str, Any]:
    """AUTO constants of run 1: equilibria (``IPS = 1``) in ``PAR(icp)`` from the
    analytic start (``IRS = 0``), folds detected (``ILP = 1``), then ``more``."""
    return {**both, "IPS": 1, "IRS": 0, "ILP": 1, "ICP": [icp], **more}


def _periodic_run(both: dict[str, Any], icp: int, ilp: int, more: dict[str, Any]) -> dict[str, Any]:
    """AUTO constants of run 2: cycles (``IPS = 2``) in ``PAR(icp)`` and the period
    ``PAR(11)``, folds detected if ``ilp = 1``, then ``more`` (``IRS``, the label of the
    Hopf point, is added when it is known: :func:`auto_side`)."""
    return {**both, "IPS": 2, "ILP": ilp, "ICP": [icp, 11], **more}


DEMOS = {
    "ab": Demo(
        name="ab",
        fortran=AB_F90,
        state_names=("u1", "u2"),
        param_names=("D", "B", "beta"),
        params0={"D": 0.0, "B": 14.0, "beta": 3.0},
        x0=(0.0, 0.0),
        free="D",
        equilibria=_equilibria_run(
            _AB_BOTH, 1, {"NTST": 50, "NMX": 400, "DS": 0.1, "DSMAX": 0.05, "UZSTOP": {1: 0.25}}
        ),
        periodic=_periodic_run(
            _AB_BOTH,
            1,
            0,
            {
                "NTST": 70,
                "NMX": 500,
                "DS": 0.01,
                "DSMAX": 0.5,
                "THL": {11: 0.0},
                "UZR": {1: [0.17, 0.22]},
                "UZSTOP": {1: 0.25, 11: 200.0},
            },
        ),
        checks=(0.17, 0.22),
        eq_settings={"ds": 0.05, "ds_max": 0.05, "p_min": 0.0, "p_max": 0.25},
        bk_settings={
            "ds": 0.01,
            "ds_min": 1e-3,
            "ds_max": 0.5,
            "p_min": 0.0,
            "p_max": 0.25,
            "max_steps": 500,
        },
        tol=1e-7,
        adapt_every=3,
        period_max=200.0,
        detect=False,
    ),
    "bru": Demo(
        name="bru",
        fortran=BRU_F90,
        state_names=("x", "y"),
        param_names=("A", "B"),
        params0={"A": 1.5, "B": 3.0},
        x0=(1.5, 2.0),
        free="B",
        equilibria=_equilibria_run(
            _BRU_BOTH, 2, {"ISP": 1, "NMX": 100, "DSMAX": 0.05, "UZSTOP": {2: 4.0}}
        ),
        periodic=_periodic_run(
            _BRU_BOTH,
            2,
            1,
            {"ISP": 2, "NMX": 500, "DSMAX": 0.1, "UZR": {2: [4.0, 4.9]}, "UZSTOP": {2: 5.0}},
        ),
        checks=(4.0, 4.9),
        eq_settings={"ds": 0.02, "ds_max": 0.05, "p_min": 2.5, "p_max": 4.0},
        bk_settings={"ds": 0.02, "ds_min": 1e-4, "ds_max": 0.1, "p_max": 5.0, "max_steps": 500},
        tol=1e-10,
        adapt_every=0,
        period_max=None,
        detect=True,
    ),
}


def auto_side(demo: Demo, work: pathlib.Path, repeats: int) -> dict[str, Any]:
    """Build, run the equilibria once, time the periodic continuation from HB1."""
    exe = an.build(demo.fortran, work / "build")
    eq = an.run_chain(exe, work / "eq", [demo.equilibria])
    hb = [p for p in eq.runs[0] if p.ty == 3]
    if not hb:
        raise RuntimeError(f"{demo.name}: AUTO found no Hopf point on the equilibria")
    fort8 = work / "eq" / "fort.8"
    po = {**demo.periodic, "IRS": hb[0].lab}
    runs, cpu = [], []
    for _ in range(repeats + 1):
        c0 = cpu_children()
        runs.append(an.run_chain(exe, work / "po", [po], fort3=fort8))
        cpu.append(cpu_children() - c0)
    rows = runs[-1].runs[0]
    fine_po = {**po, "NTST": REF_FACTOR * demo.ntst}
    fine = an.run_chain(exe, work / "fine", [fine_po], fort3=fort8).runs[0]

    def uz(rr: list[an.Point]) -> list[tuple[float, float]]:
        out = []
        for c in demo.checks:
            sel = [p for p in rr if p.ty in (4, -4) and abs(p.values[demo.par_key] - c) < 1e-5]
            out.append((sel[0].values[demo.par_key], sel[0].values["PERIOD"]) if sel
                       else (math.nan, math.nan))  # fmt: skip
        return out

    special = [(an._TY.get(p.ty, str(p.ty)), p.values[demo.par_key]) for p in rows
               if p.ty not in (0, 4, -4, 9, -9)]  # fmt: skip
    return {
        "hopf": hb[0].values[demo.par_key],
        "seconds": statistics.median(r.seconds for r in runs[1:]),
        "cpu_seconds": statistics.median(cpu[1:]),
        "auto_total_time": statistics.median(r.auto_seconds for r in runs[1:]),
        "steps": len(rows) - 1,
        "end_p": rows[-1].values[demo.par_key],
        "end_period": rows[-1].values["PERIOD"],
        "end_type": an._TY.get(rows[-1].ty, str(rows[-1].ty)),
        "checks": uz(rows),
        "checks_fine": uz(fine),
        "special": special,
    }


def _system(demo: Demo) -> Any:
    from continuation.system import System

    return System(RHS[demo.name], demo.state_names, demo.param_names)


def bk_equilibria(demo: Demo) -> Any:
    """broachkit's equilibria in ``demo.free`` (untimed), with their Hopf point H1."""
    from continuation.api import continue_equilibria

    s = _system(demo)
    return continue_equilibria(s, list(demo.x0), s.params(**demo.params0), demo.free,
                               direction="forward", **demo.eq_settings)  # fmt: skip


def bk_periodic(demo: Demo, eq: Any, ntst: int | None = None, adapt: int | None = None) -> Any:
    """broachkit's periodic branch from H1 (the timed call)."""
    from continuation import ContinuationSettings, DetectionSettings, Event, NewtonSettings
    from continuation.bvp import CollocationMesh
    from continuation.periodic import continue_from_hopf

    # special points located to AUTO's EPSS
    detect = DetectionSettings(fold=demo.detect, branch_point=demo.detect,
                               tol=float(demo.periodic["EPSS"]))  # fmt: skip
    st = ContinuationSettings(newton=NewtonSettings(tol=demo.tol), detect=detect,
                              **demo.bk_settings)  # fmt: skip
    events = [Event(f"UZ{k + 1}", param_value=c) for k, c in enumerate(demo.checks)]
    return continue_from_hopf(
        eq, "H1", st, mesh=CollocationMesh(ntst or demo.ntst, 4, 1.0), events=events,
        period_max=demo.period_max, adapt_every=demo.adapt_every if adapt is None else adapt,
        detect_pd=demo.detect, detect_ns=demo.detect,
        error_tol=None,  # AUTO's settings: its mesh (NTST, IAD) and tolerances, no more
    )  # fmt: skip


def reference_period(demo: Demo, br: Any, value: float) -> float:
    """The period at ``free = value`` on ``REF_FACTOR x NTST`` adapted intervals, from the
    nearest row of the broachkit branch ``br``."""
    from continuation.periodic import adapt_mesh, orbit_at, solve_orbit

    k = int(np.argmin(np.abs(np.asarray(br.p) - value)))
    orb = orbit_at(br, k)
    params = orb.params.replace(**{demo.free: value}) if hasattr(orb.params, "replace") else None
    if params is None:
        vals = np.array(orb.params.values, dtype=float)
        vals[demo.param_names.index(demo.free)] = value
        from continuation.params import Params

        params = Params(orb.params.names, vals)
    orb = solve_orbit(dataclasses.replace(orb, params=params), demo.free)
    orb = adapt_mesh(orb, REF_FACTOR * demo.ntst, rounds=3, free=demo.free)
    return float(orb.T)


def bk_side(demo: Demo, repeats: int) -> dict[str, Any]:
    eq = bk_equilibria(demo)
    bk_periodic(demo, eq)  # warm-up: CasADi functions built and cached
    wall, cpu = [], []
    for _ in range(repeats):
        c0, w0 = cpu_self(), time.perf_counter()
        br = bk_periodic(demo, eq)
        cpu.append(cpu_self() - c0)
        wall.append(time.perf_counter() - w0)
    uz = []
    for k in range(len(demo.checks)):
        sel = [sp for sp in br.special_points if sp.label == f"UZ{k + 1}" and sp.located]
        uz.append((float(sel[0].p), float(sel[0].x[-1])) if sel else (math.nan, math.nan))
    return {
        "status": br.status.name,
        "seconds": statistics.median(wall),
        "cpu_seconds": statistics.median(cpu),
        "steps": len(br) - 1,
        "end_p": float(br.p[-1]),
        "end_period": float(br.records["T"][-1]),
        "checks": uz,
        "trivial_error_max": float(np.max(br.records["trivial_error"])),
        "special": [(sp.label, float(sp.p)) for sp in br.special_points],
        "_branch": br,
    }


def accuracy(demo: Demo, auto: dict[str, Any], bk: dict[str, Any]) -> dict[str, Any]:
    """Period errors at the check points against references at the same parameter."""
    br = bk.pop("_branch")
    out: dict[str, Any] = {"auto": [], "auto_fine": [], "broachkit": []}
    for (pa, Ta), (pf, Tf), (pb, Tb) in zip(auto["checks"], auto["checks_fine"], bk["checks"],
                                           strict=True):  # fmt: skip
        for key, p, T in (("auto", pa, Ta), ("auto_fine", pf, Tf), ("broachkit", pb, Tb)):
            ref = reference_period(demo, br, p) if math.isfinite(p) else math.nan
            out[key].append({"p": p, "T": T, "T_ref": ref, "error": abs(T - ref)})
    return out


def render(res: dict[str, Any]) -> str:
    meta = res["meta"]
    lines = [
        "# Periodic orbits from a Hopf point: broachkit vs AUTO-07p (native)",
        "",
        f"Command: `{meta['command']}`  ",
        f"Machine: {meta['machine']}; {meta['date']}; load average {meta['load']}; "
        f"repeats {meta['repeats']} (median).",
        "",
        "| demo | NTST | AUTO wall s (CPU s) | AUTO steps | broachkit wall s (CPU s) | "
        "broachkit steps | ratio wall (CPU) | period error at checks, AUTO | broachkit | "
        "AUTO x4 vs ref |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, d in res["demos"].items():
        a, b, acc = d["auto"], d["broachkit"], d["accuracy"]

        def errs(key: str, acc: dict[str, Any] = acc) -> str:
            return ", ".join(f"{e['error']:.1e}" for e in acc[key])

        lines.append(
            f"| {name} | {d['ntst']} | {a['seconds']:.4f} ({a['cpu_seconds']:.4f}) | "
            f"{a['steps']} | {b['seconds']:.4f} ({b['cpu_seconds']:.4f}) | {b['steps']} | "
            f"**{b['seconds'] / a['seconds']:.2f}** ({b['cpu_seconds'] / a['cpu_seconds']:.2f}) "
            f"| {errs('auto')} | {errs('broachkit')} | {errs('auto_fine')} |"
        )
    lines.append("")
    for name, d in res["demos"].items():
        a, b = d["auto"], d["broachkit"]
        lines.append(
            f"* {name}: Hopf at {a['hopf']:.10g}; checks at {d['checks']}; AUTO ends "
            f"{a['end_type']} at {a['end_p']:.8g}, T = {a['end_period']:.8g}, specials "
            f"{a['special'] or 'none'}; broachkit ends {b['status']} at {b['end_p']:.8g}, "
            f"T = {b['end_period']:.8g}, specials {b['special'] or 'none'}, "
            f"max |mu_trivial - 1| {b['trivial_error_max']:.1e}."
        )
    lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--demos", default="ab,bru")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", default=str(HERE / "results" / "periodic_vs_auto_native"))
    ap.add_argument("--broachkit-only", action="store_true",
                    help="time broachkit's side only (no AUTO needed; JSON to stdout, no "
                    "files): for A/B runs of two checkouts")  # fmt: skip
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    if args.broachkit_only:
        bk = {}
        for name in [s for s in args.demos.split(",") if s]:
            if name not in DEMOS:
                print(f"--demos: unknown demo {name!r}; choose from {sorted(DEMOS)}",
                      file=sys.stderr)  # fmt: skip
                return 2
            r = bk_side(DEMOS[name], args.repeats)
            r.pop("_branch")
            bk[name] = r
        print(json.dumps(bk))
        return 0
    try:
        an.library_paths()
    except PeerUnavailable as exc:
        print(f"AUTO-07p not available: {exc}", file=sys.stderr)
        return 2
    names = [s for s in args.demos.split(",") if s]
    unknown = [s for s in names if s not in DEMOS]
    if unknown:
        print(f"--demos: unknown demo(s) {unknown}; choose from {sorted(DEMOS)}", file=sys.stderr)
        return 2
    out: dict[str, Any] = {}
    for name in names:
        demo = DEMOS[name]
        with tempfile.TemporaryDirectory(prefix=f"po_{name}_") as tmp:
            auto = auto_side(demo, pathlib.Path(tmp), args.repeats)
        bk = bk_side(demo, args.repeats)
        out[name] = {"ntst": demo.ntst, "checks": list(demo.checks), "auto": auto,
                     "broachkit": bk, "accuracy": accuracy(demo, auto, bk)}  # fmt: skip
    meta = {
        "command": "benchmarks/_work/venv/bin/python benchmarks/periodic_vs_auto_native.py "
        + " ".join(argv if argv is not None else sys.argv[1:]),
        "machine": f"{platform.machine()}, {platform.python_version()}",
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "load": " ".join(f"{v:.2f}" for v in os.getloadavg()),
        "repeats": args.repeats,
    }
    res = {"meta": meta, "demos": out}
    path = pathlib.Path(args.out)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.with_suffix(".json").write_text(json.dumps(res, indent=1, default=str))
    path.with_suffix(".md").write_text(render(res))
    print(path.with_suffix(".md").read_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
