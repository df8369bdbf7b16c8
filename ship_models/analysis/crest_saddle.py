r"""The crest saddle of the upslope connection: the equilibrium and its unstable direction.

Umeda (1999), Figs. 10-15: the surf-riding equilibrium near the wave crest is a saddle
of index 1; its one-dimensional unstable manifold leaves along the eigenvector of the
positive eigenvalue ``lambda_u``. :func:`crest_saddle` follows the crest equilibrium
from ``chi_c = 0`` (where it is the surge root,
:meth:`~ship_models.umeda_4dof.Umeda4DOF.find_equilibrium`), checks the index and
orients the unstable eigenvector *upslope* (``xi_G`` decreasing: the wave overtakes
the ship).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from continuation._types import FloatArray
from continuation.errors import ContinuationError
from continuation.params import Params
from continuation.settings import NewtonSettings


@dataclass(frozen=True)
class CrestSaddle:
    """The surf-riding saddle near the crest and its upslope unstable direction.

    Attributes
    ----------
    x : ndarray, shape (8,)
        The equilibrium.
    rate : float
        Its unstable eigenvalue ``lambda_u > 0`` (1/s).
    direction : ndarray, shape (8,)
        Unit unstable eigenvector, oriented so that ``xi_G`` decreases (upslope).
    weakest_stable : float
        ``min |Re lambda|`` over the stable eigenvalues (1/s): the slowest approach.
    n_unstable : int
        Number of eigenvalues with positive real part (1 for a saddle of index 1).
    eigenvalues : ndarray, shape (8,), complex
    eigenvectors : ndarray, shape (8, 8), complex
        Columns are the eigenvectors of ``f_x`` at the saddle.
    """

    x: FloatArray
    rate: float
    direction: FloatArray
    weakest_stable: float
    n_unstable: int
    eigenvalues: np.ndarray = field(default_factory=lambda: np.zeros(0, complex), repr=False)
    eigenvectors: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), complex), repr=False)

    def approach_rate(self, offset: FloatArray, rel: float = 1e-3) -> float:
        """Slowest stable decay rate present in ``offset`` (a state minus the saddle).

        The offset is expanded in the eigenvectors; modes whose coefficient is below
        ``rel`` times the largest are ignored (e.g. the lateral modes at ``chi_c = 0``,
        which the symmetric motion never excites). Falls back to ``weakest_stable``.
        """
        if self.eigenvectors.size == 0:
            return self.weakest_stable
        try:
            c = np.abs(np.linalg.solve(self.eigenvectors, np.asarray(offset, dtype=complex)))
        except np.linalg.LinAlgError:
            return self.weakest_stable
        stable = self.eigenvalues.real < 0
        present = stable & (c > rel * np.max(c[stable], initial=0.0))
        if not np.any(present):
            return self.weakest_stable
        return float(np.min(-self.eigenvalues.real[present]))


def crest_equilibrium(model: Any, params: Params) -> FloatArray:
    """The crest equilibrium followed from ``chi_c = 0`` (where it is the surge root):
    ``model.find_equilibrium`` continues it in ``chi_c`` (a guess with zero lateral
    states alone can converge to another root at large courses); fails if the branch
    folds before the course."""
    settings = NewtonSettings(tol=1e-11, max_iter=30, damping=True)
    res = model.find_equilibrium(params, "crest", settings=settings)
    if not res.converged:
        raise ContinuationError(
            f"no crest equilibrium at {dict(params.items())} (followed from chi_c = 0): "
            f"{res.message}"
        )
    return np.asarray(res.z, dtype=float)


def crest_saddle(model: Any, params: Params) -> CrestSaddle:
    """Solve the crest equilibrium and orient its unstable eigenvector upslope.

    Raises
    ------
    ContinuationError
        If no crest equilibrium is found or it is not a saddle of index 1.
    """
    pv = np.asarray(params.values, dtype=float)
    x = crest_equilibrium(model, params)
    w, V = np.linalg.eig(model.jacobian(x, pv))
    n_unst = int(np.sum(w.real > 0))
    if n_unst != 1:
        raise ContinuationError(
            f"the crest equilibrium has {n_unst} unstable eigenvalues (need a saddle of "
            f"index 1 for the upslope connection) at {dict(params.items())}"
        )
    k = int(np.argmax(w.real))
    v = np.real(V[:, k])
    v = v / np.linalg.norm(v)
    i_xi = model.state_index("xi_G")
    if v[i_xi] > 0:
        v = -v
    stable = w.real[w.real < 0]
    return CrestSaddle(x, float(w[k].real), v, float(np.min(-stable)), n_unst, w, V)


__all__ = ["CrestSaddle", "crest_equilibrium", "crest_saddle"]
