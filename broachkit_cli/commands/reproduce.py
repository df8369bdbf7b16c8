"""``broachkit reproduce`` (the default): reproduce the paper's results with the default vessel.

Runs the study steps in order, shows progress on stderr, and writes figures (PNG) and
data (CSV/NPZ/JSON) under ``--out/<step>``:

========== =========================================== ===================================
step       what                                        script
========== =========================================== ===================================
demo       engine demo (Bratu fold, Brusselator Hopf)   ``broachkit demo``
fig02_05   fixed points against chi_c and Fn           ``studies/fig02_05_fixed_points.py``
fig06_09   eigenvalues and unstable eigenvectors       ``studies/fig06_09_eigen.py``
fig10_15   critical Fn, unstable manifolds             ``studies/fig10_15_manifolds.py``
fig21_23   connecting orbit, critical curve            ``studies/fig21_23_connection.py``
fig16_22   sudden-change experiments                   ``studies/fig16_22_sudden_change.py``
========== =========================================== ===================================

A step whose ``summary.json`` is already on disk is skipped unless ``--force``;
``--only`` runs a subset. An interrupted run keeps the steps that finished. The study
steps are the scripts in the repository's ``studies/`` folder (``--studies`` to point
elsewhere); they are loaded by path, so an installed package without that folder runs
only the demo and says so.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import logging
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

from . import demo

NAME = "reproduce"
HELP = "reproduce the paper's results with the default vessel (the default command)"

log = logging.getLogger("broachkit")

#: Study steps: (key, title, script file in the studies folder).
STUDY_STEPS: tuple[tuple[str, str, str], ...] = (
    (
        "fig02_05",
        "Figs. 2-5: fixed points against the autopilot course",
        "fig02_05_fixed_points.py",
    ),
    ("fig06_09", "Figs. 6-9: eigenvalues and unstable eigenvectors", "fig06_09_eigen.py"),
    ("fig10_15", "Figs. 10-15: critical Fn and unstable manifolds", "fig10_15_manifolds.py"),
    (
        "fig21_23",
        "Figs. 21, 23: connecting orbit and critical Fn against the course",
        "fig21_23_connection.py",
    ),
    (
        "fig16_22",
        "Figs. 16-22: sudden-change experiments and the Fig. 23 squares",
        "fig16_22_sudden_change.py",
    ),
)


def default_studies_dir() -> Path:
    """The repository's ``studies/`` folder (next to the package folders)."""
    return Path(__file__).resolve().parents[2] / "studies"


def load_study(path: Path) -> ModuleType:
    """Import a study script by its path (it must define ``compute(out, progress)``).

    Raises
    ------
    ValueError
        If the file does not exist or defines no ``compute``.
    """
    if not path.is_file():
        raise ValueError(f"study script not found: {path} (use --studies DIR)")
    spec = importlib.util.spec_from_file_location(f"broachkit_study_{path.stem}", path)
    if spec is None or spec.loader is None:  # pragma: no cover - a .py file always has one
        raise ValueError(f"cannot load study script {path}")
    folder = str(path.parent)
    if folder not in sys.path:
        sys.path.insert(0, folder)  # the scripts import their `_common` helpers
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    if not callable(getattr(mod, "compute", None)):
        raise ValueError(f"study script {path} defines no `compute(out, progress)`")
    return mod


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit reproduce``."""
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder")
    parser.add_argument("--force", action="store_true", help="recompute finished steps")
    parser.add_argument(
        "--only",
        nargs="+",
        default=None,
        metavar="STEP",
        help="run only these steps (demo, " + ", ".join(k for k, _, _ in STUDY_STEPS) + ")",
    )
    parser.add_argument(
        "--studies", type=Path, default=None, help="folder of the study scripts (default: repo)"
    )


def _steps(args: argparse.Namespace) -> list[tuple[str, str, Callable[..., Any]]]:
    steps: list[tuple[str, str, Callable[..., Any]]] = [
        (
            "demo",
            "engine demo (Bratu fold, Brusselator Hopf)",
            lambda out, progress: demo.compute(out),
        )
    ]
    folder = args.studies if args.studies is not None else default_studies_dir()
    if folder.is_dir():
        for key, title, script in STUDY_STEPS:
            path = folder / script

            def fn(out: Path, progress: Callable[[str], None], _p: Path = path) -> Any:
                return load_study(_p).compute(out, progress=progress)

            steps.append((key, title, fn))
    elif args.studies is not None:
        raise ValueError(f"--studies: {folder} is not a folder")
    else:
        log.warning("studies folder %s not found: running the engine demo only", folder)
    keys = [k for k, _, _ in steps]
    if args.only:
        unknown = [k for k in args.only if k not in keys]
        if unknown:
            raise ValueError(f"--only: unknown step(s) {unknown}; steps are {keys}")
        steps = [s for s in steps if s[0] in args.only]
    return steps


def run(args: argparse.Namespace) -> int:
    """Run the steps; returns 0 when every step succeeded, 130 when interrupted."""
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    steps = _steps(args)
    results: dict[str, Any] = {}
    timing: dict[str, float] = {}
    t_all = time.perf_counter()
    for i, (key, title, fn) in enumerate(steps, 1):
        done = out / key / "summary.json"
        if done.exists() and not args.force:
            log.info("[%d/%d] %s: already done (%s)", i, len(steps), title, done)
            results[key] = json.loads(done.read_text())
            continue
        t0 = time.perf_counter()
        log.info("[%d/%d] %s ...", i, len(steps), title)

        def progress(msg: str, _i: int = i) -> None:
            log.info("[%d/%d]   %s", _i, len(steps), msg)

        try:
            results[key] = fn(out / key, progress)
        except KeyboardInterrupt:
            log.warning("interrupted during %s; finished steps are kept in %s", key, out)
            return 130
        timing[key] = round(time.perf_counter() - t0, 1)
        log.info("[%d/%d] %s: done in %.1f s", i, len(steps), title, timing[key])
    total = round(time.perf_counter() - t_all, 1)
    log.info("all steps finished in %.1f s; results in %s", total, out)
    summary = {"steps": list(results), "seconds": timing, "total_seconds": total}
    (out / "reproduce.json").write_text(json.dumps(summary, indent=2))
    sys.stdout.write(json.dumps(summary, indent=2) + "\n")
    return 0
