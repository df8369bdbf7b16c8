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
from typing import Any


@functools.lru_cache(maxsize=1)
def default_model() -> Any:
    """The default vessel's :class:`~ship_models.umeda_4dof.Umeda4DOF` (one per process)."""
    from ship_models import purse_seiner

    return purse_seiner()


__all__ = ["default_model"]
