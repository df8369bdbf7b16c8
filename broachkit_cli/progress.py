"""A status line for long single commands: rewritten in place on a terminal, else logged.

On a terminal the line shows the latest message and is erased when the command ends;
in a log or a pipe the messages go to :mod:`logging` at INFO (shown with
``--verbose``), so that captured stderr holds only what the user must read.
"""

from __future__ import annotations

import logging
import shutil
import sys

log = logging.getLogger("broachkit")


class StatusLine:
    """``show(msg)`` while working, ``close()`` at the end (also as a context manager)."""

    def __init__(self, *, enabled: bool = True) -> None:
        self.live = enabled and sys.stderr.isatty()
        self.width = max(40, min(shutil.get_terminal_size((100, 24)).columns, 160) - 1)
        self.shown = False

    def show(self, msg: str) -> None:
        """Display ``msg`` (one line)."""
        text = " ".join(str(msg).split())
        if self.live:
            sys.stderr.write("\r" + text[: self.width].ljust(self.width))
            sys.stderr.flush()
            self.shown = True
        log.info("%s", text)

    def close(self) -> None:
        """Erase the line."""
        if self.live and self.shown:
            sys.stderr.write("\r" + " " * self.width + "\r")
            sys.stderr.flush()
            self.shown = False

    def __enter__(self) -> StatusLine:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


__all__ = ["StatusLine"]
