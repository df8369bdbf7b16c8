r"""Sensitivity of the critical Froude number to every coefficient of the vessel.

The critical ``Fn*`` of one course is an unknown of the collocation system of the
saddle-to-shifted-saddle connection (:func:`ship_models.analysis.critical_bvp.critical_fn_bvp`):
:math:`G(z; \theta) = 0` with ``z`` the discretised orbit, the saddle, the Riccati
unknowns and ``Fn``, and :math:`\theta` any coefficient the model is built from. By
the implicit-function theorem, with :math:`G_z` the (square, non-singular at a
transversal connection) Jacobian and :math:`e_{Fn}` the unit vector of ``Fn`` in ``z``,

.. math::

    \frac{dz}{d\theta} = -G_z^{-1} G_\theta, \qquad
    \frac{dFn^*}{d\theta} = -\lambda^T G_\theta, \qquad G_z^T \lambda = e_{Fn},

so one sparse LU factorisation of :math:`G_z` and one adjoint solve give the
derivative for every coefficient at once (Cao, Li, Petzold & Serban 2003, "Adjoint
sensitivity analysis for differential-algebraic equations: the adjoint DAE system and
its numerical solution", SIAM J. Sci. Comput. 24:1076-1089, for the discrete adjoint
idea). This is the derivative of the *discrete* ``Fn*`` on the fixed mesh, which is
within the discretisation error (about 1e-7) of the continuous one.

:math:`G_\theta` is taken by central differences of the residual at the converged
``z``, with the model *rebuilt* from the vessel file at :math:`\theta \pm h`
(:func:`ship_models.estimation.build_vessel_model`), so a coefficient of the file
(given or assumed) carries the estimates that depend on it along (a total
derivative: changing ``B`` changes ``m_y``, the Inoue derivatives, the resistance...),
while an *estimated* coefficient is overridden alone (its own partial effect).
Parameters of the dynamical system (``waves.H_over_lambda``, ``waves.lambda_over_L``,
``autopilot.K_R``, ``autopilot.T_D``) are differentiated exactly by CasADi.

Intermediate quantities of the force model, which are not numbers of the file, are
reached through factors (all 1 at the base point; their elasticity is that of the
quantity):

=====================  =========================================================
``factor.R_surf``      calm-water resistance ``R(u)`` in the surge equation, the
                       propeller revolution ``n(Fn)`` held (resistance near the wave
                       celerity, where the connection runs)
``factor.T_surf``      propeller thrust ``T(u; n)`` in the surge equation, ``n`` held
``factor.R_nominal``   ``R(u_0)`` in the calm-water balance that sets ``n(Fn)``
``factor.Y_w``         amplitude of the wave sway force (Froude-Krylov + lift)
``factor.N_w``         amplitude of the wave yaw moment
``factor.K_w``         amplitude of the wave roll moment
=====================  =========================================================

and the wave surge-force amplitude is the file's own ``hydrodynamics.wave_surge_scale``
(status ``assumed``, 1 by default). ``R_surf`` and ``R_nominal`` add up to a uniform
scaling of ``R``. A factor scales its quantity along the whole orbit (the surge speed
varies along it); the ``quantity`` reported with it is its value at the wave
celerity ``u = c`` (for the default ship ``T(c; n)`` is negative: the propeller, set
for ``u_0 < c``, brakes at the celerity) or, for ``R_nominal``, at ``u_0``.

Public names
------------
:func:`critical_fn_sensitivity` — ``dFn*/dtheta`` and elasticities for all (or the
named) coefficients; :class:`Sensitivity`, :class:`SensitivityEntry`.
:func:`model_at` — the model rebuilt with some coefficients / factors changed.
:func:`resolve_at` — re-solve the connection for such a model (for checks).
:func:`uncertainty_band` — linear propagation of the vessel file's uncertainties,
with an optional sampled confirmation; :class:`UncertaintyBand`.
:func:`tornado_figure` — the sorted elasticities as a PNG.

Modules: ``factors`` (the factors and key classes), ``rebuild`` (the model rebuilt
with changed coefficients, hydrostatics reused), ``adjoint`` (the derivatives and
re-solves), ``result`` (result types), ``band`` (the uncertainty band), ``figure``
(the tornado figure).

Functions of :mod:`ship_models.analysis.critical_bvp` used: ``critical_fn_bvp``
(the connection) and the ``CriticalFn`` result type.
"""

from __future__ import annotations

from collections.abc import Sequence

from .adjoint import critical_fn_sensitivity, default_keys, resolve_at, wave_surge_amplitude
from .band import UncertaintyBand, dominant, uncertainty_band
from .factors import FACTORS, NUMERICAL_KEYS, SYSTEM_PARAMS
from .figure import tornado_figure
from .rebuild import model_at, reuse_hydrostatics
from .result import Sensitivity, SensitivityEntry, linear_prediction

__all__: Sequence[str] = [
    "FACTORS",
    "NUMERICAL_KEYS",
    "SYSTEM_PARAMS",
    "Sensitivity",
    "SensitivityEntry",
    "UncertaintyBand",
    "critical_fn_sensitivity",
    "default_keys",
    "dominant",
    "linear_prediction",
    "model_at",
    "resolve_at",
    "reuse_hydrostatics",
    "tornado_figure",
    "uncertainty_band",
    "wave_surge_amplitude",
]
