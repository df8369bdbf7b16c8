"""Benchmark: the panel-method wave-force table of one vessel, and an analysis with it.

Issue 25's target: the Capytaine table over lambda/L = 1-3 (41 wavelengths) and
headings 0-60 deg (7) in under 60 s on 2 cores, cached afterwards; an analysis with the
tabulated forces no slower than with the strip forces (ratio <= 1.1).

    python benchmarks/panel_table.py [--vessel purse_seiner] [--nx 40 --nz 8]

Prints the wall time of the table (cache bypassed), of a cached read, the machine load
(``os.getloadavg``), and the time of ``critical_fn_bvp`` at 10 deg with the strips and
with the tabulated forces (median of 3, compiled functions warm). Not a test.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import tempfile
import time

import numpy as np

from ship_models import get_vessel_data
from ship_models.analysis.critical_bvp import critical_fn_bvp
from ship_models.hydro.panel import PanelWaveBuilder, hull_mesh, panel_table
from ship_models.umeda_4dof import Umeda4DOF


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--vessel", default="purse_seiner")
    ap.add_argument("--nx", type=int, default=40)
    ap.add_argument("--nz", type=int, default=8)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    os.environ.setdefault("BROACHKIT_CACHE_DIR", tempfile.mkdtemp(prefix="broachkit_bench_"))
    data = get_vessel_data(args.vessel)
    V, F = hull_mesh(data.hull, nx=args.nx, nz=args.nz)
    w = data.forces.waves
    kw = dict(L=data.hull.L, x_G=data.info["x_G"], zeta_G=data.info["zeta_G"], rho=w.rho,
              g=w.g, lambda_over_L=np.linspace(1.0, 3.0, 41),
              chi_deg=np.arange(0.0, 61.0, 10.0))  # fmt: skip
    load0 = os.getloadavg()
    t0, c0 = time.perf_counter(), time.process_time()
    tab = panel_table(V, F, cache=False, **kw)
    t_table, c_table = time.perf_counter() - t0, time.process_time() - c0
    panel_table(V, F, **kw)  # fill the cache
    t0 = time.perf_counter()
    panel_table(V, F, **kw)
    t_cached = time.perf_counter() - t0
    print(f"panels: {tab.info['n_panels']}, problems: {41 * 7}")
    print(f"table: {t_table:.1f} s wall, {c_table:.1f} s CPU of this process (all threads) "
          f"(target < 60 s wall on 2 cores), cached read {t_cached * 1e3:.1f} ms")  # fmt: skip
    print(f"load average before/after: {load0} / {os.getloadavg()} on {os.cpu_count()} CPUs")

    strips = Umeda4DOF(data)
    panel = Umeda4DOF(data.vessel.path or args.vessel,
                      waves=PanelWaveBuilder(chi_deg=tuple(kw["chi_deg"])))  # fmt: skip
    times = {}
    for name, m in (("strips", strips), ("panel", panel)):
        critical_fn_bvp(math.radians(10.0), model=m)  # warm: compile and cache
        ts = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            c = critical_fn_bvp(math.radians(10.0), model=m)
            ts.append(time.perf_counter() - t0)
        times[name] = statistics.median(ts)
        print(f"critical_fn_bvp 10 deg, {name}: {times[name]:.2f} s (Fn* = {c.Fn:.6f})")
    print(f"analysis time ratio panel / strips: {times['panel'] / times['strips']:.2f} "
          "(target <= 1.1)")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
