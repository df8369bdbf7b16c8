"""``broachkit calibrate``: registration shim; the command lives in :mod:`.sensitivity`."""

from __future__ import annotations

from .sensitivity import CALIBRATE_HELP as HELP
from .sensitivity import CALIBRATE_NAME as NAME
from .sensitivity import add_calibrate_arguments as add_arguments
from .sensitivity import run_calibrate as run

__all__ = ["HELP", "NAME", "add_arguments", "run"]
