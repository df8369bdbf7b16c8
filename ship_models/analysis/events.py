r"""The capsize event of the ship: roll beyond the angle of vanishing stability.

Capsizing is the paper's terminal attractor ("capsizing acts a kind of attractor",
Umeda 1999). In the model the roll restoring moment is :math:`-m g\,GZ(\phi)`; beyond
the angle of vanishing stability :math:`\phi_v` (first positive zero of GZ) it heels
the ship further and no return is possible in calm water. So a trajectory with
:math:`|\phi| > \phi_v` is counted as capsized. The angle is that of the GZ curve
*in the equations of motion* (the model's smooth fit, ``model.forces.gz``); the
hydrostatic curve it was fitted to gives nearly the same value
(``model.data.info["phi_vanishing"]``).
"""

from __future__ import annotations

import math
import weakref
from typing import Any

import numpy as np
import scipy.optimize as so

from continuation.events import Event

from ..contracts import VesselModel

#: :func:`vanishing_angle` per model (its GZ curve is fixed when it is built).
_PHI_V: weakref.WeakKeyDictionary[Any, dict[int, float]] = weakref.WeakKeyDictionary()


def vanishing_angle(model: VesselModel, *, n_grid: int = 3600) -> float:
    r"""Angle of vanishing stability of the model's GZ curve (rad).

    The first zero of ``model.forces.gz`` in :math:`(0, \pi]` after it has been
    positive, bracketed on a grid of ``n_grid`` points and solved by Brent's method.

    Returns
    -------
    float
        ``phi_v`` in (0, pi]; ``pi`` if GZ stays positive (no vanishing angle). Computed
        once per model and grid (every fate classification asks for it).
    """
    try:
        known = _PHI_V.setdefault(model, {})
    except TypeError:  # a model that cannot be weakly referenced: not cached
        known = {}
    if n_grid not in known:
        known[n_grid] = _vanishing_angle(model, n_grid)
    return known[n_grid]


def _vanishing_angle(model: VesselModel, n_grid: int) -> float:
    gz = model.forces.gz
    phi = np.linspace(0.0, math.pi, n_grid + 1)[1:]
    g = np.asarray(gz(phi), dtype=float)
    idx = np.nonzero((g[:-1] > 0) & (g[1:] <= 0))[0]
    if idx.size == 0:
        return math.pi
    k = int(idx[0])
    if g[k + 1] == 0.0:
        return float(phi[k + 1])
    return float(so.brentq(lambda a: float(gz(a)), phi[k], phi[k + 1], xtol=1e-14))


def capsize_angle(model: VesselModel, angle: float | None = None) -> float:
    """The roll angle (rad) beyond which a run counts as capsized.

    ``angle`` if given (validated), else :func:`vanishing_angle` of the model.
    """
    if angle is None:
        return vanishing_angle(model)
    a = float(angle)
    if not (math.isfinite(a) and 0 < a <= math.pi):
        raise ValueError(f"`angle` must be in (0, pi] rad, got {angle!r}")
    return a


def capsize_event(
    model: VesselModel, angle: float | None = None, *, terminal: bool = True
) -> Event:
    r"""Terminal event ``|phi| - phi_cap = 0`` crossed upwards: the ship capsizes.

    Parameters
    ----------
    model : VesselModel
        Supplies the index of ``phi`` and the GZ curve.
    angle : float, optional
        Capsize angle (rad); default the angle of vanishing stability of the model's
        GZ curve (:func:`vanishing_angle`).
    terminal : bool
        Stop the simulation at capsize (default).

    Returns
    -------
    continuation.events.Event
        Named ``"capsize"``; ``fn(x, p)`` accepts one state ``(8,)`` or samples
        ``(M, 8)``. The simulator (:mod:`continuation.dynamics.simulate`) adapts it.
    """
    phi_cap = capsize_angle(model, angle)
    i = model.state_index("phi")

    def fn(x: Any, p: Any = None) -> Any:
        return np.abs(np.asarray(x)[..., i]) - phi_cap

    return Event("capsize", fn, direction="up", terminal=terminal)


__all__ = ["capsize_angle", "capsize_event", "vanishing_angle"]
