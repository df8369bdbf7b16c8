r"""IMO surf-riding Level 2: Melnikov's threshold and the exact one over the wave cases.

Run on demand (not a test): ``python benchmarks/imo_assessment.py [--vessel NAME]
[--repeat 3] [--json PATH]`` (about a minute).

Times, on the criterion's grid of ``80 x 100`` regular waves
(``ship_models/data/imo/surf_riding_level2.toml``):

* Melnikov's closed form (:func:`ship_models.assessment.melnikov.melnikov_grid`:
  Froude-Krylov amplitude per wavelength, one vectorised quadrature of the resistance
  along the separatrices, the quadratic in ``n``, a vectorised bisection for ``Fn``);
  goal < 1 s;
* the exact threshold (:func:`ship_models.assessment.exact.exact_threshold_grid`: one
  connection from the manifold's fate, then natural-parameter steps across the
  wavelengths and pseudo-arclength continuation in the steepness along each column);
  goal < 60 s on 2 cores;
* the Longuet-Higgins weights of the 17 x 16 sea-state classes.

It reports the continuation steps, the largest error estimate, and Melnikov's largest
and mean relative difference from the exact threshold.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time

import numpy as np

from ship_models.assessment import load_standard
from ship_models.assessment.criteria import sea_state_weights
from ship_models.assessment.exact import exact_threshold_grid
from ship_models.assessment.melnikov import melnikov_grid
from ship_models.surge import SurgeModel


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vessel", default="purse_seiner")
    ap.add_argument("--repeat", type=int, default=3, help="repeats of the fast parts")
    ap.add_argument("--json", default=None, help="write the numbers here")
    args = ap.parse_args()
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
    t0 = time.perf_counter()
    ex = exact_threshold_grid(model, st.lambda_over_L, st.steepness)
    t_ex = time.perf_counter() - t0
    rel = mel.Fn_cr / ex.Fn_cr - 1
    out = {
        "vessel": args.vessel,
        "grid": [int(st.lambda_over_L.size), int(st.steepness.size)],
        "melnikov_s_median": statistics.median(t_mel),
        "weights_s_median": statistics.median(t_w),
        "exact_s": t_ex,
        "exact_steps": ex.steps,
        "exact_complete": ex.complete,
        "exact_error_max": float(np.nanmax(ex.error)),
        "columns_not_ok": [s for s in ex.column_status if not s.startswith("ok")],
        "columns_saddle_node_loop": sum("saddle-node" in s for s in ex.column_status),
        "melnikov_rel_difference_max": float(np.nanmax(np.abs(rel))),
        "melnikov_rel_difference_mean": float(np.nanmean(rel)),
        "cpus": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0],
        "python": platform.python_version(),
        "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
    }
    text = json.dumps(out, indent=2)
    print(text)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            fh.write(text + "\n")


if __name__ == "__main__":
    main()
