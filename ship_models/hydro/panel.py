r"""Wave forces by a panel method (Capytaine): Froude-Krylov and diffraction, tabulated.

Method
------
Linear potential flow about the hull at its calm-water attitude, solved by the
boundary-element code Capytaine (Ancellin, M. & Dias, F. 2019, "Capytaine: a Python-based
linear potential flow solver", J. Open Source Softw. 4(36):1341; a Nemoh-derived
solver with the Delhommeau Green function of infinite depth). For a regular wave of
unit amplitude, wavenumber :math:`k = 2\pi/\lambda` and direction :math:`\beta`, the
exciting force is the Froude-Krylov part (the incident-wave pressure integrated over
the wetted hull, :math:`\hat F_{FK}`) plus the diffraction part :math:`\hat F_D` (the
pressure of the scattered potential that cancels the incident normal velocity on the
hull) (Newman, J.N. 1977, "Marine Hydrodynamics", MIT Press, Sect. 6.15-6.18).

Frequency and forward speed. The table is computed at **zero forward speed at the
wave frequency** :math:`\omega = \sqrt{gk}` (deep water; the default), the usual
assumption of Froude-Krylov-plus-diffraction corrections in surf-riding and broaching
studies. A ship surf-riding moves with the wave, so its encounter frequency
:math:`\omega_e = \omega - k u\cos\chi` tends to zero and a zero-speed diffraction is
an approximation, not a limit. As a bound, ``forward_speed_Fn`` gives Capytaine's
forward-speed option at :math:`U = Fn\sqrt{gL}`: the Green function at the encounter
frequency and the pressure :math:`i\omega_e\rho\phi + \rho U\,\partial\phi/\partial x`
(Capytaine 3.0, ``BEMSolver.solve``), without the interaction with the steady flow
around the hull, i.e. the encounter-frequency approximation of low-speed seakeeping
(the speed terms of Salvesen, N., Tuck, E.O. & Faltinsen, O. 1970, "Ship motions and
sea loads", Trans. SNAME 78:250-287, in their simplest form); the spread between the
two is the forward-speed uncertainty of the diffraction.

Axes and phase. The mesh is in Capytaine's axes (x forward, y to port, z up, origin
midship on the calm waterline); the force is taken about G. The paper's wave
(:mod:`ship_models.hydro.waves`) has elevation :math:`\eta = -a\cos k\xi` with
:math:`\xi = \xi_G + x\cos\chi - y\sin\chi` (y to starboard), i.e. the direction
:math:`\beta = \chi` in Capytaine's axes and the phase :math:`k\xi_G + \pi` at G, so
with :math:`s = \xi_G/\lambda` and Capytaine's :math:`\mathrm{Re}(\hat F e^{-i\omega t})`

.. math::

    (X, Y, N, K)_w(s) = -a\,\mathrm{Re}\bigl[(\hat F_x, -\hat F_y, -\hat M_z, \hat M_x)
    \,e^{-i k x_G\cos\chi}\,e^{2\pi i s}\bigr]

(Capytaine's incident wave has its phase origin at the mesh origin, midship; the
factor moves it to G, :math:`x_G` from midship). The sign follows from Capytaine's
time factor; it is checked, with the phase, by the equality of Capytaine's
Froude-Krylov force and the strip integration (``tests/test_panel_waves.py``).

Table and interpolation. :func:`panel_table` solves the hull once per wavelength and
heading (``lambda/L`` on ``[1, 3]``, ``chi`` on ``[0, 90]`` deg by default) and caches
the complex amplitudes on disk, keyed by a hash of every input (mesh, G, grids, water,
speed, Capytaine's version). :class:`PanelWaves` fits each real and imaginary part by
least squares in Chebyshev polynomials of ``lambda/L`` times powers of ``chi^2`` (even
surge force, odd sway, yaw and roll: the hull is symmetric), so the forces are
algebraic in ``(s, chi, H/lambda, lambda/L)`` and the right-hand side stays
CasADi-traceable (no BEM call in the ODE). The fit's largest error is kept
(``fit_error``) and the table's range is the model's validity range
(``valid_lambda_over_L``, ``valid_chi``).

The slender-body lift due to the wave particle velocity (a forward-speed effect the
zero-speed potential does not contain) is added from the strips, as for the default
model.

Capytaine is imported only here, and only when a table is computed (the optional extra
``pip install -e ".[hull]"``).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from continuation.ops import NUMPY_OPS, Ops
from continuation.typing import FloatArray

from ..contracts import SeaState
from .hull import HullForm
from .mesh import check_wetted_mesh, mesh_volume, offsets_panels
from .mesh_hull import MeshHull, wetted_panels
from .offsets import OffsetsError, OffsetsHull, hull_from_offsets, offsets_of_hull
from .waves import WaveStrips, strip_waves

if TYPE_CHECKING:  # pragma: no cover - typing only
    from ..contracts import WaveInputs

log = logging.getLogger(__name__)

#: Default grids of the table: 41 wavelengths on [1, 3] L, headings 0-90 deg.
LAMBDA_OVER_L = np.linspace(1.0, 3.0, 41)
CHI_DEG = np.arange(0.0, 91.0, 10.0)
_FORCES = ("X", "Y", "N", "K")


def cache_dir() -> Path:
    """Folder of the cached tables.

    ``$BROACHKIT_CACHE_DIR/panel``, or ``~/.cache/broachkit/panel``.
    """
    base = os.environ.get("BROACHKIT_CACHE_DIR") or str(Path.home() / ".cache" / "broachkit")
    return Path(base) / "panel"


def _capytaine() -> Any:
    try:
        import capytaine as cpt  # the optional dependency, only for the panel method
    except ImportError:
        raise ValueError(
            'the panel method needs Capytaine: pip install -e ".[hull]" (or pip install capytaine)'
        ) from None
    return cpt


@dataclass(frozen=True)
class PanelTable:
    """Complex exciting-force amplitudes per unit wave amplitude, in the paper's axes.

    Attributes
    ----------
    lambda_over_L : ndarray, shape (n_l,)
    chi : ndarray, shape (n_c,)
        Headings from the wave direction (rad).
    fk, diffraction : ndarray, complex, shape (4, n_l, n_c)
        ``(X, Y, N, K)`` amplitudes (N/m, N m/m) of the Froude-Krylov and the
        diffraction parts, with the phase convention of the module docstring.
    L : float
        Ship length the wavelengths refer to (m).
    info : dict
        Panels, speed option, timing, Capytaine version, cache key.
    """

    lambda_over_L: FloatArray
    chi: FloatArray
    fk: Any
    diffraction: Any
    L: float
    info: dict[str, Any] = field(default_factory=dict)

    def amplitude_ratio(self, i_force: int = 0) -> FloatArray:
        """``|F_FK + F_D| / |F_FK|`` of one force, shape (n_l, n_c)."""
        a = np.abs(self.fk[i_force] + self.diffraction[i_force])
        b = np.abs(self.fk[i_force])
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(b > 0, a / b, np.nan)


def hull_mesh(hull: HullForm, *, nx: int = 40, nz: int = 8) -> tuple[FloatArray, FloatArray]:
    """The wetted-hull panels of a strip hull (checked closed and outward).

    A :class:`~ship_models.hydro.mesh_hull.MeshHull` gives its own mesh clipped at the
    calm waterline (triangles; ``nx``, ``nz`` unused). An
    :class:`~ship_models.hydro.offsets.OffsetsHull` is panelled directly; another
    hull (the form-parameter strips) is first written as a table of offsets (81
    stations, 41 waterlines, :func:`~ship_models.hydro.offsets.offsets_of_hull`).
    """
    if isinstance(hull, MeshHull):  # the hull's own closed mesh, clipped at the waterline
        V, Ft = wetted_panels(hull)
        check_wetted_mesh(V, Ft, source=hull.mesh_source)  # type: ignore[arg-type]
        return V, Ft  # type: ignore[return-value]
    if not isinstance(hull, OffsetsHull):
        table = offsets_of_hull(hull, 81, 41)
        hull = hull_from_offsets(
            table, L=hull.L, D=hull.D, d_f=float(hull.d[-1]), d_a=float(hull.d[0])
        )
    V, F = offsets_panels(hull, nx=nx, nz=nz)
    check_wetted_mesh(V, F, source="of the hull")
    return V, F


def _mesh(cpt: Any, V: FloatArray, F: FloatArray) -> Any:
    """Capytaine mesh; the port-starboard symmetric one when the panels are mirror images
    (half the unknowns: about 3x faster, same result)."""
    yc = V[F].mean(axis=1)[:, 1]
    half = F[yc < 0.0]
    mirror = np.sort(np.round(V[F[yc > 0.0]].mean(axis=1) * [1, -1, 1], 9), axis=0)
    if half.shape[0] * 2 == F.shape[0] and np.array_equal(
        np.sort(np.round(V[half].mean(axis=1), 9), axis=0), mirror
    ):
        used = np.unique(half)
        remap = -np.ones(V.shape[0], dtype=np.int64)
        remap[used] = np.arange(used.size)
        h = cpt.Mesh(vertices=V[used], faces=remap[half], name="hull_starboard")
        return cpt.ReflectionSymmetricMesh(half=h, plane="xOz")
    return cpt.Mesh(vertices=V, faces=F, name="hull")


def _key(payload: dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:20]


def panel_table(
    vertices: FloatArray,
    faces: FloatArray,
    *,
    L: float,
    x_G: float,
    zeta_G: float,
    rho: float,
    g: float,
    lambda_over_L: FloatArray = LAMBDA_OVER_L,
    chi_deg: FloatArray = CHI_DEG,
    forward_speed_Fn: float | None = None,
    cache: bool = True,
    solve: bool = True,
    progress: Callable[[int, int], None] | None = None,
) -> PanelTable:
    """Froude-Krylov and diffraction amplitudes of a hull mesh, per wavelength and heading.

    Parameters
    ----------
    vertices : ndarray, shape (n_v, 3)
        Capytaine axes (x forward from midship, y to port, z up from the waterline).
    faces : ndarray, shape (n_f, 4)
        Vertex indices, normals out of the hull.
    L : float
        Length the wavelengths refer to (m).
    x_G, zeta_G : float
        G from midship (m, forward +) and above the calm waterline (m): the moment
        centre.
    rho, g : float
    lambda_over_L : array_like
        Wavelengths / L.
    chi_deg : array_like
        Headings from the wave direction (deg, >= 0; the hull is symmetric).
    forward_speed_Fn : float, optional
        Capytaine's low-speed option at ``U = Fn sqrt(g L)`` (default: zero speed).
    cache : bool
        Read and write the on-disk cache (:func:`cache_dir`).
    solve : bool
        Solve the diffraction problems (False: Froude-Krylov only, no BEM solve; the
        diffraction part is then zero and nothing is cached).
    progress : callable, optional
        ``progress(done, total)`` after each wavelength.

    Returns
    -------
    PanelTable
    """
    V = np.ascontiguousarray(vertices, dtype=float)
    Fc = np.ascontiguousarray(faces, dtype=np.int64)
    lL = np.asarray(lambda_over_L, dtype=float)
    chis = np.asarray(chi_deg, dtype=float)
    if np.any(lL <= 0) or np.any(chis < 0) or np.any(chis > 90):
        raise ValueError("`lambda_over_L` must be > 0 and `chi_deg` in [0, 90] deg")
    speed = 0.0 if forward_speed_Fn is None else float(forward_speed_Fn) * math.sqrt(g * L)
    payload = {
        "mesh": hashlib.sha256(V.tobytes() + Fc.tobytes()).hexdigest(),
        "G": [round(x_G, 12), round(zeta_G, 12)],
        "L": L, "rho": rho, "g": g, "lambda_over_L": lL.tolist(), "chi_deg": chis.tolist(),
        "speed": speed, "version": 1, "solve": bool(solve),
    }  # fmt: skip
    cpt = _capytaine()
    payload["capytaine"] = cpt.__version__
    key = _key(payload)
    path = cache_dir() / f"{key}.npz"
    if cache and path.is_file():
        z = np.load(path, allow_pickle=False)
        info = json.loads(str(z["info"]))
        info["cached"] = True
        return PanelTable(lL, np.radians(chis), z["fk"], z["diffraction"], L, info)
    t0 = time.perf_counter()
    with _one_blas_thread():
        fk, dif = _solve_table(cpt, V, Fc, lL, chis, L=L, x_G=x_G, zeta_G=zeta_G, rho=rho, g=g,
                               speed=speed, solve=solve, progress=progress)  # fmt: skip
    info = {
        "n_panels": int(Fc.shape[0]),
        "forward_speed": speed,
        "seconds": time.perf_counter() - t0,
        "capytaine": cpt.__version__,
        "key": key,
        "cached": False,
    }
    if cache and solve:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + f".{os.getpid()}.tmp.npz")
        np.savez(tmp, fk=fk, diffraction=dif, info=json.dumps(info))
        tmp.replace(path)  # atomic: a concurrent reader sees all or nothing
    return PanelTable(lL, np.radians(chis), fk, dif, L, info)


def _one_blas_thread() -> contextlib.AbstractContextManager[Any]:
    """BLAS limited to one thread for the table's small dense algebra.

    The half-hull systems (a few hundred unknowns per symmetry block) are too small to
    share: on the shared 2-core machine at load 5.7 one 320 x 320 complex LU took 300 ms
    with two OpenBLAS threads and 9 ms with one, a matrix-vector product 16.5 ms against
    0.05 ms (``benchmarks/README.md``, panel table). Capytaine's Green function keeps its
    OpenMP threads.
    """
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - a project dependency
        return contextlib.nullcontext()
    return threadpool_limits(limits=1, user_api="blas")


def _solve_table(
    cpt: Any,
    V: FloatArray,
    Fc: Any,
    lL: FloatArray,
    chis: FloatArray,
    *,
    L: float,
    x_G: float,
    zeta_G: float,
    rho: float,
    g: float,
    speed: float,
    solve: bool,
    progress: Callable[[int, int], None] | None,
) -> tuple[Any, Any]:
    """The complex amplitudes ``(fk, diffraction)``, shape ``(4, n_l, n_c)`` each.

    All headings of one frequency are solved in sequence with one influence matrix and
    its LU decomposition (Capytaine's engine keeps the last ones), so each wavelength
    costs one Green-function evaluation and one factorisation.
    """
    mesh = _mesh(cpt, V, Fc)
    body = cpt.FloatingBody(
        mesh=mesh, dofs=cpt.rigid_body_dofs(rotation_center=(x_G, 0.0, zeta_G)), name="hull"
    )
    solver = cpt.BEMSolver()
    from capytaine.bem.airy_waves import froude_krylov_force

    fk = np.zeros((4, lL.size, chis.size), dtype=complex)
    dif = np.zeros_like(fk)
    # project (X, Y, N, K) from Capytaine (Surge, Sway, Yaw, Roll): y port, z up
    dofs = (("Surge", 1.0), ("Sway", -1.0), ("Yaw", -1.0), ("Roll", 1.0))
    for i, r in enumerate(lL):
        k = 2.0 * math.pi / (r * L)
        omega = math.sqrt(g * k)
        for j, c in enumerate(chis):
            pb = cpt.DiffractionProblem(body=body, omega=omega, wave_direction=math.radians(c),
                                        rho=rho, g=g, forward_speed=speed)  # fmt: skip
            res = solver.solve(pb, keep_details=False) if solve else None
            f_fk = froude_krylov_force(pb)
            # Capytaine's incident wave has its phase at the mesh origin (midship); the
            # paper's at G: shift by e^{-i k x_G cos(chi)} (module docstring)
            shift = complex(np.exp(-1j * k * x_G * math.cos(math.radians(c))))
            for n, (dof, sign) in enumerate(dofs):
                fk[n, i, j] = sign * shift * complex(f_fk[dof])
                if res is not None:
                    dif[n, i, j] = sign * shift * complex(res.forces[dof])
        if progress is not None:
            progress(i + 1, lL.size)
    return fk, dif


def mesh_path(vessel: Any) -> Path | None:
    """The mesh file named by ``[vessel] hull_mesh`` (relative to the vessel file)."""
    name = getattr(vessel, "meta", {}).get("hull_mesh")
    if not name:
        return None
    p = Path(str(name))
    if not p.is_absolute() and getattr(vessel, "path", ""):
        p = Path(vessel.path).parent / p
    return p


def write_gdf(vertices: FloatArray, faces: FloatArray, path: str | Path, title: str = "") -> Path:
    """Write quadrilateral panels as a WAMIT ``.gdf`` file (read by Capytaine and WAMIT).

    Capytaine's axes (x forward, y to port, z up from the calm waterline), metres, no
    symmetry flags (all panels written).
    """
    p = Path(path)
    lines = [title or "broachkit hull panels", "1.0 9.80665", "0 0", str(len(faces))]
    for f in np.asarray(faces, dtype=int):
        for i in f:
            x, y, z = vertices[i]
            lines.append(f"{x:.9g} {y:.9g} {z:.9g}")
    tmp = p.with_name(p.name + ".tmp")
    tmp.write_text("\n".join(lines) + "\n")
    tmp.replace(p)
    return p


def read_hull_mesh(
    path: str | Path, *, L: float | None = None, volume: float | None = None
) -> tuple[FloatArray, FloatArray]:
    """A hull mesh file (any format Capytaine reads: GDF, Nemoh, HST, PNL, MAR; STL, OBJ,
    MSH... through meshio or trimesh when installed), clipped at the calm waterline.

    Parameters
    ----------
    path : path
        The mesh, in Capytaine's axes (x forward, y to port, z up from the calm
        waterline), metres.
    L : float, optional
        ``L_pp``: refuses a mesh whose length is not within a factor 2 (units).
    volume : float, optional
        The particulars' displacement volume ``C_b L B d_m``: refuses a mesh that
        displaces more than 2 % more or less.

    Returns
    -------
    vertices, faces
        The wetted part, checked closed up to the waterline and outward
        (:func:`~ship_models.hydro.offsets.check_wetted_mesh`).

    Raises
    ------
    OffsetsError
        Unreadable file, units, an open or inverted mesh, a contradicting volume.
    """
    cpt = _capytaine()
    try:
        mesh = cpt.load_mesh(str(path))
        wet = mesh.immersed_part()
        if hasattr(wet, "merged"):
            wet = wet.merged()
    except Exception as exc:  # the reader's own error, reduced to one line
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise OffsetsError(f"mesh {path}: cannot be read: {first}") from None
    V = np.asarray(wet.vertices, dtype=float)
    F = np.asarray(wet.faces, dtype=np.int64)
    if F.size == 0:
        raise OffsetsError(f"mesh {path}: no panel below the waterline z = 0")
    length = float(np.ptp(V[:, 0]))
    if L is not None and not 0.5 * L <= length <= 2.0 * L:
        raise OffsetsError(
            f"mesh {path}: it is {length:g} long but L_pp = {L:g} m (units inconsistent? "
            "the mesh must be in metres)"
        )
    check_wetted_mesh(V, F, source=str(path))
    if volume is not None:
        got = mesh_volume(V, F)
        if abs(got - volume) > 0.02 * got:
            raise OffsetsError(
                f"mesh {path}: displaces {got:.5g} m^3 but the particulars give "
                f"C_b L B d_m = {volume:.5g} m^3"
            )
    return V, F


# --------------------------------------------------------------------------- fit
def _cheb(t: Any, n: int, ops: Ops) -> list[Any]:
    T = [1.0 + 0.0 * t, t]
    for _ in range(2, n):
        T.append(2.0 * t * T[-1] - T[-2])
    return T[:n]


@dataclass(frozen=True)
class _Fit:
    """Least-squares fit ``sum_ij C[i, j] T_i(t) chi^(2j + odd)``."""

    coef: FloatArray  # (n_t, n_c)
    odd: bool
    lo: float
    hi: float

    def basis(self, lL: Any, chi: Any, ops: Ops) -> tuple[list[Any], list[Any]]:
        t = (2.0 * lL - (self.lo + self.hi)) / (self.hi - self.lo)
        Tt = _cheb(t, self.coef.shape[0], ops)
        c2 = chi * chi
        P = [chi if self.odd else 1.0 + 0.0 * chi]
        for _ in range(1, self.coef.shape[1]):
            P.append(P[-1] * c2)
        return Tt, P

    def __call__(self, lL: Any, chi: Any, ops: Ops) -> Any:
        Tt, P = self.basis(lL, chi, ops)
        out = 0.0
        for i, Ti in enumerate(Tt):
            row = 0.0
            for j, Pj in enumerate(P):
                row = row + float(self.coef[i, j]) * Pj
            out = out + Ti * row
        return out

    @classmethod
    def fit(cls, lL: FloatArray, chi: FloatArray, values: FloatArray, odd: bool,
            n_t: int, n_c: int) -> tuple[_Fit, float]:  # fmt: skip
        lo, hi = float(lL.min()), float(lL.max())
        LL, CC = np.meshgrid(lL, chi, indexing="ij")
        probe = cls(np.zeros((n_t, n_c)), odd, lo, hi)
        Tt, P = probe.basis(LL.ravel(), CC.ravel(), NUMPY_OPS)
        A = np.stack([Ti * Pj for Ti in Tt for Pj in P], axis=1)
        y = values.ravel()
        sol, *_ = np.linalg.lstsq(A, y, rcond=None)
        err = float(np.max(np.abs(A @ sol - y))) if y.size else 0.0
        return cls(sol.reshape(n_t, n_c), odd, lo, hi), err


@dataclass(frozen=True)
class PanelWaves:
    """Wave forces from a panel-method table (a :class:`~ship_models.contracts.WaveForceModel`).

    Attributes
    ----------
    table : PanelTable
    diffraction : bool
        Froude-Krylov + diffraction (True) or Froude-Krylov alone.
    strips : WaveStrips
        For the slender-body lift (and ``L``, ``surge_scale``).
    fits : tuple
        Per force ``(re, im)`` fits.
    fit_error : float
        Largest fit error relative to the largest amplitude of its force.
    """

    table: PanelTable
    diffraction: bool
    strips: WaveStrips
    fits: tuple[tuple[_Fit, _Fit], ...] = field(repr=False)
    fit_error: float = 0.0

    @property
    def name(self) -> str:
        """``panel_fk_diffraction`` or ``panel_fk`` (``_U`` with forward speed)."""
        base = "panel_fk_diffraction" if self.diffraction else "panel_fk"
        if self.table.info.get("forward_speed", 0.0):
            base += f"_U{self.table.info['forward_speed']:.3g}"
        return base

    @property
    def valid_lambda_over_L(self) -> tuple[float, float]:
        """Range of wavelengths of the table (outside: extrapolated)."""
        return float(self.table.lambda_over_L.min()), float(self.table.lambda_over_L.max())

    @property
    def valid_chi(self) -> float:
        """Largest |chi| of the table (rad)."""
        return float(self.table.chi.max())

    def in_range(self, lambda_over_L: float, chi: float) -> bool:
        """Whether ``(lambda_over_L, chi)`` lies in the tabulated range."""
        lo, hi = self.valid_lambda_over_L
        return lo - 1e-12 <= lambda_over_L <= hi + 1e-12 and abs(chi) <= self.valid_chi + 1e-12

    @classmethod
    def from_table(
        cls, table: PanelTable, strips: WaveStrips, *, diffraction: bool = True,
        n_t: int = 14, n_c: int = 4,
    ) -> PanelWaves:  # fmt: skip
        """Fit the table (see the module docstring)."""
        F = table.fk + (table.diffraction if diffraction else 0.0)
        # never more unknowns than table nodes along either axis (no underdetermined fit)
        n_t = min(n_t, table.lambda_over_L.size)
        n_c = min(n_c, table.chi.size)
        fits = []
        worst = 0.0
        for n in range(4):
            odd = n != 0
            pair = []
            scale = float(np.max(np.abs(F[n]))) or 1.0
            for part in (F[n].real, F[n].imag):
                f, err = _Fit.fit(table.lambda_over_L, table.chi, part, odd, n_t, n_c)
                pair.append(f)
                worst = max(worst, err / scale)
            fits.append((pair[0], pair[1]))
        return cls(table, diffraction, strips, tuple(fits), worst)

    def amplitudes(
        self, lambda_over_L: Any, chi: Any, ops: Ops = NUMPY_OPS
    ) -> list[tuple[Any, Any]]:
        """Fitted ``(Re, Im)`` of the unit-amplitude ``(X, Y, N, K)`` (one shared basis)."""
        Tt, P = self.fits[0][0].basis(lambda_over_L, chi, ops)  # even basis (X)
        out = []
        for pair in self.fits:
            vals = []
            for f in pair:
                acc = 0.0
                for i, Ti in enumerate(Tt):
                    row = 0.0
                    for j, Pj in enumerate(P):
                        row = row + float(f.coef[i, j]) * Pj
                    acc = acc + Ti * row
                vals.append(chi * acc if f.odd else acc)
            out.append((vals[0], vals[1]))
        return out

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
        r"""Wave forces ``(X_w, Y_w, N_w, K_w)`` (N, N, N m, N m) from the fitted table.

        .. math::

            (X, Y, N, K)_w = -a\,\mathrm{Re}\bigl[\hat F(\lambda/L, \chi)\,
            e^{2\pi i\,\xi_G/\lambda}\bigr],
            \qquad a = \tfrac12\,(H/\lambda)\,(\lambda/L)\,L,

        :math:`\hat F` the fitted unit-amplitude amplitudes (:meth:`amplitudes`, phase at
        G; module doc), ``X`` times the strips' ``surge_scale``, plus the strips'
        slender-body lift (:meth:`WaveStrips.lift_forces`) when ``lift``. Arguments and
        result as in :class:`~ship_models.contracts.WaveForceModel`.
        """
        Hl, lL = sea
        a = 0.5 * Hl * lL * self.strips.L
        ph = 2.0 * ops.pi * xi_over_lambda
        cs, sn = ops.cos(ph), ops.sin(ph)
        out = []
        for re, im in self.amplitudes(lL, chi, ops):
            out.append(-a * (re * cs - im * sn))  # -a Re[(re + i im) e^{i ph}]
        X, Y, N, K = out
        X = self.strips.surge_scale * X
        if lift:
            YL, NL, KL = self.strips.lift_forces(xi_over_lambda, u, chi, sea, ops)
            Y, N, K = Y + YL, N + NL, K + KL
        return X, Y, N, K


@dataclass(frozen=True)
class PanelWaveBuilder:
    """A :class:`~ship_models.contracts.WaveForceBuilder` of :class:`PanelWaves`.

    Attributes
    ----------
    diffraction : bool
        Froude-Krylov + diffraction (default) or Froude-Krylov alone.
    nx, nz : int
        Panels along the hull and from keel to waterline (each side) of the mesh made
        from the hull's offsets. A hull given by a closed mesh
        (:class:`~ship_models.hydro.mesh_hull.MeshHull`) gives that mesh clipped at the
        waterline; a vessel file naming ``[vessel] hull_mesh`` beside its offsets (or a
        wetted-surface mesh) gives that mesh instead (:func:`read_hull_mesh`,
        displacement checked against the hull's within 2 %).
    forward_speed_Fn : float or None
        Capytaine's low-speed option (default: zero speed).
    lambda_over_L, chi_deg : tuple of float
        Table grids.
    """

    diffraction: bool = True
    nx: int = 40
    nz: int = 8
    forward_speed_Fn: float | None = None
    lambda_over_L: tuple[float, ...] = tuple(LAMBDA_OVER_L)
    chi_deg: tuple[float, ...] = tuple(CHI_DEG)

    def __call__(self, inputs: WaveInputs) -> PanelWaves:
        strips = strip_waves(inputs)
        mesh_file = mesh_path(inputs.vessel)
        if mesh_file is not None and not isinstance(inputs.hull, MeshHull):
            # a panel mesh beside the offsets: the design tool's, checked against the hull
            V, F = read_hull_mesh(mesh_file, L=inputs.hull.L, volume=inputs.hull.volume)
        else:
            V, F = hull_mesh(inputs.hull, nx=self.nx, nz=self.nz)
        table = panel_table(
            V, F, L=inputs.hull.L, x_G=inputs.x_G, zeta_G=inputs.zeta_G, rho=inputs.rho,
            g=inputs.g, lambda_over_L=np.array(self.lambda_over_L),
            chi_deg=np.array(self.chi_deg), forward_speed_Fn=self.forward_speed_Fn,
            solve=self.diffraction,
        )  # fmt: skip
        log.info("panel table: %s", table.info)
        return PanelWaves.from_table(table, strips, diffraction=self.diffraction)


__all__ = [
    "CHI_DEG",
    "LAMBDA_OVER_L",
    "PanelTable",
    "PanelWaveBuilder",
    "PanelWaves",
    "cache_dir",
    "mesh_path",
    "hull_mesh",
    "panel_table",
    "read_hull_mesh",
    "write_gdf",
]
