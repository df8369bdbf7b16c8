"""Module-level tasks for tests/test_sweep.py (importable by worker processes).

Every task appends one file to ``key["log"]`` when it *finishes* an execution, so a test
counts how often each key really ran, whichever process or machine ran it.
"""

from __future__ import annotations

import os
import time
import uuid
from pathlib import Path
from typing import Any


def _ran(key: dict[str, Any], tag: str = "") -> None:
    d = Path(key["log"])
    d.mkdir(parents=True, exist_ok=True)
    (d / f"ran-{key['x']}{tag}-{uuid.uuid4().hex}").touch()


def runs(log: str | Path, x: Any) -> int:
    """Finished executions of the task with ``key["x"] == x``."""
    return len(list(Path(log).glob(f"ran-{x}-*")))


def square(key: dict[str, Any]) -> dict[str, Any]:
    """``y = x**2`` and ``x/3`` (a float whose repr must survive every backend)."""
    time.sleep(float(key.get("sleep", 0.0)))
    _ran(key)
    x = key["x"]
    return {"y": x * x, "third": x / 3.0, "pid_free": [x, "a"]}


def crash_once(key: dict[str, Any]) -> dict[str, Any]:
    """Kill its own worker process (``os._exit``) on the first try when ``key["crash"]``."""
    marker = Path(key["log"]) / f"crashed-{key['x']}"
    if key.get("crash") and not marker.exists():
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.touch()
        time.sleep(0.2)
        os._exit(3)
    return square(key)


def fail_once(key: dict[str, Any]) -> dict[str, Any]:
    """Raise on the first try when ``key["fail"]`` is 1; always when it is 2."""
    marker = Path(key["log"]) / f"failed-{key['x']}"
    if key.get("fail") == 2 or (key.get("fail") == 1 and not marker.exists()):
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.touch()
        raise ArithmeticError(f"planned failure of x = {key['x']}")
    return square(key)


def interrupt_at(key: dict[str, Any]) -> dict[str, Any]:
    """Raise ``KeyboardInterrupt`` (a Ctrl-C in the sweep's process) at ``key["stop"]``."""
    if key.get("stop"):
        raise KeyboardInterrupt
    return square(key)


def chatter(key: dict[str, Any]) -> dict[str, Any]:
    """Log a warning and an error from a library logger, then :func:`square`."""
    import logging

    log = logging.getLogger("continuation.sweep_test_chatter")
    log.warning("worker warning %s", key["x"])
    log.error("worker error %s", key["x"])
    return square(key)
