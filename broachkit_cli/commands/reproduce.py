"""``broachkit reproduce`` (the default): reproduce the paper's results with the default vessel.

Runs the study steps in order with one progress display, writes figures (PNG) and
data (CSV/NPZ/JSON) under ``--out/<step>``, then ``--out/report.html`` (the paper's
statements beside this run's figures and numbers) and ``--out/reproduce.json``, and
prints a short summary (``--json``: the JSON document):

=========== ========================================== =====================================
step        what                                        module
=========== ========================================== =====================================
demo        engine demo (Bratu fold, Brusselator Hopf)   ``broachkit demo``
fig02_05    fixed points against chi_c and Fn           ``studies.fig02_05_fixed_points``
fig06_09    eigenvalues and unstable eigenvectors       ``studies.fig06_09_eigen``
fig10_15    critical Fn, unstable manifolds             ``studies.fig10_15_manifolds``
fig21_23    connecting orbit, critical curve            ``studies.fig21_23_connection``
fig16_22    sudden-change experiments                   ``studies.fig16_22_sudden_change``
sensitivity dFn*/dtheta, uncertainty band, tornado     ``studies.sensitivity``
cycles      the cycle in Fn and chi_c, period blow-up   ``studies.cycles_vs_fn``
=========== ========================================== =====================================

A step whose folder holds ``summary.json`` and no ``.incomplete`` marker is skipped
unless ``--force``; a step that was interrupted (the marker is still there) is redone,
resuming its sweep from the checkpoints in ``<step>/sweep`` (``--force`` deletes them).

On ``--workers N`` local processes (default one per core): the sudden-change step
(:data:`SWEEP_STEP`) runs its bisections and map rows on ``N`` worker processes
(:mod:`continuation.sweep`, the environment variable ``BROACHKIT_WORKERS`` passes
``N`` on), and, with ``N > 1``, the other steps run at the same time in ``N``
background processes, shared out by their usual cost (:data:`STEP_WEIGHTS`), each
running its steps one after another. Every step computes exactly what it computes
alone, so the outputs do not depend on ``N``.
``--only`` runs a subset. The studies are the package :mod:`studies`, installed with
broachkit (``--studies DIR`` loads the scripts of another folder instead).
"""

from __future__ import annotations

import argparse
import datetime
import importlib
import importlib.util
import json
import logging
import multiprocessing
import os
import platform
import queue
import resource
import shutil
import signal
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

from ..files import is_complete, mark_complete, mark_incomplete, write_json
from ..interrupt import acknowledge
from ..options import add_json, add_out, json_safe, prepare_out
from . import demo

NAME = "reproduce"
HELP = "reproduce the paper's results with the default vessel (the default command)"

log = logging.getLogger("broachkit")

#: Study steps: (key, title, module of the :mod:`studies` package).
STUDY_STEPS: tuple[tuple[str, str, str], ...] = (
    ("fig02_05", "Figs. 2-5: fixed points against the course", "fig02_05_fixed_points"),
    ("fig06_09", "Figs. 6-9: eigenvalues and eigenvectors", "fig06_09_eigen"),
    ("fig10_15", "Figs. 10-15: critical Fn and unstable manifolds", "fig10_15_manifolds"),
    ("fig21_23", "Figs. 21, 23: connecting orbit and critical curve", "fig21_23_connection"),
    ("fig16_22", "Figs. 16-22: sudden-change experiments", "fig16_22_sudden_change"),
    ("sensitivity", "Critical Fn: sensitivities, uncertainty band, tornado", "sensitivity"),
    ("cycles", "The periodic motion: the cycle in Fn, its period blow-up", "cycles_vs_fn"),
)


#: The step that runs its own sweep on worker processes (in this process).
SWEEP_STEP = "fig16_22"
#: A step's sub-folder of sweep checkpoints (resumed after an interruption).
SWEEP_DIR = "sweep"
#: Environment variable with the sweeps' number of worker processes.
WORKERS_ENV = "BROACHKIT_WORKERS"


def load_study(path: Path) -> ModuleType:
    """Import a study script by its path (it must define ``compute(out, progress)``).

    Raises
    ------
    ValueError
        If the file does not exist or defines no ``compute``.
    """
    if not path.is_file():
        raise ValueError(f"--studies: study script not found: {path}")
    spec = importlib.util.spec_from_file_location(f"broachkit_study_{path.stem}", path)
    if spec is None or spec.loader is None:  # pragma: no cover - a .py file always has one
        raise ValueError(f"--studies: cannot load study script {path}")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    if not callable(getattr(mod, "compute", None)):
        raise ValueError(f"--studies: {path} defines no `compute(out, progress)`")
    return mod


def study_module(name: str, folder: Path | None) -> ModuleType:
    """The study ``name`` from the packaged :mod:`studies`, or from ``folder`` by path."""
    if folder is not None:
        return load_study(folder / f"{name}.py")
    return importlib.import_module(f"studies.{name}")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit reproduce``."""
    add_out(parser, "out", "the report, figures and data")
    parser.add_argument("--force", action="store_true", help="recompute finished steps")
    parser.add_argument(
        "--only",
        nargs="+",
        default=None,
        metavar="STEP",
        help="run only these steps (demo, " + ", ".join(k for k, _, _ in STUDY_STEPS) + ")",
    )
    parser.add_argument(
        "--studies",
        type=Path,
        default=None,
        help="folder of study scripts to run instead of the packaged ones",
    )
    parser.add_argument("--no-report", action="store_true", help="do not write report.html")
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="local worker processes (default: one per core; 1 runs everything in this process)",
    )
    add_json(parser)


Step = tuple[str, str, Callable[[Path, Callable[[str], None]], Any]]


def _steps(args: argparse.Namespace) -> list[Step]:
    steps: list[Step] = [
        (
            "demo",
            "engine demo (Bratu fold, Brusselator Hopf)",
            lambda out, progress: demo.compute(out),
        )
    ]
    folder = args.studies
    if folder is not None and not folder.is_dir():
        raise ValueError(f"--studies: {folder} is not a folder")
    for key, title, module in STUDY_STEPS:

        def fn(out: Path, progress: Callable[[str], None], _m: str = module) -> Any:
            return study_module(_m, folder).compute(out, progress=progress)

        steps.append((key, title, fn))
    keys = [k for k, _, _ in steps]
    if args.only:
        unknown = [k for k in args.only if k not in keys]
        if unknown:
            raise ValueError(f"--only: unknown step(s) {unknown}; steps are {keys}")
        steps = [s for s in steps if s[0] in args.only]
    return steps


def _compute_step(key: str, module: str | None, folder: Path, studies: Path | None) -> Any:
    """Run one step by name (the picklable form of a step, for another process)."""
    if module is None:
        return demo.compute(folder)
    return study_module(module, studies).compute(folder, progress=lambda msg: None)


def _background(
    todo: list[tuple[str, str | None]], out: str, studies: str | None, results: Any
) -> None:
    """Child process: run ``todo`` one after another; put each result on ``results``.

    Puts ``("done", key, summary, seconds)`` per step, ``("error", key, message)``
    and stops at the first failure. Ignores Ctrl-C (the parent stops it).
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    folder = Path(studies) if studies else None
    for key, module in todo:
        t0 = time.perf_counter()
        try:
            value = _compute_step(key, module, Path(out) / key, folder)
        except Exception as exc:  # noqa: BLE001 - reported by the parent
            results.put(("error", key, f"{type(exc).__name__}: {exc}"))
            return
        results.put(("done", key, value, round(time.perf_counter() - t0, 1)))


#: Rough CPU seconds of each step on this 2-core machine (warm compile cache), used
#: only to share the side steps out evenly between the background processes.
STEP_WEIGHTS = {
    "demo": 2.0, "fig02_05": 3.0, "fig06_09": 1.0, "fig10_15": 15.0, "fig21_23": 20.0,
    "sensitivity": 13.0, "cycles": 10.0,
}  # fmt: skip


def _groups(todo: list[tuple[str, str | None]], n: int) -> list[list[tuple[str, str | None]]]:
    """``todo`` in at most ``n`` groups of about equal weight (longest first), in step order."""
    n = max(1, min(n, len(todo)))
    load: list[float] = [0.0] * n
    groups: list[list[int]] = [[] for _ in range(n)]
    order = sorted(range(len(todo)), key=lambda i: -STEP_WEIGHTS.get(todo[i][0], 5.0))
    for i in order:
        g = min(range(n), key=load.__getitem__)
        groups[g].append(i)
        load[g] += STEP_WEIGHTS.get(todo[i][0], 5.0)
    return [[todo[i] for i in sorted(g)] for g in groups if g]


class _Background:
    """Steps running in child processes (one per group) while this one runs the sweep step."""

    def __init__(
        self, groups: list[list[tuple[str, str | None]]], out: Path, studies: Path | None
    ) -> None:
        ctx = multiprocessing.get_context("spawn")
        self.results: Any = ctx.Queue()
        self.pending = [k for g in groups for k, _ in g]
        self.procs = []
        for i, todo in enumerate(groups):
            proc = ctx.Process(
                target=_background,
                args=(todo, str(out), str(studies) if studies else None, self.results),
                name=f"broachkit-reproduce-steps-{i}",
            )
            proc.start()
            self.procs.append((proc, [k for k, _ in todo]))

    def poll(self, timeout: float) -> tuple[Any, ...] | None:
        """One message of a child, or ``None`` after ``timeout`` s."""
        try:
            return self.results.get(timeout=timeout)
        except queue.Empty:
            return None

    def dead(self) -> tuple[list[str], int | None] | None:
        """Pending steps of a child that ended without reporting them, and its exit code."""
        for proc, keys in self.procs:
            left = [k for k in keys if k in self.pending]
            if left and not proc.is_alive():
                return left, proc.exitcode
        return None

    def stop(self) -> None:
        """End the children (finished steps were reported already)."""
        for proc, _ in self.procs:
            if proc.is_alive():
                proc.terminate()
        for proc, _ in self.procs:
            proc.join(5.0)


def _workers(args: argparse.Namespace) -> int:
    n = args.workers
    if n is None:
        env = os.environ.get(WORKERS_ENV, "").strip()
        n = int(env) if env.isdigit() else (os.cpu_count() or 1)
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"--workers must be a positive integer, got {n!r}")
    return n


def _cpu_seconds() -> float:
    """User + system CPU time of this process and its finished children (s)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


class Progress:
    """One progress display for the whole job.

    On a terminal: one status line, rewritten in place (``[k/n] step: message``, the
    elapsed time of the job); elsewhere (a log, a pipe): one line per step. Sub-step
    messages also go to the log (shown with ``--verbose``).
    """

    def __init__(self, n: int, *, enabled: bool) -> None:
        self.n = n
        self.enabled = enabled
        self.live = enabled and sys.stderr.isatty()
        self.width = max(40, min(shutil.get_terminal_size((100, 24)).columns, 160) - 1)
        self.t0 = time.perf_counter()
        self.head = ""

    def _show(self, text: str) -> None:
        line = f"{self.head}{text}"[: self.width]
        sys.stderr.write("\r" + line.ljust(self.width))
        sys.stderr.flush()

    def start(self, i: int, key: str, title: str, skipped: bool = False) -> None:
        """Step ``i`` (1-based) begins (or is skipped because it is done)."""
        tail = " (done earlier)" if skipped else ""
        if self.live:
            self.head = f"[{i}/{self.n}] {title}{tail}"
            self._show(f" ({time.perf_counter() - self.t0:.0f} s)")
        elif self.enabled:
            sys.stderr.write(f"[{i}/{self.n}] {title}{tail}\n")
            sys.stderr.flush()

    def message(self, msg: str) -> None:
        """A sub-step message: on the status line, and in the log (``--verbose``)."""
        if self.live:
            self._show(f": {' '.join(msg.split())} ({time.perf_counter() - self.t0:.0f} s)")
        log.info("  %s", msg)

    def finish(self) -> None:
        """One step finished."""

    def close(self) -> None:
        """End the status line."""
        if self.live and self.head:
            sys.stderr.write("\r" + " " * self.width + "\r")
            sys.stderr.flush()
            self.head = ""


def _get(d: Any, *keys: Any) -> Any:
    for k in keys:
        if isinstance(d, dict) and k in d:
            d = d[k]
        elif isinstance(d, list) and isinstance(k, int) and -len(d) <= k < len(d):
            d = d[k]
        else:
            return None
    return d


def key_numbers(results: dict[str, Any]) -> dict[str, Any]:
    """The run's headline numbers: the critical Fn by both methods, the curve's ends.

    ``None`` for a number whose step did not run.
    """
    crit = _get(results, "fig10_15", "critical") or {}
    bis_fn = crit.get("Fn", crit.get("fn_critical"))
    curve = _get(results, "fig21_23", "curve") or {}
    ends = None
    if curve.get("chi_c_deg"):
        ends = [{"chi_c_deg": curve["chi_c_deg"][i], "Fn": curve["Fn"][i]} for i in (0, -1)]
    return {
        "chi_c_deg": _get(results, "fig21_23", "chi_c_deg")
        or _get(results, "fig10_15", "chi_c_deg"),
        "Fn_bvp": _get(results, "fig21_23", "bvp", "Fn"),
        "Fn_bisection": bis_fn,
        "Fn_bisection_bracket": crit.get("bracket"),
        "Fn_bisection_fig21_23": _get(results, "fig21_23", "bisection", "Fn"),
        "critical_curve_ends": ends,
    }


def _figures(out: Path, keys: list[str]) -> list[str]:
    figs: list[str] = []
    for key in keys:
        figs += sorted(str(p.relative_to(out)) for p in (out / key).glob("*.png"))
    return figs


def _versions() -> dict[str, str]:
    from importlib import metadata

    v = {"python": platform.python_version(), "platform": platform.platform()}
    for pkg in ("broachkit", "numpy", "scipy", "casadi", "matplotlib", "jinja2"):
        try:
            v[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            v[pkg] = "not installed"
    return v


def _summary_text(doc: dict[str, Any]) -> str:
    from studies.paper import PAPER_FN_10DEG

    k = doc["key_numbers"]
    lines = [f"broachkit reproduce: {len(doc['steps'])} step(s) in {doc['total_seconds']:.1f} s"]

    def f(x: Any, fmt: str = ".7f") -> str:
        return "n/a" if x is None else format(x, fmt)

    if k["Fn_bvp"] is not None or k["Fn_bisection"] is not None:
        lo_hi = k["Fn_bisection_bracket"] or [None, None]
        lines.append(
            f"  critical Fn at chi_c = {f(k['chi_c_deg'], 'g')} deg: {f(k['Fn_bvp'], '.8f')} "
            f"(connecting orbit), {f(k['Fn_bisection'])} in [{f(lo_hi[0])}, {f(lo_hi[1])}] "
            f"(bisection); Umeda (1999): {PAPER_FN_10DEG[0]}-{PAPER_FN_10DEG[1]}"
        )
    if k["critical_curve_ends"]:
        a, b = k["critical_curve_ends"]
        lines.append(
            f"  critical curve: Fn = {f(a['Fn'], '.5f')} at {a['chi_c_deg']:g} deg "
            f"... {f(b['Fn'], '.5f')} at {b['chi_c_deg']:g} deg"
        )
    lines.append(f"  {len(doc['figures'])} figures; data in {doc['out']}")
    if doc.get("report"):
        lines.append(f"  report: {doc['report']}")
    return "\n".join(lines) + "\n"


def run(args: argparse.Namespace) -> int:
    """Run the steps; 0 when every step ran, 130 when interrupted."""
    before = os.environ.get(WORKERS_ENV)
    try:
        return _run(args)
    finally:  # the job's worker count is not left behind in this process
        if before is None:
            os.environ.pop(WORKERS_ENV, None)
        else:
            os.environ[WORKERS_ENV] = before


def _run(args: argparse.Namespace) -> int:
    out = prepare_out(args.out)
    assert out is not None
    steps = _steps(args)
    workers = _workers(args)
    os.environ[WORKERS_ENV] = str(workers)  # the studies' sweeps read it (and child processes)
    modules: dict[str, str | None] = {"demo": None, **{k: m for k, _, m in STUDY_STEPS}}
    results: dict[str, Any] = {}
    timing: dict[str, float] = {}
    t_all = time.perf_counter()
    started = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    bar = Progress(len(steps), enabled=not args.json)
    todo: list[tuple[int, str, str, Callable[[Path, Callable[[str], None]], Any]]] = []
    for i, (key, title, fn) in enumerate(steps, 1):
        folder = out / key
        if is_complete(folder) and not args.force:
            bar.start(i, key, title, skipped=True)
            results[key] = json.loads((folder / "summary.json").read_text())
            bar.finish()
            continue
        if args.force:  # a forced rerun starts its sweeps afresh
            shutil.rmtree(folder / SWEEP_DIR, ignore_errors=True)
        todo.append((i, key, title, fn))
    # with several workers, the other steps run in child processes (one per worker,
    # balanced by STEP_WEIGHTS) beside the sweep step
    side = None
    if workers > 1 and len(todo) > 1 and any(k == SWEEP_STEP for _, k, _, _ in todo):
        others = [(k, modules.get(k)) for _, k, _, _ in todo if k != SWEEP_STEP]
        for k, _ in others:
            mark_incomplete(out / k)
        side = _Background(_groups(others, workers), out, args.studies)
        todo = [t for t in todo if t[1] == SWEEP_STEP]
        log.info("steps %s run in a background process", ", ".join(k for k, _ in others))
    try:
        for i, key, title, fn in todo:
            folder = out / key
            bar.start(i, key, title)
            mark_incomplete(folder)
            t0 = time.perf_counter()
            try:
                results[key] = fn(folder, bar.message)
            except KeyboardInterrupt:
                acknowledge()
                bar.close()
                sys.stderr.write(
                    f"interrupted during {key}; finished steps are kept in {out} "
                    "(a rerun redoes this one)\n"
                )
                return 130
            mark_complete(folder)
            timing[key] = round(time.perf_counter() - t0, 1)
            log.info("%s: done in %.1f s", key, timing[key])
            bar.finish()
        while side is not None and side.pending:
            bar.message(f"waiting for {', '.join(side.pending)} (background process)")
            msg = side.poll(1.0)
            if msg is None:
                if side.dead() is not None:
                    msg = side.poll(1.0)  # a message sent just before it ended
                    gone = side.dead()
                    if msg is None and gone is not None:
                        raise RuntimeError(
                            f"the background process running {', '.join(gone[0])} died "
                            f"(exit code {gone[1]})"
                        )
                if msg is None:
                    continue
            if msg[0] == "error":
                raise RuntimeError(f"step {msg[1]} failed: {msg[2]}")
            _, key, value, seconds = msg
            results[key], timing[key] = value, seconds
            mark_complete(out / key)
            side.pending.remove(key)
            log.info("%s: done in %.1f s (background)", key, seconds)
    except KeyboardInterrupt:
        acknowledge()
        bar.close()
        sys.stderr.write(
            f"interrupted; finished steps are kept in {out} (a rerun redoes the rest)\n"
        )
        return 130
    finally:
        bar.close()
        if side is not None:
            while side.pending and (msg := side.poll(0.05)) is not None:  # keep what finished
                if msg[0] == "done":
                    mark_complete(out / msg[1])
                    side.pending.remove(msg[1])
            side.stop()
    results = {k: results[k] for k, _, _ in steps if k in results}  # in step order
    timing = {k: timing[k] for k, _, _ in steps if k in timing}
    total = round(time.perf_counter() - t_all, 1)
    keys = list(results)
    doc: dict[str, Any] = {
        "steps": keys,
        "seconds": timing,
        "total_seconds": total,
        "cpu_seconds": round(_cpu_seconds(), 1),
        "workers": workers,
        "out": str(out),
        "key_numbers": key_numbers(results),
        "figures": _figures(out, keys),
        "versions": _versions(),
        "started": started,
        "settings": {
            "out": str(out),
            "only": " ".join(args.only) if args.only else "all steps",
            "force": bool(args.force),
            "studies": str(args.studies) if args.studies else "packaged",
            "vessel": "purse_seiner (the studies' default vessel)",
        },
        "report": None,
    }
    if not args.no_report:
        from ..report import write_report

        doc["report"] = str(write_report(out, results, doc))
    write_json(out / "reproduce.json", doc)
    if args.json:
        sys.stdout.write(json.dumps(json_safe(doc), indent=2) + "\n")
    else:
        sys.stdout.write(_summary_text(doc))
    return 0
