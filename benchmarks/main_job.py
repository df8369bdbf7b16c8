"""Whole-command timings of the main job and two single queries, optionally A/B paired.

Issue 27 asks for three commands timed as whole processes (imports, model, figures,
everything a user waits for), the median of three runs with a warm cache (the compiled
CasADi functions and the GZ disk cache exist; every result is recomputed: the main job
runs with ``--force``), before and after a change, with the machine's processor named:

- ``main``: ``reproduce --out DIR --force --workers 2`` (the main job, 2 workers);
- ``curve``: ``critical-curve --chi-c 0:50 --out DIR`` (the heteroclinic line to its end
  and, by default, the capsizing threshold every 5 deg);
- ``query``: ``fixed-points --fn 0.3248 --chi-c 10 --json`` (one single question).

Each command runs as ``python -m broachkit_cli.main ...`` in a fresh process with
``PYTHONPATH`` set to the checkout being measured (this one, and with ``--baseline
PATH`` also another checkout, e.g. a ``git archive`` of main, run alternately A B A B
so that both see the same machine). Wall time by ``time.perf_counter`` around the
process, CPU time (user + system, the process and its children, e.g. the main job's
worker processes) from ``resource.getrusage(RUSAGE_CHILDREN)``, and the 1-minute load
average before and after each run (the machine is shared: a load above 2 means other
work took CPU from the measured command). One untimed warm-up run of each command and
checkout comes first (``--warmup 0`` skips it).

Python's bytecode cache: where the environment sets ``PYTHONDONTWRITEBYTECODE`` (some
shells and agents do), no ``__pycache__`` is written, so a checkout that never had one
compiles its sources again on every run (about 0.1-0.3 s of a single query; an existing
cache is still read). An installed package, and any second run of a user's, reads its
cache. ``--bytecode`` lets the measured processes write and use the cache whatever the
environment says (the warm-up run writes it); the JSON and the first line printed say
which (``bytecode_cache``).

Run: ``python benchmarks/main_job.py [--commands main curve query] [--repeats 3]
[--baseline DIR] [--bytecode] [--out benchmarks/results/main_job.json]``. Prints one
line per run and a table of medians; writes every number to the JSON file.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a script from anywhere
    sys.path.insert(0, str(ROOT))

from continuation.atomic import write_json  # noqa: E402

#: The timed commands (arguments of ``python -m broachkit_cli.main``); ``{out}`` is a
#: fresh temporary folder per run.
COMMANDS: dict[str, list[str]] = {
    "main": ["reproduce", "--out", "{out}", "--force", "--workers", "2"],
    "curve": ["critical-curve", "--chi-c", "0:50", "--out", "{out}"],
    "query": ["fixed-points", "--fn", "0.3248", "--chi-c", "10", "--json"],
}


def processor() -> str:
    """The processor's model name (``/proc/cpuinfo``), with the core count."""
    name = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                name = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{name}, {os.cpu_count()} cores"


def commit_of(checkout: Path) -> str:
    """``git rev-parse --short HEAD`` of a checkout (plus ``+dirty``), or ``unknown``."""
    try:
        git = {"cwd": checkout, "capture_output": True, "text": True}
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], check=True, **git)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], **git)
        return head.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git checkout)"


def run_once(command: str, checkout: Path, bytecode: bool = False) -> dict[str, Any]:
    """One timed run of ``command`` with the packages of ``checkout``.

    ``bytecode``: the process may read and write Python's bytecode cache even where
    this environment sets ``PYTHONDONTWRITEBYTECODE`` (module docstring).
    """
    env = dict(os.environ, PYTHONPATH=str(checkout))
    if bytecode:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
    with tempfile.TemporaryDirectory(prefix="bk_bench_") as tmp:
        args = [a.replace("{out}", str(Path(tmp) / "out")) for a in COMMANDS[command]]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        load0 = os.getloadavg()[0]
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "broachkit_cli.main", *args], env=env,
                              cwd=tmp, capture_output=True, text=True)  # fmt: skip
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {
        "wall_s": round(wall, 2),
        "cpu_s": round(cpu, 2),
        "load_before": round(load0, 2),
        "load_after": round(os.getloadavg()[0], 2),
        "exit": proc.returncode,
        "stderr_tail": proc.stderr.strip().splitlines()[-1:] if proc.returncode else [],
    }


def main(argv: list[str] | None = None) -> int:
    """Command-line entry (module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--commands", nargs="+", choices=sorted(COMMANDS), default=list(COMMANDS))
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per command (default 3)")
    ap.add_argument("--warmup", type=int, default=1, help="untimed runs first (default 1)")
    ap.add_argument("--baseline", type=Path, default=None,
                    help="another checkout, run alternately with this one (A/B)")  # fmt: skip
    ap.add_argument("--baseline-label", default=None,
                    help="the baseline's name (its commit) if not a git checkout")  # fmt: skip
    ap.add_argument("--bytecode", action="store_true",
                    help="use the bytecode cache even if PYTHONDONTWRITEBYTECODE")  # fmt: skip
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "main_job.json")
    args = ap.parse_args(argv)
    if args.repeats < 1 or args.warmup < 0:
        ap.error("--repeats must be at least 1 and --warmup at least 0")
    sides = {"A": ROOT}
    if args.baseline is not None:
        if not (args.baseline / "broachkit_cli").is_dir():
            ap.error(f"--baseline: {args.baseline} is not a broachkit checkout")
        sides["B"] = args.baseline.resolve()
    labels = {k: commit_of(v) for k, v in sides.items()}
    if args.baseline_label and "B" in labels:
        labels["B"] = args.baseline_label
    doc: dict[str, Any] = {
        "processor": processor(),
        "python": platform.python_version(),
        "started_utc": time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime()),
        "checkouts": {k: {"path": str(v), "commit": labels[k]} for k, v in sides.items()},
        "commands": {k: COMMANDS[k] for k in args.commands},
        "bytecode_cache": (
            "used"
            if args.bytecode or not os.environ.get("PYTHONDONTWRITEBYTECODE")
            else "not written (PYTHONDONTWRITEBYTECODE): sources without one compiled every run"
        ),
        "runs": {k: {s: [] for s in sides} for k in args.commands},
    }
    print(f"# {doc['processor']}; " + "; ".join(f"{k} = {v['commit']} ({v['path']})"
                                              for k, v in doc["checkouts"].items())
          + f"; bytecode cache {doc['bytecode_cache']}")  # fmt: skip
    for command in args.commands:
        for _ in range(args.warmup):
            for side, checkout in sides.items():
                r = run_once(command, checkout, args.bytecode)
                print(f"{command} {side} warm-up: {r['wall_s']:.2f} s", flush=True)
        for i in range(args.repeats):
            for side, checkout in sides.items():
                r = run_once(command, checkout, args.bytecode)
                doc["runs"][command][side].append(r)
                print(f"{command} {side} run {i + 1}: wall {r['wall_s']:.2f} s, CPU "
                      f"{r['cpu_s']:.2f} s, load {r['load_before']:.1f} -> "
                      f"{r['load_after']:.1f}, exit {r['exit']}", flush=True)  # fmt: skip
    summary: dict[str, Any] = {}
    for command, by_side in doc["runs"].items():
        summary[command] = {}
        for side, runs in by_side.items():
            walls = [r["wall_s"] for r in runs]
            summary[command][side] = {
                "median_wall_s": statistics.median(walls),
                "min_wall_s": min(walls),
                "max_wall_s": max(walls),
                "median_cpu_s": statistics.median(r["cpu_s"] for r in runs),
                "loads": [r["load_before"] for r in runs],
            }
        if "B" in by_side:
            ratios = [a["wall_s"] / b["wall_s"] for a, b in
                      zip(by_side["A"], by_side["B"], strict=True)]  # fmt: skip
            summary[command]["A/B_wall_median"] = round(statistics.median(ratios), 3)
    doc["summary"] = summary
    doc["finished_utc"] = time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime())
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_json(args.out, doc)
    print("\n| command | checkout | median wall (min-max) | median CPU | load before runs |")
    print("|---|---|---:|---:|---|")
    for command, by in summary.items():
        for side in sides:
            s = by[side]
            print(f"| {command} | {side} | {s['median_wall_s']:.2f} s ({s['min_wall_s']:.2f}-"
                  f"{s['max_wall_s']:.2f}) | {s['median_cpu_s']:.2f} s | "
                  f"{', '.join(f'{v:.1f}' for v in s['loads'])} |")  # fmt: skip
        if "A/B_wall_median" in by:
            print(f"| {command} | A/B | {by['A/B_wall_median']:.3f} | | |")
    print(f"\nwritten {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
