"""``import continuation`` loads only what the engine needs to start: the graph, plotting
and parallel libraries are imported where they are used (issue 27: a single CLI query
must not pay for them)."""

from __future__ import annotations

import subprocess
import sys


def test_import_continuation_loads_no_graph_plot_or_cluster_library():
    code = (
        "import sys, continuation\n"
        "heavy = ('networkx', 'matplotlib', 'dask', 'distributed')\n"
        "print(','.join(m for m in heavy if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)  # fmt: skip
    assert out.stdout.strip() == ""


def test_the_global_graph_still_works_after_the_lazy_import():
    import networkx as nx

    from continuation.dynamics import compare_graphs

    g = nx.MultiDiGraph()
    assert compare_graphs(g, g) is not None
