"""Figs. 16-20, 22 and the squares of Fig. 23 of Umeda (1999): sudden-change experiments.

The initial state is the steady periodic orbit for one set of controls; the controls
are suddenly changed and the transient is classified (capsize or periodic motion);
:mod:`ship_models.analysis.sudden_change` does the work, this script draws and saves:

- Fig. 16: outcome over (initial position, Fn) for chi_c = 10 deg starting from the
  (Fn = 0.1, chi_c = 0) orbit, beside the heteroclinic-bifurcation Fn (collocation,
  :func:`~ship_models.analysis.critical_bvp.critical_fn_bvp`);
- Figs. 17-20: the transient just above the boundary (xi_G vs u/c, u/c vs heading,
  heading vs roll, time histories of heading/roll/rudder over t c / L), with Fig. 21's
  comparison of its final stage with the unstable manifold of the crest saddle;
- Fig. 22: the same from the (Fn = 0.3, chi_c = 45 deg) orbit (reached by following
  the (0.1, 0) orbit in three parameter steps: our vessel capsizes from a calm-water
  start at those controls);
- Fig. 23 squares: the experiment's critical Fn against chi_c (0-30 deg) from the
  (0.1, 0) orbit at (xi_G/lambda)_0 = 0.5, by bisection, beside the heteroclinic line
  (:func:`~ship_models.analysis.critical_curve.critical_curve`).

Writes to ``--out`` (default ``out/fig16_22``): ``fig16_map.png``, ``fig17_20_transient.png``,
``fig21_final_stage.png``, ``fig22_map.png``, ``fig23_critical_condition.png``; ``fig16_map.csv``,
``fig22_map.csv``, ``fig23_boundaries.csv``, ``transient.csv``, ``orbits.csv``,
with ``--bvp`` also ``fig16_boundary_bvp.csv``, ``fig22_boundary_bvp.csv`` (the boundary
as a landing BVP beside bisections to 1e-6, drawn on the maps),
``summary.json``.

Run: ``python studies/fig16_22_sudden_change.py [--out DIR] [--full]`` (the default
uses modest grids, about a minute; ``--full`` uses the finer grids of the paper's
figures and every 5 deg with a tighter tolerance, several minutes).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from continuation.status import Status
from continuation.sweep import check_workers, default_workers, open_backend
from ship_models.paper import PAPER_FN_BRACKET
from studies._common import (
    PLANE_LABELS,
    begin_step,
    finish_summary,
    new_figure,
    paper_quantities,
    save_csv,
    save_figure,
    save_table,
    state_columns,
    study_main,
)
from studies._sudden_tasks import compute_orbits, load_orbits, task

CHI_TO_DEG = 10.0
FROM_1 = (0.1, 0.0)  # (Fn, chi_c deg) of the first initial orbit (Figs. 16-21, 23)
FROM_2 = (0.3, 45.0)  # of the second (Fig. 22)
XI_FIG23 = 0.5
#: Fn brackets of the Fig. 23 bisections about the heteroclinic Fn, tried in turn.
FIG23_OFFSETS = ((-0.0063, 0.0017), (-0.03, 0.01))
#: Sub-folder of the step's output with the sweep's checkpoints and the orbits.
SWEEP_DIR = "sweep"
PAPER_FN = PAPER_FN_BRACKET
#: Bisection tolerance of the comparison with the landing BVP (``--bvp``).
BVP_TOL = 1e-6


def _bvp_boundary(
    model: Any,
    orb: Any,
    chi: float,
    bounds: dict[float, Any],
    key: str,
    say: Callable[[str], None],
) -> Any:
    """The boundary as a landing BVP at the bisected positions, beside tight bisections."""
    from ship_models.analysis.capsize_boundary import capsizing_boundary_bvp
    from ship_models.analysis.sudden_change import sudden_change_boundary

    xs = sorted(bounds)
    say(f"{key}: re-bisecting {len(xs)} brackets to {BVP_TOL:g}, then the landing BVP")
    tight = [
        sudden_change_boundary(model, None, chi, x, bounds[x].bracket, BVP_TOL, orbit=orb)
        for x in xs
    ]
    curve = capsizing_boundary_bvp(model, None, chi, xs, orbit=orb, bisections=tight,
                                   progress=lambda m: say(f"  {m}"))  # fmt: skip
    for note in curve.notes:
        say(f"  note: {note}")
    return curve


def _end_row(
    value: dict[str, Any],
    key: str,
    orb_name: str,
    fn: float,
    xi_grid: Any,
    model: Any,
    orbits: dict[str, Any],
) -> dict[str, Any]:
    """A map row at an end of the bisections' bracket, from their first runs there.

    The bisection at each position starts with the same run as the map's cell at the
    bracket's ends (:attr:`~ship_models.analysis.sudden_change.SuddenChangeBoundary.end_runs`:
    the same function, arguments and fixed points), so these two rows are not run
    again; a cell missing there (a bisection that did not reach its ends) is run here.
    """
    from ship_models.analysis.sudden_change import sudden_change_map

    outcomes: list[str] = []
    times: list[float | None] = []
    for xi in xi_grid:
        runs = value[f"{key}/b/{float(xi):g}"].get("end_runs", [])
        hit = [r for r in runs if r[0] == fn]
        if hit:
            outcomes.append(hit[0][1])
            times.append(hit[0][2])
            continue
        mp = sudden_change_map(model, None, math.radians(CHI_TO_DEG), [float(xi)], [fn],
                               orbit=orbits[orb_name])  # fmt: skip
        outcomes.append(str(mp.outcomes[0, 0]))
        t = float(mp.times[0, 0])
        times.append(t if math.isfinite(t) else None)
    return {"outcomes": outcomes, "times": times, "elapsed_s": 0.0}


def _map_rows(mp: Any) -> list[list[Any]]:
    return [
        [float(xi), float(fn), str(mp.outcomes[i, j]), float(mp.times[i, j])]
        for i, fn in enumerate(mp.Fn)
        for j, xi in enumerate(mp.xi_0)
    ]


def _draw_map(
    mp: Any, fn_het: float, bounds: dict[float, Any], title: str, path: Path, bvp: Any = None
) -> None:
    from ship_models.analysis.outcomes import ShipOutcome

    CAPSIZE, PERIODIC = ShipOutcome.CAPSIZE, ShipOutcome.PERIODIC

    fig = new_figure((5.8, 4.9))
    ax = fig.subplots()
    X, Y = np.meshgrid(mp.xi_0, mp.Fn)
    o = mp.outcomes
    for kind, mk, col, lab in (
        (PERIODIC, "o", "tab:blue", "periodic motion"),
        (CAPSIZE, "x", "tab:red", "capsizing due to broaching"),
    ):
        sel = o == kind
        ax.plot(X[sel], Y[sel], mk, color=col, mfc="none", ms=7, mew=1.4, label=lab)
    other = (o != PERIODIC) & (o != CAPSIZE) & (o != "")
    if np.any(other):
        ax.plot(X[other], Y[other], "s", color="tab:gray", mfc="none", ms=7, label="other")
    ax.axhline(fn_het, color="k", ls="--", lw=1.2, label=f"heteroclinic bifurcation {fn_het:.5f}")
    if bounds:
        xs = sorted(bounds)
        ax.errorbar(
            xs, [bounds[x].Fn for x in xs],
            yerr=[0.5 * (bounds[x].bracket[1] - bounds[x].bracket[0]) for x in xs],
            fmt="D", color="tab:green", ms=5, capsize=3, label="boundary by bisection (bracket)",
        )  # fmt: skip
    if bvp is not None:
        for i, seg in enumerate(bvp.segments):
            ax.plot(seg.xi_0, seg.Fn, "-", color="tab:purple", lw=1.3,
                    label="BVP landing continued in xi_0 (same k)" if i == 0 else None)  # fmt: skip
        ok = [p for p in bvp.points if p.success]
        ax.plot([p.xi_0 for p in ok], [p.Fn for p in ok], "*", color="tab:purple", ms=9,
                label="boundary by BVP (landing on the crest saddle)")  # fmt: skip
        for p in ok:
            ax.annotate(f"k={p.k}", (p.xi_0, p.Fn), textcoords="offset points", xytext=(4, -10),
                        fontsize=6, color="tab:purple")  # fmt: skip
    ax.set_xlabel("initial longitudinal position (xi_G / lambda)_0")
    ax.set_ylabel("nominal Froude number")
    ax.set_title(title, fontsize=8.5)
    ax.set_xlim(-0.05, 1.0)
    ax.ticklabel_format(axis="y", useOffset=False)
    fig.legend(loc="outside lower center", ncol=2, fontsize=6.5, frameon=False)
    save_figure(fig, path)


def workers_of(be: Any) -> int:
    """Worker processes of a backend (1: this process)."""
    return 1 if be is None else int(be.slots)


def compute(
    out: Path,
    progress: Callable[[str], None] | None = None,
    *,
    full: bool = False,
    bvp: bool = False,
    backend: Any = None,
    workers: int | None = None,
) -> dict[str, Any]:
    """Run the experiments; write figures and data; return the summary.

    ``bvp=True`` (``--bvp``) also solves the capsizing boundary of Figs. 16 and 22 as a
    landing BVP at every plotted position (:func:`~ship_models.analysis.capsize_boundary.
    capsizing_boundary_bvp`), after re-bisecting each bracket to :data:`BVP_TOL` for the
    comparison; it adds a few minutes of CPU, so the main job leaves it off.

    The bisections and map rows run on ``workers`` local processes (default one per
    core, :func:`continuation.sweep.default_workers`; 1: all in this process), checkpointed in
    ``out/sweep`` (a rerun after an interruption redoes no finished task). ``backend``
    (a :class:`continuation.sweep.Backend`, left open) runs them on a pool that is
    already there instead: the main job's, which runs its other steps too.
    """
    from studies._model import default_model

    say, t_all = begin_step(out, progress)
    model = default_model()  # one per process (shared by the steps it runs)
    workers = default_workers() if workers is None else int(check_workers(workers))
    sweep_dir = out / SWEEP_DIR
    sweep_dir.mkdir(parents=True, exist_ok=True)
    orbits_path = str(sweep_dir / "orbits.pkl")
    # one pool for the whole step: the old orbits are computed in a worker while this
    # process solves the connecting orbit; then every bisection and map row is a task
    be = backend
    if be is None and workers > 1:
        be = open_backend("processes", workers=workers)
    try:
        # on the job's shared pool the orbits are computed here: this process would
        # only wait for them, while the pool's workers run the job's other steps
        return _compute(out, say, full, model, orbits_path, be, t_all, bvp,
                        orbits_here=backend is not None)  # fmt: skip
    finally:
        if be is not None and be is not backend:
            be.close()


def _compute(
    out: Path,
    say: Callable[[str], None],
    full: bool,
    model: Any,
    orbits_path: str,
    be: Any,
    t_all: float,
    bvp: bool = False,
    orbits_here: bool = False,
) -> dict[str, Any]:
    from continuation.sweep import run_sweep, source_version
    from ship_models.analysis.critical_bvp import critical_fn_bvp
    from ship_models.analysis.critical_curve import critical_curve
    from ship_models.analysis.manifold import unstable_manifold
    from ship_models.analysis.sudden_change import (
        SuddenChangeBoundary,
        SuddenChangeMap,
        sudden_change,
    )
    from ship_models.analysis.sweeps import vessel_context
    from studies._model import default_model, heteroclinic

    chi10 = math.radians(CHI_TO_DEG)
    base = model.default_params()
    summary: dict[str, Any] = {"chi_c_to_deg": CHI_TO_DEG, "full": full}

    say("periodic orbits: (0.1, 0 deg) from a calm-water start, (0.3, 45 deg) by following it")
    orbit_job = None
    if be is not None and not orbits_here:
        orbit_job = be.executor.submit(compute_orbits, orbits_path, FROM_1, FROM_2)
    else:
        orbit_info = compute_orbits(orbits_path, FROM_1, FROM_2)

    say("heteroclinic Fn (collocation) and the critical curve 0-30 deg")
    if model is default_model():  # solved once per process (studies._model)
        conn = heteroclinic(CHI_TO_DEG)
    else:
        conn = critical_fn_bvp(chi10, model=model)
    fn_het = float(conn.Fn)
    courses_deg = np.arange(0.0, 31.0, 5.0)
    curve = critical_curve(np.radians(courses_deg), model=model, start=conn)
    summary["heteroclinic_Fn_10deg"] = fn_het
    summary["curve"] = {"chi_c_deg": list(curve.chi_c_deg), "Fn": [float(v) for v in curve.Fn]}

    if orbit_job is not None:
        orbit_info = orbit_job.result()
    orbits = load_orbits(orbits_path)
    orb1, orb2 = orbits["from_1"], orbits["from_2"]
    summary["orbits"] = {"from_0.1_0deg": orb1.to_json(), "from_0.3_45deg": orb2.to_json()}
    summary["orbit_0.3_45deg_from_calm_water"] = orbit_info["direct_2_message"]
    save_table(
        out / "orbits.csv",
        [
            "orbit",
            "period_s",
            "max_abs_multiplier",
            "closure",
            *state_columns(model.state_names, orb1.x_section[None, :]),
        ],
        [
            [
                f"Fn={FROM_1[0]} chi_c={FROM_1[1]}deg",
                orb1.period,
                float(np.max(np.abs(orb1.multipliers))),
                orb1.closure,
                *(float(v[0]) for v in state_columns(model.state_names, orb1.x_section).values()),
            ],
            [
                f"Fn={FROM_2[0]} chi_c={FROM_2[1]}deg",
                orb2.period,
                float(np.max(np.abs(orb2.multipliers))),
                orb2.closure,
                *(float(v[0]) for v in state_columns(model.state_names, orb2.x_section).values()),
            ],
        ],  # fmt: skip
        meta={"section": "xi_G/lambda = 0", "units": "SI, angles deg, rates deg/s"},
    )

    # ---- Fig. 16 and Fig. 22: outcome maps and boundaries; Fig. 23 squares
    xi_grid = np.linspace(0.0, 0.9, 10) if full else np.array([0.0, 0.25, 0.5, 0.75])
    d1 = [-0.004, -0.0015, -0.0005, 0.0005, 0.003]
    d2 = [-0.014, -0.01, -0.006, -0.002, -0.0005, 0.0005]
    if full:
        d1 = list(np.linspace(-0.004, 0.004, 9))
        d2 = list(np.linspace(-0.015, 0.005, 11))
    tol_b = 2e-5 if full else 2e-4
    sq_deg = courses_deg if full else np.array([0.0, 10.0, 20.0, 30.0])
    cases = (
        ("fig16", "from_1", d1, "fig16_map.png", "from the periodic orbit at Fn = 0.1, chi_c = 0"),
        ("fig22", "from_2", d2, "fig22_map.png",
         "from the periodic orbit at Fn = 0.3, chi_c = 45 deg"),
    )  # fmt: skip
    common = {"orbits": orbits_path, "tol": tol_b}
    keys: list[dict[str, Any]] = []
    sq_fh: dict[float, float] = {}
    for deg in sq_deg:  # the longest tasks first
        k = int(np.argmin(np.abs(curve.chi_c_deg - deg)))
        fh = float(curve.Fn[k])
        sq_fh[float(deg)] = fh
        keys.append({
            "task": "boundary", "name": f"fig23/{float(deg):g}", "orbit": "from_1",
            "chi_c": math.radians(deg), "xi_0": XI_FIG23,
            "Fn_brackets": [[fh + lo_d, fh + hi_d] for lo_d, hi_d in FIG23_OFFSETS], **common,
        })  # fmt: skip
    for key, orb_name, deltas, _, _ in cases:
        lo_d, hi_d = min(deltas), max(deltas)
        for xi in xi_grid:
            keys.append({
                "task": "boundary", "name": f"{key}/b/{float(xi):g}", "orbit": orb_name,
                "chi_c": chi10, "xi_0": float(xi),
                "Fn_brackets": [[fn_het + lo_d, fn_het + hi_d]], **common,
            })  # fmt: skip
        for i, dv in enumerate(deltas):
            if dv in (lo_d, hi_d):
                continue  # the bisections' first runs at the bracket's ends (_map_row)
            keys.append({
                "task": "row", "name": f"{key}/row/{i}", "orbit": orb_name, "chi_c": chi10,
                "Fn": float(fn_het + dv), "xi_0": [float(v) for v in xi_grid], **common,
            })  # fmt: skip
    say(f"{len(keys)} sudden-change tasks (bisections, map rows) on {workers_of(be)} worker(s)")
    t_sweep = time.perf_counter()
    res = run_sweep(
        task, keys, store=Path(orbits_path).parent / "checkpoints",
        context=orbit_info["digest"] + ";" + vessel_context("purse_seiner"),
        code_version=source_version(task, "continuation", "ship_models"),
        backend=be.executor if be is not None else "serial",
        progress=False, desc="fig16_22",
    )  # fmt: skip
    if res.status is Status.INTERRUPTED:
        raise KeyboardInterrupt  # finished tasks are checkpointed; a rerun resumes
    if not res.success:
        bad = [r for r in res.records if not r.done]
        raise RuntimeError(
            f"{len(bad)} sudden-change task(s) failed, e.g. {bad[0].key['name']}: {bad[0].errors}"
            if bad
            else f"sudden-change sweep: {res.message}"
        )
    value = {r.key["name"]: r.value for r in res.records}
    summary["sweep"] = {"tasks": len(keys), "workers": workers_of(be), "reused": res.n_reused,
                        "wall_s": round(time.perf_counter() - t_sweep, 2)}  # fmt: skip

    def boundary(v: dict[str, Any], chi: float) -> Any:
        return SuddenChangeBoundary(
            v["Fn"], tuple(v["bracket"]), tuple(v["outcomes"]), chi, v["xi_0"], v["n_runs"],
            Status[v["status"]], v["message"], v["elapsed_s"],
        )  # fmt: skip

    maps: dict[str, Any] = {}
    for key, orb_name, deltas, fig_name, title in cases:
        say(f"{key}: outcome map {len(deltas)} Fn x {xi_grid.size} positions")
        rows_v = [
            value.get(f"{key}/row/{i}")
            or _end_row(value, key, orb_name, float(fn_het + dv), xi_grid, model, orbits)
            for i, dv in enumerate(deltas)
        ]
        mp = SuddenChangeMap(
            np.array([float(v) for v in xi_grid]), np.asarray(fn_het + np.array(deltas), float),
            np.array([r["outcomes"] for r in rows_v], dtype=object),
            np.array([[math.nan if t is None else t for t in r["times"]] for r in rows_v]),
            chi10, Status.SUCCESS, sum(r["elapsed_s"] for r in rows_v),
        )  # fmt: skip
        save_table(
            out / f"{key}_map.csv",
            ["xi_0", "Fn", "outcome", "t_decided_s"],
            _map_rows(mp),
            meta={"chi_c_to_deg": CHI_TO_DEG, "heteroclinic_Fn": fn_het},
        )
        bounds = {}
        for xi in xi_grid:  # the boundary by bisection at every plotted position
            b = boundary(value[f"{key}/b/{float(xi):g}"], chi10)
            if b.success:
                bounds[float(xi)] = b
        bvp_curve = None
        if bvp:
            bvp_curve = _bvp_boundary(model, orbits[orb_name], chi10, bounds, key, say)
            from ship_models.analysis.capsize_boundary import ROW_HEADER

            save_table(
                out / f"{key}_boundary_bvp.csv", ROW_HEADER, bvp_curve.rows(),
                meta={"chi_c_to_deg": CHI_TO_DEG, "bisection_tol": BVP_TOL,
                      "notes": " | ".join(bvp_curve.notes) or "none"},
            )  # fmt: skip
        maps[key] = {
            "xi_0": [float(v) for v in mp.xi_0],
            "Fn": [float(v) for v in mp.Fn],
            "outcomes": [[str(v) for v in row] for row in mp.outcomes],
            "lowest_capsizing_Fn_of_grid": [float(v) for v in mp.boundary()],
            "boundaries": {f"{k:g}": v.to_json() for k, v in bounds.items()},
            "boundary_minus_heteroclinic": {f"{k:g}": v.Fn - fn_het for k, v in bounds.items()},
            "seconds": mp.elapsed,
        }
        if bvp_curve is not None:
            maps[key]["boundary_bvp"] = bvp_curve.to_json()
        _draw_map(
            mp, fn_het, bounds,
            f"Sudden change to chi_c = {CHI_TO_DEG:g} deg (cf. Umeda 1999, Fig. {key[3:]})\n"
            f"{title}",
            out / fig_name, bvp_curve,
        )  # fmt: skip
    summary["maps"] = maps

    say("Fig. 23: experiment's boundary against the course")
    rows = []
    squares = {}
    for deg in sq_deg:
        fh = sq_fh[float(deg)]
        b = boundary(value[f"fig23/{float(deg):g}"], math.radians(deg))
        say(f"  {deg:g} deg: {b.Fn:.6f} ({b.outcomes[1]} above; heteroclinic {fh:.6f})")
        squares[deg] = b
        rows.append(
            [deg, b.Fn, b.bracket[0], b.bracket[1], b.outcomes[0], b.outcomes[1], fh, b.Fn - fh,
             b.status.name, b.n_runs]
        )  # fmt: skip
    save_table(
        out / "fig23_boundaries.csv",
        ["chi_c_deg", "Fn_experiment", "lower", "upper", "outcome_lower", "outcome_upper",
         "Fn_heteroclinic", "difference", "status", "runs"],
        rows,
        meta={"initial_orbit": "Fn = 0.1, chi_c = 0", "xi_0": XI_FIG23, "tol": tol_b},
    )  # fmt: skip
    summary["fig23_squares"] = [
        {"chi_c_deg": float(d), **b.to_json(), "heteroclinic_Fn": float(r[6])}
        for (d, b), r in zip(squares.items(), rows, strict=True)
    ]
    fig = new_figure((5.8, 4.6))
    ax = fig.subplots()
    ok = curve.converged
    ax.plot(curve.chi_c_deg[ok], curve.Fn[ok], "-", color="k", lw=1.0)
    ax.plot(curve.chi_c_deg[ok], curve.Fn[ok], "o", color="k", ms=5,
            label="heteroclinic bifurcation (connecting orbit, filled circles)")  # fmt: skip
    ax.errorbar(
        list(squares), [b.Fn for b in squares.values()],
        yerr=[0.5 * (b.bracket[1] - b.bracket[0]) for b in squares.values()],
        fmt="s", mfc="none", ms=9, mew=1.4, color="tab:orange", capsize=3,
        label=f"numerical experiment, sudden change, (xi_G/lambda)_0 = {XI_FIG23:g} (squares)",
    )  # fmt: skip
    ax.errorbar(
        [CHI_TO_DEG], [0.5 * (PAPER_FN[0] + PAPER_FN[1])], yerr=[0.5 * (PAPER_FN[1] - PAPER_FN[0])],
        fmt="D", color="tab:red", ms=6, capsize=3,
        label=f"Umeda (1999) at {CHI_TO_DEG:g} deg: {PAPER_FN[0]}-{PAPER_FN[1]} (measured coeff.)",
    )  # fmt: skip
    ax.set_xlabel("autopilot course chi_c (deg)")
    ax.set_ylabel("nominal Froude number Fn")
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.set_title("Fig. 23: critical condition for capsizing due to broaching", fontsize=9)
    fig.legend(loc="outside lower center", ncol=1, fontsize=7, frameon=False)
    save_figure(fig, out / "fig23_critical_condition.png")

    # ---- Figs. 17-20: the transient just above the boundary, and Fig. 21
    b10 = squares.get(CHI_TO_DEG)
    fn_above = b10.bracket[1] if b10 is not None and b10.success else fn_het + 1e-4
    say(f"Figs. 17-20: transient at Fn = {fn_above:.6f} (just above the boundary)")
    pt = base.replace(Fn=fn_above, chi_c=chi10)
    run = sudden_change(model, None, pt, XI_FIG23, orbit=orb1)
    tr = run.trajectory
    c = model.celerity(pt)
    L = float(model.forces.L)
    i = {n: model.state_index(n) for n in model.state_names}
    x = tr.x
    deg = np.degrees
    save_csv(
        out / "transient.csv",
        {"t": tr.t, "t_nondim": tr.t * c / L, **state_columns(model.state_names, x)},
        meta={"Fn": fn_above, "chi_c_deg": CHI_TO_DEG, "xi_0": XI_FIG23, "outcome": run.outcome,
              "units": "SI, angles deg, rates deg/s, xi_G unwrapped"},
    )  # fmt: skip
    summary["transient"] = {
        "Fn": fn_above,
        "outcome": run.outcome,
        "t_end_s": float(tr.t[-1]),
        "t_end_nondim": float(tr.t[-1] * c / L),
        "xi_end": float(x[-1, i["xi_G"]]),
        "max_heading_deg": float(deg(np.max(x[:, i["chi"]]))),
        "roll_end_deg": float(deg(x[-1, i["phi"]])),
        "rudder_end_deg": float(deg(x[-1, i["delta"]])),
    }
    q = paper_quantities(x, model.state_names, c, L)
    fig = new_figure((9.0, 7.6))
    ax = fig.subplots(2, 2).ravel()
    for k, (qx, qy, n) in enumerate(
        (("xi_unwrapped", "u_c", 17), ("chi", "r_nd", 18), ("phi", "p_nd", 19))
    ):
        ax[k].plot(q[qx], q[qy], lw=0.8)
        ax[k].plot(q[qx][-1], q[qy][-1], "x", color="tab:red", ms=8)
        ax[k].set_xlabel(PLANE_LABELS[qx])
        ax[k].set_ylabel(PLANE_LABELS[qy])
        ax[k].set_title(f"Fig. {n}", fontsize=8)
    tn = tr.t * c / L
    for n, lab in (("chi", "heading"), ("phi", "roll"), ("delta", "rudder")):
        ax[3].plot(tn, deg(x[:, i[n]]), lw=0.9, label=f"{lab} angle")
    ax[3].set_xlim(max(0.0, tn[-1] - 12.0), tn[-1])
    ax[3].set_xlabel("nondimensional time t c / L")
    ax[3].set_ylabel("angle (deg)")
    ax[3].set_title("Fig. 20 (final stage)", fontsize=8)
    ax[3].legend(fontsize=7, loc="upper left")
    fig.suptitle(
        f"Transient just above the boundary: Fn = {fn_above:.6f}, chi_c = {CHI_TO_DEG:g} deg, "
        f"from the (0.1, 0 deg) orbit at (xi_G/lambda)_0 = {XI_FIG23:g}: {run.outcome}",
        fontsize=9,
    )
    save_figure(fig, out / "fig17_20_transient.png")

    say("Fig. 21: final stage beside the unstable manifold of the crest saddle")
    man = unstable_manifold(model, pt, "crest", t_max=300.0)
    fig = new_figure((9.0, 4.4))
    ax = fig.subplots(1, 2)
    xi_end = x[-1, i["xi_G"]]
    last = tr.t >= tr.t[-1] - 60.0
    lab = "numerical experiment (last 60 s)"
    sq = {"ms": 2.5, "mfc": "none", "color": "tab:orange", "label": lab}
    ax[0].plot(q["xi_unwrapped"][last] - math.floor(xi_end), q["u_c"][last], "s", **sq)
    ax[1].plot(q["chi"][last], q["r_nd"][last], "s", **sq)
    man_json = {}
    for name, br in man.branches.items():
        y = np.asarray(br.trajectory.x)
        qm = paper_quantities(y, model.state_names, c, L)
        col = "k" if name == "downslope" else "tab:gray"
        style = {"color": col, "lw": 1.0, "label": f"unstable manifold, {name} ({br.fate.label})"}
        ax[0].plot(qm["xi_unwrapped"] - math.floor(y[0, i["xi_G"]]), qm["u_c"], "-", **style)
        style["label"] = None
        ax[1].plot(qm["chi"], qm["r_nd"], "-", **style)
        man_json[name] = br.fate.label
    ax[0].set_xlabel(PLANE_LABELS["xi"] + " (one wave)")
    ax[0].set_ylabel(PLANE_LABELS["u_c"])
    ax[1].set_xlabel(PLANE_LABELS["chi"])
    ax[1].set_ylabel(PLANE_LABELS["r_nd"])
    fig.legend(loc="outside lower center", ncol=3, fontsize=7, frameon=False)
    fig.suptitle(f"Final stage vs unstable manifold of the crest saddle, Fn = {fn_above:.6f} "
                 "(cf. Fig. 21)", fontsize=9)  # fmt: skip
    save_figure(fig, out / "fig21_final_stage.png")
    summary["fig21_manifold_fates"] = man_json

    summary["figures"] = [
        "fig16_map.png", "fig17_20_transient.png", "fig21_final_stage.png", "fig22_map.png",
        "fig23_critical_condition.png",
    ]  # fmt: skip
    return finish_summary(out, summary, t_all, default=float)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: ``python studies/fig16_22_sudden_change.py --out DIR``."""
    return study_main(
        __doc__,
        "out/fig16_22",
        compute,
        argv,
        flags=(
            ("full", "fine grids, every 5 deg, tol 2e-5"),
            ("bvp", "also the boundary as a landing BVP (Figs. 16, 22)"),
        ),
        shown=("heteroclinic_Fn_10deg", "fig23_squares", "seconds"),
    )


if __name__ == "__main__":
    raise SystemExit(main())
