r"""Surge-sway-yaw-roll model with autopilot of Umeda (1999), Eqs. (1)-(11).

State (Eq. 1) and parameters:

.. code-block:: text

    x = (xi_G, u, v, chi, r, phi, p_roll, delta)
        xi_G   xi_G / lambda, wave-relative position of G (periodic, period 1;
               0 = wave trough, 0.5 = crest), dimensionless
        u, v   surge and sway velocity (m/s)
        chi    heading from the wave direction (rad, + to starboard)
        r      yaw rate (rad/s)
        phi    roll angle (rad, + starboard down), p_roll roll rate (rad/s)
        delta  rudder angle (rad, + turns the bow to starboard)
    p = (Fn, chi_c, H_over_lambda, lambda_over_L, K_R, T_D)

Equations (Umeda 1999, Eqs. 4-11; all forces from :class:`~ship_models.forces.ShipForces`):

.. math::

    \dot\xi_G/\lambda &= (u\cos\chi - v\sin\chi - c)/\lambda \\
    \dot u &= \{T(u; n) - R(u) + X_w\}/(m + m_x) \\
    \dot v &= \{-(m + m_x) u r + Y_v v + Y_r r + Y_\phi\phi + Y_\delta + Y_w\}/(m + m_y) \\
    \dot\chi &= r \\
    \dot r &= \{N_v v + N_r r + N_\phi\phi + N_\delta + N_w\}/(I_{zz} + J_{zz}) \\
    \dot\phi &= p \\
    \dot p &= \{m_x z_H u r + K_v v + K_r r + K_p p + K_\phi\phi + K_\delta + K_w
              - m g\,GZ(\phi)\}/(I_{xx} + J_{xx}) \\
    \dot\delta &= \{\mathrm{sat}(-K_R(\chi - \chi_c) - K_R T_D r) - \delta\}/T_E

with :math:`c = \sqrt{g\lambda/2\pi}` and the propeller revolution :math:`n(Fn)`
that balances thrust and resistance in calm water at :math:`u_0 = Fn\sqrt{gL}`.
``Y_delta`` etc. are the rudder forces (MMG form), linear in the rudder angle.

Rudder saturation (default on): the paper's broaching happens "despite the maximum
opposite rudder angle", so the commanded angle is limited smoothly,
:math:`\mathrm{sat}(x) = x / (1 + (x/\delta_{max})^{2m})^{1/(2m)}` with
``2m = saturation_order`` (16 by default): analytic, slope 1 at 0, within 0.2 % of
the identity up to 0.8 delta_max and tending to +-delta_max. ``saturation=False``
gives the linear Eq. (11) of the paper.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import scipy.optimize as so

from continuation.newton import NewtonResult, newton
from continuation.ops import CASADI_OPS, NUMPY_OPS, Ops
from continuation.params import Params
from continuation.settings import NewtonSettings
from continuation.system import System
from continuation.typing import FloatArray

from .contracts import SeaState, WaveForceBuilder
from .estimation import VesselModelData, build_vessel_model, resolve_vessel
from .forces import ShipForces
from .paper import PAPER_CHI_C, PAPER_FN
from .vessel import VesselData, load_vessel

STATE_NAMES = ("xi_G", "u", "v", "chi", "r", "phi", "p_roll", "delta")
PARAM_NAMES = ("Fn", "chi_c", "H_over_lambda", "lambda_over_L", "K_R", "T_D")


def smooth_saturation(x: Any, limit: float, order: int, ops: Ops = NUMPY_OPS) -> Any:
    r"""``x / (1 + (x/limit)^order)^(1/order)`` for even ``order`` (odd, analytic)."""
    return x / (1.0 + (x / limit) ** order) ** (1.0 / order)


def _as_vessel(
    vessel: VesselData | str | Path | VesselModelData, waves: WaveForceBuilder | None = None
) -> VesselModelData:
    if isinstance(vessel, VesselModelData):
        if waves is not None and waves is not vessel.wave_builder:
            raise ValueError(
                "`waves`: give a wave-force builder with a vessel file or VesselData, not "
                "with already resolved VesselModelData (its forces.waves is built)"
            )
        return vessel
    if not isinstance(vessel, VesselData):
        vessel = load_vessel(vessel)
    return resolve_vessel(vessel, waves=waves)


def rebuilt_data(template: VesselModelData, data: VesselModelData | VesselData) -> VesselModelData:
    """``data`` resolved with ``template``'s wave-force builder (VesselModelData as is)."""
    if isinstance(data, VesselModelData):
        return data
    if not isinstance(data, VesselData):
        raise ValueError(
            f"`data` must be VesselData or VesselModelData, got a {type(data).__name__}"
        )
    return build_vessel_model(data, waves=template.wave_builder)


#: ``T - R + X_w`` as a CasADi function per model and grid size (built on first use).
_SURGE_BALANCE: weakref.WeakKeyDictionary[Any, dict[int, ca.Function]] = weakref.WeakKeyDictionary()


def _surge_balance_function(model: Umeda4DOF, size: int) -> ca.Function:
    """``(xi (size,), u, chi_c, n, H/lambda, lambda/L) -> T(u; n) - R(u) + X_w(xi)`` (N).

    The same force expressions as the right-hand side (the wave-force model traced
    with CasADi, without lift), evaluated on a whole grid of ``xi_G/lambda`` in one
    call (:meth:`Umeda4DOF.surge_balance` scans 201 positions per starting guess).
    """
    per = _SURGE_BALANCE.setdefault(model, {})
    fn = per.get(size)
    if fn is None:
        F = model.forces
        xi, u, chi, n, Hl, lL = (ca.SX.sym(k) for k in ("xi", "u", "chi", "n", "Hl", "lL"))
        X = F.waves.forces(xi, u, chi, SeaState(Hl, lL), CASADI_OPS, lift=False)[0]
        net = F.thrust_force(u, n, CASADI_OPS) - F.resistance_force(u, CASADI_OPS) + X
        one = ca.Function("surge_balance", [xi, u, chi, n, Hl, lL], [net])
        fn = per[size] = one.map(size)
    return fn


class VesselSystem(System):
    """A ship model on resolved vessel data, as a :class:`continuation.System`.

    What :class:`Umeda4DOF` and :class:`~ship_models.surge.SurgeModel` share: the
    vessel resolved once with its wave-force builder (:func:`_as_vessel`), the state
    ``xi_G`` periodic with period 1, the CasADi backend, parameter defaults from the
    paper and the vessel file, :meth:`rebuild` with the same options, and the wave
    celerity. A subclass writes its right-hand side ``_rhs(x, p, ops)``.

    Parameters
    ----------
    vessel : VesselData, str, Path or VesselModelData
        A vessel description, the name/path of a vessel file, or resolved data.
    waves : WaveForceBuilder or None
        Builds the wave-force model (None: Froude-Krylov strips).
    state_names, param_names : tuple of str
        Names of the states (``xi_G`` first) and parameters (``lambda_over_L`` among
        them).
    defaults : mapping of str to float or str
        Default of each parameter: a number, or the vessel-file key it is read from
        (e.g. ``"waves.H_over_lambda"``).
    label : str
        Name of the system before the vessel's (``umeda_4dof`` gives
        ``umeda_4dof[purse_seiner]``).

    Attributes
    ----------
    data : VesselModelData
        Resolved vessel, hull, GZ curve and force coefficients.
    forces : ShipForces
        Shortcut for ``data.forces``.
    vessel : VesselData
        Shortcut for ``data.vessel``.
    """

    def __init__(
        self,
        vessel: VesselData | str | Path | VesselModelData,
        waves: WaveForceBuilder | None,
        *,
        state_names: tuple[str, ...],
        param_names: tuple[str, ...],
        defaults: Mapping[str, float | str],
        label: str,
    ) -> None:
        self.data = _as_vessel(vessel, waves)
        self.forces: ShipForces = self.data.forces
        self.vessel = self.data.vessel
        values = {k: self.vessel.get(d) if isinstance(d, str) else d for k, d in defaults.items()}
        super().__init__(
            self._rhs,
            state_names,
            param_names,
            periodic={"xi_G": 1.0},
            defaults=values,
            name=f"{label}[{self.vessel.name}]",
            backend="casadi",
        )

    def _rhs(self, x: Any, p: Any, ops: Ops) -> Any:
        raise NotImplementedError  # pragma: no cover - written by each model

    @property
    def options(self) -> dict[str, Any]:
        """Keyword options of the constructor besides the vessel (none here)."""
        return {}

    def rebuild(self, data: VesselModelData | VesselData) -> VesselSystem:
        """This model (same class, options and wave-force builder) on other vessel data.

        Parameters
        ----------
        data : VesselModelData or VesselData
            Resolved data used as it is, or a vessel resolved with this model's
            wave-force builder (``self.data.wave_builder``).
        """
        return type(self)(rebuilt_data(self.data, data), **self.options)

    def index(self, name: str) -> int:
        """Index of a state name (``"xi_G"``, ``"u"``, ...)."""
        return self.state_index(name)

    def default_params(self) -> Params:
        """The constructor's defaults: ``Fn = PAPER_FN`` (0.3248), ``chi_c = 10 deg`` (4-DOF),
        the vessel file's wave and autopilot gains (Umeda 1999)."""
        return self.params()

    def celerity(self, params: Params | FloatArray) -> float:
        """Wave celerity ``c`` (m/s) for these parameters."""
        pv = self.check_params(params)
        return float(self.forces.celerity(pv[self.param_names.index("lambda_over_L")]))


class Umeda4DOF(VesselSystem):
    """Umeda's (1999) surge-sway-yaw-roll-rudder model as a :class:`continuation.System`.

    Parameters
    ----------
    vessel : VesselData, str or Path
        A vessel description (or the name/path of a vessel file), resolved with
        :func:`ship_models.estimation.resolve_vessel`.
    saturation : bool
        Smoothly limit the rudder at ``rudder.delta_max`` (default True).
    saturation_order : int
        Even exponent of the smooth saturation (default 16).
    wave_lift : bool
        Include the slender-body lift due to wave particle velocity (default True).
    waves : WaveForceBuilder, optional
        Builds the wave-force model from the hull (default: Froude-Krylov strips,
        :func:`~ship_models.hydro.waves.strip_waves`); see :mod:`ship_models.contracts`.

    Attributes
    ----------
    data, forces, vessel
        The resolved vessel and its forces (:class:`VesselSystem`).
    saturation, saturation_order, wave_lift
        The options above (:attr:`options`).

    Examples
    --------
    >>> from ship_models import purse_seiner
    >>> m = purse_seiner()
    >>> p = m.default_params()
    >>> x = m.equilibrium_guess(p, where="crest")
    """

    def __init__(
        self,
        vessel: VesselData | str | Path | VesselModelData = "purse_seiner",
        *,
        saturation: bool = True,
        saturation_order: int = 16,
        wave_lift: bool = True,
        waves: WaveForceBuilder | None = None,
    ) -> None:
        if saturation_order < 2 or saturation_order % 2:
            raise ValueError(
                f"`saturation_order` must be an even integer >= 2, got {saturation_order}"
            )
        self.saturation = bool(saturation)
        self.saturation_order = int(saturation_order)
        self.wave_lift = bool(wave_lift)
        defaults = {
            "Fn": PAPER_FN,
            "chi_c": PAPER_CHI_C,
            "H_over_lambda": "waves.H_over_lambda",
            "lambda_over_L": "waves.lambda_over_L",
            "K_R": "autopilot.K_R",
            "T_D": "autopilot.T_D",
        }
        super().__init__(
            vessel,
            waves,
            state_names=STATE_NAMES,
            param_names=PARAM_NAMES,
            defaults=defaults,
            label="umeda_4dof",
        )

    # ------------------------------------------------------------------ equations
    def _rhs(self, x: Any, p: Any, ops: Ops) -> Any:
        F = self.forces
        xi, u, v, chi, r, phi, pr, delta = (x[i] for i in range(8))
        Fn, chi_c, Hl, lL, K_R, T_D = (p[i] for i in range(6))
        lam = F.wavelength(lL)
        c = F.celerity(lL, ops)
        n = F.revolutions(Fn, ops)
        Xw, Yw, Nw, Kw = F.waves.forces(xi, u, chi, SeaState(Hl, lL), ops, lift=self.wave_lift)
        FN = F.rudder_normal_force(u, v, r, delta, n, ops)
        YR = -(1.0 + F.a_H) * FN
        NR = -(F.x_R + F.a_H * F.x_H) * FN
        KR = (F.z_R + F.a_H * F.z_H) * FN
        Yv, Yr = F.Y_v1 * u, F.Y_r1 * u
        Nv, Nr = F.N_v1 * u, F.N_r1 * u
        u2 = u * u
        f1 = (u * ops.cos(chi) - v * ops.sin(chi) - c) / lam
        f2 = F.surge_acceleration(u, n, Xw, ops)
        f3 = (-(F.mass + F.m_x) * u * r + Yv * v + Yr * r + F.Y_phi2 * u2 * phi + YR + Yw) / (
            F.mass + F.m_y
        )
        f4 = r
        f5 = (Nv * v + Nr * r + F.N_phi2 * u2 * phi + NR + Nw) / (F.I_zz + F.J_zz)
        f6 = pr
        f7 = (
            F.m_x * F.z_H * u * r
            - F.z_H * Yv * v
            - F.z_H * Yr * r
            + F.roll_damping(u) * pr
            + F.K_phi2 * u2 * phi
            + KR
            + Kw
            - F.mass * F.g * F.gz(phi, ops)
        ) / F.I_xx_J_xx
        cmd = -K_R * (chi - chi_c) - K_R * T_D * r
        if self.saturation:
            cmd = smooth_saturation(cmd, F.delta_max, self.saturation_order, ops)
        f8 = (cmd - delta) / F.T_E
        return ops.stack([f1, f2, f3, f4, f5, f6, f7, f8])

    # ------------------------------------------------------------------ helpers
    @property
    def options(self) -> dict[str, Any]:
        """The keyword options of this model (``saturation``, ``saturation_order``,
        ``wave_lift``), as the constructor takes them."""
        return {
            "saturation": self.saturation,
            "saturation_order": self.saturation_order,
            "wave_lift": self.wave_lift,
        }

    def check_params(self, p: Any, name: str = "p") -> FloatArray:
        """Parameter vector (as :meth:`continuation.System.check_params`).

        Also checks, once per new ``(Fn, lambda/L)``, the speeds the analysis visits
        (nominal speed to wave celerity) against the validity ranges of the resistance
        and thrust estimates (:meth:`ShipForces.check_validity`: a WARNING names the
        coefficient and the speed, once per coefficient).
        """
        arr = super().check_params(p, name)
        key = (float(arr[0]), float(arr[3]))
        if key != getattr(self, "_validity_checked", None):
            self._validity_checked = key
            self.forces.check_validity(key[0], key[1], self.vessel.name)
        return arr

    def revolutions(self, params: Params | FloatArray) -> float:
        """Propeller revolution ``n(Fn)`` (1/s)."""
        pv = self.check_params(params)
        return float(self.forces.revolutions(pv[0]))

    def surge_balance(self, xi: FloatArray | float, params: Params | FloatArray) -> FloatArray:
        """Surge force ``T - R + X_w`` at ``u = c/cos(chi_c)``, ``chi = chi_c`` (N), vs xi_G."""
        pv = self.check_params(params)
        F = self.forces
        Fn, chi_c, Hl, lL = pv[:4]
        c = float(F.celerity(lL))
        u = c / np.cos(chi_c)
        n = F.revolutions(Fn)
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        fn = _surge_balance_function(self, xi.size)
        return np.asarray(fn(xi, u, chi_c, n, Hl, lL), dtype=float).reshape(-1)

    def equilibrium_guess(self, params: Params | FloatArray, where: str = "crest") -> FloatArray:
        """Starting guess for a surf-riding equilibrium near the crest or the trough.

        Lateral states zero, ``chi = chi_c``, ``u = c / cos(chi_c)``, and ``xi_G`` where
        the surge force balances (bracketing root of :meth:`surge_balance`): on the
        crest side of the wave (``where="crest"``, 0.25 < xi_G < 0.75) or the trough side.

        Raises
        ------
        ValueError
            If ``where`` is not "crest"/"trough", or the surge force does not change sign
            (no surf-riding equilibrium for these parameters).
        """
        if where not in ("crest", "trough"):
            raise ValueError(f"`where` must be 'crest' or 'trough', got {where!r}")
        pv = self.check_params(params)
        chi_c = pv[1]
        c = self.celerity(pv)
        grid = np.linspace(0.0, 1.0, 201)
        f = self.surge_balance(grid, pv)
        roots = []
        for i in range(grid.size - 1):
            if f[i] == 0.0 or f[i] * f[i + 1] < 0:
                g = lambda s: float(self.surge_balance(s, pv)[0])  # noqa: E731
                roots.append(so.brentq(g, grid[i], grid[i + 1], xtol=1e-14))
        if not roots:
            raise ValueError(
                "no surf-riding equilibrium: the surge force T - R + X_w does not vanish at "
                f"u = c for {dict(zip(PARAM_NAMES, pv, strict=True))}"
            )
        roots_a = np.mod(np.array(roots), 1.0)
        crest_side = np.abs(roots_a - 0.5) < 0.25
        pick = roots_a[crest_side] if where == "crest" else roots_a[~crest_side]
        if pick.size == 0:
            pick = roots_a
        target = 0.5 if where == "crest" else 0.0
        dist = np.abs(np.mod(pick - target + 0.5, 1.0) - 0.5)
        xi0 = float(pick[np.argmin(dist)])
        x = np.zeros(8)
        x[0], x[1], x[3] = xi0, c / np.cos(chi_c), chi_c
        return x

    def find_equilibrium(
        self,
        params: Params | FloatArray,
        where: str = "crest",
        *,
        guess: FloatArray | None = None,
        settings: NewtonSettings | None = None,
        throw: bool = False,
    ) -> NewtonResult:
        """The surf-riding equilibrium near the crest or the trough, by Newton's method.

        With ``guess`` (or at ``chi_c = 0``), a Newton solve from it (or from
        :meth:`equilibrium_guess`). Otherwise the guess with zero lateral states is only
        good near ``chi_c = 0`` (at ``chi_c >= ~27 deg`` Newton from it lands on another
        equilibrium), so the ``chi_c = 0`` point is continued in ``chi_c`` to the target
        by pseudo-arclength (:func:`continuation.api.continue_equilibria`) and polished
        there: the result is the point of the branch that starts at the crest (trough) at
        ``chi_c = 0``, as :func:`ship_models.analysis.fixed_points.find_fixed_point`
        labels it. If that branch folds back before reaching ``chi_c``, the result is not
        converged and its message says so (never another equilibrium silently).
        """
        pv = self.check_params(params)
        s = settings or NewtonSettings(tol=1e-9, max_iter=50, damping=True)

        def solve(x0: FloatArray) -> NewtonResult:
            return newton(
                lambda z: self.f(z, pv), lambda z: self.jacobian(z, pv), x0, s, throw=throw
            )

        chi_c = float(pv[1])
        if guess is not None or chi_c == 0.0:
            x0 = self.equilibrium_guess(pv, where) if guess is None else self.check_state(guess)
            return solve(x0)
        from continuation.status import Status

        p0 = Params(PARAM_NAMES, pv).replace(chi_c=0.0)
        start = newton(
            lambda z: self.f(z, p0.values),
            lambda z: self.jacobian(z, p0.values),
            self.equilibrium_guess(p0.values, where),
            s,
        )
        if not start.converged:
            return _failed(start, f"no {where} equilibrium at chi_c = 0: {start.message}", throw)
        br = follow_in_chi_c(self, start.z, p0, chi_c, ds_max=0.05)
        if br.status is not Status.PARAM_BOUND or abs(float(br.p[-1]) - chi_c) > 1e-12:
            msg = (
                f"the {where} equilibrium branch from chi_c = 0 does not reach chi_c = "
                f"{math.degrees(chi_c):.4g} deg (it ends at {math.degrees(br.p[-1]):.4g} deg: "
                f"{br.message})"
            )
            return _failed(NewtonResult(br.x[-1], False, 0, math.inf, br.status, msg), msg, throw)
        return solve(br.x[-1])

    def random_state(self, seed: int | None = None) -> FloatArray:
        """A random, physically plausible state (for tests), shape (8,)."""
        rng = np.random.default_rng(seed)
        c = self.celerity(self.default_params())
        return np.array(
            [
                rng.uniform(0.0, 1.0),
                rng.uniform(0.5, 1.2) * c,
                rng.uniform(-0.5, 0.5),
                rng.uniform(-0.6, 0.6),
                rng.uniform(-0.1, 0.1),
                rng.uniform(-0.4, 0.4),
                rng.uniform(-0.2, 0.2),
                rng.uniform(-0.4, 0.4),
            ]
        )


def follow_in_chi_c(
    model: Any,
    x0: FloatArray,
    params: Params,
    chi_c_end: float,
    *,
    ds: float = 0.01,
    ds_max: float = 0.05,
    **options: Any,
) -> Any:
    """Follow an equilibrium from ``chi_c = 0`` to the course ``chi_c_end`` (rad).

    The one path from the ``chi_c = 0`` surge roots to a course, shared by
    :meth:`Umeda4DOF.find_equilibrium` and
    :func:`ship_models.analysis.fixed_points.trace_in_chi_c`: pseudo-arclength
    continuation in ``chi_c`` (:func:`continuation.api.continue_equilibria`,
    ``direction="forward"``, bounded by 0 and ``chi_c_end``), steps ``ds`` (signed
    towards ``chi_c_end``) up to ``ds_max``.

    Parameters
    ----------
    model : Umeda4DOF
    x0 : ndarray, shape (8,)
        The equilibrium at ``chi_c = 0`` (``params["chi_c"]`` must be 0).
    params : Params
    chi_c_end : float
        Nonzero end of the course range.
    ds, ds_max : float
        Initial (unsigned) and largest step.
    **options
        Further options of ``continue_equilibria`` (``max_steps``, ``progress``).

    Returns
    -------
    Branch
        Ends at ``chi_c_end`` (status ``PARAM_BOUND``) unless it folds back first.
    """
    from continuation.api import continue_equilibria  # (api imports the engine)

    lo, hi = (0.0, chi_c_end) if chi_c_end > 0 else (chi_c_end, 0.0)
    return continue_equilibria(
        model,
        x0,
        params,
        "chi_c",
        ds=math.copysign(ds, chi_c_end),
        ds_max=ds_max,
        p_min=lo,
        p_max=hi,
        direction="forward",
        **options,
    )


def _failed(res: NewtonResult, message: str, throw: bool) -> NewtonResult:
    """``res`` as a failure with ``message`` (ConvergenceError with ``throw``)."""
    if throw:
        from continuation.errors import ConvergenceError

        raise ConvergenceError(message)
    from continuation.status import Status

    status = res.status if not res.status.ok else Status.NEWTON_FAILED
    return NewtonResult(res.z, False, res.iterations, res.residual_norm, status, message)


__all__ = [
    "PARAM_NAMES",
    "STATE_NAMES",
    "Umeda4DOF",
    "VesselSystem",
    "rebuilt_data",
    "smooth_saturation",
]
