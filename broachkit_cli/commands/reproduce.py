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

A step whose folder holds ``summary.json``, no ``.incomplete`` marker and a record of
the inputs it was computed from (``inputs.json``: the vessel file's content, the
settings, the code version; :mod:`broachkit_cli.step_inputs`) equal to this run's is
reused unless ``--force``; any other step is computed (again), and the summary names
the steps reused and the reason each other step was recomputed. A step that was
interrupted (the marker is still there) is redone, resuming its sweep from the
checkpoints in ``<step>/sweep`` (themselves keyed by their inputs and the code
version, :mod:`continuation.sweep`; ``--force`` deletes them).

On ``--workers N`` local processes (default one per core; ``N = 1``: everything in
this process): one pool of ``N`` worker processes (:mod:`continuation.sweep`) serves
the whole job. The other steps are its tasks, handed to it heaviest first
(:data:`STEP_WEIGHTS`) one per free worker (:class:`_SideSteps`); the sudden-change
step (:data:`SWEEP_STEP`) runs in this process (its old periodic orbits too) and puts
its bisections and map rows on the same pool (``N`` is passed to it
as an argument; ``$BROACHKIT_WORKERS`` is the default of ``--workers``), so a worker
that finishes a step takes the next task, whichever step it belongs to. Every step
computes exactly what it computes alone, so the outputs do not depend on ``N``.
``--only`` runs a subset. The studies are the package :mod:`studies`, installed with
broachkit (``--studies DIR`` loads the scripts of another folder instead).
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import contextlib
import datetime
import importlib
import importlib.util
import inspect
import json
import logging
import platform
import resource
import shutil
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

from ..files import is_complete, mark_complete, mark_incomplete, write_json
from ..interrupt import acknowledge
from ..options import add_json, add_out, check_workers, prepare_out, print_json
from ..step_inputs import INPUTS_FILE, compare, read_record, step_inputs, vessel_file
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


#: Steps run only when named in ``--only`` (slow, or needing an extra).
OPTIONAL_STEPS: tuple[tuple[str, str, str], ...] = (
    ("diffraction", "Wave forces with diffraction (panel method, the hull extra)", "diffraction"),
)

#: The step that runs its own sweep on worker processes (in this process).
SWEEP_STEP = "fig16_22"
#: A step's sub-folder of sweep checkpoints (resumed after an interruption).
SWEEP_DIR = "sweep"


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
        help="run only these steps (demo, "
        + ", ".join(k for k, _, _ in STUDY_STEPS)
        + "; optional: "
        + ", ".join(k for k, _, _ in OPTIONAL_STEPS)
        + ")",
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
    optional = [s for s in OPTIONAL_STEPS if args.only and s[0] in args.only]
    for key, title, module in (*STUDY_STEPS, *optional):

        def fn(out: Path, progress: Callable[[str], None], _m: str = module) -> Any:
            return study_module(_m, folder).compute(out, progress=progress)

        steps.append((key, title, fn))
    keys = [k for k, _, _ in steps] + [k for k, _, _ in OPTIONAL_STEPS if k not in
                                         {s[0] for s in steps}]  # fmt: skip
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


def _step_task(key: str, module: str | None, out: str, studies: str | None) -> tuple[Any, float]:
    """Pool task: run one step by name; its summary and its seconds."""
    t0 = time.perf_counter()
    value = _compute_step(key, module, Path(out) / key, Path(studies) if studies else None)
    return value, round(time.perf_counter() - t0, 1)


#: Rough CPU seconds of each step on this 2-core machine (warm compile cache), used
#: only to submit the side steps heaviest first (the pool then balances them).
STEP_WEIGHTS = {
    "demo": 2.0, "fig02_05": 2.5, "fig06_09": 1.0, "fig10_15": 8.0, "fig21_23": 40.0,
    "sensitivity": 11.0, "cycles": 7.5,
}  # fmt: skip


def _heaviest_first(todo: list[tuple[str, str | None]]) -> list[tuple[str, str | None]]:
    """``todo`` by decreasing :data:`STEP_WEIGHTS` (unknown steps: 5), ties in step order."""
    return sorted(todo, key=lambda kv: -STEP_WEIGHTS.get(kv[0], 5.0))


class _SideSteps:
    """The steps other than the sweep step, as tasks of the job's process pool.

    The sweep step's own tasks go to the same pool (one pool of ``--workers``
    processes for the whole job: nothing starts twice, and a worker that finishes a
    step takes the next task, whichever step it belongs to).

    The steps are handed to the pool heaviest first and only as workers free up: one
    per worker at the start, the next one when one finishes (a callback). So the
    sweep step's tasks, submitted meanwhile, run before the lighter side steps, and
    these fill the workers at the end of the job while this process finishes the
    sweep step's figures (no worker idles while the job's last step runs here).
    """

    def __init__(
        self, pool: Any, todo: list[tuple[str, str | None]], out: Path, studies: Path | None
    ) -> None:
        self.pool = pool
        self.pending = [k for k, _ in todo]
        self.futures: dict[Any, str] = {}
        self._queue = _heaviest_first(todo)
        self._args = (str(out), str(studies) if studies else None)
        self._lock = threading.Lock()
        self._closed = False
        for _ in range(min(max(int(getattr(pool, "slots", 1)), 1), len(self._queue))):
            self._submit_next()

    def _submit_next(self, _done: Any = None) -> None:
        """Hand the next step to the pool (also the done-callback of each step's future)."""
        with self._lock:
            if self._closed or not self._queue:
                return
            key, module = self._queue.pop(0)
            fut = self.pool.executor.submit(_step_task, key, module, *self._args)
            self.futures[fut] = key
        fut.add_done_callback(self._submit_next)

    def finished(self, timeout: float) -> list[tuple[str, Any, float]]:
        """Steps finished within ``timeout`` s: ``(key, summary, seconds)``.

        Raises
        ------
        RuntimeError
            Naming the step, if one failed or its worker died.
        """
        with self._lock:
            futures = list(self.futures)
        done, _ = cf.wait(futures, timeout=timeout, return_when=cf.FIRST_COMPLETED)
        out = []
        for fut in done:
            with self._lock:
                key = self.futures.pop(fut)
            try:
                value, seconds = fut.result()
            except cf.BrokenExecutor as exc:
                raise RuntimeError(f"the worker process running {key} died ({exc})") from None
            except Exception as exc:  # noqa: BLE001 - reported with the step's name
                raise RuntimeError(f"step {key} failed: {exc}") from None
            self.pending.remove(key)
            out.append((key, value, seconds))
        return out

    def cancel(self) -> None:
        """Drop the steps not started yet (the pool's close stops the running ones)."""
        with self._lock:
            self._closed = True
            self._queue.clear()
            futures = list(self.futures)
        for fut in futures:
            fut.cancel()


#: The steps that start from the connection at 10 deg (:func:`studies._model.heteroclinic`).
CONNECTION_STEPS = ("fig21_23", "fig16_22", "sensitivity", "cycles")


def _pool_start(studies: Path | None, connection: bool = False) -> str:
    """Start method of the job's pool: ``"fork"`` after loading what every worker needs.

    Every worker imports the studies and the ship model and builds the default vessel's
    model (:func:`studies._model.default_model`), about 1.5 CPU-s each when spawned.
    The sweep step needs all of it in this process too, so it is loaded here first and
    the workers are forked from this process (Linux, one thread running, as
    :func:`continuation.sweep.forked.can_fork` requires): they start with it in memory.
    The steps compute the same numbers either way (the model holds functions, not
    results; :mod:`studies._model`). Elsewhere, or with ``--studies`` (scripts loaded
    by path), the workers are spawned.

    With ``connection``, the heteroclinic connection at 10 deg that four steps start
    from (:func:`studies._model.heteroclinic`) is solved here first, once, about 1 s:
    every worker inherits it and the connection solver's functions, instead of each
    step solving it again. If it fails, the steps solve it and report it themselves.
    """
    from continuation.sweep.forked import can_fork

    if studies is not None or not can_fork():
        return "spawn"
    import studies._common  # noqa: F401 - the plotting helpers every study imports
    from studies._model import default_model, heteroclinic

    default_model()
    if connection:
        try:
            heteroclinic(10.0)
        except Exception as exc:  # noqa: BLE001 - the steps solve it again and report it
            log.info("the shared connection at 10 deg failed here: %s", exc)
    return "fork" if can_fork() else "spawn"


def _workers(args: argparse.Namespace) -> int:
    """``--workers``, else ``$BROACHKIT_WORKERS`` when set, else one per core (checked)."""
    return check_workers(args.workers)


def _inputs_of_steps(
    steps: list[Step], modules: dict[str, str | None], studies: Path | None
) -> dict[str, dict[str, Any]]:
    """The inputs of each step (:func:`~broachkit_cli.step_inputs.step_inputs`)."""
    settings = {"studies": str(studies.resolve()) if studies else "packaged"}
    vessel = vessel_file()
    inputs: dict[str, dict[str, Any]] = {}
    for key, _, _ in steps:
        module = modules.get(key)
        script = None
        if module is not None:
            if studies is not None:
                script = studies / f"{module}.py"
            else:
                spec = importlib.util.find_spec(f"studies.{module}")
                script = Path(spec.origin) if spec and spec.origin else None
        if module is not None and (script is None or not script.is_file()):
            raise ValueError(f"--studies: study script not found: {script}")
        inputs[key] = step_inputs(key, script, vessel=vessel, settings=settings)
    return inputs


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
        tail = " (done earlier with the same inputs)" if skipped else ""
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
        fin = [i for i, f in enumerate(curve["Fn"]) if f is not None and f == f]
        if fin:
            ends = [{"chi_c_deg": curve["chi_c_deg"][i], "Fn": curve["Fn"][i]}
                    for i in (fin[0], fin[-1])]  # fmt: skip
    return {
        "chi_c_deg": _get(results, "fig21_23", "chi_c_deg")
        or _get(results, "fig10_15", "chi_c_deg"),
        "Fn_bvp": _get(results, "fig21_23", "bvp", "Fn"),
        "Fn_bisection": bis_fn,
        "Fn_bisection_bracket": crit.get("bracket"),
        "Fn_bisection_fig21_23": _get(results, "fig21_23", "bisection", "Fn"),
        "critical_curve_ends": ends,
        "heteroclinic_end": (
            {"chi_c_deg": curve.get("end_chi_c_deg"), "Fn": curve.get("end_Fn")}
            if curve.get("end_chi_c_deg") is not None
            else None
        ),
        "threshold": _threshold_numbers(_get(results, "fig21_23", "threshold")),
    }


def _threshold_numbers(th: Any) -> dict[str, Any] | None:
    """The capsizing threshold per course and where it parts from the heteroclinic Fn."""
    if not th:
        return None
    t = th["threshold"]
    return {
        "chi_c_deg": t["chi_c_deg"],
        "Fn": t["Fn"],
        "error": t["error"],
        "mechanism": t["mechanism"],
        "Fn_heteroclinic": t["Fn_heteroclinic"],
        "is_heteroclinic": t["is_heteroclinic"],
        "confirmed": t["confirmed"],
        "parting_chi_c_deg": th.get("parting_chi_c_deg"),
    }


def _figures(out: Path, keys: list[str]) -> list[str]:
    figs: list[str] = []
    for key in keys:
        figs += sorted(
            str(p.relative_to(out)) for p in (out / key).glob("*.png") if not p.name.startswith(".")
        )
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
            f"  heteroclinic Fn at chi_c = {f(k['chi_c_deg'], 'g')} deg: "
            f"{f(k['Fn_bvp'], '.8f')} "
            f"(connecting orbit), {f(k['Fn_bisection'])} in [{f(lo_hi[0])}, {f(lo_hi[1])}] "
            f"(bisection); Umeda (1999): {PAPER_FN_10DEG[0]}-{PAPER_FN_10DEG[1]}"
        )
    th = k.get("threshold")
    if th:
        for c, fn, mech in zip(th["chi_c_deg"], th["Fn"], th["mechanism"], strict=True):
            lines.append(
                f"  capsizing threshold at chi_c = {c:g} deg: Fn = {f(fn, '.5f')} ({mech})"
            )
        if th.get("parting_chi_c_deg"):
            a, b = th["parting_chi_c_deg"]
            lines.append(
                f"  the threshold is the heteroclinic Fn up to {a:g} deg, below it from {b:g} deg"
            )
    if k["critical_curve_ends"]:
        a, b = k["critical_curve_ends"]
        lines.append(
            f"  heteroclinic line: Fn = {f(a['Fn'], '.5f')} at {a['chi_c_deg']:g} deg "
            f"... {f(b['Fn'], '.5f')} at {b['chi_c_deg']:g} deg"
        )
    reused = {k: v["reason"] for k, v in doc.get("reuse", {}).items() if v["reused"]}
    redone = {k: v["reason"] for k, v in doc.get("reuse", {}).items() if not v["reused"]}
    if reused:
        why = sorted(set(reused.values()))
        lines.append(
            f"  reused from an earlier run: {', '.join(reused)} ({'; '.join(why)}: "
            "the inputs they were computed from are this run's)"
        )
    if any(reason != "not run before" for reason in redone.values()):
        groups: dict[str, list[str]] = {}
        for k, reason in redone.items():
            groups.setdefault(reason, []).append(k)
        lines.append(
            "  recomputed: "
            + "; ".join(f"{', '.join(ks)} ({reason})" for reason, ks in groups.items())
        )
    lines.append(f"  {len(doc['figures'])} figures; data in {doc['out']}")
    if doc.get("report"):
        lines.append(f"  report: {doc['report']}")
    return "\n".join(lines) + "\n"


def _run_step(
    key: str,
    fn: Callable[[Path, Callable[[str], None]], Any],
    folder: Path,
    say: Callable[[str], None],
    pool: Any,
    module: str | None,
    studies: Path | None,
    workers: int = 1,
) -> Any:
    """Run a step here; the sweep step on ``pool`` (or ``workers`` processes) when its
    ``compute`` takes a ``backend`` (``workers``)."""
    if key != SWEEP_STEP or module is None:
        return fn(folder, say)
    mod = study_module(module, studies)  # loaded once (a --studies script runs on load)
    accepts = inspect.signature(mod.compute).parameters
    kw: dict[str, Any] = {}
    if pool is not None and "backend" in accepts:
        kw["backend"] = pool
    if "workers" in accepts:
        kw["workers"] = workers
    return mod.compute(folder, progress=say, **kw)


def run(args: argparse.Namespace) -> int:
    """Run the steps; 0 when every step ran, 130 when interrupted."""
    return _run(args)


def _run(args: argparse.Namespace) -> int:
    out = prepare_out(args.out)
    assert out is not None
    steps = _steps(args)
    workers = _workers(args)
    modules: dict[str, str | None] = {
        "demo": None, **{k: m for k, _, m in (*STUDY_STEPS, *OPTIONAL_STEPS)}
    }  # fmt: skip
    results: dict[str, Any] = {}
    timing: dict[str, float] = {}
    t_all = time.perf_counter()
    started = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    bar = Progress(len(steps), enabled=not args.json)
    todo: list[tuple[int, str, str, Callable[[Path, Callable[[str], None]], Any]]] = []
    inputs = _inputs_of_steps(steps, modules, args.studies)
    reuse: dict[str, dict[str, Any]] = {}
    for i, (key, title, fn) in enumerate(steps, 1):
        folder = out / key
        if args.force:
            ok, why = False, "--force"
        elif not is_complete(folder):
            ok, why = False, "not finished earlier" if folder.exists() else "not run before"
        else:
            ok, why = compare(read_record(folder), inputs[key])
        reuse[key] = {"reused": ok, "reason": why}
        if ok:
            bar.start(i, key, title, skipped=True)
            results[key] = json.loads((folder / "summary.json").read_text())
            bar.finish()
            continue
        with contextlib.suppress(FileNotFoundError):
            (folder / INPUTS_FILE).unlink()  # the old results no longer match a record
        if args.force:  # a forced rerun starts its sweeps afresh
            shutil.rmtree(folder / SWEEP_DIR, ignore_errors=True)
        todo.append((i, key, title, fn))
    # with several workers: one process pool for the job; the other steps are its tasks
    # (heaviest first), the sweep step runs here and puts its tasks on the same pool
    pool = side = None
    if workers > 1 and len(todo) > 1:
        from continuation.sweep import open_backend

        others = [(k, modules.get(k)) for _, k, _, _ in todo if k != SWEEP_STEP]
        for k, _ in others:
            mark_incomplete(out / k)
        shared = any(k in CONNECTION_STEPS for _, k, _, _ in todo)
        start = _pool_start(args.studies, connection=shared)
        pool = open_backend("processes", workers=workers, start_method=start)
        side = _SideSteps(pool, others, out, args.studies)
        todo = [t for t in todo if t[1] == SWEEP_STEP]
        log.info("steps %s run on %d worker processes", ", ".join(k for k, _ in others), workers)

    def collect(timeout: float) -> None:
        for key, value, seconds in side.finished(timeout) if side is not None else []:
            results[key], timing[key] = value, seconds
            write_json(out / key / INPUTS_FILE, inputs[key])
            mark_complete(out / key)
            log.info("%s: done in %.1f s (worker process)", key, seconds)

    completed = False  # every step ran: the pool has nothing left to run
    try:
        for i, key, title, fn in todo:
            folder = out / key
            bar.start(i, key, title)
            mark_incomplete(folder)
            t0 = time.perf_counter()
            try:
                results[key] = _run_step(
                    key, fn, folder, bar.message, pool, modules.get(key), args.studies, workers
                )
            except KeyboardInterrupt:
                acknowledge()
                bar.close()
                sys.stderr.write(
                    f"interrupted during {key}; finished steps are kept in {out} "
                    "(a rerun redoes this one)\n"
                )
                return 130
            write_json(folder / INPUTS_FILE, inputs[key])
            mark_complete(folder)
            timing[key] = round(time.perf_counter() - t0, 1)
            log.info("%s: done in %.1f s", key, timing[key])
            bar.finish()
        while side is not None and side.pending:
            bar.message(f"waiting for {', '.join(side.pending)} (worker processes)")
            collect(1.0)
        completed = True
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
            try:
                collect(0.0)  # keep what finished
            except RuntimeError:
                pass  # the failure is being reported already
            side.cancel()
        if pool is not None:
            # after Ctrl-C or a failure the pool may still hold the interrupted sweep
            # step's tasks (even when every other step finished): stop them, never wait
            pool.close(cancel=not completed or bool(side and side.pending))
    results = {k: results[k] for k, _, _ in steps if k in results}  # in step order
    timing = {k: timing[k] for k, _, _ in steps if k in timing}
    from studies.fig23_combined import draw as draw_fig23

    draw_fig23(out, results)  # Fig. 23 with both lines and the squares, once both steps ran
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
        "reuse": {k: reuse[k] for k in keys if k in reuse},
        "inputs": {k: inputs[k] for k in keys},
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
        print_json(doc)
    else:
        sys.stdout.write(_summary_text(doc))
    return 0
