"""Compiled stage functions (continuation.casadi_compile): the same values as
CasADi's virtual machine, cached on disk, and a clean fallback without compilation."""

from __future__ import annotations

import importlib
import shutil

import numpy as np
import pytest

from continuation import System
from continuation.periodic.collocation import _BUFFERS, StageEvaluator

compiled_mod = importlib.import_module("continuation.casadi_compile")


def _rhs(x, p, ops):
    return ops.stack(
        [
            p[0] - (p[1] + 1) * x[0] + x[0] ** 2 * x[1] + ops.sin(x[2]),
            p[1] * x[0] - x[0] ** 2 * x[1],
            ops.exp(-x[0]) * x[2] - p[0],
        ]
    )


def _system() -> System:
    return System(_rhs, ("x", "y", "z"), ("A", "B"))


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("BROACHKIT_CACHE", str(tmp_path))
    monkeypatch.setattr(compiled_mod, "MIN_INSTRUCTIONS", 0)  # compile even this one
    return tmp_path / "casadi"


def _points(K: int) -> np.ndarray:
    return np.random.default_rng(3).uniform(0.2, 1.5, (K, 3))


@pytest.mark.skipif(compiled_mod._compiler() is None, reason="no C compiler")
def test_compiled_values_equal_the_virtual_machine_and_are_cached(cache):
    # one background compilation per process at a time: let those that earlier tests
    # started finish first, or this one would only be queued behind them
    compiled_mod.wait()
    s = _system()
    P = np.array([1.5, 3.2])
    X = _points(12)
    ev = StageEvaluator(s, 12, free=1)
    vm = [a.copy() for a in ev.all(X, P)]  # starts the compilation, evaluates by the VM
    assert not _BUFFERS[ev][2]
    compiled_mod.wait(120)
    out = ev.all(X, P)
    assert _BUFFERS[ev][2]  # switched to the compiled function
    for a, b in zip(vm, out, strict=True):
        np.testing.assert_allclose(b, a, rtol=1e-14, atol=1e-14)
    libs = list(cache.glob("*.so"))
    assert len(libs) == 1 and not [p for p in cache.iterdir() if p.is_dir()]
    # a new system object with the same equations loads the library at once
    ev2 = StageEvaluator(_system(), 12, free=1)
    ev2.all(X, P)
    assert _BUFFERS[ev2][2]
    # the free-parameter column is df/dB: -x + ... in the first equation, x in the second
    np.testing.assert_allclose(out[2][:, :2, 0], np.c_[-X[:, 0], X[:, 0]], rtol=1e-14)


def test_no_compilation_when_switched_off(cache, monkeypatch):
    monkeypatch.setenv("BROACHKIT_COMPILE", "0")
    s = _system()
    ev = StageEvaluator(s, 5, free=0)
    F, J, Jp = ev.all(_points(5), np.array([1.5, 3.2]))
    assert not _BUFFERS[ev][2]
    assert not cache.exists() or not list(cache.iterdir())
    np.testing.assert_allclose(Jp[:, :, 0], np.c_[np.ones(5), np.zeros(5), -np.ones(5)])


def test_no_compiler_found(cache, monkeypatch):
    monkeypatch.setenv("CC", "")
    monkeypatch.setattr(shutil, "which", lambda name: None)
    assert compiled_mod._compiler() is None
    ev = StageEvaluator(_system(), 4, free=0)
    ev.all(_points(4), np.array([1.5, 3.2]))
    assert not _BUFFERS[ev][2]


def test_stage_functions_are_not_pickled_with_the_system():
    """The cached CasADi functions live beside the system, not in it: a system sent to
    sweep workers pickles to the same bytes before and after a periodic evaluation."""
    import pickle

    s = _system()
    before = len(pickle.dumps(s))
    ev = StageEvaluator(s, 6, free=0)
    ev.all(_points(6), np.array([1.5, 3.2]))
    assert len(pickle.dumps(s)) == before
    s2 = pickle.loads(pickle.dumps(s))
    F2 = StageEvaluator(s2, 6, free=0).all(_points(6), np.array([1.5, 3.2]))[0]
    np.testing.assert_allclose(F2, ev.all(_points(6), np.array([1.5, 3.2]))[0], rtol=1e-15)
