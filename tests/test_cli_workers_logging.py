"""Worker counts: one check with a stated maximum; library and Dask logs quiet by default."""

from __future__ import annotations

import logging

import pytest

from broachkit_cli.main import configure_logging, main
from continuation.sweep import MAX_WORKERS


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
