"""``import continuation`` loads only what the engine needs to start: the graph, plotting
and parallel libraries are imported where they are used (issue 27: a single CLI query
must not pay for them). The packages re-export their names lazily (PEP 562,
:mod:`continuation._lazy`): every public name importable as before, its module loaded
on first use."""

from __future__ import annotations

import ast
import importlib
import inspect
import subprocess
import sys
import types

import pytest


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


# --- lazy re-exports (PEP 562): every public name as before, loaded on first use ------


LAZY_PACKAGES = (
    "continuation",
    "continuation.algorithms",
    "continuation.bvp",
    "continuation.codim2",
    "continuation.dynamics",
    "continuation.periodic",
    "continuation.sweep",
    "continuation.switching",
    "ship_models",
)


def _type_checking_imports(module: types.ModuleType) -> dict[str, str]:
    """Name -> sub-module of the ``if TYPE_CHECKING:`` imports of a package's source."""
    tree = ast.parse(inspect.getsource(module))
    out: dict[str, str] = {}
    for node in tree.body:
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
            for imp in node.body:
                assert isinstance(imp, ast.ImportFrom) and imp.level == 1
                out.update({a.name: str(imp.module) for a in imp.names})
    return out


@pytest.mark.parametrize("name", LAZY_PACKAGES)
def test_every_public_name_resolves_to_its_definition(name):
    pkg = importlib.import_module(name)
    table = (
        {n: sub for sub, names in pkg._EXPORTS.items() for n in names}
        if hasattr(pkg, "_EXPORTS")
        else {n: sub.lstrip(".") for n, sub in pkg._LAZY.items()}
    )
    # the lazy table, the static imports for type checkers and __all__ agree
    assert _type_checking_imports(pkg) == table
    defined_here = {n for n in pkg.__all__ if n in vars(pkg) and n not in table}
    assert set(pkg.__all__) == set(table) | defined_here
    for public, sub in table.items():
        value = getattr(pkg, public)
        assert value is getattr(importlib.import_module(f"{name}.{sub}"), public), public
        assert public in dir(pkg)


def _fresh(code: str) -> str:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)  # fmt: skip
    return out.stdout.strip()


def test_a_name_loads_only_its_own_module():
    code = (
        "import sys\n"
        "from continuation import Status, Params\n"
        "from ship_models import PAPER_FN\n"
        "heavy = ('scipy.optimize', 'scipy.integrate', 'casadi', 'continuation.system',\n"
        "         'continuation.dynamics.simulate', 'continuation.bvp.solve',\n"
        "         'continuation.periodic.continuation', 'ship_models.registry')\n"
        "print(','.join(m for m in heavy if m in sys.modules))\n"
    )
    assert _fresh(code) == ""


def test_a_function_named_as_its_module_stays_the_function():
    # ``continuation.dynamics.simulate`` is the function (as with eager imports), however
    # the sub-module of the same name was imported first
    code = (
        "import continuation.dynamics.simulate\n"
        "import continuation.periodic.floquet\n"
        "import sys, types\n"
        "from continuation.dynamics import simulate\n"
        "from continuation.periodic import floquet\n"
        "import continuation\n"
        "print(callable(simulate), callable(floquet),\n"
        "      continuation.simulate is sys.modules['continuation.dynamics.simulate'].simulate,\n"
        "      isinstance(continuation.dynamics.simulate, types.FunctionType))\n"
    )
    assert _fresh(code) == "True True True True"


def test_sub_modules_are_attributes_as_before():
    code = (
        "import continuation, ship_models\n"
        "print(continuation.newton.__name__, continuation.dynamics.saddles.__name__,\n"
        "      ship_models.vessel.__name__)\n"
        "try:\n"
        "    continuation.no_such_name\n"
        "except AttributeError as exc:\n"
        "    print(exc)\n"
    )
    assert _fresh(code).splitlines() == [
        "continuation.newton continuation.dynamics.saddles ship_models.vessel",
        "module 'continuation' has no attribute 'no_such_name'",
    ]
