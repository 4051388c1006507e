"""The authority kept per vehicle model (fsr_control.design.authority_cache): the computed numbers, from memory or
disk, never stale for a changed vehicle, and an unwritable or corrupt cache only costs the computation."""

from __future__ import annotations

import numpy as np
import pytest

from fsr_control.design import authority_cache
from fsr_control.design.authority import authority, force_set
from fsr_sim.model import load_vehicle


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "authority"
    monkeypatch.setenv("FSR_AUTHORITY_CACHE", str(folder))
    monkeypatch.setattr(authority_cache, "_MEMORY", {})
    return folder


def test_cached_numbers_are_the_computed_ones_from_memory_and_disk(cache, monkeypatch):
    vehicle = load_vehicle("quadrotor_ex4")
    computed = authority(vehicle)
    assert authority_cache.model_authority(vehicle) == computed
    (path,) = cache.glob("*.json")
    assert path.stem == authority_cache.vehicle_key(vehicle)
    monkeypatch.setattr(authority_cache, "_MEMORY", {})
    monkeypatch.setattr(authority_cache, "authority", lambda *_: pytest.fail("computed again, not read"))
    assert authority_cache.model_authority(vehicle) == computed
    assert computed.scaled(0.7) == authority(vehicle, 0.7)


def test_a_changed_vehicle_has_another_key(cache):
    vehicle = load_vehicle("quadrotor_ex4")
    heavier = vehicle.with_mass_properties(mass=vehicle.mass * 1.1)
    assert authority_cache.vehicle_key(heavier) != authority_cache.vehicle_key(vehicle)
    assert authority_cache.model_authority(heavier).hover_thrust == pytest.approx(heavier.weight)


def test_unwritable_or_corrupt_cache_is_computed(tmp_path, monkeypatch):
    vehicle = load_vehicle("octocopter")
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("FSR_AUTHORITY_CACHE", str(blocker / "authority"))
    monkeypatch.setattr(authority_cache, "_MEMORY", {})
    assert authority_cache.model_authority(vehicle) == authority(vehicle)
    folder = tmp_path / "corrupt"
    folder.mkdir()
    (folder / f"{authority_cache.vehicle_key(vehicle)}.json").write_text("{truncated")
    monkeypatch.setenv("FSR_AUTHORITY_CACHE", str(folder))
    monkeypatch.setattr(authority_cache, "_MEMORY", {})
    assert authority_cache.model_authority(vehicle) == authority(vehicle)
    with pytest.raises(ValueError, match="already scaled"):
        authority(vehicle, 0.5).scaled(0.5)


def test_the_force_set_of_a_fully_actuated_vehicle_is_kept_too(cache, monkeypatch):
    vehicle = load_vehicle("tilting_quadrotor_ex5")
    computed = force_set(vehicle)
    kept = authority_cache.model_force_set(vehicle)
    np.testing.assert_array_equal(kept.normals, computed.normals)
    monkeypatch.setattr(authority_cache, "_MEMORY", {})
    monkeypatch.setattr(authority_cache, "force_set", lambda *_: pytest.fail("computed again, not read"))
    read = authority_cache.model_force_set(vehicle)
    np.testing.assert_array_equal(read.offsets, computed.offsets)
    np.testing.assert_array_equal(read.hover, computed.hover)
    assert authority_cache.model_force_set(load_vehicle("quadrotor_ex4")) is None
