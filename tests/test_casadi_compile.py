"""Compiled CasADi functions (continuation.casadi_compile): compiled only where allowed.

A function missing from the cache is compiled only inside ``allow_compilation`` (a long
driver); elsewhere the original is used, and a library already in the cache is loaded.
The compiled copy gives the same values as CasADi's virtual machine (to round-off).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import continuation.casadi_compile as cc


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("BROACHKIT_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("BROACHKIT_COMPILE", raising=False)
    monkeypatch.setattr(cc, "_MEMO", {})
    monkeypatch.setattr(cc, "_BY_ID", {})
    return tmp_path


def _fn(c: float) -> ca.Function:
    x = ca.SX.sym("x", 3)
    p = ca.SX.sym("p", 2)
    y = ca.vertcat(ca.sin(x[0]) * p[0] + c, x[1] * x[2] - p[1], ca.exp(-(x[0] ** 2)) * x[2])
    return ca.Function("f", [x, p], [y])


@pytest.mark.skipif(cc._compiler() is None, reason="no C compiler")
def test_compiled_only_inside_allow_compilation_then_from_the_cache(cache):
    f = _fn(0.25)
    assert cc.compiled(f) is f  # not cached, not allowed: the virtual machine
    assert not list(cache.glob("*.so"))
    assert not cc.compilation_allowed()
    with cc.allow_compilation():
        assert cc.compilation_allowed()
        with cc.allow_compilation(False):
            assert cc.compiled(f) is f  # an inner block forbids it again
        g = cc.compiled(f)
    assert not cc.compilation_allowed()
    assert g is not f and len(list(cache.glob("*.so"))) == 1
    x, p = np.array([0.3, -1.2, 0.7]), np.array([1.5, 0.4])
    np.testing.assert_allclose(np.asarray(g(x, p)), np.asarray(f(x, p)), rtol=1e-14, atol=1e-15)
    # a new object with the same code, outside any block: loaded from the cache
    cc._MEMO.clear()
    f2 = _fn(0.25)
    g2 = cc.compiled(f2)
    assert g2 is not f2
    np.testing.assert_allclose(np.asarray(g2(x, p)), np.asarray(f(x, p)), rtol=1e-14)
    # other constants are other code: not compiled outside a block
    f3 = _fn(0.5)
    assert cc.compiled(f3) is f3


@pytest.mark.skipif(cc._compiler() is None, reason="no C compiler")
def test_compiling_decorator_allows_inside_the_call_only(cache):
    seen = []

    @cc.compiling
    def driver(a: int) -> int:
        seen.append(cc.compilation_allowed())
        return a + 1

    assert driver(1) == 2 and seen == [True] and not cc.compilation_allowed()


def test_compile_switched_off_returns_the_original(cache, monkeypatch):
    monkeypatch.setenv("BROACHKIT_COMPILE", "0")
    f = _fn(0.1)
    with cc.allow_compilation():
        assert cc.compiled(f) is f


@pytest.mark.skipif(cc._compiler() is None, reason="no C compiler")
def test_a_function_another_process_compiles_is_not_compiled_twice(cache, monkeypatch):
    f = _fn(0.75)
    calls = []
    monkeypatch.setattr(cc.subprocess, "run", lambda *a, **k: calls.append(a))
    lib = cc._library([f], cc._compiler())[1]
    assert lib.parent == cache
    lib.with_suffix(".building").mkdir()  # another process's compilation is running
    with cc.allow_compilation():
        assert cc.compiled(f) is f  # the virtual machine meanwhile
    assert not calls


def test_uncompiled_neither_compiles_nor_generates_code(cache, monkeypatch):
    """Inside ``uncompiled()`` (one-off models) a function is neither compiled nor looked
    up in the cache (no C code generated to find its library), even inside an
    ``allow_compilation`` block; outside, it is looked up as before."""
    fn = _fn(0.25)
    generated = []
    real = cc._library
    monkeypatch.setattr(cc, "_library", lambda fns, c: generated.append(1) or real(fns, c))
    with cc.uncompiled(), cc.allow_compilation():
        assert cc.compiled(fn) is fn
    assert generated == [] and not list(cache.iterdir())
    if cc._compiler() is not None:
        assert cc.compiled(fn) is fn  # not allowed, not cached: the original, but ...
        assert generated == [1]  # ... its code was generated to look for the library
