r"""IMO surf-riding Level 2: Melnikov's threshold and the exact one over the wave cases.

Run on demand (not a test): ``python benchmarks/imo_assessment.py [--vessel NAME]
[--repeat 3] [--workers 2] [--direct] [--json PATH] [--grids PATH]`` (under a minute
on a quiet 2-core machine; ``--direct`` adds the in-process path, about 30 s more).

Times, on the criterion's grid of ``80 x 100`` regular waves
(``ship_models/data/imo/surf_riding_level2.toml``):

* Melnikov's closed form (:func:`ship_models.assessment.melnikov.melnikov_grid`:
  Froude-Krylov amplitude per wavelength, one vectorised quadrature of the resistance
  along the separatrices, the quadratic in ``n``, a vectorised bisection for ``Fn``);
  goal < 1 s;
* the exact threshold on the sweep engine
  (:func:`ship_models.assessment.exact_sweep.exact_threshold_sweep`: 8 tasks of 10
  wavelengths on ``--workers`` local processes, the backend ``broachkit assess``
  uses by default; each task one connection from the manifold's fate, then
  natural-parameter steps across its wavelengths and pseudo-arclength continuation in
  the steepness along each column); goal < 60 s on 2 cores, wall time including the
  workers' start;
* with ``--direct`` the same grid in this process
  (:func:`ship_models.assessment.exact.exact_threshold_grid`, one start for the whole
  grid) and the largest difference between the two paths, against their error
  estimates;
* the Longuet-Higgins weights of the 17 x 16 sea-state classes.

It reports the continuation steps, the largest error estimate, Melnikov's largest
and mean relative difference from the exact threshold, the CPU time of the sweep's
workers (and of the in-process path), and the load average before and after. The
machine is shared: a wall time means little without the load, and with the kernel's
autogroup scheduling (``/proc/sys/kernel/sched_autogroup_enabled``) CPU is shared
between sessions, not processes, so on a loaded machine the two workers of one
session together get about the share one process would: the CPU time is the number
that does not depend on the others.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import time

import numpy as np

from ship_models.assessment import load_standard
from ship_models.assessment.criteria import sea_state_weights
from ship_models.assessment.exact import exact_threshold_grid
from ship_models.assessment.exact_sweep import exact_threshold_sweep
from ship_models.assessment.melnikov import melnikov_grid
from ship_models.surge import SurgeModel


def main() -> None:
    """Run the benchmark and print its numbers as JSON."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vessel", default="purse_seiner")
    ap.add_argument("--repeat", type=int, default=3, help="repeats of the fast parts")
    ap.add_argument("--workers", type=int, default=2, help="local processes of the sweep")
    ap.add_argument("--direct", action="store_true", help="also the in-process path")
    ap.add_argument("--json", default=None, help="write the numbers here")
    ap.add_argument("--grids", default=None, help="write the threshold grids here (.npz)")
    args = ap.parse_args()
    load_before = os.getloadavg()
    model = SurgeModel(args.vessel)
    st = load_standard()
    F = model.forces
    t_mel = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        mel = melnikov_grid(F, st.lambda_over_L, st.steepness)
        t_mel.append(time.perf_counter() - t0)
    t_w = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        sea_state_weights(st, F.L, st.Hs_classes, st.Tz_classes, g=F.g)
        t_w.append(time.perf_counter() - t0)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    ex = exact_threshold_sweep(
        args.vessel, st.lambda_over_L, st.steepness, backend="processes",
        workers=args.workers, progress=False,
    )  # fmt: skip
    t_ex = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    load_after = os.getloadavg()
    rel = mel.Fn_cr / ex.Fn_cr - 1
    out = {
        "vessel": args.vessel,
        "grid": [int(st.lambda_over_L.size), int(st.steepness.size)],
        "melnikov_s_median": statistics.median(t_mel),
        "weights_s_median": statistics.median(t_w),
        "exact_sweep_s": t_ex,
        "exact_sweep_workers_cpu_s": (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime),
        "exact_engine": ex.engine,
        "exact_steps": ex.steps,
        "exact_complete": ex.complete,
        "exact_error_max": float(np.nanmax(ex.error)),
        "exact_error_median": float(np.nanmedian(ex.error)),
        "columns_not_ok": [s for s in ex.column_status if not s.startswith("ok")],
        "columns_saddle_node_loop": sum("saddle-node" in s for s in ex.column_status),
        "melnikov_rel_difference_max": float(np.nanmax(np.abs(rel))),
        "melnikov_rel_difference_mean": float(np.nanmean(rel)),
        "cpus": os.cpu_count(),
        "load_average_before": [round(v, 2) for v in load_before],
        "load_average_after_sweep": [round(v, 2) for v in load_after],
        "python": platform.python_version(),
        "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
    }
    grids = {"Fn_cr_sweep": ex.Fn_cr, "error_sweep": ex.error, "Fn_cr_melnikov": mel.Fn_cr}
    if args.direct:
        s0 = resource.getrusage(resource.RUSAGE_SELF)
        t0 = time.perf_counter()
        dx = exact_threshold_grid(model, st.lambda_over_L, st.steepness)
        s1 = resource.getrusage(resource.RUSAGE_SELF)
        diff = np.abs(dx.Fn_cr - ex.Fn_cr)
        out.update(
            exact_direct_s=time.perf_counter() - t0,
            exact_direct_cpu_s=(s1.ru_utime + s1.ru_stime) - (s0.ru_utime + s0.ru_stime),
            direct_steps=dx.steps,
            sweep_vs_direct_max_abs_difference=float(np.nanmax(diff)),
            sweep_vs_direct_max_difference_over_estimates=float(
                np.nanmax(diff / (dx.error + ex.error))
            ),
            load_average_after_direct=[round(v, 2) for v in os.getloadavg()],
        )
        grids.update(Fn_cr_direct=dx.Fn_cr, error_direct=dx.error)
    text = json.dumps(out, indent=2)
    print(text)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            fh.write(text + "\n")
    if args.grids:
        with open(args.grids, "wb") as fh:
            np.savez(fh, **grids)


if __name__ == "__main__":
    main()
