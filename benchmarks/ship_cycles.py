"""Benchmark: the ship's cycle branch (chi_c = 10 deg) from Fn 0.1 to its end.

Target (issue 12): under 10 s on the 2-core machine. Measures the wall time of the
start cycle (simulation + collocation correction) and of the branch
(:func:`ship_models.analysis.cycles.cycle_branch`, 60 intervals of degree 4, mesh
adapted every 10 steps, ended at T = 60 s), rows, time per step, and where the time
goes (``--profile``: a second run under cProfile, cumulative time of the engine's
parts). Writes
``benchmarks/results/ship_cycles.json``.

Also reported: CPU time (user + system of this process; a background compilation of the
stage function runs in a child process, see ``continuation.casadi_compile.compiled_soon``), the
load average, and whether the branch ran on the compiled stage function (``compiled``:
false on the first run on a machine, while it compiles; ``BROACHKIT_COMPILE=0`` forces
CasADi's virtual machine).

Run on demand: ``python benchmarks/ship_cycles.py [--profile]`` (under a minute).
"""

from __future__ import annotations

import cProfile
import json
import math
import os
import pstats
import sys
import time
from pathlib import Path

PARTS = {
    "floquet (condensation + periodic eigenvalues)": "floquet.py:floquet",
    "Jacobian assembly (PeriodicOrbitProblem.linearize)": "problem.py:linearize",
    "f, f_x, f_p at the stages (VM or compiled)": "collocation.py:all",
    "SuperLU factorisations (splu)": "linsolve.py:splu",
}


def main() -> int:
    """Run once and print / write the numbers."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    import ship_models
    from ship_models.analysis.cycles import cycle_branch, simulated_cycle

    model = ship_models.get_model("purse_seiner")
    params = model.default_params().replace(Fn=0.1, chi_c=math.radians(10.0))
    t0 = time.perf_counter()
    orbit = simulated_cycle(model, params)
    t_start = time.perf_counter() - t0
    load = os.getloadavg()
    t1, c1 = time.perf_counter(), time.process_time()
    cb = cycle_branch(orbit, "Fn", p_max=0.4, period_max=60.0)
    t_branch, c_branch = time.perf_counter() - t1, time.process_time() - c1
    from continuation.periodic import problem_at
    from continuation.periodic.collocation import _BUFFERS

    used = _BUFFERS.get(problem_at(cb.branch, len(cb.p) - 1)._eval)  # type: ignore[attr-defined]
    compiled = bool(used is not None and used[2])
    parts = {}
    if "--profile" in sys.argv:  # a second, profiled run: where the time goes
        prof = cProfile.Profile()
        prof.enable()
        cycle_branch(orbit, "Fn", p_max=0.4, period_max=60.0)
        prof.disable()
        stats = pstats.Stats(prof).stats  # type: ignore[attr-defined]
        for label, key in PARTS.items():
            parts[label] = sum(v[3] for k, v in stats.items() if f"{Path(k[0]).name}:{k[2]}" == key)
    res = {
        "start_cycle_s": t_start,
        "branch_s": t_branch,
        "branch_cpu_s": c_branch,
        "compiled": compiled,
        "load_average": load,
        "rows": len(cb.p),
        "s_per_step": t_branch / max(len(cb.p) - 1, 1),
        "Fn_last": float(cb.p[-1]),
        "Fn_fit": cb.limit,
        "status": cb.status.name,
        "parts_s": parts,
        "target_s": 10.0,
    }
    out = Path(__file__).resolve().parent / "results" / "ship_cycles.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(res, indent=2))
    print(json.dumps(res, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
