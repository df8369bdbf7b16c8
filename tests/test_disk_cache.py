"""The on-disk cache of estimation steps (ship_models.disk_cache)."""

from __future__ import annotations

import numpy as np

from ship_models import disk_cache


def _slow(a, *, b=1.0):
    _slow.calls += 1
    return np.array([a, b]) * 2.0


_slow.calls = 0


def test_a_hit_returns_the_same_result_and_new_inputs_miss(tmp_path, monkeypatch):
    monkeypatch.setenv("BROACHKIT_CACHE_DIR", str(tmp_path))
    _slow.calls = 0
    first = disk_cache.cached_call("slow", _slow, 1.5, b=2.0)
    again = disk_cache.cached_call("slow", _slow, 1.5, b=2.0)
    assert _slow.calls == 1 and np.array_equal(first, again)
    disk_cache.cached_call("slow", _slow, 1.5, b=3.0)  # another input: computed
    assert _slow.calls == 2
    assert len(list((tmp_path / "estimation").glob("slow-*.pkl"))) == 2


def test_a_damaged_entry_is_recomputed_and_the_cache_can_be_off(tmp_path, monkeypatch):
    monkeypatch.setenv("BROACHKIT_CACHE_DIR", str(tmp_path))
    _slow.calls = 0
    disk_cache.cached_call("slow", _slow, 4.0)
    (entry,) = (tmp_path / "estimation").glob("slow-*.pkl")
    entry.write_bytes(b"not a pickle")
    assert np.array_equal(disk_cache.cached_call("slow", _slow, 4.0), [8.0, 2.0])
    assert _slow.calls == 2
    monkeypatch.setenv("BROACHKIT_CACHE", "0")
    disk_cache.cached_call("slow", _slow, 4.0)
    assert _slow.calls == 3


def test_the_model_built_from_the_cache_equals_a_fresh_build(tmp_path, monkeypatch):
    from ship_models.estimation import build_vessel_model
    from ship_models.vessel import load_vessel

    monkeypatch.setenv("BROACHKIT_CACHE_DIR", str(tmp_path))
    v = load_vessel("purse_seiner")
    cold = build_vessel_model(v)
    warm = build_vessel_model(v)  # GZ curve and topside fit from the disk
    monkeypatch.setenv("BROACHKIT_CACHE", "0")
    fresh = build_vessel_model(v)
    phi = np.radians(np.linspace(0.0, 80.0, 41))
    for m in (warm, fresh):
        assert np.array_equal(m.forces.gz(phi), cold.forces.gz(phi))
