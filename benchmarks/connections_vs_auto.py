r"""Connecting orbits: broachkit against AUTO-07p/HomCont (native), at equal accuracy.

For each demo of :mod:`benchmarks.connection_demos` (``kpr``, ``cir``, ``san``), in one run:

(a) **one connection solve** at the demo's parameters. AUTO: the demo's own route to it
    (its runs from its start: the ``ISTART=3`` homotopy from the saddle for kpr, our
    starting data for cir, the closed-form orbit at ``a = 0`` for san), as a native
    executable; broachkit: :func:`continuation.bvp.find_connection` from the saddle
    alone (its unstable manifold integrated until the closest return, cut, one solve
    on ``N`` intervals with 0-2 rounds of mesh adaptation), :func:`bk_solve`. broachkit's
    time includes its starting orbit; AUTO's does not for cir (its data are given).
(b) **one continuation** of that connection in a second parameter, from the solution
    of (a) to a fixed end value of the second parameter (AUTO: ``UZSTOP``; broachkit:
    the bound ``p_min``/``p_max``), with AUTO's ``DS`` and ``DSMAX``.

Accuracy is the error of the solved parameter against a reference computed here: the
closed form where there is one (san: ``mu~ = 0`` exactly, the orbit lies on
``y^2 = x^2 (1 - x), z = 0`` for every ``a, alpha``), else a fine-mesh, long-interval
solve by broachkit (400 intervals, adapted, ``T = 3 T_demo``), cross-checked by AUTO on
``NTST x 6`` with ``T`` doubled (their difference is reported). broachkit's setting in
(a): for each ``T`` (its own from the eigenvalues, 1, 1.5 and 2 times ``T_demo``) and
number of adaptation rounds (0, 1, 2), the smallest ``N`` (8..200) whose error is at most
AUTO's; of these candidates the fastest (least of 5 runs), then timed. In (b) the same
scan of the start solve, by the error at the end of the continuation (the start
solve is not timed in (b), as AUTO's (b) restarts from its (a)), the fastest
continuation timed. A
setting that cannot reach AUTO's error is reported as such, never rounded into a win.

Timing: CPU time (user + system; AUTO: of its child processes, broachkit: of this
process), medians of ``--repeats`` runs; wall times are in the JSON. Both run on one
thread: AUTO with ``OMP_NUM_THREADS=1``, broachkit with one BLAS thread (set before
NumPy loads: idle OpenBLAS threads spin and double the CPU time of these small
problems). AUTO's time is that of its executables (process start to exit, reading
``fort.2``/``fort.3``, writing ``fort.7/8/9``), compiled before; broachkit's is the call in
this process with one :class:`~continuation.system.System` per demo, after one untimed
warm-up (CasADi's functions are built at the first call and cached per system).

Run (after ``bash benchmarks/setup_env.sh``)::

    benchmarks/_work/venv/bin/python benchmarks/connections_vs_auto.py

writes ``benchmarks/results/connections_vs_auto.{json,md}`` (options ``--demos``,
``--repeats``, ``--out``).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one thread for both tools (before NumPy loads)

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import logging  # noqa: E402
import math  # noqa: E402
import pathlib  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from benchmarks.connection_demos import DEMOS, Demo, guess_on, manifold_guess  # noqa: E402
from benchmarks.peers import auto_native as an  # noqa: E402
from benchmarks.peers.common import PeerUnavailable  # noqa: E402
from benchmarks.timing import cpu_children, median_time, min_time  # noqa: E402

log = logging.getLogger("connections_vs_auto")

# broachkit's candidate meshes for "equal accuracy", cheapest first; T: None = its own
N_CANDIDATES = (8, 10, 12, 14, 16, 18, 20, 22, 25, 28, 30, 33, 36, 40, 45, 50, 55, 60, 70, 80,
                100, 120, 140, 170, 200)  # fmt: skip
T_FACTORS: tuple[float | None, ...] = (None, 1.0, 1.5, 2.0)
ADAPT_ROUNDS = (0, 1, 2)  # rounds of mesh equidistribution in broachkit's solve
ADAPT_REFERENCE = 2


# ======================================================================= broachkit side
# Everything broachkit-specific is in these three functions.
def smallest_meshes(
    demo: Demo, system: Any, accept: Callable[[Any, int, float | None, int], Any]
) -> list[Any]:
    """For each end time (``T_FACTORS``) and adaptation count (``ADAPT_ROUNDS``), the
    pick of the smallest mesh of ``N_CANDIDATES`` that passes.

    ``accept(result, N, T, adapt)`` gets :func:`bk_solve`'s result on each candidate
    mesh in turn and returns the pick (None: not passed, try the next N).
    """
    picks = []
    for f in T_FACTORS:
        T = None if f is None else f * demo.T
        for adapt in ADAPT_ROUNDS:
            for N in N_CANDIDATES:
                pick = accept(bk_solve(demo, system, N, T, adapt), N, T, adapt)
                if pick is not None:
                    picks.append(pick)
                    break
    return picks


def bk_solve(demo: Demo, system: Any, N: int, T: float | None, adapt: int) -> Any:
    """One broachkit connection from the saddle alone: ``find_connection`` (homoclinic,
    ``N`` intervals of degree 4, ``T`` or its own, ``adapt`` rounds of mesh adaptation,
    no error estimates); returns the ConnectionResult (``.success``, ``.value(name)``)."""
    from continuation.bvp import ConnectionAccuracy, find_connection

    return find_connection(
        system,
        system.params(**demo.params),
        demo.solved,
        source=demo.saddle(demo.pvec()),
        shift=0,
        branch=demo.branch,
        T=T,
        n_intervals=N,
        accuracy=ConnectionAccuracy(estimate=False),
        adapt=adapt,
    )


def bk_reference(
    demo: Demo, system: Any, params: dict[str, float], orbit: tuple[np.ndarray, np.ndarray],
    N: int, T: float,
) -> Any:  # fmt: skip
    """A reference solve at ``params`` from the orbit ``(t, x)``: ``N`` intervals on
    ``[0, T]``, adapted twice, no estimates."""
    from continuation.bvp import (
        CollocationMesh,
        ConnectionAccuracy,
        HeteroclinicProblem,
        solve_connection,
    )

    vals = {**demo.params, **params}
    xs = demo.saddle(np.array([vals[k] for k in demo.params]))
    prob = HeteroclinicProblem(
        system,
        system.params(**vals),
        demo.solved,
        saddle_from=xs,
        shift=np.zeros(len(xs)),
        mesh=CollocationMesh(N, 4, T),
    )
    acc = ConnectionAccuracy(estimate=False)
    return solve_connection(prob, guess_on(*orbit, T), adapt=ADAPT_REFERENCE, accuracy=acc)


def bk_continue(result: Any, demo: Demo, end: float, ds: float, ds_max: float) -> Any:
    """Continue the connection ``result`` in ``demo.second`` from its value to ``end``
    (``continue_connection``; pseudo-arclength); returns the Branch."""
    from continuation.bvp import continue_connection
    from continuation.settings import ContinuationSettings

    p0 = result.params[demo.second]
    lo, hi = (end, math.inf) if end < p0 else (-math.inf, end)
    settings = ContinuationSettings(
        ds=ds, ds_max=ds_max, ds_min=1e-6, p_min=lo, p_max=hi, max_steps=400
    )
    return continue_connection(
        result, demo.second, settings, direction="backward" if end < p0 else "forward"
    )


# Where the continuation (b) ends, in the second parameter (inside the demo's branch).
CONTINUE_TO = {"kpr": -2.0, "cir": 0.3, "san": 1.0}  # cir: hyperbolic for beta > 0 only


def _auto_times(fn: Callable[[], an.ChainResult], repeats: int) -> tuple[float, float, float]:
    """``(median CPU s of the child processes, median wall s, AUTO's own Total Time)``."""
    cpu, wall, tot = [], [], []
    for _ in range(repeats):
        c0 = cpu_children()
        r = fn()
        cpu.append(cpu_children() - c0)
        wall.append(r.seconds)
        tot.append(r.auto_seconds)
    return statistics.median(cpu), statistics.median(wall), statistics.median(tot)


# ============================================================================ AUTO side
class AutoDemo:
    """The AUTO-07p executable of a demo and its runs (see connection_demos)."""

    def __init__(self, demo: Demo, work: pathlib.Path) -> None:
        self.demo = demo
        self.work = work / demo.key
        src = demo.fortran
        self.files: dict[str, str] = {}
        if demo.key == "cir":  # starting data: our simulated manifold, T of the data
            t, _ = manifold_guess(demo)
            src = src.replace("NU0", f"{demo.params['nu']!r}d0").replace(
                "T0", f"{float(t[-1] - t[0])!r}d0"
            )
        if demo.auto_files is not None:
            self.files = demo.auto_files(demo)
        self.exe = an.build(src, self.work / "build")

    def _resolve(
        self, chain: list[dict[str, Any]], scale: int = 1, prev: list[an.Point] | None = None
    ) -> list[dict[str, Any]]:
        out = []
        d = self.work / "resolve"
        for c in chain:
            c = dict(c)
            if scale != 1:
                c["NTST"] = c["NTST"] * scale
                c["DSMAX"] = c["DSMAX"]
            if isinstance(c.get("IRS"), tuple):
                c["IRS"] = an.label_of(prev, *c["IRS"])
            out.append(c)
            if len(out) < len(chain):
                prev = an.run_chain(self.exe, d, out, self.files).runs[-1]
        return out

    def solve_chain(self, scale: int = 1) -> list[dict[str, Any]]:
        return self._resolve(self.demo.auto_solve, scale)

    def solve(self, chain: list[dict[str, Any]], tag: str = "solve") -> an.ChainResult:
        return an.run_chain(self.exe, self.work / tag, chain, self.files)

    def continue_constants(
        self, solved: an.ChainResult, end: float, scale: int = 1
    ) -> dict[str, Any]:
        c = dict(self.demo.auto_continue)
        c["IRS"] = an.last(solved.runs[-1]).lab
        c["UZSTOP"] = {self.demo.auto_index[self.demo.second]: end}
        c["NMX"] = 400
        if scale != 1:
            c["NTST"] = c["NTST"] * scale
        return c

    def cont(self, solved: an.ChainResult, c: dict[str, Any], tag: str = "cont") -> an.ChainResult:
        return an.run_chain(
            self.exe, self.work / tag, [c], self.files, fort3=solved.directory / "fort.8"
        )

    def extend_T(self, solved: an.ChainResult, T: float, ntst: int) -> float:
        """The solved parameter after continuing in (T, solved) to ``T`` on NTST=ntst."""
        c = dict(self.demo.auto_solve[-1])
        c.update(
            IRS=an.last(solved.runs[-1]).lab,
            ICP=[11, self.demo.auto_index[self.demo.solved]],
            NTST=ntst,
            NMX=400,
            UZSTOP={11: T},
            ISTART=1,
        )
        c.pop("dat", None)
        c.pop("UZR", None)
        r = an.run_chain(
            self.exe, self.work / "extend", [c], self.files, fort3=solved.directory / "fort.8"
        )
        return self.value(r)

    def value(self, r: an.ChainResult, name: str | None = None) -> float:
        name = name or self.demo.solved
        return an.last(r.runs[-1]).values[f"PAR({self.demo.auto_index[name]})"]


# ============================================================================== driver
def reference(
    demo: Demo, system: Any, params: dict[str, float], orbit: tuple[np.ndarray, np.ndarray]
) -> dict[str, Any]:
    """The solved parameter at ``params`` (the solved one: a guess): closed form (san),
    else broachkit on 400 adapted intervals with ``T = 3 T_demo`` (its change from
    ``2 T_demo`` is reported as a truncation check). ``orbit``: ``(t, x)`` near it."""
    if demo.key == "san":
        return {"value": 0.0, "how": "closed form (mu~ = 0)"}
    r2 = bk_reference(demo, system, params, orbit, 400, 2 * demo.T)
    r3 = bk_reference(demo, system, params, orbit, 400, 3 * demo.T)
    if not (r2.success and r3.success):
        raise RuntimeError(f"{demo.key}: reference solve failed: {r2.message} / {r3.message}")
    v2, v3 = r2.value(demo.solved), r3.value(demo.solved)
    return {
        "value": v3,
        "how": "broachkit N=400 adapted, T = 3 T_demo",
        "change_2T_to_3T": abs(v3 - v2),
    }


def _orbit(result: Any) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(result.t, dtype=float), np.asarray(result.x, dtype=float)


def bench_demo(demo: Demo, work: pathlib.Path, repeats: int) -> dict[str, Any]:
    out: dict[str, Any] = {
        "key": demo.key,
        "title": demo.title,
        "solved": demo.solved,
        "second": demo.second,
        "T_demo": demo.T,
    }
    system = demo.system()  # one per demo: its CasADi functions are built once
    ad = AutoDemo(demo, work)
    # ---- (a) AUTO solve
    chain = ad.solve_chain()
    solved = ad.solve(chain)
    a_val = ad.value(solved)
    a_cpu, a_wall, a_tot = _auto_times(lambda: ad.solve(chain), repeats)
    first = bk_solve(demo, system, 40, None, 2)
    if not first.success:
        raise RuntimeError(f"{demo.key}: find_connection failed: {first.message}")
    ref = reference(demo, system, demo.params, _orbit(first))
    # AUTO fine (cross-check): NTST x 6 for the last run, T doubled
    try:
        fine = ad.solve(
            ad.solve_chain(scale=1)[:-1] + [{**chain[-1], "NTST": chain[-1]["NTST"] * 6}],
            tag="fine",
        )
        a_fine = ad.extend_T(fine, 2 * demo.T, chain[-1]["NTST"] * 6)
        ref["auto_fine_2T"] = a_fine
        ref["auto_fine_minus_ref"] = a_fine - ref["value"]
    except RuntimeError as exc:
        ref["auto_fine_2T"] = f"failed: {str(exc)[:200]}"
    a_err = abs(a_val - ref["value"])
    out["reference"] = ref
    out["auto_solve"] = {
        "value": a_val,
        "error": a_err,
        "seconds": a_cpu,
        "wall_seconds": a_wall,
        "auto_total_time": a_tot,
        "runs": len(chain),
        "steps": [len(r) for r in solved.runs],
        "NTST": chain[-1]["NTST"],
        "NCOL": chain[-1]["NCOL"],
    }
    # ---- (a) broachkit at equal accuracy: for each T and number of adaptation rounds
    # the smallest N whose error is at most AUTO's; of those, the fastest
    scan = []

    def solve_passes(r: Any, N: int, T: float | None, adapt: int) -> Any:
        err = abs(r.value(demo.solved) - ref["value"]) if r.success else math.inf
        scan.append({"N": N, "T": r.mesh.T, "adapt": adapt, "status": r.status.name, "error": err})
        return (N, T, adapt) if err <= a_err else None

    passing: list[tuple[int, float | None, int]] = smallest_meshes(demo, system, solve_passes)
    bk: dict[str, Any] = {"scan": scan}
    if not passing:
        bk["status"] = "did not reach AUTO's error on any candidate mesh"
        out["broachkit_solve"] = bk
        return out
    quick = [min_time(lambda c=c: bk_solve(demo, system, *c)) for c in passing]
    bk["candidates"] = [
        {"N": N, "T": T, "adapt": ad, "seconds": q}
        for (N, T, ad), q in zip(passing, quick, strict=True)
    ]
    N, T, adapt = passing[int(np.argmin(quick))]
    sec, wall, res = median_time(lambda: bk_solve(demo, system, N, T, adapt), repeats)
    bk.update(
        N=N,
        T=res.mesh.T,
        T_own=T is None,
        adapt=adapt,
        degree=4,
        value=res.value(demo.solved),
        error=abs(res.value(demo.solved) - ref["value"]),
        seconds=sec,
        wall_seconds=wall,
        ratio=sec / out["auto_solve"]["seconds"],
        newton_iters=res.newton_iters,
    )
    out["broachkit_solve"] = bk
    # ---- (b) AUTO continuation to the end value
    end = CONTINUE_TO[demo.key]
    cc = ad.continue_constants(solved, end)
    ar = ad.cont(solved, cc)
    last = an.last(ar.runs[-1])
    a_end_second = last.values[f"PAR({demo.auto_index[demo.second]})"]
    a_end_val = last.values[f"PAR({demo.auto_index[demo.solved]})"]
    c_cpu, c_wall, c_tot = _auto_times(lambda: ad.cont(solved, cc), repeats)
    from continuation.bvp import connection_at

    # the orbit at the end for the references: from the 40-interval adapted solve (the
    # setting chosen for (a) may be too coarse to give a guess there)
    br0 = bk_continue(first, demo, end, cc["DS"], cc["DSMAX"])
    end_orbit = _orbit(connection_at(br0, -1))
    ref_end = reference(
        demo, system, {**demo.params, demo.second: a_end_second, demo.solved: a_end_val},
        end_orbit,
    )  # fmt: skip
    out["auto_continue"] = {
        "end": a_end_second,
        "reached": abs(a_end_second - end) < 1e-6,
        "value_at_end": a_end_val,
        "error_at_end": abs(a_end_val - ref_end["value"]),
        "steps": len(ar.runs[-1]),
        "seconds": c_cpu,
        "wall_seconds": c_wall,
        "auto_total_time": c_tot,
        "NTST": cc["NTST"],
        "DS": cc["DS"],
        "DSMAX": cc["DSMAX"],
        "reference_at_end": ref_end,
    }
    try:  # cross-check of the end reference: AUTO's continuation on NTST x 6
        fine_c = ad.cont(solved, ad.continue_constants(solved, end, scale=6), tag="cont_fine")
        ref_end["auto_fine"] = an.last(fine_c.runs[-1]).values[
            f"PAR({demo.auto_index[demo.solved]})"
        ]
        ref_end["auto_fine_minus_ref"] = ref_end["auto_fine"] - ref_end["value"]
    except RuntimeError as exc:
        ref_end["auto_fine"] = f"failed: {str(exc)[:200]}"
    # ---- (b) broachkit continuation: the smallest N (same T as the solve) whose error
    # at the end is at most AUTO's; each candidate run once, the chosen one timed
    a_err_end = out["auto_continue"]["error_at_end"]
    bc: dict[str, Any] = {"scan": []}
    # reference at broachkit's end (the bound itself), from the orbit at br0's end
    end_bk = float(br0.p[-1])
    if abs(end_bk - a_end_second) > 1e-12:
        ref_bk = reference(
            demo,
            system,
            {**demo.params, demo.second: end_bk, demo.solved: float(br0.records[demo.solved][-1])},
            end_orbit,
        )["value"]
    else:
        ref_bk = ref_end["value"]
    bc["reference_at_end"] = ref_bk

    def continuation_passes(start: Any, NN: int, TT: float | None, ad: int) -> Any:
        row: dict[str, Any] = {"N": NN, "T": start.mesh.T, "adapt": ad}
        if not start.success:
            bc["scan"].append({**row, "status": start.status.name})
            return None
        br = bk_continue(start, demo, end, cc["DS"], cc["DSMAX"])
        p_end = float(br.p[-1])
        v_end = float(br.records[demo.solved][-1])
        err = abs(v_end - ref_bk) if abs(p_end - end_bk) < 1e-12 else math.inf
        bc["scan"].append({**row, "status": br.status.name, "end": p_end, "error": err})
        return (NN, ad, start, p_end, v_end, err) if err <= a_err_end else None

    picks = smallest_meshes(demo, system, continuation_passes)
    if not picks:
        bc["status"] = "did not reach AUTO's error at the end on any candidate mesh"
    else:
        quick = [
            min_time(lambda c=c: bk_continue(c[2], demo, end, cc["DS"], cc["DSMAX"])) for c in picks
        ]
        bc["candidates"] = [
            {"N": c[0], "T": c[2].mesh.T, "adapt": c[1], "seconds": q}
            for c, q in zip(picks, quick, strict=True)
        ]
        NN, adapt_b, start, p_end, v_end, err = picks[int(np.argmin(quick))]
        sec, wall, br = median_time(
            lambda: bk_continue(start, demo, end, cc["DS"], cc["DSMAX"]), repeats
        )
        bc.update(
            N=NN,
            adapt=adapt_b,
            T=start.mesh.T,
            steps=len(br.p) - 1,
            status=br.status.name,
            end=p_end,
            value_at_end=v_end,
            error_at_end=err,
            seconds=sec,
            wall_seconds=wall,
            ratio=sec / out["auto_continue"]["seconds"],
        )
    out["broachkit_continue"] = bc
    return out


def _fmt(x: Any, spec: str = ".2e") -> str:
    return format(x, spec) if isinstance(x, (int, float)) and math.isfinite(x) else str(x)


def render(results: list[dict[str, Any]], meta: dict[str, Any]) -> str:
    lines = [
        "# Connecting orbits: broachkit vs AUTO-07p/HomCont (native)",
        "",
        f"Command: `{meta['command']}`  ",
        f"Machine: {meta['machine']}; {meta['date']}; load average {meta['load']}; "
        f"repeats {meta['repeats']} (medians of CPU seconds, one thread each).",
        "",
        "## (a) one connection solve at the demo's parameters",
        "",
        "| demo | solved | reference | AUTO value | AUTO error | AUTO s (NTST x NCOL) "
        "| broachkit N x 4, T, adapt | bk error | bk s | bk/AUTO |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        a, b, ref = r.get("auto_solve", {}), r.get("broachkit_solve", {}), r.get("reference", {})
        if "error" in r:
            lines.append(f"| {r['key']} | failed: {r['error']} |||||||||")
            continue
        lines.append(
            f"| {r['key']} | {r['solved']} | {ref.get('value', float('nan')):.12g} | "
            f"{a['value']:.12g} | {_fmt(a['error'])} | "
            f"{a['seconds']:.4f} ({a['NTST']}x{a['NCOL']}) | "
            + (
                f"{b['N']}, {b['T']:.4g}{' (own)' if b['T_own'] else ''}, adapt {b['adapt']} | "
                f"{_fmt(b['error'])} | {b['seconds']:.4f} | {b['ratio']:.2f} |"
                if "seconds" in b
                else f"{b.get('status', '-')} ||||"
            )
        )
    lines += [
        "",
        "## (b) one continuation of it in a second parameter",
        "",
        "| demo | second: from -> to | AUTO steps | AUTO error at end | AUTO s "
        "| bk N, T, adapt | bk steps | bk status | bk error at end | bk s | bk/AUTO |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        a, b = r.get("auto_continue"), r.get("broachkit_continue")
        if not a or not b:
            continue
        if "seconds" not in b:
            lines.append(
                f"| {r['key']} | {r['second']} | {a['steps']} | "
                f"{_fmt(a['error_at_end'])} | {a['seconds']:.4f} | {b['status']} |||||"
            )
            continue
        lines.append(
            f"| {r['key']} | {r['second']}: {r['start_second']:g} -> {a['end']:.6g} | "
            f"{a['steps']} | "
            f"{_fmt(a['error_at_end'])} | {a['seconds']:.4f} | "
            f"{b['N']}, {b['T']:.4g}, adapt {b['adapt']} | {b['steps']} | "
            f"{b['status']} | {_fmt(b['error_at_end'])} | {b['seconds']:.4f} | {b['ratio']:.2f} |"
        )
    lines += ["", "References and cross-checks:", ""]
    for r in results:
        ref = r.get("reference", {})
        lines.append(
            f"* {r['key']}: {ref.get('how')}; AUTO NTST x 6 with T doubled: "
            f"{_fmt(ref.get('auto_fine_2T'), '.12g')} "
            f"(minus reference {_fmt(ref.get('auto_fine_minus_ref'))}); "
            f"change of the reference from 2T to 3T: {_fmt(ref.get('change_2T_to_3T'))}"
        )
        re_ = r.get("auto_continue", {}).get("reference_at_end", {})
        if re_:
            lines.append(
                f"  * at the end of (b): reference {_fmt(re_.get('value'), '.12g')}; "
                f"AUTO NTST x 6: {_fmt(re_.get('auto_fine'), '.12g')} (minus reference "
                f"{_fmt(re_.get('auto_fine_minus_ref'))})"
            )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--demos", default=",".join(DEMOS))
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", default=str(HERE / "results" / "connections_vs_auto"))
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    logging.getLogger("continuation").setLevel(logging.WARNING)  # (the scan's solves)
    try:
        an.library_paths()
    except PeerUnavailable as exc:
        print(f"AUTO-07p not available: {exc}", file=sys.stderr)
        return 2
    load0 = " ".join(f"{v:.2f}" for v in os.getloadavg())
    results = []
    with tempfile.TemporaryDirectory(prefix="conn_vs_auto_") as tmp:
        for key in args.demos.split(","):
            demo = DEMOS[key]
            log.info("%s ...", key)
            try:
                r = bench_demo(demo, pathlib.Path(tmp), args.repeats)
            except Exception as exc:  # a failed demo is reported, not hidden
                r = {"key": key, "error": f"{type(exc).__name__}: {str(exc)[:300]}"}
            r["start_second"] = demo.params[demo.second]
            results.append(r)
            log.info("%s", json.dumps(r, default=str)[:400])
    meta = {
        "command": "benchmarks/_work/venv/bin/python benchmarks/connections_vs_auto.py "
        + " ".join(argv if argv is not None else sys.argv[1:]),
        "machine": f"{platform.machine()}, {platform.python_version()}",
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "repeats": args.repeats,
        "load": " ".join(f"{v:.2f}" for v in os.getloadavg()),
        "load_at_start": load0,
    }
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(
        json.dumps(
            {"meta": meta, "results": results},
            indent=1,
            default=lambda o: dataclasses.asdict(o) if dataclasses.is_dataclass(o) else str(o),
        )
    )
    out.with_suffix(".md").write_text(render(results, meta))
    print(out.with_suffix(".md").read_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
