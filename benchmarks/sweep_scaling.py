"""Sweep scaling and simulation throughput (issue 13). Run on demand, once.

    python -m benchmarks.sweep_scaling [--positions 4] [--out benchmarks/results]

1. Simulations per second of one sudden-change trajectory of the purse seiner
   (Fn = 0.1, chi_c = 0 orbit state, switched to the heteroclinic Fn at 10 deg,
   200 s with the capsize event): :func:`continuation.dynamics.simulate` against
   :func:`scipy.integrate.solve_ivp` with the model's NumPy right-hand side
   (``model.rhs(x, p, NUMPY_OPS)``), both RK45-class adaptive at rtol 1e-9,
   atol 1e-11, and the final-state difference between them.
2. A boundary sweep (``positions`` bisections, no map) on 1 and 2 local processes
   and on a Dask ``LocalCluster`` of 2 workers, each from an empty checkpoint
   directory: wall time, tasks/s and speed-up against 1 process.
3. The surface's cost per point: one wavelength line of ``n`` steepnesses by
   continuation against one bisection by simulation at one point.

Writes ``sweep_scaling.json`` and prints a Markdown table. The machine is shared:
state its load beside the numbers.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from continuation.dynamics import SimEvent, simulate
from continuation.ops import NUMPY_OPS


def sims_per_second(repeats: int = 3) -> dict:
    from ship_models import get_model as _model
    from ship_models.analysis.critical_bvp import critical_fn_bvp
    from ship_models.analysis.events import capsize_angle
    from ship_models.analysis.sudden_change import periodic_orbit

    m = _model("purse_seiner")
    chi = math.radians(10.0)
    fh = critical_fn_bvp(chi, model=m).Fn
    orb = periodic_orbit(m, m.default_params().replace(Fn=0.1, chi_c=0.0), throw=True)
    x0 = orb.state_at(0.5)
    p = m.default_params().replace(Fn=fh - 0.002, chi_c=chi)
    pv = np.asarray(p.values, dtype=float)
    i_phi = m.state_index("phi")
    phi_cap = capsize_angle(m, None)
    T, rtol, atol = 200.0, 1e-9, 1e-11
    ev = SimEvent("capsize", lambda t, x: abs(x[i_phi]) - phi_cap, terminal=True, direction=1)

    def ours() -> np.ndarray:
        tr = simulate(m, x0, pv, (0.0, T), events=[ev], rtol=rtol, atol=atol)
        return np.asarray(tr.x[-1])

    def cap(t, x):
        return abs(x[i_phi]) - phi_cap

    cap.terminal, cap.direction = True, 1

    def scipy_numpy() -> np.ndarray:
        sol = solve_ivp(
            lambda t, x: np.asarray(m.rhs(x, pv, NUMPY_OPS), dtype=float),
            (0.0, T), x0, method="RK45", rtol=rtol, atol=atol, events=[cap],
        )  # fmt: skip
        return sol.y[:, -1]

    out: dict = {}
    for name, fn in (("broachkit simulate", ours), ("solve_ivp + NumPy rhs", scipy_numpy)):
        fn()  # warm-up (compilation, caches)
        t0, c0 = time.perf_counter(), time.process_time()
        for _ in range(repeats):
            xe = fn()
        dt = (time.perf_counter() - t0) / repeats
        cpu = (time.process_time() - c0) / repeats
        out[name] = {
            "seconds_per_sim": dt,
            "sims_per_s": 1.0 / dt,
            "cpu_seconds_per_sim": cpu,
            "x_end": xe.tolist(),
        }
    a, b = (np.asarray(v["x_end"]) for v in out.values())
    ours_, peer = out["broachkit simulate"], out["solve_ivp + NumPy rhs"]
    out["ratio"] = ours_["sims_per_s"] / peer["sims_per_s"]
    # CPU time: on a shared machine the wall-time ratio moves with the load
    out["ratio_cpu"] = peer["cpu_seconds_per_sim"] / ours_["cpu_seconds_per_sim"]
    out["final_state_max_diff"] = float(np.max(np.abs(a - b)))
    out["t_end_s"], out["rtol"], out["atol"] = T, rtol, atol
    return out


def boundary_scaling(positions: int) -> dict:
    from ship_models.analysis.sweeps import boundary_sweep

    runs = {}
    tables = {}
    for label, opts in (
        ("1 process", {"backend": "processes", "workers": 1}),
        ("2 processes", {"backend": "processes", "workers": 2}),
        ("LocalCluster 2 workers", {"backend": "dask", "workers": 2}),
    ):
        with tempfile.TemporaryDirectory() as d:
            t0 = time.perf_counter()
            r = boundary_sweep(
                "purse_seiner", 10.0, positions=positions, map_offsets=None,
                store=Path(d) / "ck", progress=False, **opts,
            )  # fmt: skip
            wall = time.perf_counter() - t0
        sw = r.boundaries.elapsed_s
        runs[label] = {
            "wall_s": wall,
            "sweep_s": sw,
            "tasks": r.boundaries.n_tasks,
            "tasks_per_s": r.boundaries.n_tasks / sw,
            "success": r.boundaries.success,
        }
        tables[label] = r.boundaries.rows()
    base = runs["1 process"]["sweep_s"]
    for v in runs.values():
        v["speedup"] = base / v["sweep_s"]
    first = next(iter(tables.values()))
    return {"runs": runs, "identical_tables": all(t == first for t in tables.values())}


def surface_cost(n: int) -> dict:
    from ship_models import get_model as _model
    from ship_models.analysis.critical_bisection import upslope_bisection as critical_fn_bisection
    from ship_models.analysis.sweeps import critical_line

    m = _model("purse_seiner")
    chi = math.radians(10.0)
    hs = np.linspace(0.08, 0.11, n)
    t0 = time.perf_counter()
    line = critical_line(m, chi, 1.5, hs)
    t_line = time.perf_counter() - t0
    fn = float(line.Fn[-1])
    t0 = time.perf_counter()
    b = critical_fn_bisection(
        chi, model=m, params=m.default_params().replace(H_over_lambda=float(hs[-1])),
        Fn_bracket=(fn - 2e-3, fn + 2e-3), tol=1e-6,
    )  # fmt: skip
    t_bis = time.perf_counter() - t0
    return {
        "points": n,
        "line_s": t_line,
        "line_s_per_point": t_line / n,
        "bisection_s_per_point": t_bis,
        "bisection_runs": b.n_evaluations,
        "line_Fn_at_end": fn,
        "bisection_bracket": list(b.bracket),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--positions", type=int, default=4)
    ap.add_argument("--line-points", type=int, default=4)
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results")
    ap.add_argument(
        "--simulation-only",
        action="store_true",
        help="measure only the simulations per second (writes sweep_scaling_simulation.json)",
    )
    ap.add_argument("--repeats", type=int, default=3, help="timed simulations of each kind")
    args = ap.parse_args()
    load0 = os.getloadavg()
    sim = sims_per_second(args.repeats)
    res = {"cpu_count": os.cpu_count(), "loadavg_start": load0, "simulation": sim}
    if not args.simulation_only:
        res["boundary"] = boundary_scaling(args.positions)
        res["surface"] = surface_cost(args.line_points)
    res["loadavg_end"] = os.getloadavg()
    args.out.mkdir(parents=True, exist_ok=True)
    name = "sweep_scaling_simulation.json" if args.simulation_only else "sweep_scaling.json"
    (args.out / name).write_text(json.dumps(res, indent=1) + "\n")
    s = res["simulation"]
    print("| simulator | s / sim (wall) | CPU s / sim | sims/s |\n|---|---|---|---|")
    for k in ("broachkit simulate", "solve_ivp + NumPy rhs"):
        print(
            f"| {k} | {s[k]['seconds_per_sim']:.3f} | {s[k]['cpu_seconds_per_sim']:.3f} | "
            f"{s[k]['sims_per_s']:.2f} |"
        )
    print(
        f"ratio {s['ratio']:.1f}x (wall), {s['ratio_cpu']:.1f}x (CPU); final states differ "
        f"by {s['final_state_max_diff']:.1e}; load average {load0} -> {res['loadavg_end']}\n"
    )
    if args.simulation_only:
        return
    print("| backend | tasks | sweep s | tasks/s | speed-up |\n|---|---|---|---|---|")
    for k, v in res["boundary"]["runs"].items():
        print(
            f"| {k} | {v['tasks']} | {v['sweep_s']:.1f} | {v['tasks_per_s']:.3f} | "
            f"{v['speedup']:.2f} |"
        )
    print(f"identical tables: {res['boundary']['identical_tables']}\n")
    c = res["surface"]
    print(
        f"surface: {c['line_s_per_point']:.1f} s/point by continuation ({c['points']} points) "
        f"vs {c['bisection_s_per_point']:.1f} s for one bisection ({c['bisection_runs']} runs)"
    )
    print(f"load average {res['loadavg_start']} -> {res['loadavg_end']}")


if __name__ == "__main__":
    main()
