"""The studies' vessel model, built once per process.

Every study of the main job uses the default vessel (Umeda's purse seiner,
:func:`ship_models.purse_seiner`). Building the model is cheap (about 0.15 s), but each
new instance then pays its own first use of every solver: the CasADi functions of the
connection problem, the time-scaled right-hand side of the integrator, the compiled
libraries loaded and checked (about 1 s of CPU for a connection solve, 0.4 s for a
first simulation). The main job runs several steps in each worker process, so the
steps share one instance per process (:func:`default_model`). The model holds no
state that changes a result (its caches hold functions, not solutions), so a step
computes the same numbers with a shared or a new instance.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any


@functools.lru_cache(maxsize=1)
def default_model() -> Any:
    """The default vessel's :class:`~ship_models.umeda_4dof.Umeda4DOF` (one per process)."""
    from ship_models import purse_seiner

    return purse_seiner()


@functools.lru_cache(maxsize=4)
def heteroclinic(chi_c_deg: float = 10.0) -> Any:
    """The default vessel's heteroclinic connection at ``chi_c_deg`` (one solve per process).

    :func:`~ship_models.analysis.critical_bvp.critical_fn_bvp` on :func:`default_model`
    at its defaults. Four steps of the main job start from the connection at 10 deg
    (Figs. 21-23, Figs. 16-22, the sensitivities, the cycles); they share one solve in
    each process, and the main job solves it before its worker processes are forked
    (:func:`broachkit_cli.commands.reproduce`), so they inherit it with the solver's
    functions already built. The result is frozen (its users read it, the curve continues from
    it), and the solver is deterministic, so a shared
    and a new solve give the same numbers.
    """
    import math

    from ship_models.analysis.critical_bvp import critical_fn_bvp

    return critical_fn_bvp(math.radians(chi_c_deg), model=default_model())


def bisection_near(
    run: Callable[[tuple[float, float]], Any],
    guess: float,
    half_width: float,
    wide: tuple[float, float],
) -> Any:
    """A bisection of fates by simulation near ``guess`` (width ``2 half_width``), else ``wide``.

    ``run(bracket)`` bisects in ``bracket = (Fn_lo, Fn_hi)`` and returns a result with
    a ``status``; it simulates the fates at both ends first and returns ``NO_BRACKET``
    when they are not those of a bracket. The narrow bracket about ``guess`` (the
    collocation value of the switch), ``(guess - 2w/3, guess + 4w/3)`` with
    ``w = half_width``, is tried first (``guess`` lies at a third of it, which no
    halving reaches: the fate is never asked exactly at the connection, where it is
    decided by rounding). When its ends hold, the
    bisection still finds the switch of the fates by simulation alone, and the guess
    only saves the halvings down to its neighbourhood (about 8 of 15 from a 0.05 wide
    bracket to 1e-6). Otherwise (no guess, or the switch farther away) ``wide`` is
    bisected.
    """
    import math

    from continuation.status import Status

    if math.isfinite(guess):
        b = run((guess - 2.0 * half_width / 3.0, guess + 4.0 * half_width / 3.0))
        if b.status is not Status.NO_BRACKET:
            return b
    return run(wide)


__all__ = ["bisection_near", "default_model", "heteroclinic"]
