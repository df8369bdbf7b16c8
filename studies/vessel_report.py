"""One-page vessel report: particulars, hull, GZ, resistance, thrust, wave forces, data status.

Usage::

    python studies/vessel_report.py NAME [--out DIR]

``NAME`` is a registered model name (``broachkit vessels list``) or the path to a
vessel ``.toml`` file. Written to ``DIR`` (default ``out/vessel_report``):

=================================  =====================================================
``<vessel>_report.png``            the one-page figure
``<vessel>_particulars.csv``       particulars and derived numbers (value, unit)
``<vessel>_coefficients.csv``      every coefficient: value, unit, status, source
``<vessel>_gz.csv``                heel (deg), hydrostatic GZ and its sine-series fit (m)
``<vessel>_resistance_thrust.csv`` R(u) of the model, Holtrop-Mennen estimate, thrust
                                   T(u; n(Fn_k)) at several commanded Fn_k (N)
``<vessel>_wave_amplitudes.csv``   amplitudes over one wavelength of X_w, Y_w (N) and
                                   N_w, K_w (N m) against heading chi (deg), at u = c
=================================  =====================================================

The wave forces of the model are linear in the wave (Froude-Krylov plus lift), so
each is :math:`A\\sin 2\\pi\\xi + B\\cos 2\\pi\\xi` in the wave-relative position
:math:`\\xi = \\xi_G/\\lambda`, and its amplitude is
:math:`\\sqrt{F(0)^2 + F(1/4)^2}` (two evaluations per heading).

Run time: about 3 s per vessel (mostly resolving the vessel: hull, GZ curve).
"""

from __future__ import annotations

import argparse
import sys
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ship_models import get_vessel_data
from ship_models.contracts import SeaState
from ship_models.estimation import VesselModelData
from ship_models.hydro.hydrostatics import is_code_criteria
from studies._common import figure_style, new_figure, output_dir, save_csv, save_figure, save_table

STATUSES = ("given", "measured", "estimated", "assumed")
STATUS_COLORS = {
    "given": "tab:blue",
    "measured": "tab:green",
    "estimated": "tab:orange",
    "assumed": "tab:red",
}


@dataclass(frozen=True)
class ReportFiles:
    """Paths of the files written by :func:`build_report`."""

    png: Path
    particulars: Path
    coefficients: Path
    gz: Path
    resistance_thrust: Path
    wave_amplitudes: Path


# ---------------------------------------------------------------------- numbers
def wave_amplitudes(
    data: VesselModelData,
    chi: np.ndarray,
    *,
    u: float | None = None,
    lift: bool = True,
    H_over_lambda: float | None = None,
    lambda_over_L: float | None = None,
) -> np.ndarray:
    """Amplitudes over one wavelength of ``(X_w, Y_w, N_w, K_w)`` against heading.

    Parameters
    ----------
    data : VesselModelData
    chi : ndarray, shape (M,)
        Headings from the wave direction (rad).
    u : float, optional
        Surge speed for the lift terms (m/s); default the wave celerity.
    lift : bool
        Include the lift due to wave particle velocity.
    H_over_lambda, lambda_over_L : float, optional
        The wave; default the vessel file's.

    Returns
    -------
    ndarray, shape (M, 4)
        ``sqrt(F(xi=0)^2 + F(xi=1/4)^2)`` for each force (N, N, N m, N m).
    """
    F = data.forces
    v = data.vessel
    Hl = v.get("waves.H_over_lambda") if H_over_lambda is None else H_over_lambda
    lL = v.get("waves.lambda_over_L") if lambda_over_L is None else lambda_over_L
    speed = float(F.celerity(lL)) if u is None else float(u)
    out = np.zeros((np.size(chi), 4))
    for i, c in enumerate(np.atleast_1d(chi)):
        f0 = np.array(F.waves.forces(0.0, speed, c, SeaState(Hl, lL), lift=lift), dtype=float)
        f1 = np.array(F.waves.forces(0.25, speed, c, SeaState(Hl, lL), lift=lift), dtype=float)
        out[i] = np.hypot(f0, f1)
    return out


def commanded_froude_numbers(Fn_c: float) -> np.ndarray:
    """Four commanded Froude numbers for the thrust curves: 1/4 .. 1 of ``Fn_c`` (to 0.01)."""
    return np.unique(np.round(np.array([0.25, 0.5, 0.75, 1.0]) * Fn_c, 2))


def _holtrop_resistance(data: VesselModelData, u: np.ndarray) -> np.ndarray:
    v = data.vessel
    kw: dict[str, float] = {}
    if v.has("resistance.form_factor"):
        kw["form_factor"] = v.get("resistance.form_factor")
    if v.has("resistance.C_A"):
        kw["C_A"] = v.get("resistance.C_A")
    return data.holtrop.total_resistance(
        u, rho=v.get("environment.rho"), g=v.get("environment.g"), nu=v.get("environment.nu"), **kw
    )


def particulars_rows(data: VesselModelData) -> list[tuple[str, float, str]]:
    """``(quantity, value, unit)`` of the main particulars and derived numbers."""
    v, info, F = data.vessel, data.info, data.forces
    g, L = v.get("environment.g"), v.get("particulars.L_pp")
    lL = v.get("waves.lambda_over_L")
    c = float(F.celerity(lL))
    phi_m, gz_m = data.gz.max_gz
    rows = [
        ("L_pp", L, "m"),
        ("B", v.get("particulars.B"), "m"),
        ("D", v.get("particulars.D"), "m"),
        ("d_f", v.get("particulars.d_f"), "m"),
        ("d_a", v.get("particulars.d_a"), "m"),
        ("C_b", v.get("particulars.C_b"), "-"),
        ("displacement", info["mass"] / 1000.0, "t"),
        ("GM", v.get("loading.GM"), "m"),
        ("KG (from GM and hull)", info["KG"], "m"),
        ("T_phi", v.get("loading.T_phi"), "s"),
        ("GZ_max", gz_m, "m"),
        ("heel at GZ_max", float(np.rad2deg(phi_m)), "deg"),
        ("vanishing angle", float(np.rad2deg(info["phi_vanishing"])), "deg"),
        ("IS Code margin", float(info["is_code_margin"]), "-"),
        ("D_p", v.get("propulsion.D_p"), "m"),
        ("A_R", v.get("rudder.A_R"), "m^2"),
        ("H/lambda", v.get("waves.H_over_lambda"), "-"),
        ("lambda/L_pp", lL, "-"),
        ("wave celerity c", c, "m/s"),
        ("Fn of c", c / np.sqrt(g * L), "-"),
    ]
    return [(q, float(x), u) for q, x, u in rows]


# ---------------------------------------------------------------------- report
def build_report(name: str | Path, out: str | Path | None = None) -> ReportFiles:
    """Compute the report of vessel ``name`` and write PNG and CSV files into ``out``.

    Parameters
    ----------
    name : str or Path
        Registered model name or path to a vessel ``.toml`` file.
    out : path, optional
        Output folder (default ``output_dir("vessel_report")``).

    Returns
    -------
    ReportFiles
    """
    data = get_vessel_data(name)
    outdir = Path(out) if out is not None else output_dir("vessel_report")
    outdir.mkdir(parents=True, exist_ok=True)
    v, F = data.vessel, data.forces
    stem = v.name
    g, L = v.get("environment.g"), v.get("particulars.L_pp")
    sqrt_gL = float(np.sqrt(g * L))
    Hl, lL = v.get("waves.H_over_lambda"), v.get("waves.lambda_over_L")
    c = float(F.celerity(lL))
    Fn_c = c / sqrt_gL
    src = {"vessel": stem, "file": v.path}

    # particulars and coefficients
    prow = particulars_rows(data)
    f_part = save_table(
        outdir / f"{stem}_particulars.csv", ("quantity", "value", "unit"), prow, meta=src
    )
    crow = [
        (k, c_.value, c_.unit, c_.status, c_.source) for k, c_ in sorted(v.coefficients.items())
    ]
    f_coef = save_table(
        outdir / f"{stem}_coefficients.csv",
        ("key", "value", "unit", "status", "source"),
        crow,
        meta=src,
    )

    # GZ
    gz = data.gz
    f_gz = save_csv(
        outdir / f"{stem}_gz.csv",
        {"phi_deg": np.rad2deg(gz.phi), "gz_hydrostatic_m": gz.gz, "gz_fit_m": gz(gz.phi)},
        meta={**src, "GM_m": v.get("loading.GM"), "fit": "sine series with GZ'(0) = GM"},
    )

    # resistance and thrust
    Fn_hi = min(1.25 * Fn_c, F.resistance.u_max / sqrt_gL)
    Fn = np.linspace(0.02, Fn_hi, 120)
    u = Fn * sqrt_gL
    R = np.asarray(F.resistance_force(u), dtype=float)
    R_h = _holtrop_resistance(data, u)
    Fn_k = commanded_froude_numbers(Fn_c)
    cols: dict[str, Any] = {"Fn": Fn, "u_m_s": u, "R_model_N": R, "R_holtrop_N": R_h}
    for fk in Fn_k:
        n = float(F.revolutions(fk))
        cols[f"T_Fn{fk:.2f}_N"] = np.asarray(F.thrust_force(u, n), dtype=float)
    uses_r0 = v.has("resistance.R0_prime")
    f_rt = save_csv(
        outdir / f"{stem}_resistance_thrust.csv",
        cols,
        meta={
            **src,
            "R_model": "R0' rho/2 L d u^2 (MMG)" if uses_r0 else "spline fit of Holtrop-Mennen",
            "T": "T(u; n(Fn_k)), n(Fn_k) balances R at u = Fn_k sqrt(g L)",
        },
    )

    # wave-force amplitudes against heading
    chi_deg = np.arange(0.0, 180.0 + 1e-9, 5.0)
    amp = wave_amplitudes(data, np.deg2rad(chi_deg), u=c)
    amp_fk = wave_amplitudes(data, np.deg2rad(chi_deg), u=c, lift=False)
    f_wave = save_csv(
        outdir / f"{stem}_wave_amplitudes.csv",
        {
            "chi_deg": chi_deg,
            "X_amp_N": amp[:, 0],
            "Y_amp_N": amp[:, 1],
            "N_amp_Nm": amp[:, 2],
            "K_amp_Nm": amp[:, 3],
            "X_fk_amp_N": amp_fk[:, 0],
            "Y_fk_amp_N": amp_fk[:, 1],
            "N_fk_amp_Nm": amp_fk[:, 2],
            "K_fk_amp_Nm": amp_fk[:, 3],
        },
        meta={**src, "H_over_lambda": Hl, "lambda_over_L": lL, "u_m_s": c},
    )

    with figure_style():
        fig = new_figure((13.0, 14.0))
        gs = fig.add_gridspec(3, 3, height_ratios=[1.0, 1.0, 1.0])
        desc = v.meta.get("description", "")
        title = f"Vessel report: {stem}" + (f" - {desc}" if desc else "")
        # wrapped: a long description used to run past the figure's edges
        fig.suptitle("\n".join(textwrap.wrap(title, 130)), fontsize=12)
        _panel_particulars(fig.add_subplot(gs[0, 0]), prow)
        _panel_gz(fig.add_subplot(gs[0, 1]), data)
        _panel_resistance(fig.add_subplot(gs[0, 2]), Fn, cols, Fn_k, Fn_c, uses_r0)
        _panel_hull(fig.add_subplot(gs[1, 0]), data)
        _panel_wave(
            fig.add_subplot(gs[1, 1]), fig.add_subplot(gs[1, 2]), chi_deg, amp, amp_fk, Hl, lL
        )
        _panel_status(fig.add_subplot(gs[2, :]), data)
        f_png = save_figure(fig, outdir / f"{stem}_report.png")
    return ReportFiles(f_png, f_part, f_coef, f_gz, f_rt, f_wave)


# ---------------------------------------------------------------------- panels
def _panel_particulars(ax: Any, rows: Sequence[tuple[str, float, str]]) -> None:
    ax.axis("off")
    ax.set_title("Particulars and derived numbers", loc="left")
    lines = [f"{q:<22} {x:>12.5g} {u}" for q, x, u in rows]
    ax.text(
        0.0, 1.0, "\n".join(lines), family="monospace", fontsize=8, va="top", transform=ax.transAxes
    )


def _panel_gz(ax: Any, data: VesselModelData) -> None:
    gz = data.gz
    deg = np.rad2deg(gz.phi)
    ax.plot(deg, gz.gz, ".", ms=2.5, color="0.4", label="hydrostatics (free trim)")
    ax.plot(deg, gz(gz.phi), "-", color="tab:blue", label=f"sine fit ({gz.coeffs.size} terms)")
    GM = gz.GM
    rad = np.deg2rad(57.3)
    ax.plot([0.0, 57.3], [0.0, GM * rad], ":", color="tab:gray", label=f"GM = {GM:g} m")
    crit = is_code_criteria(gz)
    margin = min(val / req - 1.0 for val, req in crit.values())
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlim(0.0, 180.0)
    top = max(float(np.max(gz.gz)), 1e-3)
    ax.set_ylim(max(float(np.min(gz.gz)), -1.0 * top) * 1.1, 1.6 * top)
    ax.set_xlabel("heel angle phi (deg)")
    ax.set_ylabel("GZ (m)")
    ax.set_title(
        "Righting arm (smallest IMO IS Code margin " + f"{100 * margin:+.2f} %)", fontsize=10
    )
    ax.legend(loc="upper right")


def _panel_resistance(
    ax: Any, Fn: np.ndarray, cols: dict[str, Any], Fn_k: np.ndarray, Fn_c: float, uses_r0: bool
) -> None:
    scale = 1e-3 if np.max(cols["R_model_N"]) < 5e6 else 1e-6
    unit = "kN" if scale == 1e-3 else "MN"
    ax.plot(Fn, cols["R_model_N"] * scale, "k-", lw=2, label="R(u), model")
    ax.plot(
        Fn,
        cols["R_holtrop_N"] * scale,
        "k--",
        lw=1,
        label="R(u), Holtrop-Mennen" + (" (comparison)" if uses_r0 else " formula"),
    )
    for fk in Fn_k:
        ax.plot(Fn, cols[f"T_Fn{fk:.2f}_N"] * scale, "-", label=f"T(u; n) at Fn = {fk:.2f}")
    ax.axvline(Fn_c, color="tab:purple", lw=1, ls=":")
    ymax = 1.3 * float(np.max(cols["R_model_N"])) * scale
    ax.set_ylim(-0.15 * ymax, ymax)
    ax.text(Fn_c, 0.97 * ymax, " wave\n celerity", color="tab:purple", va="top", fontsize=8)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel("u / sqrt(g L_pp)")
    ax.set_ylabel(f"force ({unit})")
    ax.set_title("Calm-water resistance and propeller thrust")
    ax.legend(loc="upper left", fontsize=7)


def _panel_hull(ax: Any, data: VesselModelData) -> None:
    h = data.hull
    L = h.L
    order = np.argsort(h.x)
    x = h.x[order] / L
    area = h.area[order]
    ax.plot(x, area / np.max(area), "-o", ms=2.5, label="section area S(x) / S_max")
    ax.plot(x, h.b_wl[order] / (0.5 * h.B), "-s", ms=2.5, label="waterline half-breadth / (B/2)")
    ax.plot(x, h.beta[order], "-^", ms=2.5, label="section coefficient beta")
    ax.set_xlim(-0.5, 0.5)
    ax.set_ylim(0.0, 1.1)
    ax.set_xlabel("x / L_pp (from midship, + forward)")
    ax.set_ylabel("ratio")
    ax.set_title(f"Strip hull ({h.n_stations} stations), volume {h.volume:.4g} m^3")
    ax.legend(loc="lower center", fontsize=7)


def _panel_wave(
    ax_f: Any,
    ax_m: Any,
    chi_deg: np.ndarray,
    amp: np.ndarray,
    amp_fk: np.ndarray,
    Hl: float,
    lL: float,
) -> None:
    _amplitudes(
        ax_f,
        chi_deg,
        amp[:, :2],
        "N",
        [
            (amp[:, 0], "-", "tab:blue", "X_w (surge)"),
            (amp[:, 1], "-", "tab:orange", "Y_w (sway), with lift"),
            (amp_fk[:, 1], "--", "tab:orange", "Y_w, Froude-Krylov only"),
        ],
        f"Wave-force amplitudes, H/lambda = 1/{1 / Hl:.3g}, lambda/L = {lL:g}",
    )
    _amplitudes(
        ax_m,
        chi_deg,
        amp[:, 2:],
        "N m",
        [
            (amp[:, 2], "-", "tab:green", "N_w (yaw), with lift"),
            (amp_fk[:, 2], "--", "tab:green", "N_w, Froude-Krylov only"),
            (amp[:, 3], "-", "tab:red", "K_w (roll), with lift"),
        ],
        "Wave-moment amplitudes (u = wave celerity)",
    )


def _amplitudes(
    ax: Any,
    chi_deg: np.ndarray,
    sized_by: np.ndarray,
    unit: str,
    curves: list[tuple[np.ndarray, str, str, str]],
    title: str,
) -> None:
    """Amplitude curves ``(values, line style, colour, label)`` against the heading, in
    k``unit`` or M``unit`` (M when ``sized_by`` reaches 5e6)."""
    scale = 1e-3 if np.max(sized_by) < 5e6 else 1e-6
    for y, style, color, label in curves:
        ax.plot(chi_deg, y * scale, style, color=color, label=label)
    ax.set_xlabel("heading from wave direction chi (deg)")
    ax.set_ylabel(f"amplitude ({'k' if scale == 1e-3 else 'M'}{unit})")
    ax.set_title(title)
    ax.set_xlim(0.0, 180.0)
    ax.legend(loc="upper right", fontsize=7)


def _panel_status(ax: Any, data: VesselModelData) -> None:
    ax.axis("off")
    coeffs = data.vessel.coefficients
    by: dict[str, list[str]] = {s: [] for s in STATUSES}
    for k, c in sorted(coeffs.items()):
        by[c.status].append(f"{k.split('.', 1)[1]:<17.17} {c.value:>10.4g} {c.unit}")
    total = len(coeffs)
    ax.set_title(
        f"Coefficients by status ({total}: "
        + ", ".join(f"{len(by[s])} {s}" for s in STATUSES)
        + "); sources in the coefficients CSV",
        loc="left",
    )
    for i, s in enumerate(STATUSES):
        x0 = i / len(STATUSES)
        ax.text(
            x0,
            1.0,
            f"{s} ({len(by[s])})",
            color=STATUS_COLORS[s],
            fontsize=9,
            weight="bold",
            va="top",
            transform=ax.transAxes,
        )
        ax.text(
            x0,
            0.965,
            "\n".join(by[s]) if by[s] else "(none)",
            family="monospace",
            fontsize=7.2,
            va="top",
            transform=ax.transAxes,
        )


# ---------------------------------------------------------------------- command line
def main(argv: Sequence[str] | None = None) -> int:
    """Command line: ``vessel_report.py NAME [--out DIR]``."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("name", help="registered model name or path to a vessel .toml file")
    parser.add_argument("--out", type=Path, default=None, help="output folder")
    args = parser.parse_args(argv)
    try:
        files = build_report(args.name, args.out)
    except ValueError as exc:
        sys.stderr.write(f"vessel_report: error: {exc}\n")
        return 2
    for f in (
        files.png,
        files.particulars,
        files.coefficients,
        files.gz,
        files.resistance_thrust,
        files.wave_amplitudes,
    ):
        sys.stdout.write(f"{f}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
