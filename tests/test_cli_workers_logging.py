"""Worker counts: one check with a stated maximum; library and Dask logs quiet by default."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
from pathlib import Path

import pytest

from broachkit_cli.main import configure_logging, main
from continuation.sweep import MAX_WORKERS
from continuation.sweep.backends import WORKER_LOG_ENV

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent


@pytest.mark.parametrize(
    "argv",
    [
        ["sweep", "boundary", "--workers", "100000"],
        ["sweep", "courses", "--processes", "100000"],
        ["reproduce", "--workers", "100000", "--only", "demo"],
        ["critical-curve", "--workers", "100000"],
    ],
)
def test_a_huge_worker_count_is_refused_before_anything_starts(tmp_path, capsys, argv):
    out = [] if argv[0] == "critical-curve" else ["--out", str(tmp_path / "o")]
    assert main([*argv, *out]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"must be at most {MAX_WORKERS}" in err and "got 100000" in err
    assert not list(tmp_path.glob("o/*/summary.json"))


def test_the_environment_count_is_checked_with_the_same_rule(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("BROACHKIT_WORKERS", "100000")
    assert main(["sweep", "boundary", "--out", str(tmp_path / "o")]) == 2
    assert "BROACHKIT_WORKERS must be at most" in capsys.readouterr().err


def test_library_and_dask_messages_are_quiet_unless_verbose(capsys):
    try:
        configure_logging(False)
        logging.getLogger("distributed.worker").warning("dask chatter")
        logging.getLogger("continuation.driver").warning("library chatter")
        logging.getLogger("broachkit_cli.commands.sweep").warning("front-door warning")
        err = capsys.readouterr().err
        assert "chatter" not in err and "front-door warning" in err
        configure_logging(True)
        logging.getLogger("continuation.driver").warning("library chatter")
        assert "library chatter" in capsys.readouterr().err
    finally:
        configure_logging(False)
        root = logging.getLogger()
        for h in [h for h in root.handlers if getattr(h, "_broachkit", False)]:
            root.removeHandler(h)


def _run_code(code: str, env_level: str | None) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    env.pop(WORKER_LOG_ENV, None)
    if env_level is not None:
        env[WORKER_LOG_ENV] = env_level
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS), str(ROOT), env.get("PYTHONPATH", "")])
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, timeout=300, check=False)  # fmt: skip


@pytest.mark.parametrize("backend", ["processes", pytest.param("dask", marks=pytest.mark.slow)])
@pytest.mark.parametrize("level", ["ERROR", None])
def test_spawned_workers_log_only_what_the_front_end_asked_for(tmp_path, backend, level):
    """A spawned worker (process pool, Dask) has no logging configured: without the
    front end's level (``broachkit`` without ``--verbose`` sets ERROR) every library
    warning reached stderr through Python's last-resort handler, once per worker."""
    code = (
        "import sweep_tasks as T\n"
        "from continuation.sweep import run_sweep\n"
        f"keys = [{{'x': i, 'log': {str(tmp_path)!r}}} for i in range(2)]\n"
        f"r = run_sweep(T.chatter, keys, backend={backend!r}, workers=1, progress=False)\n"
        "print(r.status.name, r.n_failed)\n"
    )
    out = _run_code(code, level)
    assert out.stdout.split() == ["SUCCESS", "0"], out.stderr
    assert ("worker warning" in out.stderr) is (level is None), out.stderr
    assert "worker error 0" in out.stderr and "worker error 1" in out.stderr  # errors show


@pytest.mark.parametrize("verbose", [False, True])
def test_forked_children_are_quiet_unless_verbose(verbose):
    """Forked children (``ForkedTasks``) keep the command's logging: a library warning
    in a child shows only with ``--verbose``."""
    code = (
        "import logging\n"
        "from broachkit_cli.main import configure_logging\n"
        "from continuation.sweep.forked import ForkedTasks\n"
        f"configure_logging({verbose})\n"
        "def one(i):\n"
        "    logging.getLogger('continuation.driver').warning('child warning %d', i)\n"
        "    return i\n"
        "with ForkedTasks(one, range(4), children=2) as run:\n"
        "    n = run.n_children\n"
        "    res = run.results()\n"
        "print(n, sorted(res.values()))\n"
    )
    out = _run_code(code, None)
    assert out.returncode == 0, out.stderr
    if "2 [0, 1, 2, 3]" not in out.stdout:
        pytest.skip(f"no forked children here: {out.stdout.strip()}")
    assert ("child warning" in out.stderr) is verbose, out.stderr
