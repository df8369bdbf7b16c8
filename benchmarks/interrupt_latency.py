"""How long does a ``broachkit`` command take to end after Ctrl-C, and what is left?

Ctrl-C at a terminal sends SIGINT to the whole foreground process group; this script
does the same: it starts the command in a new session (its own process group), sends
SIGINT to the group ``t`` seconds after the start, and measures

- ``exit_s``: seconds from the signal until the command exited,
- ``gone_s``: seconds until no process of the group runs any more (zombies and
  multiprocessing's resource tracker, which removes its semaphores after its parent is
  gone, are not counted),
- ``rc``: the exit code (130 for an interrupt, as the rest of the CLI),
- ``traceback``: whether stderr holds a Python traceback or ``KeyboardInterrupt``,
- ``stderr_lines``: the lines written to stderr.

Each delay gets a fresh ``--out`` folder unless ``--same-out`` (then the runs resume one
another). Example (a Dask ``LocalCluster`` sweep, Ctrl-C during the cluster's start and
while its tasks run)::

    python benchmarks/interrupt_latency.py --at 0.5,1,2,4,6,8,10 -- \\
        sweep boundary --positions 12 --tol 1e-6 --no-map --no-progress --workers 2

With ``--after-children 1`` the delays count from the first worker process of the
group (for a Dask sweep: the moment its ``LocalCluster`` starts its workers, which
then take seconds to import their modules). The command after ``--`` is a
``broachkit`` sub-command; ``--out DIR`` is appended.
Used by ``tests/test_cli_interrupt.py``.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any


def group_alive(pgid: int) -> list[str]:
    """Running processes of the group ``pgid`` as ``"pid args"``.

    Zombies and multiprocessing's resource tracker are left out.
    """
    out = subprocess.run(["pgrep", "-g", str(pgid)], capture_output=True, text=True)
    alive = []
    for pid in out.stdout.split():
        cmd = subprocess.run(
            ["ps", "-o", "stat=,args=", "-p", pid], capture_output=True, text=True
        ).stdout.strip()
        if cmd and not cmd.startswith("Z") and "resource_tracker" not in cmd:
            alive.append(f"{pid} {cmd.split(None, 1)[-1][:100]}")
    return alive


def interrupt_at(
    args: list[str],
    at: float,
    out: Path,
    *,
    after_children: int = 0,
    ready: Callable[[], bool] | None = None,
    timeout: float = 30.0,
    env: dict | None = None,
) -> dict[str, Any]:
    """Run ``broachkit ARGS --out OUT``, Ctrl-C its process group after ``at`` seconds.

    Parameters
    ----------
    after_children : int
        Count ``at`` from the moment the group first has this many processes besides
        the command's own (e.g. 1: from the first worker process of a cluster being
        started); 0 counts from the start.
    ready : callable, optional
        Count ``at`` from the moment ``ready()`` is first true (polled; after
        ``after_children``), e.g. when a file the command writes exists.

    Returns
    -------
    dict
        ``at``, ``clock_s`` (seconds from the start to the moment ``at`` was counted
        from), ``rc``, ``exit_s``, ``gone_s``, ``left`` (processes alive at exit),
        ``traceback``, ``stderr_lines``; ``rc`` is None (and ``exit_s`` the timeout)
        when it did not end within ``timeout`` seconds, and ``"finished_before"`` is
        True when it ended before the signal.
    """
    argv = [sys.executable, "-m", "broachkit_cli.main", *args, "--out", str(out)]
    with tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(
            argv, stdout=subprocess.DEVNULL, stderr=err, start_new_session=True, env=env
        )
        t_start = t_clock = time.monotonic()
        finished_before = False
        while after_children and proc.poll() is None:
            if len(group_alive(proc.pid)) > after_children:
                t_clock = time.monotonic()
                break
            time.sleep(0.02)
        while ready is not None and proc.poll() is None:
            if ready():
                t_clock = time.monotonic()
                break
            time.sleep(0.02)
        while time.monotonic() - t_clock < at:
            if proc.poll() is not None:
                finished_before = True
                break
            time.sleep(0.01)
        finished_before = finished_before or proc.poll() is not None
        t0 = time.monotonic()
        rc = None
        left: list[str] = []
        try:
            if not finished_before:
                os.killpg(proc.pid, signal.SIGINT)
            try:
                rc = proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                rc = None
            exit_s = time.monotonic() - t0
            left = group_alive(proc.pid)
            while group_alive(proc.pid) and time.monotonic() - t0 < timeout:
                time.sleep(0.05)
            gone_s = time.monotonic() - t0
        finally:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
        err.seek(0)
        text = err.read()
    return {
        "at": at,
        "clock_s": round(t_clock - t_start, 3),
        "rc": rc if rc is not None else proc.returncode,
        "timed_out": rc is None,
        "finished_before": finished_before,
        "exit_s": round(exit_s, 3),
        "gone_s": round(gone_s, 3),
        "left": left,
        "traceback": "Traceback" in text or "KeyboardInterrupt" in text,
        "stderr_lines": text.splitlines(),
    }


def main(argv: list[str] | None = None) -> int:
    """Command line: ``interrupt_latency.py [--at 1,2] [--out DIR] -- ARGS``."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if "--" not in argv:
        print("usage: interrupt_latency.py [--at T,T] [--same-out] [--out DIR] -- ARGS")
        return 2
    cut = argv.index("--")
    p = argparse.ArgumentParser()
    p.add_argument("--at", default="0.5,1,2,4,6,8,10", help="seconds after the start")
    p.add_argument("--out", type=Path, default=None, help="base folder (default: a temp dir)")
    p.add_argument("--same-out", action="store_true", help="one --out for all (resume)")
    p.add_argument("--json", type=Path, default=None, help="also write the rows here")
    p.add_argument(
        "--after-children",
        type=int,
        default=0,
        help="count --at from when the group has this many processes besides the command",
    )
    opts = p.parse_args(argv[:cut])
    cmd = argv[cut + 1 :]
    base = opts.out or Path(tempfile.mkdtemp(prefix="broachkit-int-"))
    rows = []
    for i, at in enumerate(float(t) for t in opts.at.split(",")):
        out = base / ("run" if opts.same_out else f"run{i}_{at:g}s")
        r = interrupt_at(cmd, at, out, after_children=opts.after_children)
        rows.append(r)
        print(
            f"SIGINT at {at:5.1f} s (+{r['clock_s']:.1f}): rc {r['rc']}, "
            f"exit {r['exit_s']:.2f} s, all gone {r['gone_s']:.2f} s, "
            f"left {len(r['left'])}, traceback {r['traceback']}"
            + (" (finished before the signal)" if r["finished_before"] else "")
            + "".join(f"\n    stderr: {line}" for line in r["stderr_lines"][-3:])
        )
    if opts.json:
        opts.json.write_text(json.dumps(rows, indent=1))
    worst = max(r["gone_s"] for r in rows)
    print(f"worst: all processes gone {worst:.2f} s after the signal")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
