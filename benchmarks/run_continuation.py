#!/usr/bin/env python
"""Continuation benchmark: broachkit against AUTO-07p, bice, pycont-lite and a SciPy baseline.

Usage::

    python benchmarks/run_continuation.py                 # everything that is installed
    python benchmarks/run_continuation.py --repeats 7 --problems bratu20 brusselator \
        --tools broachkit auto07p-native

Every (tool, problem) pair runs in its own fresh worker process (the Python of
``benchmarks/_work/venv`` when ``benchmarks/setup_env.sh`` has made it, else the current
one), so imports, caches and peak memory do not leak from one measurement into the next.
A worker builds the tool's model once (*setup*: CasADi trace, AUTO-07p Fortran build,
...), makes one untimed warm-up run (skipped when a run takes longer than
``--warmup-limit`` seconds), then times ``--repeats`` runs (fewer when one run takes longer
than ``--budget / repeats`` seconds) and reports the median wall time
(``time.perf_counter``), the number of accepted steps and the special points of the last
run.

Peak memory is the peak resident set size (``resource.getrusage(...).ru_maxrss``) of the
worker process, measured after the runs, with the value right after its imports as the
baseline; for ``auto07p-ctypes`` the forked AUTO child is included (``RUSAGE_CHILDREN``);
for ``auto07p-native`` it is the executable's own peak RSS (``/usr/bin/time -f %M``).

The *floor* of a problem, measured inside the broachkit worker, is the median time of one
bordered LU solve plus one eigenvalue solve at that size, on the Jacobian at the start
point bordered by ``f_p`` and a dense unit row: dense ``scipy.linalg.lu_factor`` +
``lu_solve`` + ``scipy.linalg.eigvals`` for the small problems, sparse
``scipy.sparse.linalg.splu`` + ``solve`` + ``scipy.sparse.linalg.eigs(k=6, sigma=0)`` for
Bratu N=200.

Writes ``benchmarks/results/continuation.json`` and ``benchmarks/results/continuation.md``
and replaces the results section of ``benchmarks/README.md``.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.timing import cpu_total  # noqa: E402

VENV_PYTHON = HERE / "_work" / "venv" / "bin" / "python"
RESULTS = HERE / "results"
TOOLS = ("broachkit", "scipy-palc", "auto07p-native", "auto07p-ctypes", "bice", "pycont-lite")
PEERS = ("auto07p-native", "auto07p-ctypes", "bice", "pycont-lite")
BEGIN, END = "<!-- BEGIN RESULTS -->", "<!-- END RESULTS -->"


# ============================================================================ worker side
def _maxrss_kib(who: int = resource.RUSAGE_SELF) -> int:
    return int(resource.getrusage(who).ru_maxrss)  # KiB on Linux


def _floor(problem: Any, reps: int) -> dict[str, Any]:
    """Median time of one bordered LU solve + one eigenvalue solve (see module docstring)."""
    import numpy as np
    import scipy.linalg as la
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    n = problem.n
    pv = problem.param_vector()
    J = problem.jac(problem.x0, pv)
    fp = problem.dfdp(problem.x0, pv)
    row = np.full(n + 1, 1.0 / math.sqrt(n + 1))
    rhs = np.zeros(n + 1)
    rhs[n] = 1.0
    if problem.sparse:
        Jc = sp.coo_matrix(J)
        A = sp.csc_matrix(
            (
                np.concatenate((Jc.data, fp, row)),
                (
                    np.concatenate((Jc.row, np.arange(n), np.full(n + 1, n))),
                    np.concatenate((Jc.col, np.full(n, n), np.arange(n + 1))),
                ),
            ),
            shape=(n + 1, n + 1),
        )
        Jcsc = sp.csc_matrix(J)

        def lin() -> None:
            spla.splu(A).solve(rhs)

        def eig() -> None:
            spla.eigs(Jcsc, k=6, sigma=0.0, which="LM", return_eigenvectors=False)

        how = "sparse splu + solve, eigs(k=6, sigma=0)"
    else:
        Jd = np.asarray(J)
        A = np.zeros((n + 1, n + 1))
        A[:n, :n] = Jd
        A[:n, n] = fp
        A[n] = row

        def lin() -> None:
            la.lu_solve(la.lu_factor(A, check_finite=False), rhs, check_finite=False)

        def eig() -> None:
            la.eigvals(Jd, check_finite=False)

        how = "dense lu_factor + lu_solve, eigvals"

    def med(fn: Any) -> float:
        for _ in range(3):
            fn()
        ts = []
        for _ in range(reps):
            t0 = time.perf_counter()
            fn()
            ts.append(time.perf_counter() - t0)
        return statistics.median(ts)

    t_lin, t_eig = med(lin), med(eig)
    return {"how": how, "lu_s": t_lin, "eig_s": t_eig, "total_s": t_lin + t_eig}


def _our_events(problem: Any) -> tuple[Any, ...]:
    if not math.isfinite(problem.norm_max):
        return ()
    import numpy as np

    from continuation.events import Event

    cap = problem.norm_max
    return (
        Event(
            "norm_cap",
            lambda x, p: float(np.linalg.norm(x)) - cap,
            direction="up",
            terminal=True,
        ),
    )


class _Runner:
    """Setup once, then ``run() -> (seconds, steps, special, p_end, status, extra)``."""

    setup_s: float = 0.0
    rss_note: str = "worker process"
    exe_rss_kib: int | None = None

    def run(self) -> tuple[float, dict[str, Any]]:
        raise NotImplementedError


class _Ours(_Runner):
    def __init__(self, problem: Any) -> None:
        from continuation.api import continue_equilibria

        self.problem = problem
        t0 = time.perf_counter()
        self.system = problem.system()
        self.events = _our_events(problem)
        self.setup_s = time.perf_counter() - t0
        self.fn = continue_equilibria

    def run(self) -> tuple[float, dict[str, Any]]:
        p = self.problem
        t0 = time.perf_counter()
        br = self.fn(
            self.system,
            p.x0,
            dict(p.params),
            p.free,
            **p.step_settings(),
            direction="forward",
            events=self.events,
        )
        dt = time.perf_counter() - t0
        special = [
            (sp.kind.value, float(sp.p)) for sp in br.special_points if sp.kind.value != "user"
        ]
        return dt, {
            "steps": len(br) - 1,
            "special": special,
            "p_end": float(br.p[-1]),
            "status": br.status.name,
            "extra": {"newton_iters_mean": float(br.newton_iters[1:].mean())},
        }


class _Scipy(_Runner):
    def __init__(self, problem: Any) -> None:
        from benchmarks.scipy_palc import palc_problem

        self.problem = problem
        self.fn = palc_problem

    def run(self) -> tuple[float, dict[str, Any]]:
        t0 = time.perf_counter()
        r = self.fn(self.problem)
        dt = time.perf_counter() - t0
        return dt, {
            "steps": r.steps,
            "special": [(s.kind, s.p) for s in r.special],
            "p_end": float(r.p[-1]),
            "status": r.status,
            "extra": {"newton_iters_mean": float(r.newton_iters[1:].mean())},
        }


def _peer_dict(res: Any) -> dict[str, Any]:
    return {
        "steps": res.steps,
        "special": [(k, float(p)) for k, p in res.special],
        "p_end": res.p_end,
        "status": res.status,
        "extra": res.extra,
    }


class _AutoNative(_Runner):
    rss_note = "AUTO-07p executable alone (/usr/bin/time %M)"

    def __init__(self, problem: Any) -> None:
        from benchmarks.peers.auto07p import NativeAuto

        self.native = NativeAuto(problem, tempfile.gettempdir())
        self.setup_s = self.native.setup_seconds
        self.warm = True  # the setup run was AUTO's warm-up

    def run(self) -> tuple[float, dict[str, Any]]:
        dt = self.native.run()
        return dt, _peer_dict(self.native.result())

    def close(self) -> None:
        rss = self.native.peak_rss_kib()
        self.exe_rss_kib = rss
        self.native.close()


class _PythonPeer(_Runner):
    """A peer driven by one adapter function ``run(problem) -> PeerResult``."""

    module: str = ""
    function: str = "run"

    def __init__(self, problem: Any) -> None:
        import importlib

        self.problem = problem
        self.fn = getattr(importlib.import_module(self.module), self.function)

    def run(self) -> tuple[float, dict[str, Any]]:
        t0 = time.perf_counter()
        r = self.fn(self.problem)
        return time.perf_counter() - t0, _peer_dict(r)


class _AutoCtypes(_PythonPeer):
    rss_note = "worker + forked AUTO-07p child"
    module = "benchmarks.peers.auto07p"
    function = "run_ctypes"


class _Bice(_PythonPeer):
    module = "benchmarks.peers.bice_peer"


class _Pycont(_PythonPeer):
    module = "benchmarks.peers.pycont_peer"


RUNNERS = {
    "broachkit": _Ours,
    "scipy-palc": _Scipy,
    "auto07p-native": _AutoNative,
    "auto07p-ctypes": _AutoCtypes,
    "bice": _Bice,
    "pycont-lite": _Pycont,
}


def worker(
    tool: str, problem_name: str, repeats: int, budget: float, warmup_limit: float, floor_reps: int
) -> dict[str, Any]:
    """Measure one tool on one problem (runs in its own process)."""
    import numpy as np  # noqa: F401  (import cost belongs to the baseline RSS)

    from benchmarks.peers.common import PeerUnavailable
    from benchmarks.problems import all_problems

    problem = all_problems()[problem_name]
    out: dict[str, Any] = {"tool": tool, "problem": problem_name, "ok": False}
    try:
        runner = RUNNERS[tool](problem)
    except PeerUnavailable as exc:
        out["reason"] = f"not available: {exc}"
        return out
    out["rss_base_kib"] = _maxrss_kib()
    out["setup_s"] = runner.setup_s
    sink = io.StringIO()
    cpus: list[float] = []

    def timed() -> tuple[float, dict[str, Any]]:
        c0 = cpu_total()
        dt, info = runner.run()
        cpus.append(cpu_total() - c0)
        return dt, info

    try:
        with contextlib.redirect_stdout(sink):
            times: list[float] = []
            if not getattr(runner, "warm", False):
                dt, info = timed()
                if dt > warmup_limit:  # too slow to throw away: it counts
                    times.append(dt)
                else:
                    cpus.clear()
            first = times[0] if times else None
            n_rep = repeats
            if first is not None:
                n_rep = max(1, min(repeats, int(budget / first)))
            while len(times) < n_rep:
                dt, info = timed()
                times.append(dt)
                if len(times) == 1 and dt * repeats > budget:
                    n_rep = max(1, int(budget / dt))
            if hasattr(runner, "close"):
                runner.close()
    except Exception as exc:  # a peer that fails on a problem is reported, not hidden
        out["reason"] = f"failed: {type(exc).__name__}: {exc}"
        out["traceback"] = traceback.format_exc(limit=8)
        return out
    out.update(info)
    out["ok"] = True
    out["times_s"] = times
    out["median_s"] = statistics.median(times)
    out["per_step_s"] = out["median_s"] / max(out["steps"], 1)
    out["cpu_s"] = cpus
    out["cpu_median_s"] = statistics.median(cpus)
    out["cpu_per_step_s"] = out["cpu_median_s"] / max(out["steps"], 1)
    out["rss_peak_kib"] = max(_maxrss_kib(), _maxrss_kib(resource.RUSAGE_CHILDREN))
    out["rss_note"] = runner.rss_note
    if runner.exe_rss_kib is not None:
        out["rss_peak_kib"] = runner.exe_rss_kib
        out["rss_base_kib"] = None
    if tool == "broachkit":
        out["floor"] = _floor(problem, floor_reps)
    return out


# ============================================================================ driver side
def _python() -> str:
    return str(VENV_PYTHON) if VENV_PYTHON.exists() else sys.executable


def _spawn(tool: str, problem: str, args: argparse.Namespace) -> dict[str, Any]:
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as fh:
        path = fh.name
    cmd = [
        _python(),
        str(Path(__file__).resolve()),
        "--worker",
        tool,
        problem,
        "--repeats",
        str(args.repeats),
        "--budget",
        str(args.budget),
        "--warmup-limit",
        str(args.warmup_limit),
        "--floor-reps",
        str(args.floor_reps),
        "--out",
        path,
    ]
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    try:
        proc = subprocess.run(
            cmd, capture_output=True, text=True, timeout=args.timeout, env=env, check=False
        )
        if proc.returncode != 0:
            tail = (proc.stderr or proc.stdout).strip().splitlines()[-3:]
            return {
                "tool": tool,
                "problem": problem,
                "ok": False,
                "reason": f"worker exited {proc.returncode}: {' | '.join(tail)}",
            }
        return json.loads(Path(path).read_text())
    except subprocess.TimeoutExpired:
        return {
            "tool": tool,
            "problem": problem,
            "ok": False,
            "reason": f"timed out after {args.timeout:.0f} s",
        }
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)


def _median_round(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The worker result with the median of the rounds' median times (all rounds' medians
    kept as ``round_medians_s``); a failed round fails the measurement."""
    bad = [r for r in runs if not r["ok"]]
    if bad:
        return bad[0]
    ordered = sorted(runs, key=lambda r: r["median_s"])
    out = dict(ordered[(len(ordered) - 1) // 2])
    out["round_medians_s"] = [r["median_s"] for r in runs]
    return out


def _fmt_p(p: float) -> str:
    return f"{p:.10g}"


def _ms(s: float | None) -> str:
    if s is None:
        return "-"
    return f"{s * 1e3:.3g}" if s < 1.0 else f"{s * 1e3:,.0f}"


def _mib(kib: int | None) -> str:
    return "-" if kib is None else f"{kib / 1024:.0f}"


_FOLD_LIKE = {"fold", "+", "-"}  # bice labels a real eigenvalue crossing "+" or "-"


def _special_cell(found: list[Any], expected: Any) -> str:
    """Found points with their distance to the reference, and the missed references."""
    parts = []
    used: set[int] = set()
    for e in expected:
        kinds = _FOLD_LIKE if e.kind == "fold" else {e.kind}
        cand = [(abs(p - e.p), i) for i, (k, p) in enumerate(found) if k in kinds and i not in used]
        if not cand:
            parts.append(f"**missed {e.kind} {_fmt_p(e.p)}**")
            continue
        d, i = min(cand)
        used.add(i)
        k, p = found[i]
        parts.append(f"{k} {_fmt_p(p)} (err {d:.0e})")
    for i, (k, p) in enumerate(found):
        if i not in used:
            parts.append(f"extra {k} {_fmt_p(p)}")
    return "; ".join(parts) or "none"


def markdown(results: list[dict[str, Any]], meta: dict[str, Any]) -> str:
    """The results as Markdown tables, one per problem, plus a summary."""
    from benchmarks.problems import all_problems

    probs = all_problems()
    cmds = " then ".join(f"`{c}`" for c in meta.get("commands", [meta["command"]]))
    lines = [
        f"Measured {meta['date']} on {meta['machine']} with {cmds} "
        f"({meta['repeats']} timed repeats, median"
        + (
            f"; {meta['rounds']} worker processes per tool and problem, interleaved, the "
            "one with the median of their medians reported"
            if meta.get("rounds", 1) > 1
            else ""
        )
        + "). 1-minute load average "
        f"{meta['loadavg_start'][0]:.1f} at the start, {meta['loadavg_end'][0]:.1f} at the end "
        "of the last command (the machine is shared with other work, which inflates wall "
        "times; CPU times suffer less).",
        "",
    ]
    summary = []
    for name, prob in probs.items():
        rows = [r for r in results if r["problem"] == name]
        if not rows:
            continue
        ref = ", ".join(f"{e.kind} {e.p:.13g} ({e.source})" for e in prob.expected)
        lines += [f"### {prob.title}", "", f"Reference: {ref}.", ""]
        ours = next((r for r in rows if r["tool"] == "broachkit" and r["ok"]), None)
        floor = ours.get("floor") if ours else None
        lines += [
            "| tool | special points: p (abs. error) | steps | median run [ms] | per step [ms] "
            "| median CPU [ms] | setup [ms] | peak RSS [MiB] (+ over setup) | stop |",
            "|---|---|---:|---:|---:|---:|---:|---:|---|",
        ]
        for r in rows:
            if not r["ok"]:
                lines.append(f"| {r['tool']} | {r.get('reason', 'failed')} | | | | | | | |")
                continue
            sp = _special_cell(r["special"], prob.expected)
            base = r.get("rss_base_kib")
            mem = _mib(r["rss_peak_kib"])
            if base is not None:
                mem += f" (+{_mib(r['rss_peak_kib'] - base)})"
            else:
                mem += " (exe)"
            lines.append(
                f"| {r['tool']} | {sp} | {r['steps']} | {_ms(r['median_s'])} | "
                f"{_ms(r['per_step_s'])} | {_ms(r.get('cpu_median_s'))} | "
                f"{_ms(r.get('setup_s'))} | "
                f"{mem} | {r['status']} |"
            )
        if floor:
            ratio = ours["per_step_s"] / floor["total_s"]
            lines += [
                "",
                f"Raw floor ({floor['how']}): {_ms(floor['lu_s'])} ms + {_ms(floor['eig_s'])} ms"
                f" = {_ms(floor['total_s'])} ms; broachkit per step = **{ratio:.1f}x** floor.",
            ]
        if ours:
            peers = [r for r in rows if r["ok"] and r["tool"] in PEERS]
            if peers:
                best = min(peers, key=lambda r: r["median_s"])
                summary.append((name, ours, best, floor))
        lines.append("")
    if summary:
        lines += [
            "### Summary against the targets",
            "",
            "| problem | broachkit run [ms] | fastest peer (wall) | its run [ms] "
            "| broachkit / peer, wall | broachkit / peer, CPU | broachkit per step / floor |",
            "|---|---:|---|---:|---:|---:|---:|",
        ]
        rounds = []
        for name, ours, best, floor in summary:
            fl = f"{ours['per_step_s'] / floor['total_s']:.1f}x" if floor else "-"
            cpu = ours["cpu_median_s"] / best["cpu_median_s"] if best["cpu_median_s"] else math.nan
            lines.append(
                f"| {name} | {_ms(ours['median_s'])} | {best['tool']} | {_ms(best['median_s'])} | "
                f"{ours['median_s'] / best['median_s']:.2f} | {cpu:.2f} | {fl} |"
            )
            a, b = ours.get("round_medians_s"), best.get("round_medians_s")
            if a and b and len(a) == len(b) > 1:
                ratios = ", ".join(f"{x / y:.2f}" for x, y in zip(a, b, strict=True))
                rounds.append(f"* {name}: broachkit / {best['tool']} per round: {ratios}")
        lines.append("")
        if rounds:
            lines += ["Wall-time ratio in each round (worker processes run back to back):", ""]
            lines += [*rounds, ""]
    return "\n".join(lines)


def _update_readme(md: str) -> None:
    readme = HERE / "README.md"
    if not readme.exists():
        return
    text = readme.read_text()
    if BEGIN in text and END in text:
        head, rest = text.split(BEGIN, 1)
        _, tail = rest.split(END, 1)
        readme.write_text(f"{head}{BEGIN}\n{md}\n{END}{tail}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--problems", nargs="*", default=None, help="default: all")
    ap.add_argument("--tools", nargs="*", default=None, help=f"default: {' '.join(TOOLS)}")
    ap.add_argument("--repeats", type=int, default=5, help="timed runs per measurement")
    ap.add_argument(
        "--budget",
        type=float,
        default=60.0,
        help="seconds of timed runs per measurement (fewer repeats if slow)",
    )
    ap.add_argument(
        "--warmup-limit",
        type=float,
        default=10.0,
        help="a warm-up run longer than this counts as a timed run",
    )
    ap.add_argument("--floor-reps", type=int, default=200)
    ap.add_argument("--timeout", type=float, default=1800.0, help="per worker, seconds")
    ap.add_argument(
        "--rounds",
        type=int,
        default=1,
        help="fresh worker processes per (tool, problem), interleaved between the tools; "
        "the run reported is the one with the median of their medians",
    )
    ap.add_argument("--no-readme", action="store_true", help="do not touch README.md")
    ap.add_argument(
        "--update",
        action="store_true",
        help="keep the other entries of results/continuation.json, replace only those measured now",
    )
    ap.add_argument(
        "--report-only",
        action="store_true",
        help="only re-render results/continuation.md and README.md from the existing JSON",
    )
    ap.add_argument("--worker", nargs=2, metavar=("TOOL", "PROBLEM"), help=argparse.SUPPRESS)
    ap.add_argument("--out", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.worker:
        res = worker(
            args.worker[0],
            args.worker[1],
            args.repeats,
            args.budget,
            args.warmup_limit,
            args.floor_reps,
        )
        Path(args.out).write_text(json.dumps(res))
        return 0

    from benchmarks.problems import all_problems

    if args.report_only:
        data = json.loads((RESULTS / "continuation.json").read_text())
        md = markdown(data["results"], data["meta"])
        (RESULTS / "continuation.md").write_text(md)
        if not args.no_readme:
            _update_readme(md)
        print(md)
        return 0
    problems = args.problems or list(all_problems())
    tools = args.tools or list(TOOLS)
    for t in tools:
        if t not in RUNNERS:
            raise SystemExit(f"unknown tool {t!r}; choose from {TOOLS}")
    load_start = os.getloadavg()
    results = []
    if args.rounds < 1:
        raise SystemExit("--rounds must be >= 1")
    for prob in problems:
        runs: dict[str, list[dict[str, Any]]] = {t: [] for t in tools}
        for _ in range(args.rounds):  # interleaved: tool A, tool B, ..., tool A, ...
            for tool in tools:
                t0 = time.perf_counter()
                r = _spawn(tool, prob, args)
                runs[tool].append(r)
                msg = (
                    f"{_ms(r['median_s'])} ms, {r['steps']} steps, {r['special']}"
                    if r["ok"]
                    else r.get("reason", "")
                )
                print(f"[{time.perf_counter() - t0:6.1f} s] {prob:12s} {tool:15s} {msg}",
                      flush=True)  # fmt: skip
        for tool in tools:
            results.append(_median_round(runs[tool]))
    cmd = "python benchmarks/run_continuation.py" + (
        "" if argv is None and len(sys.argv) == 1 else " " + " ".join(sys.argv[1:])
    )
    meta = {
        "date": time.strftime("%Y-%m-%d"),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, Python "
        f"{platform.python_version()} ({_python()})",
        "command": cmd.strip(),
        "repeats": args.repeats,
        "rounds": args.rounds,
        "loadavg_start": load_start,
        "loadavg_end": os.getloadavg(),
    }
    for r in results:
        r["measured"] = {
            "date": meta["date"],
            "command": meta["command"],
            "loadavg": [meta["loadavg_start"][0], meta["loadavg_end"][0]],
        }
    RESULTS.mkdir(exist_ok=True)
    out_json = RESULTS / "continuation.json"
    if args.update and out_json.exists():
        old = json.loads(out_json.read_text())
        done = {(r["tool"], r["problem"]) for r in results}
        kept = [r for r in old["results"] if (r["tool"], r["problem"]) not in done]
        merged = kept + results
        order = {name: i for i, name in enumerate(all_problems())}
        tool_order = {t: i for i, t in enumerate(TOOLS)}
        merged.sort(key=lambda r: (order.get(r["problem"], 99), tool_order.get(r["tool"], 99)))
        results = merged
        cmds = {r["measured"]["command"] for r in results if "measured" in r}
        if any("measured" not in r for r in results):  # entries of an older file
            cmds.update(old["meta"].get("commands", [old["meta"].get("command", "?")]))
        meta["commands"] = sorted(cmds)
    else:
        meta["commands"] = [meta["command"]]
    out_json.write_text(json.dumps({"meta": meta, "results": results}, indent=1))
    md = markdown(results, meta)
    (RESULTS / "continuation.md").write_text(md)
    if not args.no_readme:
        _update_readme(md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
