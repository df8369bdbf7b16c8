r"""Is a connecting orbit a capsizing boundary? (Umeda 1999, Sect. 4)

The critical ``Fn`` is where the upslope branch of the crest saddle's unstable manifold
lands on the *same* crest saddle one wavelength back. A solution of the collocation
system can satisfy the boundary conditions without being that orbit:

* it rolls past the angle of vanishing stability :math:`\phi_v` of the GZ curve
  (:func:`~ship_models.analysis.events.capsize_angle`): the ship has capsized on the
  way, the orbit is a capsize, not the boundary between capsize and survival;
* its end saddle is not the crest saddle continued from ``chi_c = 0``
  (:meth:`~ship_models.umeda_4dof.Umeda4DOF.find_equilibrium`), or that saddle does
  not exist at the solved ``Fn`` (its branch folds before the course).

:func:`boundary_refusal` returns the reason (empty when the orbit is a boundary).
"""

from __future__ import annotations

import math

import numpy as np

from continuation.params import Params
from continuation.settings import NewtonSettings
from continuation.typing import FloatArray

from ..contracts import VesselModel
from .events import capsize_angle

#: Largest 2-norm distance between the orbit's saddle and the crest saddle followed
#: from ``chi_c = 0`` for them to count as the same equilibrium.
SADDLE_MATCH = 1e-6


def max_roll(model: VesselModel, x: FloatArray) -> float:
    """``max |phi|`` (rad) over the orbit samples ``x (M, n)``."""
    return float(np.max(np.abs(np.asarray(x, dtype=float)[:, model.state_index("phi")])))


def boundary_refusal(model: VesselModel, x: FloatArray, x_from: FloatArray, params: Params) -> str:
    """Why the orbit ``x (M, n)`` from the saddle ``x_from`` is no capsizing boundary.

    Parameters
    ----------
    model : VesselModel
    x : ndarray, shape (M, n)
        Orbit samples.
    x_from : ndarray, shape (n,)
        Its start saddle.
    params : Params
        Parameters of the solution (solved ``Fn`` included).

    Returns
    -------
    str
        ``""`` for a boundary; otherwise one sentence with the reason.
    """
    phi_v = capsize_angle(model)
    phi_max = max_roll(model, x)
    if phi_max >= phi_v:
        return (
            f"the orbit rolls to |phi| = {math.degrees(phi_max):.1f} deg, past the angle of "
            f"vanishing stability {math.degrees(phi_v):.1f} deg: a capsize, not a capsizing "
            "boundary"
        )
    settings = NewtonSettings(tol=1e-11, max_iter=30, damping=True)
    eq = model.find_equilibrium(params, "crest", settings=settings)
    where = (
        f"chi_c = {math.degrees(float(params['chi_c'])):.4g} deg, Fn = {float(params['Fn']):.6g}"
    )
    if not eq.converged:
        return f"the crest saddle continued from chi_c = 0 does not exist at {where}: {eq.message}"
    d = float(np.linalg.norm(np.asarray(x_from, dtype=float) - np.asarray(eq.z, dtype=float)))
    if d > SADDLE_MATCH:
        return (
            f"the orbit starts on an equilibrium {d:.2e} away from the crest saddle continued "
            f"from chi_c = 0 at {where}: not the upslope connection"
        )
    return ""


__all__ = ["SADDLE_MATCH", "boundary_refusal", "max_roll"]
