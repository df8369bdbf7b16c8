"""``broachkit reproduce`` (the default): reproduce the paper with the default vessel.

Runs every registered study step in order, shows progress on stderr, and writes
figures (PNG) and data (CSV/NPZ/JSON) under ``--out``. A step whose results are
already on disk is skipped unless ``--force``; an interrupted run keeps what
finished.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

from . import demo

NAME = "reproduce"
HELP = "reproduce the paper's results with the default vessel (the default command)"

log = logging.getLogger("broachkit")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit reproduce``."""
    parser.add_argument("--out", type=Path, default=Path("out"), help="output folder")
    parser.add_argument("--force", action="store_true", help="recompute finished steps")


def run(args: argparse.Namespace) -> int:
    """Run all steps; returns 0 when every step succeeded."""
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    steps = [("engine demo (Bratu fold, Brusselator Hopf)", "demo", demo.compute)]
    results = {}
    for i, (title, key, fn) in enumerate(steps, 1):
        done = out / key / "summary.json"
        if done.exists() and not args.force:
            log.info("[%d/%d] %s: already done (%s)", i, len(steps), title, done)
            results[key] = json.loads(done.read_text())
            continue
        t0 = time.perf_counter()
        log.info("[%d/%d] %s ...", i, len(steps), title)
        results[key] = fn(out / key)
        log.info("[%d/%d] %s: done in %.1f s", i, len(steps), title, time.perf_counter() - t0)
    sys.stdout.write(json.dumps(results, indent=2) + "\n")
    return 0
