r"""Estimation pipeline: from a vessel file to every coefficient of the model.

:func:`resolve_vessel` fills each coefficient that the file does not give with a
named method and records it with status ``estimated`` (or ``assumed`` where no
method exists) and the method in ``source``; coefficients given in the file (or by
:meth:`VesselData.with_overrides`) are never replaced. :func:`build_forces` turns
the resolved data into :class:`~ship_models.forces.ShipForces` (strip arrays, GZ
series, resistance spline), the numbers of Eqs. (4)-(11).

Methods (one module each under :mod:`ship_models.hydro`):

==========================  ==================================================
quantity                    method
==========================  ==================================================
hull sections S, B, d       parametric form-parameter hull (:mod:`.hydro.hull`)
C_wp                        Schneekluth & Bertram (1998)
R(u)                        ITTC-1957 + Holtrop & Mennen (1982) / Holtrop (1984),
                            or the MMG straight-running coefficient R0' if given
K_T(J)                      Wageningen B-series (Oosterveld & van Oossanen 1975)
w_P, t_P                    Taylor (1933); Holtrop (1984)
m_x                         Söding (1982) fit of Motora's charts
m_y, J_zz                   strip theory, Lewis sections at zero frequency
Y_v, Y_r, N_v, N_r          Inoue, Hirano & Kijima (1981)
f_alpha                     Fujii & Tsuda (1961)
I_xx + J_xx                 from T_phi and GM
K_p(u)                      zeta_0 (assumed) + Ikeda et al. (1978) lift damping
GZ(phi)                     hull hydrostatics, free sinkage and trim
X_w, Y_w, N_w, K_w          Froude-Krylov strips + slender-body lift
X_w diffraction (optional)  G.I. Taylor (1928) long-wave m_x/(rho V) ratio
==========================  ==================================================

Published coefficients can be given instead of estimated (every such key is
optional in the file): added masses dimensionally (``m_x``) or as MMG primes
(``m_x_prime = m_x / (rho/2 L^2 d)``, ``J_zz_prime = J_zz / (rho/2 L^4 d)``), the
resistance as the MMG coefficient ``resistance.R0_prime`` (then
:math:`R(u) = R'_0\,\tfrac12\rho L d\,u^2`, Yasukawa & Yoshimura 2015),
the rudder span ``rudder.H_R``. Hull derivatives measured about another origin than G
(the MMG standard method uses midship) are moved to G when ``hydrodynamics.x_ref``
names that origin (:func:`derivatives_about_g`).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import inspect
import logging
import pickle
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .contracts import WaveForceBuilder, WaveInputs
from .forces import ShipForces
from .hydro.added_mass import lewis_sway_added_mass, soding_surge_added_mass
from .hydro.curves import Polynomial1D, interpolating_spline
from .hydro.diffraction import taylor_diffraction_ratio
from .hydro.heel import (
    SON_NOMOTO_BAND,
    SON_NOMOTO_SOURCE,
    HeelDerivatives,
    son_nomoto_heel_derivatives,
    son_nomoto_validity,
)
from .hydro.hull import FormParameters, HullForm, parametric_hull, schneekluth_cwp
from .hydro.hydrostatics import GZCurve, gz_curve, is_code_margin, marginal_topside_height
from .hydro.manoeuvring import fujii_lift_slope, inoue_hull_derivatives
from .hydro.mesh_hull import MeshHull, hull_from_mesh
from .hydro.mesh_io import is_wetted_surface, read_mesh_file
from .hydro.offsets import OffsetsError, OffsetsHull, hull_from_offsets, read_offsets
from .hydro.propeller import (
    Propeller,
    bseries_kt_curve,
    bseries_zero_thrust_J,
    fit_kt_quadratic,
    holtrop_thrust_deduction,
    taylor_wake,
)
from .hydro.resistance import (
    HOLTROP_FN_MAX,
    HOLTROP_RANGE_SOURCE,
    HoltropHull,
    ResistanceFit,
    fit_resistance,
    resistance_table,
)
from .hydro.roll import ikeda_lift_damping_per_speed, roll_inertia
from .hydro.upright import check_particulars
from .hydro.upright import hydrostatics as offsets_hydrostatics
from .hydro.waves import strip_waves
from .validity import ValidityRange
from .validity import report as report_validity
from .vessel import Coefficient, VesselData, VesselFileError

log = logging.getLogger(__name__)


def _est(value: float, unit: str, source: str, status: str = "estimated") -> Coefficient:
    return Coefficient(float(value), unit, source, status)


def _named_file(v: VesselData, key: str) -> Path | None:
    """The file named by ``[vessel] <key>``, relative to the vessel file; None if unset."""
    name = v.meta.get(key)
    if not name:
        return None
    p = Path(str(name))
    if not p.is_absolute() and v.path:
        p = Path(v.path).parent / p
    return p


def offsets_path(v: VesselData) -> Path | None:
    """The offsets file named by ``[vessel] hull_offsets`` (relative to the vessel file)."""
    return _named_file(v, "hull_offsets")


def _particulars(v: VesselData, *names: str) -> dict[str, float]:
    """The vessel's principal particulars ``names`` as keyword arguments of the hull
    builders (``L`` is ``particulars.L_pp``, the others their own names)."""
    return {n: v.get(f"particulars.{'L_pp' if n == 'L' else n}") for n in names}


def form_parameters(v: VesselData, C_wp: float | None = None) -> FormParameters:
    """The form parameters of the vessel's hull (``particulars.*``, ``hull.C_M``).

    Parameters
    ----------
    v : VesselData
    C_wp : float, optional
        Waterplane coefficient (default ``hull.C_wp`` of the file; the resolved
        vessel's estimate when the file has none).

    Returns
    -------
    FormParameters
        ``lcb`` from midship, forward + (the file's ``lcb_aft`` with its sign turned).
    """
    return FormParameters(
        **_particulars(v, "L", "B", "D", "d_f", "d_a", "C_b"),
        lcb=-v.get("particulars.lcb_aft"),
        C_M=v.get("hull.C_M"),
        C_wp=v.get("hull.C_wp") if C_wp is None else C_wp,
    )


def offsets_hull(v: VesselData) -> OffsetsHull:
    """The strip hull of the vessel's ``[vessel] hull_offsets`` table, checked against
    the particulars (C_b, l.c.b., B); VesselFileError naming the contradiction."""
    p = offsets_path(v)
    if p is None:
        raise VesselFileError("`vessel.hull_offsets`: the vessel has no offsets file")
    try:
        table = read_offsets(p)
        hull = hull_from_offsets(
            table,
            **_particulars(v, "L", "D", "d_f", "d_a"),
            n_per_interval=max(2, int(v.get("hull.n_stations")) // max(1, table.x.size - 1)),
        )
        check_particulars(
            offsets_hydrostatics(hull),
            L=v.get("particulars.L_pp"),
            B=v.get("particulars.B"),
            d_m=0.5 * (v.get("particulars.d_f") + v.get("particulars.d_a")),
            C_b=v.get("particulars.C_b"),
            lcb_aft=v.get("particulars.lcb_aft"),
            B_hull=2.0 * float(np.max(hull.b_wl)),
            source=str(p),
        )
    except OffsetsError as exc:
        raise VesselFileError(f"`vessel.hull_offsets`: {exc}") from None
    return hull


def hull_mesh_path(v: VesselData) -> Path | None:
    """The mesh file named by ``[vessel] hull_mesh`` (relative to the vessel file)."""
    return _named_file(v, "hull_mesh")


def mesh_is_hull(v: VesselData) -> bool:
    """Whether ``[vessel] hull_mesh`` is the hull (strips, hydrostatics, GZ and panels
    from the mesh) rather than the panel mesh only.

    The mesh is the hull unless the file also names ``hull_offsets`` or the mesh is a
    wetted surface only (open, its free edges on the waterline: what panel codes use),
    which serves the panel method beside the offsets or the particulars.
    """
    p = hull_mesh_path(v)
    if p is None or offsets_path(v) is not None:
        return False
    if not p.is_file():
        return True  # refused with the file's name when the hull is built
    try:
        stat = p.stat()
        return not _wetted_only(str(p), stat.st_mtime_ns, stat.st_size)
    except OffsetsError:
        return True  # unreadable: refused in one line when the hull is built


@functools.lru_cache(maxsize=32)
def _wetted_only(path: str, mtime_ns: int, size: int) -> bool:
    return is_wetted_surface(*read_mesh_file(path))


def mesh_hull(v: VesselData) -> MeshHull:
    """The hull of the vessel's ``[vessel] hull_mesh`` (a closed mesh), checked against
    the particulars (drafts, C_b, l.c.b., B); VesselFileError naming the problem."""
    p = hull_mesh_path(v)
    if p is None:
        raise VesselFileError("`vessel.hull_mesh`: the vessel has no mesh file")
    try:
        if not p.is_file():
            raise OffsetsError(f"no mesh file {str(p)!r}")
        digest = hashlib.sha256(p.read_bytes()).hexdigest()  # the key: the file's content
        return _memo_call(
            "mesh_hull",
            _hull_from_mesh_file,
            str(p),
            digest,
            **_particulars(v, "L", "D", "d_f", "d_a", "B", "C_b", "lcb_aft"),
            n_per_interval=2,
            n_stations=max(41, int(v.get("hull.n_stations")) + 1),
        )
    except OffsetsError as exc:
        raise VesselFileError(f"`vessel.hull_mesh`: {exc}") from None


def _hull_from_mesh_file(path: str, digest: str, **kwargs: Any) -> MeshHull:
    """:func:`hull_from_mesh` of a file whose content hashes to ``digest`` (cache key)."""
    return hull_from_mesh(path, **kwargs)


def _hull(v: VesselData, C_wp: float) -> HullForm:
    if offsets_path(v) is not None:
        return offsets_hull(v)
    if mesh_is_hull(v):
        return mesh_hull(v)
    return parametric_hull(
        form_parameters(v, C_wp),
        n_stations=int(v.get("hull.n_stations")),
        beta_min=v.get("hull.beta_min"),
        beta_max=v.get("hull.beta_max"),
    )


def _holtrop(v: VesselData, hull: HullForm, C_wp: float, S: float) -> HoltropHull:
    L = v.get("particulars.L_pp")
    return HoltropHull(
        L=L,
        B=v.get("particulars.B"),
        T=0.5 * (v.get("particulars.d_f") + v.get("particulars.d_a")),
        T_F=v.get("particulars.d_f"),
        volume=hull.volume,
        C_M=v.get("hull.C_M"),
        C_wp=C_wp,
        lcb_percent=-100.0 * v.get("particulars.lcb_aft") / L,
        S=S,
        C_stern=v.get("resistance.C_stern"),
    )


def _quadratic_fit(J: Any, kt: Any) -> tuple[float, float, float]:
    A = np.column_stack([np.ones_like(J), J, J**2])
    c = np.linalg.lstsq(A, kt, rcond=None)[0]
    return float(c[0]), float(c[1]), float(c[2])


def derivatives_about_g(prime: dict[str, float], a_over_L: float) -> dict[str, float]:
    r"""Move the linear hull derivatives from an origin O to the centre of gravity G.

    With G a distance :math:`a = x_G - x_O` ahead of O, the lateral velocity at O is
    :math:`v_O = v_G - a r` and the yaw moment about G is :math:`N_G = N_O - a Y`, so

    .. math::

        Y'_v{}^G &= Y'_v, \qquad Y'_r{}^G = Y'_r - a' Y'_v, \qquad
        N'_v{}^G = N'_v - a' Y'_v, \\
        N'_r{}^G &= N'_r - a'(Y'_r + N'_v) + a'^2 Y'_v, \qquad a' = a / L,

    (non-dimensionalised as in :mod:`ship_models.hydro.manoeuvring`). The added-mass
    cross-coupling that the same shift creates (:math:`-a\,m_y\dot r` in the sway
    equation) is not part of Umeda's (1999) equations and is neglected.

    Parameters
    ----------
    prime : dict
        ``Y_v_prime, Y_r_prime, N_v_prime, N_r_prime`` about O.
    a_over_L : float
        :math:`(x_G - x_O)/L`.

    Returns
    -------
    dict
        The same keys, about G (other keys are copied unchanged).
    """
    a = float(a_over_L)
    Yv, Yr, Nv, Nr = (prime[k] for k in ("Y_v_prime", "Y_r_prime", "N_v_prime", "N_r_prime"))
    out = dict(prime)
    out["Y_r_prime"] = Yr - a * Yv
    out["N_v_prime"] = Nv - a * Yv
    out["N_r_prime"] = Nr - a * (Yr + Nv) + a * a * Yv
    return out


@dataclass(frozen=True)
class VesselModelData:
    """Everything derived from a vessel file.

    Attributes
    ----------
    vessel : VesselData
        The resolved data (file values plus estimates, with sources).
    forces : ShipForces
        Coefficients of the equations of motion.
    hull : HullForm
        Strip hull.
    gz : GZCurve
        Hydrostatic righting-arm curve and its fit.
    holtrop : HoltropHull
        Resistance regression inputs (for reports and checks).
    info : dict
        Derived numbers for reports (wetted-surface check, fit errors, ...).
    wave_builder : WaveForceBuilder
        How ``forces.waves`` was made (:func:`~ship_models.hydro.waves.strip_waves`
        by default); a rebuild with changed coefficients uses it again.
    """

    vessel: VesselData
    forces: ShipForces
    hull: HullForm
    gz: GZCurve
    holtrop: HoltropHull
    info: dict[str, float]
    wave_builder: WaveForceBuilder = field(default=strip_waves, repr=False)


_CACHE: dict[tuple[Any, ...], VesselModelData] = {}
_CACHE_SIZE = 8


def _builder_key(waves: WaveForceBuilder | None) -> Any:
    if waves is None:
        return None
    try:
        hash(waves)
    except TypeError:
        return ("id", id(waves))
    return waves


def resolve_vessel(vessel: VesselData, *, waves: WaveForceBuilder | None = None) -> VesselModelData:
    """Cached :func:`build_vessel_model` (keyed by the vessel's name and coefficients
    and the wave-force builder)."""
    meta = tuple(sorted((k, str(v)) for k, v in vessel.meta.items()))  # wave_forces, offsets
    key = (vessel.name, vessel.path, meta, tuple(sorted(vessel.coefficients.items())),
           tuple(sorted(vessel.curves.items())), _builder_key(waves))  # fmt: skip
    hit = _CACHE.get(key)
    if hit is not None:
        return hit
    out = build_vessel_model(vessel, waves=waves)
    if len(_CACHE) >= _CACHE_SIZE:
        _CACHE.pop(next(iter(_CACHE)))
    _CACHE[key] = out
    return out


# ---------------------------------------------------------------------- memo
class _Memo:
    """Results of the expensive estimation steps keyed by their exact inputs."""

    def __init__(self) -> None:
        self.store: dict[bytes, Any] = {}
        self.stats = {"hits": 0, "misses": 0}

    def get(self, key: bytes, make: Callable[[], Any]) -> Any:
        if key in self.store:
            self.stats["hits"] += 1
            return self.store[key]
        self.stats["misses"] += 1
        out = self.store[key] = make()
        return out


_MEMO: ContextVar[_Memo | None] = ContextVar("broachkit_estimation_memo", default=None)


@contextlib.contextmanager
def reuse_hydrostatics() -> Iterator[dict[str, int]]:
    """Inside the context, rebuilds reuse the expensive steps with identical inputs.

    :func:`build_vessel_model` computes the GZ curve (``gz_curve``), the IS-Code
    topside fit (``marginal_topside_height``; together about 1.3 s of a 1.5 s build)
    and the resistance spline (``fit_resistance``) through a memo keyed by their exact
    inputs (the pickled hull form with all its arrays, GM and the keywords; for the
    spline the resistance's values on the fit's own sample grid), so a rebuild with
    one coefficient changed recomputes only what depends on it. Yields ``{"hits":
    .., "misses": ..}`` (updated as the context runs). Nested contexts share the
    outer memo.
    """
    outer = _MEMO.get()
    if outer is not None:
        yield outer.stats
        return
    memo = _Memo()
    token = _MEMO.set(memo)
    try:
        yield memo.stats
    finally:
        _MEMO.reset(token)


def _memo_call(name: str, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)`` through the in-process memo (inside
    :func:`reuse_hydrostatics`) and the disk cache (:mod:`ship_models.disk_cache`)."""
    from .disk_cache import cached_call

    memo = _MEMO.get()
    if memo is None:
        return cached_call(name, fn, *args, **kwargs)
    key = pickle.dumps((name, args, sorted(kwargs.items())), protocol=4)
    return memo.get(key, lambda: cached_call(name, fn, *args, **kwargs))


def _memo_fit(fun: Callable[[Any], Any], u_max: float, knot_spacing: float, **kwargs: Any) -> Any:
    memo = _MEMO.get()
    if memo is None:
        return fit_resistance(fun, u_max, knot_spacing, **kwargs)
    n_default = inspect.signature(fit_resistance).parameters["n_samples"].default
    u = np.linspace(0.0, u_max, int(kwargs.get("n_samples", n_default)))
    R = np.asarray(fun(u), dtype=float)  # the fit depends on ``fun`` only through these
    key = pickle.dumps(("fit_resistance", R, float(u_max), float(knot_spacing),
                        sorted(kwargs.items())), protocol=4)  # fmt: skip
    return memo.get(key, lambda: fit_resistance(fun, u_max, knot_spacing, **kwargs))


#: ``[vessel] wave_forces`` of a vessel file: the wave-force model it asks for.
WAVE_FORCE_MODELS = ("froude_krylov_strips", "panel_fk_diffraction", "panel_fk")


def _file_wave_builder(vessel: VesselData) -> WaveForceBuilder:
    """The builder named by ``[vessel] wave_forces`` (default: Froude-Krylov strips)."""
    name = str(vessel.meta.get("wave_forces", WAVE_FORCE_MODELS[0]))
    if name == "froude_krylov_strips":
        if vessel.meta.get("hull_mesh") and not mesh_is_hull(vessel):
            raise VesselFileError(
                "`vessel.hull_mesh` is used by the panel method only (a wetted-surface mesh, "
                "or a mesh beside `vessel.hull_offsets`): set `vessel.wave_forces` to "
                "'panel_fk_diffraction' or 'panel_fk' (the strips use the offsets or the "
                "particulars), or give a closed mesh of the whole hull"
            )
        return strip_waves
    if name in ("panel_fk_diffraction", "panel_fk"):
        from .hydro.panel import PanelWaveBuilder  # Capytaine only when asked for

        return PanelWaveBuilder(diffraction=name == "panel_fk_diffraction")
    raise VesselFileError(f"`vessel.wave_forces` must be one of {WAVE_FORCE_MODELS}, got {name!r}")


def build_vessel_model(
    vessel: VesselData, *, waves: WaveForceBuilder | None = None
) -> VesselModelData:
    """Estimate every coefficient the file does not give and build the force model.

    Parameters
    ----------
    vessel : VesselData
        A validated vessel description.
    waves : WaveForceBuilder, optional
        Makes the wave-force model from the hull and loading
        (:class:`~ship_models.contracts.WaveInputs`); default the one the file names
        in ``[vessel] wave_forces`` (:data:`WAVE_FORCE_MODELS`), else the
        Froude-Krylov strips :func:`~ship_models.hydro.waves.strip_waves`.

    Returns
    -------
    VesselModelData
        With ``vessel`` holding file values plus estimates (status ``estimated`` or
        ``assumed``, method in ``source``) and ``wave_builder`` the builder used.
    """
    builder: WaveForceBuilder = _file_wave_builder(vessel) if waves is None else waves
    if not callable(builder):
        raise ValueError(
            f"`waves` must be a wave-force builder (a callable taking WaveInputs), got "
            f"a {type(builder).__name__}"
        )
    v = vessel
    est: dict[str, Coefficient] = {}
    rho, g, nu = v.get("environment.rho"), v.get("environment.g"), v.get("environment.nu")
    L, B = v.get("particulars.L_pp"), v.get("particulars.B")
    d_f, d_a = v.get("particulars.d_f"), v.get("particulars.d_a")
    d_m = 0.5 * (d_f + d_a)
    C_b = v.get("particulars.C_b")
    lcb_aft = v.get("particulars.lcb_aft")
    GM, T_phi = v.get("loading.GM"), v.get("loading.T_phi")

    # ---- hull ---------------------------------------------------------------
    if v.has("hull.C_wp"):
        C_wp = v.get("hull.C_wp")
    elif offsets_path(v) is not None:
        oh = offsets_hull(v)
        C_wp = oh.waterplane_area / (L * B)
        est["hull.C_wp"] = _est(C_wp, "-", f"waterplane area of the offsets {offsets_path(v)}")
    elif mesh_is_hull(v):
        mh = mesh_hull(v)
        C_wp = offsets_hydrostatics(mh).A_wp / (L * B)
        est["hull.C_wp"] = _est(C_wp, "-", f"waterplane area of the mesh {hull_mesh_path(v)}")
    else:
        C_wp = schneekluth_cwp(C_b)
        est["hull.C_wp"] = _est(
            C_wp,
            "-",
            "(1 + 2 C_b)/3: Schneekluth & Bertram (1998), Ship Design for Efficiency and Economy",
        )
    hull = _hull(v, C_wp)
    S_hull = hull.wetted_surface()
    if v.has("particulars.S_f"):
        S_f = v.get("particulars.S_f")
    else:
        S_f = S_hull
        est["particulars.S_f"] = _est(S_f, "m^2", "girth integral of the hull's sections")
    # a mesh hull displaces its exact (polyhedral) volume; the strips agree to the slicing
    volume = offsets_hydrostatics(hull).volume if isinstance(hull, MeshHull) else hull.volume
    if v.has("loading.mass"):
        mass = v.get("loading.mass")
    else:
        mass = rho * volume
        est["loading.mass"] = _est(mass, "kg", "rho C_b L_pp B d_m")
    x_G = -lcb_aft  # G above B in calm water

    # ---- stability ------------------------------------------------------------
    if isinstance(hull, MeshHull):  # the mesh is the watertight envelope
        topside = v.get("stability.topside_height") if v.has("stability.topside_height") else 0.0
        if topside != 0.0:
            raise VesselFileError(
                f"`stability.topside_height` = {topside:g} m: a hull given by a mesh is its "
                "own watertight envelope (model enclosed superstructures in the mesh); give 0 "
                "or leave it out"
            )
        if not v.has("stability.topside_height"):
            est["stability.topside_height"] = _est(
                0.0, "m", f"the mesh {hull_mesh_path(v)} is the watertight envelope", "assumed"
            )
    elif v.has("stability.topside_height"):
        topside = v.get("stability.topside_height")
    else:
        topside = _memo_call("marginal_topside_height", marginal_topside_height, hull, GM)
        est["stability.topside_height"] = _est(
            topside,
            "m",
            "smallest watertight extension of the sides above D (stand-in for enclosed "
            "superstructures) for which the GZ curve meets the IMO 2008 IS Code general "
            "criteria (Part A 2.2) to within the 1 mm tolerance of the fit (the computed "
            "margin may miss zero by ~1e-4): the paper's condition 'marginally complies'",
        )
    gz = _memo_call(
        "gz_curve",
        gz_curve,
        hull,
        GM,
        heel_step=v.get("stability.heel_step"),
        n_terms=int(v.get("stability.n_gz_terms")),
        topside_height=topside,
    )
    zeta_G = gz.zeta_G
    if zeta_G + d_m <= 0.0:  # KG = KM - GM: G at or below the keel
        raise VesselFileError(
            f"`loading.GM` = {GM} m exceeds this hull's KM = {zeta_G + d_m + GM:.4g} m "
            f"(KG = {zeta_G + d_m:.4g} m: G below the keel)"
        )

    # ---- resistance -----------------------------------------------------------
    hh = _holtrop(v, hull, C_wp, S_f)
    hull_type = v.meta.get("hull_type", "")
    validity: list[ValidityRange] = []
    rfit: Any
    if v.resistance_method == "table":
        curve = v.curves["resistance"]
        rfit = resistance_table(curve.x, curve.y)
        validity.append(
            ValidityRange(
                f"resistance table ({curve.status}: {curve.source})",
                "u",
                0.0,
                curve.x_range[1],
                "speed range of the measured table",
            )
        )
    elif v.has("resistance.R0_prime"):
        # MMG standard method: R(u) = R0' rho/2 L d u^2 (exact, no fit)
        u_max = (
            v.get("resistance.Fn_max_fit") * np.sqrt(g * L)
            if v.has("resistance.Fn_max_fit")
            else np.sqrt(g * L)
        )
        r2 = v.get("resistance.R0_prime") * 0.5 * rho * L * d_m * u_max**2
        rfit = ResistanceFit(np.array([r2, 0.0]), np.zeros(0), np.zeros(0), float(u_max), 0.0)
    else:
        if v.has("resistance.form_factor"):
            k1 = v.get("resistance.form_factor")
        else:
            k1 = hh.form_factor()
            est["resistance.form_factor"] = _est(
                k1, "-", "1 + k1: Holtrop (1984), A statistical re-analysis of resistance data"
            )
        if v.has("resistance.C_A"):
            C_A = v.get("resistance.C_A")
        else:
            C_A = hh.correlation_allowance()
            est["resistance.C_A"] = _est(C_A, "-", "Holtrop (1984) correlation allowance")
        u_max = v.get("resistance.Fn_max_fit") * np.sqrt(g * L)
        knot = v.get("resistance.knot_spacing_Fn") * np.sqrt(g * L)

        def R_formula(u: Any) -> Any:
            return hh.total_resistance(u, rho=rho, g=g, nu=nu, form_factor=k1, C_A=C_A)

        rfit = _memo_fit(R_formula, u_max, knot)
        fn_hi = HOLTROP_FN_MAX.get(hull_type)
        if fn_hi is not None:
            validity.append(
                ValidityRange(
                    "resistance (Holtrop & Mennen 1982 / Holtrop 1984 regression)",
                    "Fn",
                    0.0,
                    fn_hi,
                    HOLTROP_RANGE_SOURCE,
                )
            )
        validity.append(
            ValidityRange("resistance spline fit", "u", 0.0, rfit.u_max, "resistance.Fn_max_fit")
        )

    # ---- propeller -------------------------------------------------------------
    D_p = v.get("propulsion.D_p")
    prop_method = v.propeller_method
    kt_curve: Any = None
    Z = int(v.get("propulsion.n_blades"))
    PD, AE = v.get("propulsion.P_over_D"), v.get("propulsion.AE_over_A0")
    if prop_method == "curve":
        c = v.curves["K_T"]
        if c.is_table:
            kt_curve = interpolating_spline(np.array(c.x), np.array(c.y))
        else:
            kt_curve = Polynomial1D(np.array(c.coefficients), c.x_range)
        Jg = np.linspace(c.x_range[0], min(c.x_range[1], 1.5), 200)
        kt = _quadratic_fit(Jg, kt_curve(Jg))
        kt_err = float("nan")
        validity.append(
            ValidityRange(
                f"K_T curve ({c.status}: {c.source})",
                "J",
                c.x_range[0],
                c.x_range[1],
                "range of the measured K_T(J)",
            )  # fmt: skip
        )
    elif v.has("propulsion.K_T0") and prop_method == "bseries_quadratic":
        kt = (v.get("propulsion.K_T0"), v.get("propulsion.K_T1"), v.get("propulsion.K_T2"))
        kt_err = float("nan")
    else:
        J_fit = v.get("propulsion.J_max_fit")
        k0, k1_, k2, kt_err = fit_kt_quadratic(PD, AE, Z, J_fit)
        kt = (k0, k1_, k2)
        J_zero = bseries_zero_thrust_J(PD, AE, Z)
        if prop_method == "bseries":
            kt_curve = bseries_kt_curve(PD, AE, Z)
            kt_err = 0.0
            validity.append(
                ValidityRange(
                    f"K_T (Wageningen B{Z}-{AE:.2f}, P/D {PD:.3g}, full polynomial)",
                    "J",
                    0.0,
                    J_zero,
                    "K_T >= 0 (Oosterveld & van Oossanen 1975 fit open-water data; beyond, "
                    "a windmilling propeller: a monotone C2 continuation, assumed)",
                )  # fmt: skip
            )
        else:
            src = (
                f"least-squares quadratic in J on [0, {J_fit}] of the "
                f"Wageningen B{Z}-{AE:.2f} P/D={PD} polynomial (Oosterveld & van Oossanen 1975)"
            )
            for name, val in zip(("K_T0", "K_T1", "K_T2"), kt, strict=True):
                est[f"propulsion.{name}"] = _est(val, "-", src)
            validity.append(
                ValidityRange(
                    f"K_T (quadratic fit of the B{Z}-{AE:.2f} P/D {PD:.3g} polynomial)",
                    "J",
                    0.0,
                    min(J_fit, J_zero),
                    f"fitted on J <= {J_fit}; B-series K_T = 0 at J = {J_zero:.3f}",
                )  # fmt: skip
            )
    if v.has("propulsion.w_P"):
        w_P = v.get("propulsion.w_P")
    else:
        w_P = taylor_wake(C_b)
        est["propulsion.w_P"] = _est(w_P, "-", "0.5 C_b - 0.05: Taylor (1933) single screw")
    if v.has("propulsion.t_P"):
        t_P = v.get("propulsion.t_P")
    else:
        t_P = holtrop_thrust_deduction(
            B, L, d_m, D_p, hh.C_P, hh.lcb_percent, v.get("resistance.C_stern")
        )
        est["propulsion.t_P"] = _est(t_P, "-", "Holtrop (1984) single-screw thrust deduction")
    w_curve = t_curve = None
    for name in ("w_P", "t_P"):
        if name in v.curves:
            cv = v.curves[name]
            spl = interpolating_spline(np.array(cv.x), np.array(cv.y), slope_start=0.0)
            if name == "w_P":
                w_curve = spl
            else:
                t_curve = spl
            validity.append(
                ValidityRange(
                    f"{name}(u) curve ({cv.source})",
                    "u",
                    0.0,
                    cv.x_range[1],
                    "speed range of the measured curve",
                )  # fmt: skip
            )
    propeller = None
    if kt_curve is not None or w_curve is not None or t_curve is not None:
        if kt_curve is None:
            kt_curve = Polynomial1D(np.array(kt, dtype=float), (0.0, np.inf))
        propeller = Propeller(D_p, kt_curve, (float(kt[0]), float(kt[1]), float(kt[2])),
                              w_P, t_P, w_curve, t_curve)  # fmt: skip
        # the revolution solve is a fixed number of Newton steps (CasADi-traceable):
        # check it converged over the Froude numbers analyses use, or refuse the curve
        for Fn_chk in (0.1, 0.2, 0.3, 0.4, 0.5):
            u_chk = Fn_chk * np.sqrt(g * L)
            res = propeller.revolution_residual(u_chk, float(rfit.evaluate(u_chk)), rho)
            if not res < 1e-9:
                raise VesselFileError(
                    f"`curves.K_T` / propeller: no thrust-resistance balance found at Fn "
                    f"{Fn_chk} (relative residual {res:.1e}); check that K_T(J) decreases "
                    "and stays positive over the advance ratios of the nominal speeds"
                )

    # ---- added masses -----------------------------------------------------------
    m22 = lewis_sway_added_mass(rho, hull.b_wl, hull.d, hull.beta)
    half_rho_L2d = 0.5 * rho * L**2 * d_m
    if v.has("hydrodynamics.m_x"):
        m_x = v.get("hydrodynamics.m_x")
    elif v.has("hydrodynamics.m_x_prime"):
        m_x = v.get("hydrodynamics.m_x_prime") * half_rho_L2d
    else:
        m_x = soding_surge_added_mass(rho, volume, L)
        est["hydrodynamics.m_x"] = _est(
            m_x, "kg", "2.7 rho V^(5/3)/L^2: Soding (1982) fit of Motora's charts"
        )
    if v.has("hydrodynamics.m_y"):
        m_y = v.get("hydrodynamics.m_y")
    elif v.has("hydrodynamics.m_y_prime"):
        m_y = v.get("hydrodynamics.m_y_prime") * half_rho_L2d
    else:
        m_y = float(hull.w @ m22)
        est["hydrodynamics.m_y"] = _est(
            m_y, "kg", "strip theory, Lewis sections at zero frequency (Lewis 1929)"
        )
    J_zz_given = v.has("hydrodynamics.J_zz") or v.has("hydrodynamics.J_zz_prime")
    if v.has("hydrodynamics.J_zz"):
        J_zz = v.get("hydrodynamics.J_zz")
    elif v.has("hydrodynamics.J_zz_prime"):
        J_zz = v.get("hydrodynamics.J_zz_prime") * half_rho_L2d * L**2
    else:
        J_zz = float(hull.w @ ((hull.x - x_G) ** 2 * m22))
        est["hydrodynamics.J_zz"] = _est(
            J_zz, "kg m^2", "strip theory, Lewis sections at zero frequency (Lewis 1929)"
        )
    I_zz = mass * (v.get("particulars.kappa_zz_over_L") * L) ** 2
    if v.has("hydrodynamics.I_xx_plus_J_xx"):
        Ixx = v.get("hydrodynamics.I_xx_plus_J_xx")
    else:
        Ixx = roll_inertia(mass, g, GM, T_phi)
        est["hydrodynamics.I_xx_plus_J_xx"] = _est(
            Ixx, "kg m^2", "m g GM (T_phi / 2 pi)^2 from the given T_phi and GM"
        )

    # ---- manoeuvring derivatives ------------------------------------------------
    ino = inoue_hull_derivatives(L, B, d_m, d_a - d_f, C_b)
    prime: dict[str, float] = {}
    for name, val in ino.items():
        key = f"hydrodynamics.{name}"
        if v.has(key):
            prime[name] = v.get(key)
        else:
            prime[name] = val
            est[key] = _est(
                val,
                "-",
                "Inoue, Hirano & Kijima (1981), Hydrodynamic derivatives on ship "
                "manoeuvring, ISP 28(321)",
            )
    if v.has("hydrodynamics.x_ref"):
        # derivatives (and a given J_zz) measured about x_ref: move them to G
        a_ref = x_G - v.get("hydrodynamics.x_ref")
        prime = derivatives_about_g(prime, a_ref / L)
        if J_zz_given:
            J_zz = J_zz + a_ref**2 * m_y  # parallel axes, no added-mass cross term
    heel_est: HeelDerivatives | None = None
    if v.heel_derivatives_method == "son_nomoto_ratio":
        z_H_over_d = v.get("roll.z_H_over_d") + zeta_G / d_m  # lateral force below G
        form = {"L/B": L / B, "B/d": B / d_m, "C_b": C_b}
        heel_est = son_nomoto_heel_derivatives(
            prime["Y_v_prime"],
            prime["N_v_prime"],
            z_H_over_d,
            L_over_B=form["L/B"],
            B_over_d=form["B/d"],
            C_b=form["C_b"],
        )
        for key, (lo, hi) in son_nomoto_validity().items():
            report_validity(
                v.name,
                ValidityRange(
                    "heel derivatives (Son & Nomoto 1981 ratios, an analogy)",
                    key,
                    lo,
                    hi,
                    f"+-{SON_NOMOTO_BAND:.0%} of the container ship SR 108's {key}",
                ),
                form[key],
                "this hull",
            )
    for name in ("Y_phi_prime", "N_phi_prime", "K_phi_prime"):
        key = f"hydrodynamics.{name}"
        if v.has(key):
            prime[name] = v.get(key)
        elif heel_est is not None:
            prime[name] = float(getattr(heel_est, name))
            out = (
                "; outside its hull form: " + ", ".join(heel_est.outside)
                if heel_est.outside
                else ""
            )
            est[key] = _est(
                prime[name],
                "-",
                "analogy: the ratio to the drift derivative (about G) of the same equation of "
                f"{SON_NOMOTO_SOURCE} (ship_models.hydro.heel){out}",
            )
        else:
            prime[name] = 0.0
            est[key] = _est(
                0.0,
                "-",
                "heel-induced hydrodynamic force neglected (no regression for this hull form; "
                "vessel.heel_derivatives_method = 'son_nomoto_ratio' gives an analogy estimate)",
                "assumed",
            )
    if v.has("rudder.f_alpha"):
        f_alpha = v.get("rudder.f_alpha")
    else:
        f_alpha = fujii_lift_slope(v.get("rudder.aspect_ratio"))
        est["rudder.f_alpha"] = _est(
            f_alpha, "-", "6.13 Lambda/(Lambda + 2.25): Fujii & Tsuda (1961)"
        )

    # ---- roll damping --------------------------------------------------------------
    omega_phi = 2.0 * np.pi / T_phi
    if v.has("hydrodynamics.K_p0"):
        Kp0 = v.get("hydrodynamics.K_p0")
    else:
        Kp0 = 2.0 * v.get("roll.zeta_0") * omega_phi
        est["hydrodynamics.K_p0"] = _est(
            Kp0, "-", "2 zeta_0 omega_phi from the assumed zero-speed damping ratio roll.zeta_0"
        )
    OG = -zeta_G  # depth of G below the waterline
    if v.has("hydrodynamics.K_p_lift_prime"):
        Kp_lift = v.get("hydrodynamics.K_p_lift_prime")
    else:
        Kp_lift = ikeda_lift_damping_per_speed(rho, L, B, d_m, v.get("hull.C_M"), OG) / (
            0.5 * rho * L * d_m**3
        )
        est["hydrodynamics.K_p_lift_prime"] = _est(
            Kp_lift,
            "-",
            "hull lift roll damping: Ikeda, Himeno & Tanaka (1978), substitute for Takahashi",
        )

    # ---- geometry of forces -------------------------------------------------------------
    z_H = v.get("roll.z_H_over_d") * d_m + zeta_G  # body z (down) of the lateral force below G
    A_R = v.get("rudder.A_R")
    if v.has("rudder.H_R"):
        h_R = v.get("rudder.H_R")
    else:
        h_R = float(np.sqrt(v.get("rudder.aspect_ratio") * A_R))
    z_R = (d_a - 0.5 * h_R) + zeta_G  # rudder centre: lower edge at the keel line aft
    eta = min(1.0, D_p / h_R)
    if v.has("hydrodynamics.wave_surge_scale"):
        surge_scale = v.get("hydrodynamics.wave_surge_scale")
    else:
        surge_scale = 1.0
        est["hydrodynamics.wave_surge_scale"] = _est(
            1.0,
            "-",
            "no correction of the wave surge force of the selected wave_surge_model "
            "(Froude-Krylov, as in Umeda 1999)",
            "assumed",
        )
    diffraction_factor = 1.0
    if v.wave_surge_model == "froude_krylov_taylor":
        if v.has("hydrodynamics.wave_surge_diffraction"):
            r_D = v.get("hydrodynamics.wave_surge_diffraction")
        else:
            r_D = taylor_diffraction_ratio(m_x, rho, volume)
            est["hydrodynamics.wave_surge_diffraction"] = _est(
                r_D,
                "-",
                "m_x/(rho V): long-wave diffraction part of the surge force, G.I. Taylor "
                "(1928) Proc. R. Soc. Lond. A 120:260-283 (ship_models.hydro.diffraction)",
            )
        diffraction_factor = 1.0 + r_D
    wave_model = builder(
        WaveInputs(
            vessel=vessel,
            hull=hull,
            x_G=x_G,
            zeta_G=zeta_G,
            m22=m22,
            z_H=z_H,
            rho=rho,
            g=g,
            n_depth=int(v.get("hull.n_depth")),
            surge_scale=surge_scale * diffraction_factor,
        )
    )
    if not callable(getattr(wave_model, "forces", None)):
        raise ValueError(
            f"`waves`: the builder gave a {type(wave_model).__name__}, which has no "
            "forces(xi_over_lambda, u, chi, H_over_lambda, lambda_over_L, ops, *, lift) method"
        )
    q_speed = 0.5 * rho * L * d_m
    forces = ShipForces(
        rho=rho,
        g=g,
        L=L,
        B=B,
        d_m=d_m,
        mass=mass,
        m_x=m_x,
        m_y=m_y,
        I_zz=I_zz,
        J_zz=J_zz,
        I_xx_J_xx=Ixx,
        Y_v1=prime["Y_v_prime"] * q_speed,
        Y_r1=prime["Y_r_prime"] * q_speed * L,
        N_v1=prime["N_v_prime"] * q_speed * L,
        N_r1=prime["N_r_prime"] * q_speed * L * L,
        Y_phi2=prime["Y_phi_prime"] * q_speed,
        N_phi2=prime["N_phi_prime"] * q_speed * L,
        K_phi2=prime["K_phi_prime"] * q_speed * d_m,
        z_H=z_H,
        K_p0=-Kp0 * Ixx,
        K_p1=-Kp_lift * 0.5 * rho * L * d_m**3,
        A_R=A_R,
        f_alpha=f_alpha,
        a_H=v.get("rudder.a_H"),
        x_R=-0.5 * L - x_G,
        x_H=v.get("rudder.x_H_over_L") * L - x_G,
        z_R=z_R,
        gamma_R=v.get("rudder.gamma_R"),
        l_R=v.get("rudder.l_R_over_L") * L,
        epsilon=v.get("rudder.epsilon"),
        kappa=v.get("rudder.kappa"),
        eta=eta,
        D_p=D_p,
        w_P=w_P,
        t_P=t_P,
        kt=(float(kt[0]), float(kt[1]), float(kt[2])),
        resistance=rfit,
        gz_coeffs=np.array(gz.coeffs),
        waves=wave_model,
        T_E=v.get("autopilot.T_E"),
        delta_max=v.get("rudder.delta_max"),
        propeller=propeller,
        validity=tuple(validity),
    )
    phi_m, gz_m = gz.max_gz
    info = {
        "volume": volume,
        "mass": mass,
        "wetted_surface_hull": S_hull,
        "wetted_surface_used": S_f,
        "zeta_G": zeta_G,
        "KG": zeta_G + d_m,
        "KM": zeta_G + d_m + GM,
        "gz_fit_error": gz.fit_error,
        "phi_gz_max": phi_m,
        "gz_max": gz_m,
        "phi_vanishing": gz.vanishing_angle,
        "topside_height": topside,
        "is_code_margin": is_code_margin(gz),
        "resistance_fit_error": rfit.max_rel_error,
        "kt_fit_error": kt_err,
        "z_H": z_H,
        "z_R": z_R,
        "eta_rudder": eta,
        "x_G": x_G,
        "I_zz": I_zz,
    }
    resolved = vessel.with_estimates(est)
    log.debug("resolved vessel %s with %d estimates", vessel.name, len(est))
    return VesselModelData(resolved, forces, hull, gz, hh, info, builder)


__all__ = [
    "VesselModelData",
    "build_vessel_model",
    "derivatives_about_g",
    "form_parameters",
    "resolve_vessel",
    "reuse_hydrostatics",
]
