"""Branch switching at simple branch points (see :mod:`continuation.switching.switch`)."""

from .switch import CrossingTangents, crossing_tangents, switch_branch

__all__ = ["CrossingTangents", "crossing_tangents", "switch_branch"]
