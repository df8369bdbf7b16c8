r"""The crest saddle of the upslope connection, followed from ``chi_c = 0``.

Umeda (1999), Figs. 10-15: the surf-riding equilibrium near the wave crest is a saddle
of index 1; its one-dimensional unstable manifold leaves along the eigenvector of the
positive eigenvalue ``lambda_u``. :func:`crest_saddle` takes the crest equilibrium on
the branch that starts at the surge root at ``chi_c = 0``
(:meth:`~ship_models.umeda_4dof.Umeda4DOF.find_equilibrium` continues it in ``chi_c``)
and returns it as the ship's one saddle type,
:class:`~ship_models.analysis.fixed_points.FixedPoint` (label ``"crest"``, with its
eigen-structure), after checking that it has exactly one unstable eigenvalue.
"""

from __future__ import annotations

import numpy as np

from continuation.errors import ContinuationError
from continuation.params import Params
from continuation.settings import NewtonSettings
from continuation.typing import FloatArray

from ..contracts import VesselModel
from .eigen import eigen_structure
from .fixed_points import FixedPoint


def crest_equilibrium(model: VesselModel, params: Params) -> tuple[FloatArray, float]:
    """The crest equilibrium followed from ``chi_c = 0`` and its residual ``max |F|``.

    ``model.find_equilibrium`` continues the ``chi_c = 0`` surge root in ``chi_c`` (a
    guess with zero lateral states alone can converge to another root at large
    courses).

    Raises
    ------
    ContinuationError
        If the branch folds before the course (no crest equilibrium there).
    """
    settings = NewtonSettings(tol=1e-11, max_iter=30, damping=True)
    res = model.find_equilibrium(params, "crest", settings=settings)
    if not res.converged:
        import math

        raise ContinuationError(
            f"the crest saddle does not exist at chi_c = "
            f"{math.degrees(float(params['chi_c'])):.4g} deg, Fn = {float(params['Fn']):.6g} "
            f"(followed from chi_c = 0): {res.message}"
        )
    return np.asarray(res.z, dtype=float), float(res.residual_norm)


def crest_saddle(model: VesselModel, params: Params) -> FixedPoint:
    """The crest equilibrium as a saddle of index 1 with its eigen-structure.

    Returns
    -------
    FixedPoint
        Label ``"crest"``; ``x`` as followed (not re-polished), shape (8,).

    Raises
    ------
    ContinuationError
        If no crest equilibrium is found or it is not a saddle of index 1.
    """
    x, residual = crest_equilibrium(model, params)
    es = eigen_structure(model, x, params)
    n_unst = int(np.sum(es.values.real > 0))
    if n_unst != 1:
        raise ContinuationError(
            f"the crest equilibrium has {n_unst} unstable eigenvalues (need a saddle of "
            f"index 1 for the upslope connection) at {dict(params.items())}"
        )
    return FixedPoint("crest", x, params, es, residual)


__all__ = ["crest_equilibrium", "crest_saddle"]
