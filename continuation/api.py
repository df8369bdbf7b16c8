r"""One-line entry points for users: :func:`continue_equilibria`.

>>> from continuation import System
>>> from continuation.api import continue_equilibria
>>> sys = System(lambda x, p, ops: ops.stack([p[0] - x[0] ** 2]), ("x",), ("mu",))
>>> br = continue_equilibria(sys, [1.0], {"mu": 1.0}, "mu", p_min=-1.0, p_max=2.0)
>>> [sp.kind.value for sp in br.special_points]
['fold']
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Literal

from .branch import Branch, BranchPoint
from .driver import continue_branch
from .events import Event
from .params import Params
from .problem import EquilibriumProblem
from .settings import ContinuationSettings
from .system import System, as_params

_DEFAULTS = {
    "ds": 1e-2,
    "ds_min": 1e-8,
    "ds_max": 1e-1,
    "p_min": -math.inf,
    "p_max": math.inf,
    "max_steps": 500,
}


def continue_equilibria(
    system: System,
    x0: Any,
    params: Params | Mapping[str, float] | Sequence[float] | Any,
    free: str,
    *,
    ds: float = 1e-2,
    ds_min: float = 1e-8,
    ds_max: float = 1e-1,
    p_min: float = -math.inf,
    p_max: float = math.inf,
    max_steps: int = 500,
    direction: Literal["forward", "backward", "both"] = "both",
    settings: ContinuationSettings | None = None,
    events: Sequence[Event] = (),
    throw: bool = False,
    progress: Callable[[BranchPoint], None] | None = None,
    algorithm: Any = None,
) -> Branch:
    r"""Continue equilibria ``f(x, p) = 0`` of ``system`` in the parameter ``free``.

    Builds an :class:`~continuation.problem.EquilibriumProblem` and calls
    :func:`~continuation.driver.continue_branch` with pseudo-arclength continuation.

    Parameters
    ----------
    system : System
        The dynamical system ``x' = f(x, p)``.
    x0 : array_like, shape (n,)
        Equilibrium, or a guess of one: corrected by Newton's method at the start value
        of ``free`` before the branch starts.
    params : Params, mapping or array_like (m,)
        All parameter values; ``params[free]`` is the start value. A mapping may omit
        parameters that have defaults in ``system``.
    free : str
        Name of the continuation parameter.
    ds, ds_min, ds_max, p_min, p_max, max_steps
        Step control and bounds (see :class:`~continuation.settings.ContinuationSettings`).
        When ``settings`` is also given, any of these that differ from their defaults
        override the corresponding field of ``settings``.
    direction : {"both", "forward", "backward"}
        ``"both"`` (default) returns one branch ordered from the backward end to the
        forward end; see :func:`~continuation.driver.continue_branch`.
    settings : ContinuationSettings, optional
    events : sequence of Event
    throw : bool
        Raise on a failing start (``ConvergenceError``) or failing branch.
    progress : callable, optional
        Called with each accepted :class:`~continuation.branch.BranchPoint`.
    algorithm : ContinuationAlgorithm, optional
        Default ``PALC()``.

    Returns
    -------
    Branch
        With ``state_names`` of the system; ``branch.param(name)`` gives any parameter
        along it. A start that does not converge gives an empty branch with
        ``Status.NEWTON_FAILED``.

    Raises
    ------
    ValueError
        Unknown ``free`` or parameter names, wrong shape of ``x0``, NaN in ``x0`` or
        ``params``, ``ds`` bounds out of order.
    """
    if not isinstance(free, str) or free not in system.param_names:
        raise ValueError(f"`free` must be one of {system.param_names}, got {free!r}")
    x = system.check_state(x0, "x0")
    par = as_params(system, params)
    given: dict[str, Any] = {
        "ds": ds,
        "ds_min": ds_min,
        "ds_max": ds_max,
        "p_min": p_min,
        "p_max": p_max,
        "max_steps": max_steps,
    }
    if settings is None:
        settings = ContinuationSettings(**given)
    else:
        if not isinstance(settings, ContinuationSettings):
            raise ValueError(f"`settings` must be a ContinuationSettings, got {type(settings)}")
        changed = {k: v for k, v in given.items() if v != _DEFAULTS[k]}
        if changed:
            settings = dataclasses.replace(settings, **changed)
    problem = EquilibriumProblem(system, par, free)
    return continue_branch(
        problem,
        x,
        par[free],
        algorithm,
        settings,
        events=events,
        direction=direction,
        throw=throw,
        progress=progress,
    )


__all__ = ["continue_equilibria"]
