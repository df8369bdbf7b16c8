r"""Periodic orbits from a Hopf point: broachkit against AUTO-07p (native), AUTO's demo ``ab``.

The A -> B reaction in a stirred tank (Uppal, Ray & Poore 1974, "On the dynamic behavior
of continuous stirred tank reactors", Chem. Eng. Sci. 29:967-985), in AUTO's scaling::

    u1' = -u1 + D (1 - u1) e^{u2}
    u2' = -u2 + D B (1 - u1) e^{u2} - beta u2

with ``B = 14, beta = 3``. The equilibria from ``u = 0`` at ``D = 0`` are continued in
the Damkoehler number ``D``; the periodic orbits are continued in ``(D, T)`` from the
first Hopf point, as in AUTO's demo ``ab`` (its run 3: ``IPS = 2``, ``NTST = 70``,
``NCOL = 4``, adaptive mesh ``IAD = 3``, ``EPSL = EPSU = 1e-7``, ``DS = 0.01``,
``DSMAX = 0.5``), here up to the period ``T_END`` (the orbits end at a homoclinic orbit
where the period grows without bound). The equation file is this benchmark's own
Fortran (no AUTO-07p file is copied), linked against AUTO's library from bifpy
(``benchmarks/peers/auto_native.py``).

Measured: AUTO's periodic-orbit continuation alone (restarting from the Hopf point of
the equilibrium run), median wall time of the executable; its steps, the last ``D`` and
period, and the period at ``D = D_CHECK`` (a ``UZR`` point) against a reference from AUTO
itself on ``NTST = 4 x 70``. broachkit's side (:func:`bk_periodic`) calls the API the
``periodic`` work is building (``continuation.periodic``: ``periodic_orbit_from_hopf`` and
``continue_periodic``); where that package is missing the table says "not available on
this checkout".

Run::

    benchmarks/_work/venv/bin/python benchmarks/periodic_vs_auto_native.py

writes ``benchmarks/results/periodic_vs_auto_native.{json,md}``.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import platform
import statistics
import sys
import tempfile
import time
from typing import Any

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from benchmarks.peers import auto_native as an  # noqa: E402
from benchmarks.peers.common import PeerUnavailable  # noqa: E402

B, BETA = 14.0, 3.0
T_END = 200.0  # stop the periodic branch at this period
D_CHECK = 0.17  # a UZR point on the periodic branch where the period is compared
NTST, NCOL = 70, 4

AB_F90 = """subroutine func(ndim, u, icp, par, ijac, f, dfdu, dfdp)
  implicit none
  integer, intent(in) :: ndim, icp(*), ijac
  double precision, intent(in) :: u(ndim), par(*)
  double precision, intent(out) :: f(ndim)
  double precision, intent(inout) :: dfdu(ndim, ndim), dfdp(ndim, *)
  double precision :: e
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
subroutine stpnt(ndim, u, par, t)
  implicit none
  integer, intent(in) :: ndim
  double precision, intent(inout) :: u(ndim), par(*)
  double precision, intent(in) :: t
  par(1:3) = (/ 0d0, BB, BETA /)
  u(1:2) = 0d0
end subroutine stpnt
subroutine bcnd
end subroutine bcnd
subroutine icnd
end subroutine icnd
subroutine fopt
end subroutine fopt
subroutine pvls
end subroutine pvls
""".replace("BB", f"{B!r}d0").replace("BETA", f"{BETA!r}d0")

COMMON = {
    "NDIM": 2,
    "NCOL": NCOL,
    "IAD": 3,
    "ISW": 1,
    "IPLT": 0,
    "NBC": 0,
    "NINT": 0,
    "MXBF": 10,
    "IID": 0,
    "ITMX": 8,
    "ITNW": 5,
    "NWTN": 3,
    "JAC": 1,
    "EPSL": 1e-7,
    "EPSU": 1e-7,
    "EPSS": 1e-5,
    "IADS": 1,
    "NPAR": 3,
    "NPR": 1000,
}
EQUILIBRIA = {
    **COMMON,
    "IPS": 1,
    "IRS": 0,
    "ILP": 1,
    "ICP": [1],
    "NTST": 50,
    "ISP": 1,
    "NMX": 400,
    "DS": 0.1,
    "DSMIN": 0.001,
    "DSMAX": 0.05,
    "UZSTOP": {1: 0.25},
}
PERIODIC = {
    **COMMON,
    "IPS": 2,
    "ILP": 0,
    "ICP": [1, 11],
    "NTST": NTST,
    "ISP": 1,
    "NMX": 500,
    "DS": 0.01,
    "DSMIN": 0.001,
    "DSMAX": 0.5,
    "THL": {11: 0.0},
    "UZR": {1: D_CHECK},
    "UZSTOP": {1: 0.25, 11: T_END},
}


def auto_side(work: pathlib.Path, repeats: int) -> dict[str, Any]:
    """Build, run the equilibria once, time the periodic continuation from HB1."""
    exe = an.build(AB_F90, work / "build")
    eq = an.run_chain(exe, work / "eq", [EQUILIBRIA])
    hb = [p for p in eq.runs[0] if p.ty == 3]
    if not hb:
        raise RuntimeError("AUTO found no Hopf point on the equilibria")
    fort8 = work / "eq" / "fort.8"
    po = {**PERIODIC, "IRS": hb[0].lab}
    runs = [an.run_chain(exe, work / "po", [po], fort3=fort8) for _ in range(repeats + 1)]
    rows = runs[-1].runs[0]
    fine = an.run_chain(exe, work / "fine", [{**po, "NTST": 4 * NTST}], fort3=fort8).runs[0]

    def period_at_check(rr: list[an.Point]) -> float:
        uz = [p for p in rr if p.ty in (4, -4) and abs(p.values["PAR(1)"] - D_CHECK) < 1e-6]
        return uz[0].values["PERIOD"] if uz else math.nan

    special = [
        (an._TY.get(p.ty, str(p.ty)), p.values["PAR(1)"])
        for p in rows
        if p.ty not in (0, 4, -4, 9, -9)
    ]
    return {
        "hopf_D": hb[0].values["PAR(1)"],
        "seconds": statistics.median(r.seconds for r in runs[1:]),
        "auto_total_time": statistics.median(r.auto_seconds for r in runs[1:]),
        "steps": len(rows) - 1,
        "end_D": rows[-1].values["PAR(1)"],
        "end_period": rows[-1].values["PERIOD"],
        "end_type": an._TY.get(rows[-1].ty, str(rows[-1].ty)),
        "period_at_check": period_at_check(rows),
        "period_at_check_fine": period_at_check(fine),
        "special": special,
        "NTST": NTST,
        "NCOL": NCOL,
    }


def bk_periodic() -> dict[str, Any]:
    """broachkit's side against the expected ``continuation.periodic`` API.

    Calls ``continue_equilibria`` (today's API) for the equilibria, then
    ``periodic_orbit_from_hopf(branch, "H1")`` and ``continue_periodic(...)`` from
    ``continuation.periodic`` with the same mesh (70 intervals, degree 4). Returns
    ``{"status": "not available on this checkout"}`` when that package is missing.
    """
    try:
        from continuation.periodic import continue_periodic, periodic_orbit_from_hopf
    except ImportError as exc:
        return {"status": "not available on this checkout", "reason": str(exc)}
    from continuation.api import continue_equilibria
    from continuation.system import System

    def rhs(x: Any, p: Any, ops: Any) -> Any:
        e = ops.exp(x[1])
        return ops.stack(
            [-x[0] + p[0] * (1 - x[0]) * e, -x[1] + p[0] * p[1] * (1 - x[0]) * e - p[2] * x[1]]
        )

    s = System(rhs, ("u1", "u2"), ("D", "B", "beta"))

    def run() -> Any:
        eq = continue_equilibria(
            s,
            [0.0, 0.0],
            s.params(D=0.0, B=B, beta=BETA),
            "D",
            ds=0.1,
            ds_max=0.05,
            p_min=0.0,
            p_max=0.25,
            direction="forward",
        )
        start = periodic_orbit_from_hopf(eq, "H1", n_intervals=NTST, degree=NCOL)
        return continue_periodic(
            start, "D", p_min=0.0, p_max=0.25, T_max=T_END, ds=0.01, ds_max=0.5
        )

    run()  # warm-up
    t0 = time.perf_counter()
    br = run()
    sec = time.perf_counter() - t0
    out: dict[str, Any] = {
        "status": str(getattr(br, "status", "?")),
        "seconds": sec,
        "steps": len(br.p) - 1,
        "end_D": float(br.p[-1]),
    }
    period = getattr(br, "records", {}).get("T") if hasattr(br, "records") else None
    if period is not None:
        out["end_period"] = float(np.asarray(period)[-1])
        pr = np.asarray(period, dtype=float)
        pp = np.asarray(br.p, dtype=float)
        k = np.flatnonzero(np.diff(np.sign(pp - D_CHECK)) != 0)
        if k.size:
            i = int(k[0])
            w = (D_CHECK - pp[i]) / (pp[i + 1] - pp[i])
            out["period_at_check"] = float((1 - w) * pr[i] + w * pr[i + 1])  # linear: rough
    return out


def render(res: dict[str, Any]) -> str:
    a, b, meta = res["auto"], res["broachkit"], res["meta"]
    lines = [
        "# Periodic orbits from a Hopf point: broachkit vs AUTO-07p (native), demo `ab`",
        "",
        f"Command: `{meta['command']}`  ",
        f"Machine: {meta['machine']}; {meta['date']}; repeats {meta['repeats']} (median).",
        "",
        f"Equilibria in D (B = {B:g}, beta = {BETA:g}); HB1 at D = {a['hopf_D']:.10g}; "
        f"periodic orbits in (D, T) from HB1, NTST = {a['NTST']}, NCOL = {a['NCOL']}, "
        f"up to T = {T_END:g}.",
        "",
        "| tool | wall s | steps | end D | end period | period at D = "
        f"{D_CHECK:g} | its error | ratio bk/AUTO |",
        "|---|---|---|---|---|---|---|---|",
    ]
    err = abs(a["period_at_check"] - a["period_at_check_fine"])
    lines.append(
        f"| AUTO-07p | {a['seconds']:.4f} (own: {a['auto_total_time']:.4f}) | "
        f"{a['steps']} | {a['end_D']:.8g} | {a['end_period']:.6g} | "
        f"{a['period_at_check']:.10g} | {err:.1e} (vs NTST = {4 * NTST}) | 1 |"
    )
    if "seconds" in b:
        pc = b.get("period_at_check", math.nan)
        lines.append(
            f"| broachkit | {b['seconds']:.4f} | {b['steps']} | {b['end_D']:.8g} | "
            f"{b.get('end_period', math.nan):.6g} | {pc:.10g} | "
            f"{abs(pc - a['period_at_check_fine']):.1e} | "
            f"{b['seconds'] / a['seconds']:.2f} |"
        )
    else:
        lines.append(f"| broachkit | {b['status']} ||||||| ")
    lines += [
        "",
        f"AUTO's special points on the periodic branch: {a['special'] or 'none'}; "
        f"last point type {a['end_type']}.",
        "",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", default=str(HERE / "results" / "periodic_vs_auto_native"))
    args = ap.parse_args(argv)
    try:
        an.library_paths()
    except PeerUnavailable as exc:
        print(f"AUTO-07p not available: {exc}", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="po_vs_auto_") as tmp:
        auto = auto_side(pathlib.Path(tmp), args.repeats)
    bk = bk_periodic()
    meta = {
        "command": "benchmarks/_work/venv/bin/python benchmarks/periodic_vs_auto_native.py "
        + " ".join(argv if argv is not None else sys.argv[1:]),
        "machine": f"{platform.machine()}, {platform.python_version()}",
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "repeats": args.repeats,
    }
    res = {"meta": meta, "auto": auto, "broachkit": bk}
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(res, indent=1, default=str))
    out.with_suffix(".md").write_text(render(res))
    print(out.with_suffix(".md").read_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
