"""Fixtures shared by all test modules (the toy systems themselves are in
``helpers.py``)."""

from __future__ import annotations

import logging

import pytest
from helpers import fold_normal_form

from continuation.system import System


@pytest.fixture
def fold_system() -> System:
    return fold_normal_form()


@pytest.fixture
def single_threaded() -> None:
    """Wait (up to 10 s) until this process runs one thread, as forking needs.

    Threads that earlier tests left winding down (a process pool's manager thread
    after its shutdown, a Ctrl-C watcher) end within that; one still alive then
    fails the test with its name.
    """
    import threading
    import time

    end = time.monotonic() + 10.0
    while threading.active_count() > 1 and time.monotonic() < end:
        time.sleep(0.05)
    others = [t.name for t in threading.enumerate() if t is not threading.main_thread()]
    assert not others, f"threads still alive: {others}"


@pytest.fixture(autouse=True)
def _cli_log_handler_removed():
    """Remove the stderr handler an in-process ``broachkit_cli.main.main`` call installs
    (``configure_logging``, marked ``_broachkit``) and restore the root level after
    each test.

    The handler holds the ``sys.stderr`` of the test that ran the command, which under
    ``capsys``/``capfd`` is a capture stream closed when that test ends; left in place,
    every later warning logged anywhere printed "--- Logging error --- ... I/O
    operation on closed file" tracebacks, and a ``--verbose`` command left the root
    logger at DEBUG for the rest of the session.
    """
    root = logging.getLogger()
    level = root.level
    yield
    for h in list(root.handlers):
        if getattr(h, "_broachkit", False):
            root.removeHandler(h)
            h.close()
    root.setLevel(level)


@pytest.fixture(scope="module")
def model():
    """Umeda's purse seiner (one instance per test module)."""
    from ship_models import purse_seiner

    return purse_seiner()


@pytest.fixture(scope="module")
def orbit(model):
    """The purse seiner's periodic orbit at the paper's first initial controls
    (Fn = 0.1, chi_c = 0), by shooting."""
    from ship_models.analysis.sudden_change import periodic_orbit

    o = periodic_orbit(model, model.default_params().replace(Fn=0.1, chi_c=0.0))
    assert o.success, o.message
    return o


@pytest.fixture(scope="module")
def fn_het(model):
    """Heteroclinic-bifurcation Fn at chi_c = 10 deg by collocation (independent method)."""
    from helpers import CHI10

    from ship_models.analysis.critical_bvp import critical_fn_bvp

    conn = critical_fn_bvp(CHI10, model=model)
    assert conn.success
    return float(conn.Fn)
