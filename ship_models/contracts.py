r"""The written contracts of the ship layer: a vessel model and its wave-force model.

Two extension points, each a :class:`typing.Protocol` (structural: nothing to
inherit, a class that has the members conforms):

:class:`WaveForceModel`
    The wave-induced surge and sway forces and the yaw and roll moments on the hull
    in a regular wave, ``forces(xi_G/lambda, u, chi, sea, ops, *, lift) -> (X_w, Y_w,
    N_w, K_w)``, written once for NumPy and CasADi operands (``ops``), so the
    right-hand side of the equations of motion (Umeda 1999, Eqs. 5-8) stays symbolic.
    The default is the Froude-Krylov strip integration of
    :class:`~ship_models.hydro.waves.WaveStrips`; the panel-method table of
    :mod:`ship_models.hydro.panel` is another.
:class:`SeaState`
    The wave the forces are evaluated in, ``SeaState(H/lambda, lambda/L)`` (the two
    wave parameters of the system, floats or CasADi symbols), with the wavelength,
    wavenumber and amplitude it gives on a ship of length ``L``.
:class:`WaveForceBuilder`
    How a wave-force model is made from the hull and the loading
    (:class:`WaveInputs`): :func:`ship_models.estimation.build_vessel_model` calls it
    once per vessel, and again whenever the vessel is rebuilt with changed
    coefficients (sensitivity, calibration), so a model's own wave physics is kept.
:class:`VesselModel`
    What the analyses (:mod:`ship_models.analysis`) use of a ship model: state and
    parameter names, the right-hand side and its Jacobian, the vessel data and the
    forces, the wave celerity, the surf-riding equilibria, and :meth:`VesselModel.rebuild`
    (the same model class, options and wave-force model on changed vessel data).
    :class:`~ship_models.umeda_4dof.Umeda4DOF` conforms.

A new vessel with its own wave forces passes a builder:
``build_vessel_model(vessel, waves=my_builder)`` or ``Umeda4DOF(vessel,
waves=my_builder)``; see ``docs/vessel_with_own_wave_forces.md``,
``docs/vessel_from_offsets.md`` and ``tests/test_vessel_contracts.py``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple, Protocol, runtime_checkable

from continuation.ops import NUMPY_OPS, Ops
from continuation.params import Params
from continuation.typing import FloatArray

if TYPE_CHECKING:  # pragma: no cover - typing only
    from continuation.newton import NewtonResult
    from continuation.settings import NewtonSettings

    from .estimation import VesselModelData
    from .forces import ShipForces
    from .hydro.hull import HullForm
    from .vessel import VesselData


class SeaState(NamedTuple):
    r"""The regular wave a :class:`WaveForceModel` is evaluated in (Umeda 1999, Eqs. 5-8).

    The two wave parameters of the system as one value: floats, or CasADi symbols
    when the right-hand side is traced (the forces must then stay differentiable in
    them). On a ship of length :math:`L` they give

    .. math::

        \lambda = (\lambda/L)\,L, \qquad k = 2\pi/\lambda, \qquad
        a = \tfrac12\,(H/\lambda)\,\lambda

    (:meth:`wave`; deep water, the wave height :math:`H = 2a`).

    Attributes
    ----------
    H_over_lambda : scalar
        Wave steepness :math:`H/\lambda`.
    lambda_over_L : scalar
        Wavelength over the ship length :math:`\lambda/L`.
    """

    H_over_lambda: Any
    lambda_over_L: Any

    def wave(self, L: float, ops: Ops = NUMPY_OPS) -> tuple[Any, Any, Any]:
        r"""Wavelength, wavenumber and amplitude on a ship of length ``L``.

        Parameters
        ----------
        L : float
            Ship length the wavelength ratio refers to (m).
        ops : Ops
            NumPy or CasADi namespace (:mod:`continuation.ops`).

        Returns
        -------
        lam, k, a : scalar
            :math:`\lambda` (m), :math:`k = 2\pi/\lambda` (1/m) and the amplitude
            :math:`a = H/2` (m), scalars or CasADi expressions like the fields.
        """
        lam = self.lambda_over_L * L
        return lam, 2.0 * ops.pi / lam, 0.5 * self.H_over_lambda * lam


@runtime_checkable
class WaveForceModel(Protocol):
    r"""Wave forces on the hull at its calm-water attitude (body axes at G).

    Attributes
    ----------
    name : str
        Short label of the method (``"froude_krylov_strips"``,
        ``"panel_fk_diffraction"``, ...), reported by ``broachkit critical --json``.
    """

    @property
    def name(self) -> str:
        """Short label of the wave-force method."""
        ...

    def forces(
        self,
        xi_over_lambda: Any,
        u: Any,
        chi: Any,
        sea: SeaState,
        ops: Ops = NUMPY_OPS,
        *,
        lift: bool = True,
    ) -> tuple[Any, Any, Any, Any]:
        r"""Wave forces ``(X_w, Y_w, N_w, K_w)`` (N, N, N m, N m).

        Parameters
        ----------
        xi_over_lambda : scalar
            :math:`\xi_G/\lambda` (0 at a trough, 0.5 at a crest).
        u : scalar
            Surge velocity (m/s) (used by speed-dependent parts, e.g. wave lift).
        chi : scalar
            Heading from the wave direction (rad, + to starboard).
        sea : SeaState
            Wave steepness and wavelength ratio (parameters of the system: the
            result must be differentiable in them with CasADi operands).
        ops : Ops
            NumPy or CasADi namespace (:mod:`continuation.ops`).
        lift : bool
            Include the hydrodynamic lift due to the wave particle velocity.

        Returns
        -------
        X_w, Y_w, N_w, K_w : scalar
            Surge and sway forces (N), yaw and roll moments (N m) about G, each a
            scalar (a CasADi expression with CasADi operands).
        """
        ...


@dataclass(frozen=True)
class WaveInputs:
    """What a :class:`WaveForceBuilder` receives (SI units, lengths from G).

    Attributes
    ----------
    vessel : VesselData
        The vessel as given (file values; estimates not yet added).
    hull : HullForm
        The strip hull (sections, waterline, stations from midship).
    x_G : float
        Longitudinal position of G from midship (m, forward +).
    zeta_G : float
        Height of G above the calm waterline (m).
    m22 : ndarray, shape (n_stations,)
        Sway added mass per unit length of each station (kg/m).
    z_H : float
        Depth of the hull lateral force centre below G (m).
    rho, g : float
        Water density (kg/m^3) and gravity (m/s^2).
    n_depth : int
        Gauss-Legendre nodes over the draft of each section.
    surge_scale : float
        Factor on the surge force that the vessel file asks for
        (``hydrodynamics.wave_surge_scale`` times a diffraction factor).
    """

    vessel: VesselData
    hull: HullForm
    x_G: float
    zeta_G: float
    m22: FloatArray
    z_H: float
    rho: float
    g: float
    n_depth: int
    surge_scale: float


@runtime_checkable
class WaveForceBuilder(Protocol):
    """``builder(inputs: WaveInputs) -> WaveForceModel`` (a function or a callable object).

    A builder should be cheap to compare (a module-level function, or a frozen
    dataclass of its options): the vessel cache is keyed by it.
    """

    def __call__(self, inputs: WaveInputs) -> WaveForceModel:
        """The wave-force model of this hull and loading."""
        ...


@runtime_checkable
class VesselModel(Protocol):
    """A ship model as the analyses of :mod:`ship_models.analysis` use it.

    Attributes
    ----------
    state_names, param_names : tuple of str
        Names of the states (``xi_G`` first, periodic with period 1) and parameters
        (``Fn``, ``chi_c``, ``H_over_lambda``, ``lambda_over_L``, ...).
    data : VesselModelData
        The resolved vessel, hull, GZ curve and forces.
    forces : ShipForces
        The coefficients of the equations of motion; ``forces.waves`` is the
        :class:`WaveForceModel`.
    vessel : VesselData
        The resolved vessel (file values plus estimates).
    """

    state_names: tuple[str, ...]
    param_names: tuple[str, ...]
    data: VesselModelData
    forces: ShipForces
    vessel: VesselData

    @property
    def n_states(self) -> int:
        """Number of states."""
        ...

    def index(self, name: str) -> int:
        """Index of a state name."""
        ...

    def state_index(self, name: str) -> int:
        """Index of a state name; ValueError listing the valid names."""
        ...

    def param_index(self, name: str) -> int:
        """Index of a parameter name; ValueError listing the valid names."""
        ...

    def check_params(self, params: Any, name: str = "params") -> FloatArray:
        """Parameters as a checked array in ``param_names`` order."""
        ...

    def f(self, x: FloatArray, p: Params | FloatArray) -> FloatArray:
        """Right-hand side, shape (n,)."""
        ...

    def jacobian(self, x: FloatArray, p: Params | FloatArray) -> Any:
        """Jacobian ``df/dx``, shape (n, n)."""
        ...

    def as_params(self, p: Any = None, name: str = "params") -> Params:
        """Named parameters from a Params, mapping or array (None: the defaults), checked."""
        ...

    def params(self, **values: float) -> Params:
        """Parameters with the model's defaults, some replaced."""
        ...

    def default_params(self) -> Params:
        """The model's default parameters."""
        ...

    def celerity(self, params: Params | FloatArray) -> float:
        """Wave celerity ``c`` (m/s) at these parameters."""
        ...

    def equilibrium_guess(self, params: Params | FloatArray, where: str = "crest") -> FloatArray:
        """A starting guess of the surf-riding equilibrium near the crest or trough."""
        ...

    def find_equilibrium(
        self,
        params: Params | FloatArray,
        where: str = "crest",
        *,
        guess: FloatArray | None = None,
        settings: NewtonSettings | None = None,
        throw: bool = False,
    ) -> NewtonResult:
        """The surf-riding equilibrium near the crest or trough (Newton)."""
        ...

    def rebuild(self, data: VesselModelData | VesselData) -> VesselModel:
        """The same model class, options and wave-force builder on other vessel data.

        A :class:`~ship_models.vessel.VesselData` is resolved with this model's
        wave-force builder; a :class:`~ship_models.estimation.VesselModelData` is
        used as it is (its ``forces.waves`` included).
        """
        ...


def wave_model_name(model: Any) -> str:
    """The :attr:`WaveForceModel.name` behind a model (``"unknown"`` if it has none)."""
    forces = getattr(model, "forces", None)
    waves = getattr(forces, "waves", None)
    return str(getattr(waves, "name", "unknown"))


__all__ = [
    "SeaState",
    "VesselModel",
    "WaveForceBuilder",
    "WaveForceModel",
    "WaveInputs",
    "wave_model_name",
]
