"""What every peer adapter returns, so the driver can tabulate them alike."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass
class PeerResult:
    """Outcome of one continuation run by one tool.

    Attributes
    ----------
    steps : int
        Accepted continuation steps (branch points minus the start point).
    special : list of (str, float)
        ``(kind, p)`` of the special points reported by the tool, in branch order;
        ``kind`` is ``"fold"``, ``"hopf"`` or ``"bp"``, or the tool's own label when it
        does not say which (e.g. bice's ``"+"``).
    p_end : float
        Free parameter at the last point.
    status : str
        Why the run stopped, in the tool's words.
    extra : dict
        Tool-specific details (e.g. Newton iterations, number of branches).
    """

    steps: int
    special: list[tuple[str, float]]
    p_end: float
    status: str
    extra: dict[str, Any] = field(default_factory=dict)


class PeerUnavailable(RuntimeError):
    """The peer is not installed or cannot run this problem; the message says why."""


__all__ = ["PeerResult", "PeerUnavailable"]
