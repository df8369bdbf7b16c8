r"""A hull from its table of offsets: reading, checks, strips, hydrostatics and panels.

Table of offsets (the lines plan's numbers)
--------------------------------------------
Half-breadths :math:`y_{ik}` of the moulded hull at stations :math:`x_i` and waterlines
:math:`z_k`, in a CSV file::

    # broachkit offsets v1
    # units = m
    # x: station from the aft perpendicular (m, forward +); columns: waterline heights
    # above the baseline (m); cells: half-breadths (m), 0 where the hull has no width
    x, 0.0, 0.5, 1.0, 1.5, 2.0
    0.0, 0.0, 0.10, 0.25, 0.40, 0.52
    1.725, 0.0, 0.61, 0.93, 1.10, 1.17
    ...

Lines ``#`` are comments, except ``# units = m`` (or ``mm``: every number is then
divided by 1000). The first other line is the header: a label, then the waterline
heights. Conventions are those of a lines plan (e.g. Lewis, E.V. (ed.) 1988,
"Principles of Naval Architecture", 2nd rev., Vol. I, SNAME, Ch. I Sect. 2): stations
from the aft perpendicular (AP, ``x = 0``) to the forward perpendicular (FP, ``x =
L_pp``), stations beyond them allowed (overhangs); heights above the baseline (the keel
at midship); one side given (symmetric hull). Stations and waterlines strictly
increase; half-breadths are finite and non-negative; the table spans the draft.

The hull between the given numbers is the *bilinear* surface: linear in z between
waterlines and linear in x between stations. Everything below is computed on that
one surface (so the strips, the hydrostatics and the panels describe the same hull):

* strips (:class:`OffsetsHull`, a :class:`~ship_models.hydro.hull.HullForm`): two
  Gauss-Legendre stations per station interval, sections integrated over the
  waterline intervals below the local draft by composite Gauss-Legendre quadrature
  (exact for the piecewise-linear section);
* hydrostatics (:func:`ship_models.hydro.upright.hydrostatics`): displacement volume,
  LCB, KB, BM, waterplane area and its moments, by the same quadrature;
* panels (:func:`ship_models.hydro.mesh.offsets_panels`): quadrilaterals with their
  vertices on the surface, from the keel to the waterline, ends closed.

The waterline is the plane through the drafts ``d_a`` at the AP and ``d_f`` at the FP
(trim by the stern if ``d_a > d_f``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from continuation.typing import FloatArray

from .hull import FormParameters, HullForm, _sections, parametric_hull

#: First line of an offsets file written by :func:`write_offsets`.
OFFSETS_HEADER = "# broachkit offsets v1"
_UNITS = {"m": 1.0, "mm": 1e-3}


class OffsetsError(ValueError):
    """A bad table of offsets or mesh; the one-line message names the problem."""


@dataclass(frozen=True)
class OffsetsTable:
    """Half-breadths of a hull at stations and waterlines (SI units).

    Attributes
    ----------
    x : ndarray, shape (I,)
        Stations from the aft perpendicular (m, forward +), strictly increasing.
    z : ndarray, shape (K,)
        Waterline heights above the baseline (m), strictly increasing.
    y : ndarray, shape (I, K)
        Half-breadths (m), >= 0.
    source : str
        Where the numbers come from (file path or text).
    """

    x: FloatArray
    z: FloatArray
    y: FloatArray
    source: str = ""

    def __post_init__(self) -> None:
        x = np.asarray(self.x, dtype=float).reshape(-1)
        z = np.asarray(self.z, dtype=float).reshape(-1)
        y = np.asarray(self.y, dtype=float)
        where = f" in {self.source}" if self.source else ""
        if x.size < 3 or z.size < 2:
            raise OffsetsError(f"offsets{where}: need at least 3 stations and 2 waterlines")
        if y.shape != (x.size, z.size):
            raise OffsetsError(
                f"offsets{where}: half-breadths have shape {y.shape}, expected "
                f"({x.size} stations, {z.size} waterlines)"
            )
        for name, a in (("station", x), ("waterline", z), ("half-breadth", y)):
            if not np.all(np.isfinite(a)):
                raise OffsetsError(f"offsets{where}: a {name} value is not a finite number")
        i = np.flatnonzero(np.diff(x) <= 0)
        if i.size:
            raise OffsetsError(
                f"offsets{where}: stations must increase strictly from aft to forward "
                f"(station {i[0] + 2} at x = {x[i[0] + 1]:g} m follows x = {x[i[0]]:g} m)"
            )
        k = np.flatnonzero(np.diff(z) <= 0)
        if k.size:
            raise OffsetsError(
                f"offsets{where}: waterlines must increase strictly upwards "
                f"(z = {z[k[0] + 1]:g} m follows z = {z[k[0]]:g} m)"
            )
        if z[0] < 0:
            raise OffsetsError(f"offsets{where}: waterline z = {z[0]:g} m is below the baseline")
        neg = np.argwhere(y < 0)
        if neg.size:
            a, b = neg[0]
            raise OffsetsError(
                f"offsets{where}: negative half-breadth {y[a, b]:g} m at station x = "
                f"{x[a]:g} m, waterline z = {z[b]:g} m"
            )
        if not np.any(y > 0):
            raise OffsetsError(f"offsets{where}: every half-breadth is zero")
        for name, a in (("x", x), ("z", z), ("y", y)):
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @property
    def length(self) -> float:
        """Length of the tabulated hull, last minus first station (m)."""
        return float(self.x[-1] - self.x[0])

    def half_breadth(self, x: FloatArray, z: FloatArray) -> FloatArray:
        """Half-breadth of the bilinear surface at ``(x, z)`` (broadcast), m.

        Outside the table: 0 beyond the end stations; the top waterline's breadth above
        the table (wall sides); the bottom waterline's below it.
        """
        x = np.asarray(x, dtype=float)
        z = np.asarray(z, dtype=float)
        xb, zb = np.broadcast_arrays(x, z)
        i = np.clip(np.searchsorted(self.x, xb, side="right") - 1, 0, self.x.size - 2)
        k = np.clip(np.searchsorted(self.z, zb, side="right") - 1, 0, self.z.size - 2)
        tx = np.clip((xb - self.x[i]) / (self.x[i + 1] - self.x[i]), 0.0, 1.0)
        tz = np.clip((zb - self.z[k]) / (self.z[k + 1] - self.z[k]), 0.0, 1.0)
        y = self.y
        out = (1 - tx) * ((1 - tz) * y[i, k] + tz * y[i, k + 1]) + tx * (
            (1 - tz) * y[i + 1, k] + tz * y[i + 1, k + 1]
        )
        inside = (xb >= self.x[0]) & (xb <= self.x[-1])
        return np.where(inside, out, 0.0)


def read_offsets(path: str | Path) -> OffsetsTable:
    """Read a CSV table of offsets (format in the module docstring).

    Raises
    ------
    OffsetsError
        Missing file, unknown units, ragged rows, non-numbers, or a table that
        :class:`OffsetsTable` refuses (one line naming the problem).
    """
    p = Path(path)
    if not p.is_file():
        raise OffsetsError(f"no offsets file {str(p)!r}")
    scale = 1.0
    rows: list[list[str]] = []
    for n, raw in enumerate(p.read_text().splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            body = line[1:].strip()
            if body.replace(" ", "").startswith("units="):
                unit = body.split("=", 1)[1].strip()
                if unit not in _UNITS:
                    raise OffsetsError(
                        f"{p}:{n}: units must be one of {sorted(_UNITS)}, got {unit!r}"
                    )
                scale = _UNITS[unit]
            continue
        rows.append([c.strip() for c in line.split(",")])
    if len(rows) < 2:
        raise OffsetsError(f"{p}: no table (a header of waterline heights and station rows)")
    head, body = rows[0], rows[1:]
    try:
        z = np.array([float(c) for c in head[1:]])
    except ValueError:
        raise OffsetsError(
            f"{p}: the header must be a label then the waterline heights, got {head}"
        ) from None
    xs, ys = [], []
    for j, r in enumerate(body, start=2):
        if len(r) != len(head):
            raise OffsetsError(
                f"{p}: table row {j} has {len(r)} cells, the header {len(head)} "
                "(one station position and one half-breadth per waterline)"
            )
        try:
            vals = [float(c) for c in r]
        except ValueError:
            raise OffsetsError(f"{p}: table row {j} has a cell that is not a number") from None
        xs.append(vals[0])
        ys.append(vals[1:])
    return OffsetsTable(np.array(xs) * scale, z * scale, np.array(ys) * scale, str(p))


def write_offsets(table: OffsetsTable, path: str | Path, comment: str = "") -> Path:
    """Write ``table`` as a CSV offsets file (metres) readable by :func:`read_offsets`."""
    lines = [OFFSETS_HEADER, "# units = m"]
    lines += [f"# {c}" for c in comment.splitlines() if c.strip()]
    lines.append(
        "# x: station from the aft perpendicular (m, forward +); columns: waterline "
        "heights above the baseline (m); cells: half-breadths (m)"
    )
    lines.append(", ".join(["x"] + [f"{v:.6f}" for v in table.z]))
    for xi, row in zip(table.x, table.y, strict=True):
        lines.append(", ".join([f"{xi:.6f}"] + [f"{v:.6f}" for v in row]))
    p = Path(path)
    tmp = p.with_name(p.name + ".tmp")
    tmp.write_text("\n".join(lines) + "\n")
    tmp.replace(p)
    return p


# --------------------------------------------------------------------------- strips
def draft_at(x_ap: FloatArray, L: float, d_f: float, d_a: float) -> FloatArray:
    """Draft above the baseline at stations ``x_ap`` from the AP (m)."""
    return d_a + (d_f - d_a) * np.asarray(x_ap, dtype=float) / L


@dataclass(frozen=True)
class OffsetsHull(HullForm):
    """A :class:`HullForm` whose sections are a table of offsets (the bilinear surface).

    Build with :func:`hull_from_offsets`. The strip stations are Gauss-Legendre
    points of the table's station intervals; ``b_wl``, ``d`` and the equivalent
    section exponent ``n_exp`` (from the section coefficient, for the Lewis added
    masses only) are per strip station; the depth quadrature, section areas, centre
    of buoyancy, half-breadths and the GZ polygons use the table itself.

    Attributes
    ----------
    table : OffsetsTable
    x_ap : float
        Position of the AP in the strip frame (``-L/2``: strips are from midship).
    d_f, d_a : float
        Drafts at the FP and AP above the baseline (m).
    n_gauss : int
        Gauss-Legendre nodes per waterline interval in the depth quadrature.
    """

    table: OffsetsTable = field(default=None, repr=False)  # type: ignore[assignment]
    d_f: float = 0.0
    d_a: float = 0.0
    n_gauss: int = 3

    def _x_ap(self) -> FloatArray:
        return self.x + 0.5 * self.L

    def depth_quadrature(self, m: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Composite Gauss-Legendre nodes over the waterline intervals below each draft.

        ``m`` is the number of nodes per waterline interval (at least 2); the arrays
        have shape ``(J, (K' ) m)`` with ``K'`` the intervals below the deepest draft
        (intervals above a station's draft get zero weight).
        """
        m = max(2, int(m) // max(1, self.table.z.size - 1) + 1, self.n_gauss)
        t, wt = np.polynomial.legendre.leggauss(m)
        T = self.d[:, None]  # draft above the baseline = depth of the keel
        zk = self.table.z
        lo = np.concatenate([[0.0], zk[(zk > 0) & (zk < T.max())]])
        hi = np.concatenate([lo[1:], [T.max()]])
        a = np.minimum(lo[None, :], T)
        b = np.minimum(hi[None, :], T)  # (J, n_int), intervals clipped at the draft
        h = 0.5 * (a + b)[:, :, None] + 0.5 * (b - a)[:, :, None] * t[None, None, :]
        wz = (0.5 * (b - a)[:, :, None] * wt[None, None, :]).reshape(self.n_stations, -1)
        h = h.reshape(self.n_stations, -1)
        zeta = h - T  # height above the calm waterline (<= 0)
        xq = np.broadcast_to(self._x_ap()[:, None], h.shape)
        bq = self.table.half_breadth(xq, h)
        return zeta, wz, bq

    @property
    def area(self) -> FloatArray:
        """Section areas below the waterline (m^2), shape (J,)."""
        _, wz, b = self.depth_quadrature(self.n_gauss)
        return np.sum(wz * 2.0 * b, axis=1)

    @property
    def vcb(self) -> float:
        """Height of the centre of buoyancy above the calm waterline (m, negative)."""
        zeta, wz, b = self.depth_quadrature(self.n_gauss)
        mom = np.sum(wz * 2.0 * b * zeta, axis=1)
        return float(self.w @ mom) / self.volume

    def half_breadth(self, j: int | FloatArray, zeta: FloatArray) -> FloatArray:
        """Half-breadth at height ``zeta`` above the calm waterline of station(s) ``j``."""
        j = np.asarray(j)
        return self.table.half_breadth(self._x_ap()[j], np.asarray(zeta, dtype=float) + self.d[j])

    def wetted_surface(self, n_girth: int = 200) -> float:
        """Wetted surface from the section girths of the bilinear surface (m^2)."""
        s = np.linspace(0.0, 1.0, n_girth + 1)
        h = s[None, :] * self.d[:, None]
        y = self.table.half_breadth(np.broadcast_to(self._x_ap()[:, None], h.shape), h)
        girth = 2.0 * (np.sum(np.hypot(np.diff(y, axis=1), np.diff(h, axis=1)), axis=1) + y[:, 0])
        return float(self.w @ girth)

    def section_polygons(self, topside_height: float = 0.0) -> FloatArray:
        """Closed counter-clockwise section polygons ``(J, V, 2)`` as ``(y, zeta)``.

        Keel centre, the starboard offsets of the waterlines up to the top waterline,
        wall sides up to the deck ``D + topside_height`` above the baseline, then the
        port side mirrored (the form :func:`~ship_models.hydro.hydrostatics.gz_curve`
        clips at heel).
        """
        zk = self.table.z
        deck = self.D + topside_height
        hs = np.concatenate([[0.0], zk[(zk > 0) & (zk < deck)], [deck]])
        xq = np.broadcast_to(self._x_ap()[:, None], (self.n_stations, hs.size))
        yb = self.table.half_breadth(xq, np.broadcast_to(hs, xq.shape))
        zb = hs[None, :] - self.d[:, None]
        ys = np.concatenate([np.zeros((self.n_stations, 1)), yb], axis=1)
        zs = np.concatenate([zb[:, :1], zb], axis=1)
        yp = -ys[:, ::-1]
        zp = zs[:, ::-1]
        y = np.concatenate([ys, yp[:, :-1]], axis=1)
        z = np.concatenate([zs, zp[:, :-1]], axis=1)
        return np.stack([y, z], axis=-1)


def hull_from_offsets(
    table: OffsetsTable,
    *,
    L: float,
    D: float,
    d_f: float,
    d_a: float,
    n_per_interval: int = 2,
    n_gauss: int = 3,
) -> OffsetsHull:
    """The strip hull of a table of offsets at the drafts ``d_f`` (FP), ``d_a`` (AP).

    Parameters
    ----------
    table : OffsetsTable
    L : float
        Length between perpendiculars (m): the FP is at ``x = L`` of the table.
    D : float
        Depth to the deck above the baseline (m).
    d_f, d_a : float
        Drafts above the baseline at the FP and AP (m).
    n_per_interval : int
        Gauss-Legendre strip stations per station interval.
    n_gauss : int
        Gauss-Legendre nodes per waterline interval in the depth quadrature.

    Raises
    ------
    OffsetsError
        Units inconsistent with ``L`` (the table spans less than half or more than
        twice ``L``), a table that does not reach the draft, drafts not below ``D``.
    """
    src = f" ({table.source})" if table.source else ""
    span = table.length
    if not 0.5 * L <= span <= 2.0 * L:
        raise OffsetsError(
            f"offsets{src}: the stations span {span:g} m but L_pp = {L:g} m (units "
            "inconsistent? the file says `# units = m` or `# units = mm`)"
        )
    T = draft_at(table.x, L, d_f, d_a)
    if np.any(T <= 0) or max(d_f, d_a) >= D:
        raise OffsetsError(f"offsets{src}: drafts must be positive and below the depth D = {D:g} m")
    if table.z[-1] < max(d_f, d_a):
        raise OffsetsError(
            f"offsets{src}: the top waterline z = {table.z[-1]:g} m is below the draft "
            f"{max(d_f, d_a):g} m: the table must span the draft"
        )
    t, wt = np.polynomial.legendre.leggauss(n_per_interval)
    x0, x1 = table.x[:-1, None], table.x[1:, None]
    xs = (0.5 * (x0 + x1) + 0.5 * (x1 - x0) * t[None, :]).reshape(-1)
    ws = (0.5 * (x1 - x0) * wt[None, :]).reshape(-1)
    d = draft_at(xs, L, d_f, d_a)
    b_wl = table.half_breadth(xs, d)
    # equivalent section coefficient (for the Lewis added masses only)
    tmp = OffsetsHull(
        L, 2 * float(np.max(table.y)), D, xs - 0.5 * L, ws, d, b_wl, np.ones_like(xs),
        {"kind": 2.0}, table, d_f, d_a, n_gauss,
    )  # fmt: skip
    area = tmp.area
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = np.where(b_wl > 0, area / (2.0 * b_wl * d), 0.5)
    beta = np.clip(beta, 0.05, 0.999)
    B = 2.0 * float(np.max(table.half_breadth(xs[:, None], np.linspace(0, max(d_f, d_a), 41))))
    return OffsetsHull(
        L, B, D, xs - 0.5 * L, ws, d, b_wl, beta / (1.0 - beta), {"kind": 2.0},
        table, d_f, d_a, n_gauss,
    )  # fmt: skip


def offsets_of_hull(hull: HullForm, n_stations: int = 41, n_waterlines: int = 21) -> OffsetsTable:
    """A table of offsets sampled from a strip hull (e.g. the form-parameter hull).

    Stations equally spaced from the AP to the FP, waterlines equally spaced from the
    baseline (the keel line, straight: trim is in the drafts) to the deck, plus one
    at each end draft. Half-breadths from the hull's section family at its own
    stations (wall sides above the waterline), interpolated linearly along the ship
    with zero breadth at the perpendiculars.
    """
    L = hull.L
    xs = np.linspace(0.0, L, n_stations)
    zs = np.linspace(0.0, hull.D, n_waterlines)
    ends = [float(hull.d[0]), float(hull.d[-1])]
    zs = np.unique(np.concatenate([zs, ends]))
    x_h = hull.x + 0.5 * L
    xa = np.concatenate([[0.0], x_h, [L]])
    Y = np.zeros((xs.size, zs.size))
    for k, zk in enumerate(zs):
        zeta = zk - hull.d  # height above the calm waterline at each strip station
        yk = np.array([float(hull.half_breadth(j, np.array(min(zeta[j], 0.0))))
                       for j in range(hull.n_stations)])  # fmt: skip
        yk = np.where(zeta > 0, hull.b_wl, yk)  # wall sides above the waterline
        Y[:, k] = np.interp(xs, xa, np.concatenate([[0.0], yk, [0.0]]))
    return OffsetsTable(xs, zs, Y, "sampled from a strip hull")


def form_parameter_offsets(
    form: FormParameters,
    *,
    n_stations: int = 41,
    n_waterlines: int = 21,
    beta_min: float = 0.5,
    beta_max: float = 0.98,
) -> OffsetsTable:
    """The form-parameter hull of :func:`~ship_models.hydro.hull.parametric_hull` as offsets.

    The particulars-only path written out as a hull, so both paths meet: the
    exponents of the sectional-area curve are fitted as there (displacement
    ``C_b L B d_m`` and the l.c.b.), and the sections of that continuous form are
    sampled at ``n_stations`` equally spaced stations (AP to FP) and ``n_waterlines``
    waterlines from the keel line to the deck (plus the end drafts).

    Parameters
    ----------
    form : FormParameters
        Particulars and form coefficients.
    n_stations, n_waterlines : int
        Stations and waterlines of the table.
    beta_min, beta_max : float
        Bounds on the section coefficient (as for ``parametric_hull``).

    Returns
    -------
    OffsetsTable
    """
    ref = parametric_hull(form, n_stations=80, beta_min=beta_min, beta_max=beta_max)
    L, B, D, d_f, d_a, d_m = form.L, form.B, form.D, form.d_f, form.d_a, form.d_m
    xs = np.linspace(0.0, L, n_stations)
    t = 2.0 * xs / L - 1.0
    d = draft_at(xs, L, d_f, d_a)
    b_wl, beta = _sections(
        t, d, B, d_m, form.C_M, ref.info["q_waterline"], ref.info["p_aft"], ref.info["p_fore"],
        beta_min, beta_max,
    )  # fmt: skip
    n = beta / (1.0 - beta)
    zs = np.unique(np.concatenate([np.linspace(0.0, D, n_waterlines), [d_f, d_a]]))
    s = np.clip((d[:, None] - zs[None, :]) / d[:, None], 0.0, 1.0)  # 1 at the keel
    with np.errstate(over="ignore"):
        Y = b_wl[:, None] * (1.0 - s ** n[:, None])
    return OffsetsTable(xs, zs, Y, "form-parameter hull of the particulars")


def wigley_offsets(
    *, L: float, B: float, T: float, D: float, n_stations: int = 21, n_waterlines: int = 11
) -> OffsetsTable:
    r"""Offsets of the Wigley parabolic hull, a published mathematical hull form.

    .. math::

        y(x, z) = \frac{B}{2}\Bigl(1 - \xi^2\Bigr)\Bigl(1 - \zeta^2\Bigr), \quad
        \xi = \frac{2x}{L} - 1,\ \zeta = \frac{T - z}{T}\ (0 \le z \le T),

    wall-sided above the waterline (Wigley, W.C.S. 1934, "A comparison of experiment
    and calculated wave-profiles and wave-resistances for a form having parabolic
    waterlines", Proc. R. Soc. Lond. A 144:144-159; the seakeeping benchmark hulls of
    Journee, J.M.J. 1992, "Experiments and calculations on four Wigley hull forms",
    Delft Univ. of Technology, Ship Hydromechanics Lab. Report 909). Closed forms used
    as checks: :math:`C_b = 4/9`, :math:`C_{wp} = C_M = 2/3`, LCB at midship,
    :math:`KB = 5T/8`, :math:`BM = 3B^2/(35T)`.

    Stations equally spaced from the AP (``x = 0``) to the FP (``x = L``); waterlines
    equally spaced from the keel to the draft, then to the deck ``D``.
    """
    xs = np.linspace(0.0, L, n_stations)
    zs = np.linspace(0.0, T, n_waterlines)
    if D > T:
        zs = np.concatenate([zs, [D]])
    xi = 2.0 * xs / L - 1.0
    zeta = np.clip((T - zs) / T, 0.0, 1.0)
    Y = 0.5 * B * (1.0 - xi[:, None] ** 2) * (1.0 - zeta[None, :] ** 2)
    return OffsetsTable(xs, zs, Y, "Wigley parabolic hull (Wigley 1934)")


__all__ = [
    "OFFSETS_HEADER",
    "OffsetsError",
    "OffsetsHull",
    "OffsetsTable",
    "draft_at",
    "form_parameter_offsets",
    "hull_from_offsets",
    "offsets_of_hull",
    "read_offsets",
    "wigley_offsets",
    "write_offsets",
]
