r"""The capsizing threshold curve with mechanisms, against the heteroclinic line alone.

Run on demand (not a test): ``python benchmarks/threshold_curve.py [--step 4]
[--workers 2] [--json PATH]``.

Times, in one process after a warm-up solve (CasADi functions compiled and cached):

* **heteroclinic line**: :func:`ship_models.analysis.critical_curve.critical_curve`
  over ``chi_c = 0, step, ..., 44`` deg (continuation of the connection to its fold);
* **threshold curve**: :func:`ship_models.analysis.threshold_curve.threshold_curve` at
  the same courses, seeded by that line: per course a scan and bisection of the upslope
  branch's fates and, where the threshold is not heteroclinic, the overtaken cycle's
  bifurcations (its mechanism).

Wall-clock (``time.perf_counter``) and the process's CPU time (children included), with
the machine's load average printed beside them: on a shared machine quote the ratio of
the two lines and the per-course medians, not one absolute time. The issue's target is
the threshold curve from 0 deg to its end in under 30 s on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

if str(Path(__file__).resolve().parents[1]) not in sys.path:  # (run as a script)
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks.timing import cpu_total  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; print a table (and write JSON with ``--json``)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=4.0, help="course step in degrees (4)")
    ap.add_argument("--workers", type=int, default=2, help="processes (2)")
    ap.add_argument("--json", type=Path, default=None, help="write the results here")
    args = ap.parse_args(argv)
    from ship_models import get_model
    from ship_models.analysis.critical_bvp import critical_fn_bvp
    from ship_models.analysis.critical_curve import critical_curve
    from ship_models.analysis.threshold_curve import threshold_curve

    model = get_model("purse_seiner")
    critical_fn_bvp(math.radians(10.0), model=model)  # warm-up
    deg = np.arange(0.0, 44.0 + 1e-9, args.step)
    chi = np.radians(deg)
    load0 = os.getloadavg()[0]
    t0, c0 = time.perf_counter(), cpu_total()
    curve = critical_curve(chi, model=model, workers=args.workers)
    t_line, c_line = time.perf_counter() - t0, cpu_total() - c0
    t0, c0 = time.perf_counter(), cpu_total()
    tc = threshold_curve(chi, model=model, heteroclinic=curve, workers=args.workers)
    t_th, c_th = time.perf_counter() - t0, cpu_total() - c0
    rows = [
        {"chi_c_deg": float(d), "Fn": t.Fn if math.isfinite(t.Fn) else None,
         "mechanism": t.mechanism, "status": t.status.name, "seconds": t.elapsed,
         "fates": len(t.samples)}
        for d, t in zip(deg, tc.thresholds, strict=True)
    ]  # fmt: skip
    doc = {
        "machine": {
            "processor": platform.processor() or platform.machine(),
            "cpus": os.cpu_count(),
            "load_before": load0,
            "load_after": os.getloadavg()[0],
        },  # fmt: skip
        "courses_deg": deg.tolist(),
        "workers": args.workers,
        "heteroclinic_line": {"wall_s": t_line, "cpu_s": c_line, "status": curve.status.name},
        "threshold_curve": {
            "wall_s": t_th,
            "cpu_s": c_th,
            "status": tc.status.name,
            "message": tc.message,
        },  # fmt: skip
        "per_course": rows,
        "target_wall_s": 30.0,
    }
    out = sys.stdout
    out.write(f"load {load0:.1f} -> {doc['machine']['load_after']:.1f}, {args.workers} workers\n")
    out.write(f"heteroclinic line   {t_line:7.1f} s wall {c_line:7.1f} s CPU\n")
    out.write(f"threshold curve     {t_th:7.1f} s wall {c_th:7.1f} s CPU (target 30 s wall)\n")
    for r in rows:
        out.write(f"  {r['chi_c_deg']:5.1f} deg  {r['seconds']:6.1f} s  {r['fates']:3d} fates  "
                  f"{r['mechanism']} ({r['status']})\n")  # fmt: skip
    if args.json is not None:
        args.json.write_text(json.dumps(doc, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
