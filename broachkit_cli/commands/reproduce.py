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
=========== ========================================== =====================================

A step whose folder holds ``summary.json`` and no ``.incomplete`` marker is skipped
unless ``--force``; a step that was interrupted (the marker is still there) is redone.
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
import platform
import shutil
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

from ..files import is_complete, mark_complete, mark_incomplete, write_json
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
)


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
    out = prepare_out(args.out)
    assert out is not None
    steps = _steps(args)
    results: dict[str, Any] = {}
    timing: dict[str, float] = {}
    t_all = time.perf_counter()
    started = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    bar = Progress(len(steps), enabled=not args.json)
    try:
        for i, (key, title, fn) in enumerate(steps, 1):
            folder = out / key
            if is_complete(folder) and not args.force:
                bar.start(i, key, title, skipped=True)
                results[key] = json.loads((folder / "summary.json").read_text())
                bar.finish()
                continue
            bar.start(i, key, title)
            mark_incomplete(folder)
            t0 = time.perf_counter()
            try:
                results[key] = fn(folder, bar.message)
            except KeyboardInterrupt:
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
    finally:
        bar.close()
    total = round(time.perf_counter() - t_all, 1)
    keys = list(results)
    doc: dict[str, Any] = {
        "steps": keys,
        "seconds": timing,
        "total_seconds": total,
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
