"""fsr-compile prunes the cache folders of other versions of the core: old ones, and beyond the newest few, but
never the current one, one written in the last hour, or a folder that is not fsr's."""

from __future__ import annotations

import os
from pathlib import Path

from fsr_bringup.cli.compile_cli import KEEP_MOST, prune_cache

DAY = 86400.0
NOW = 1_000_000_000.0


def key_folder(base: Path, index: int, age_s: float, module: str = "fsr_sim.core.plant") -> Path:
    folder = base / f"{index:016x}"
    (folder / module).mkdir(parents=True)
    entry = folder / module / "plant.nbi"
    entry.write_bytes(b"x")
    for path in (entry, folder / module, folder):
        os.utime(path, (NOW - age_s, NOW - age_s))
    return folder


def test_old_and_surplus_folders_go_the_current_recent_and_foreign_ones_stay(tmp_path):
    current = key_folder(tmp_path, 0, 30 * DAY)  # old, but the one in use
    old = key_folder(tmp_path, 1, 8 * DAY)
    recent = [key_folder(tmp_path, 2 + i, (i + 1) * 7200.0) for i in range(KEEP_MOST - 1)]  # 2 h .. 14 h old
    surplus = key_folder(tmp_path, 100, 2 * DAY)  # beyond the newest KEEP_MOST
    within_the_hour = key_folder(tmp_path, 101, 0.5 * 3600.0)  # newest: with the recent ones, KEEP_MOST
    foreign = key_folder(tmp_path, 102, 30 * DAY, module="other_project.module")
    not_a_key = tmp_path / "notes"
    not_a_key.mkdir()
    removed = prune_cache(tmp_path, current, now=NOW)
    assert sorted(removed) == sorted([old, surplus])
    for folder in (current, *recent, within_the_hour, foreign, not_a_key):
        assert folder.is_dir(), folder
    assert not old.exists() and not surplus.exists()


def test_a_missing_cache_base_is_nothing_to_prune(tmp_path):
    assert prune_cache(tmp_path / "missing", tmp_path / "missing" / ("0" * 16)) == []


def test_folders_written_within_the_hour_stay_however_many(tmp_path):
    current = key_folder(tmp_path, 0, 0.0)
    busy = [key_folder(tmp_path, 1 + i, 60.0 * (i + 1)) for i in range(KEEP_MOST + 3)]  # other checkouts flying now
    assert prune_cache(tmp_path, current, now=NOW) == []
    assert all(folder.is_dir() for folder in busy)
