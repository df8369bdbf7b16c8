"""Ctrl-C (SIGINT) stops a simulation quickly, inside CVODES's long native calls too
(with the right-hand side in the virtual machine and compiled, ``compiled``).

Each test runs a long simulation in a child process, waits until the child has finished
its first block of output samples, sends it SIGINT and checks that the child ends within
3 s with ``KeyboardInterrupt``, keeping the samples already integrated (and right: the
energy of the conservative test system stays constant along them).

The test system is the conservative oscillator :math:`\\dot q = c v`,
:math:`\\dot v = -c V'(q)` with :math:`V(q) = -\\sum_{k=1}^{100} \\cos(k q) / k^4` and
``c = 25`` (a period of about 0.2): its right-hand side costs a few hundred operations
and one CVODES call (50 samples of ``dt = 1``) takes several seconds of native code, so
the interrupt must reach the integrator *inside* the call.
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from continuation.sigint import _Sigints, sigint_recorded

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, signal, sys, time
import numpy as np
signal.signal(signal.SIGINT, signal.default_int_handler)  # as in an interactive run
from continuation.dynamics import classify_fate, simulate
from continuation.status import Status
from continuation.system import System

K, C = 100, 25.0
def rhs(x, p, ops):
    acc = 0
    for k in range(1, K + 1):
        acc = acc + ops.sin(k * x[0]) / k**3
    return ops.stack([C * x[1], -C * acc])

def energy(x):
    k = np.arange(1, K + 1)
    return 0.5 * x[:, 1] ** 2 - np.sum(np.cos(np.outer(x[:, 0], k)) / k**4, axis=1)

S = System(rhs, ("q", "v"), ())
t_start = time.perf_counter()
def progress(t, x):
    print(json.dumps({"block": t, "seconds": time.perf_counter() - t_start}), flush=True)

if sys.argv[1] == "compiled":  # the same with the compiled right-hand side in CVODES
    import os, tempfile
    import continuation.casadi_compile as cc
    from continuation.dynamics.simulate import Simulator
    os.environ["BROACHKIT_CACHE_DIR"] = tempfile.mkdtemp(prefix="bk_sigint_")
    cc.MIN_INSTRUCTIONS = 0
    be = Simulator(S, [])._backend
    be.uses_compiled()  # starts the compilation
    cc.wait(300)
    assert be.uses_compiled(), "the right-hand side was not compiled"
    t_start = time.perf_counter()
if sys.argv[1] in ("simulate", "compiled"):
    tr = simulate(S, [1.0, 0.0], [], (0.0, 1000.0), dt=1.0, progress=progress)
    status = tr.status
else:  # no equilibria, no section: undecided after t_max, 20 segments of one call each
    fate = classify_fate(S, [], [1.0, 0.0], t_max=1000.0, segment=50.0, dt=1.0,
                         progress=progress)
    tr, status = fate.trajectory, fate.status
E = energy(tr.x)
print(json.dumps({"status": status.name, "t_final": float(tr.t[-1]),
                  "energy_drift": float(np.max(np.abs(E - E[0])))}), flush=True)
if status is Status.INTERRUPTED:
    raise KeyboardInterrupt
"""


def _run_and_interrupt(kind: str) -> tuple[float, dict, dict, subprocess.CompletedProcess]:
    proc = subprocess.Popen(
        [sys.executable, "-c", CHILD, kind],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = proc.stdout.readline()  # the first block is done: the second one runs
        first = json.loads(line)
        t_sig = time.monotonic()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
        delay = time.monotonic() - t_sig
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    last = json.loads(out.strip().splitlines()[-1])
    return delay, first, last, subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


@pytest.mark.parametrize("kind", ["simulate", "classify", "compiled"])
def test_sigint_stops_a_long_cvodes_call_and_keeps_the_finished_samples(kind):
    delay, first, last, proc = _run_and_interrupt(kind)
    seen = f"first block {first}, child's last line {last}, stderr {proc.stderr[-600:]!r}"
    assert delay < 3.0, f"took {delay:.2f} s to stop; {seen}"
    # the interrupt did not wait for the running native call: one call lasts longer
    assert delay < 0.5 * first["seconds"], f"took {delay:.2f} s to stop; {seen}"
    assert last["status"] == "INTERRUPTED"
    assert first["block"] <= last["t_final"] < 1000.0  # what finished is kept
    # and it is the right solution: the energy is conserved to the integrator's global
    # error (about 1.6e-7 after 50 time units, some 250 periods, at rtol = 1e-10)
    assert last["energy_drift"] < 1e-6
    assert proc.returncode == -signal.SIGINT and "KeyboardInterrupt" in proc.stderr


def test_sigint_recorded_counts_chains_and_restores_the_handler():
    seen = []

    def handler(signum, frame):
        seen.append(signum)

    old = signal.signal(signal.SIGINT, handler)
    try:
        with sigint_recorded():
            with sigint_recorded():  # nested (a classifier's segments): one install
                n0 = _Sigints.count
                signal.raise_signal(signal.SIGINT)
                assert _Sigints.count == n0 + 1
            assert signal.getsignal(signal.SIGINT) is not handler
        assert seen == [signal.SIGINT]  # the previous handler still ran
        assert signal.getsignal(signal.SIGINT) is handler
    finally:
        signal.signal(signal.SIGINT, old)


def _oscillator():
    from continuation.system import System

    return System(lambda x, p, ops: ops.stack([x[1], -x[0]]), ("q", "v"), ())


def test_an_interrupt_handled_during_a_call_that_ends_normally_is_not_lost(monkeypatch):
    """If a SIGINT was handled while a CVODES call ran but the call still returned (its
    KeyboardInterrupt lost inside the native code), the simulation stops after that call
    as INTERRUPTED, keeping what was integrated before it."""
    import numpy as np

    from continuation.dynamics import simulate
    from continuation.dynamics.integrators import _CvodesBackend
    from continuation.status import Status

    real = _CvodesBackend._integrator
    calls = []

    class Lossy:
        def __init__(self, integ, n_out):
            self.integ, self.n_out = integ, n_out

        def call(self, args):
            out = self.integ.call(args)
            calls.append(self.n_out)
            if len(calls) == 3:  # as if the handler ran inside the third call
                _Sigints.count += 1
            return out

    monkeypatch.setattr(
        _CvodesBackend, "_integrator", lambda self, n, s: Lossy(real(self, n, s), n)
    )
    tr = simulate(_oscillator(), [1.0, 0.0], [], (0.0, 1000.0), dt=1.0)
    assert tr.status is Status.INTERRUPTED
    assert len(calls) == 3  # stopped right after the call, not at the end
    # the samples of the two calls before it are kept (dt = 1), and they are right
    assert tr.t[-1] == calls[0] + calls[1] < 1000.0
    np.testing.assert_allclose(tr.x[:, 0], np.cos(tr.t), atol=1e-6)  # global error, rtol 1e-10


@pytest.mark.parametrize("kind", ["simulate", "classify"])
def test_an_interrupt_casadi_discards_in_its_argument_conversion_still_stops(monkeypatch, kind):
    """CasADi converts NumPy arguments with a Python helper (``casadi.DM_from_array``)
    inside its SWIG type check and clears an exception raised there: a Ctrl-C whose
    handler runs in that helper used to be lost (the run went on to its end). Here the
    handler is made to run there, on the 5th conversion."""
    import casadi

    from continuation.dynamics import classify_fate, simulate
    from continuation.status import Status

    real = casadi.DM_from_array
    seen = []

    def from_array(m, check_only=True):
        seen.append(1)
        if len(seen) == 5:
            _Sigints.count += 1  # what the handler does, then it raises
            raise KeyboardInterrupt
        return real(m, check_only)

    monkeypatch.setitem(vars(casadi), "DM_from_array", from_array)
    S = _oscillator()
    if kind == "simulate":
        tr = simulate(S, [1.0, 0.0], [], (0.0, 1000.0), dt=1.0)
        status = tr.status
    else:
        fate = classify_fate(S, [], [1.0, 0.0], t_max=1000.0, segment=50.0, dt=1.0,
                             poincare=None)  # fmt: skip
        tr, status = fate.trajectory, fate.status
    assert len(seen) >= 5  # the helper is used, so the loss can happen
    assert status is Status.INTERRUPTED
    assert tr.t[-1] < 200.0  # stopped within a call or two, not at t = 1000
