"""A single command-line query loads what it needs and nothing else (issue 27, item 6).

The time of ``broachkit fixed-points`` (about 1 s) is mostly imports; it is measured by
``benchmarks/main_job.py --commands query``, not here (the machine is shared). These
tests keep the imports from growing back: the command line loads only the command it
runs, and the query none of the engine's or Python's heavy packages it does not use.
"""

from __future__ import annotations

import importlib
import json
import os
import pkgutil
import subprocess
import sys

import pytest

import broachkit_cli.commands
from broachkit_cli.blas import THREAD_VARIABLES
from broachkit_cli.main import COMMANDS, DEFAULT_COMMAND, requested_command


def test_the_command_table_names_every_command_module():
    on_disk = {
        f"broachkit_cli.commands.{m.name}"
        for m in pkgutil.iter_modules(broachkit_cli.commands.__path__)
    }
    assert set(COMMANDS.values()) == on_disk
    for name, modname in COMMANDS.items():
        assert importlib.import_module(modname).NAME == name


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["fixed-points", "--fn", "0.3"], "fixed-points"),
        (["-v", "critical-curve"], "critical-curve"),
        (["--verbose", "vessels", "-h"], "vessels"),
        ([], DEFAULT_COMMAND),
        (["--out", "X"], DEFAULT_COMMAND),
        (["-v"], DEFAULT_COMMAND),
        (["no-such-command"], DEFAULT_COMMAND),
        (["-h"], None),
        (["-v", "--help", "fixed-points"], None),
    ],
)
def test_the_command_a_command_line_runs(argv, expected):
    assert requested_command(argv) == expected


#: Loaded by no single fixed-points query: other commands, the parallel, graph, plotting
#: and template libraries, and the parts of the engine and of SciPy it does not use.
NOT_FOR_A_QUERY = (
    "broachkit_cli.commands.reproduce",
    "broachkit_cli.commands.critical",
    "broachkit_cli.commands.sweep",
    "broachkit_cli.report",
    "dask",
    "distributed",
    "networkx",
    "matplotlib",
    "jinja2",
    "tqdm",
    "numba",
    "scipy.integrate",
    "scipy.interpolate",
    "continuation.bvp",
    "continuation.periodic",
    "continuation.codim2",
    "continuation.switching",
    "continuation.dynamics.simulate",
    "continuation.dynamics.integrators",
    "continuation.plotting",
    "continuation.sweep.run",
    "ship_models.analysis.manifold",
    "ship_models.assessment",
    "studies",
)


def test_a_fixed_points_query_imports_only_what_it_uses():
    code = (
        "import contextlib, io, json, sys\n"
        "from broachkit_cli.main import main\n"
        "out = io.StringIO()\n"
        "with contextlib.redirect_stdout(out):\n"
        "    code = main(['fixed-points', '--fn', '0.3248', '--chi-c', '10', '--json'])\n"
        f"heavy = {NOT_FOR_A_QUERY!r}\n"
        "loaded = [m for m in heavy if m in sys.modules]\n"
        "print(json.dumps({'code': code, 'loaded': loaded,\n"
        "                  'points': len(json.loads(out.getvalue())['fixed_points'])}))\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)  # fmt: skip
    res = json.loads(run.stdout.strip().splitlines()[-1])
    assert res["code"] == 0 and res["points"] >= 2  # the crest saddle and the trough
    assert res["loaded"] == []


def _blas_probe(env_extra: dict[str, str]) -> dict[str, object]:
    code = (
        "import json, os\n"
        "from broachkit_cli.blas import THREAD_VARIABLES, one_blas_thread\n"
        "with one_blas_thread():\n"
        "    import threadpoolctl\n"
        "    inside = [i['num_threads'] for i in threadpoolctl.threadpool_info()\n"
        "              if i['user_api'] == 'blas']\n"
        "after = {v: os.environ.get(v) for v in THREAD_VARIABLES}\n"
        "pools = [i['num_threads'] for i in threadpoolctl.threadpool_info()\n"
        "         if i['user_api'] == 'blas']\n"
        "print(json.dumps({'inside': inside, 'after': after, 'pools': pools}))\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**env, **env_extra})  # fmt: skip
    return json.loads(run.stdout.strip().splitlines()[-1])


def test_one_blas_thread_starts_blas_with_one_thread_and_restores_the_environment():
    res = _blas_probe({})
    assert res["inside"] and set(res["inside"]) == {1}  # NumPy's and SciPy's BLAS
    assert set(res["pools"]) == {1}  # started so: one thread after the context too
    assert res["after"] == dict.fromkeys(THREAD_VARIABLES)  # children see the user's


def test_one_blas_thread_keeps_a_count_the_user_set():
    res = _blas_probe({"OPENBLAS_NUM_THREADS": "2"})
    assert res["after"]["OPENBLAS_NUM_THREADS"] == "2"
    assert set(res["inside"]) == {1}  # limited for the command's own calls all the same
