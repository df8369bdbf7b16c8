"""A numerical failure of a command is one line on stderr and exit 1, never a traceback
(``broachkit_cli.options.numerical_failure_exit``, used by ``critical`` and
``critical-curve``)."""

from __future__ import annotations

import argparse

import pytest

from broachkit_cli.commands import critical, critical_curve
from continuation.errors import ContinuationError


@pytest.mark.parametrize("command", [critical, critical_curve], ids=lambda m: m.NAME)
def test_numerical_failure_is_one_line_and_exit_1(command, monkeypatch, capsys):
    def fail(args: argparse.Namespace) -> int:
        raise ContinuationError("the connection did not converge")

    monkeypatch.setattr(command, "_run", fail)
    assert command.run(argparse.Namespace()) == 1
    err = capsys.readouterr().err
    assert err == f"broachkit {command.NAME}: the connection did not converge\n"
